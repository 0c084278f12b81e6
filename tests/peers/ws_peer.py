#!/usr/bin/env python3
"""A WebSocket server (wsproto, as pymavlink's wsserver: uses) that
answers MAVLink PINGs in binary messages, and misbehaves on request, for
mavping's WebSocket link tests:

  ws_peer.py PORT [--auth USER:PASS] [--text-after N] [--close-after N]
                  [--status CODE]

  --auth USER:PASS  refuse a handshake without that basic authentication
                    (HTTP 401)
  --status CODE     refuse every handshake with this HTTP status
  --text-after N    after N PING replies, send a text message
  --close-after N   after N PING replies, close the WebSocket (1001,
                    "going away")

One client at a time. Prints "ready"; on SIGTERM one JSON line: handshakes
accepted and refused (and the Authorization header each brought), PING
requests, replies.
"""
import argparse
import base64
import json
import os
import signal
import socket
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import common as mavlink  # noqa: E402
from wsproto import ConnectionType, WSConnection  # noqa: E402
from wsproto.events import (  # noqa: E402
    AcceptConnection, BytesMessage, CloseConnection, RejectConnection, Request, TextMessage)


class Out:
    def __init__(self):
        self.data = b""

    def write(self, data):
        self.data += data


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port", type=int)
    ap.add_argument("--auth")
    ap.add_argument("--status", type=int)
    ap.add_argument("--text-after", type=int)
    ap.add_argument("--close-after", type=int)
    a = ap.parse_args()
    truth = {"accepted": 0, "refused": 0, "authorization": [], "ping_requests": 0, "replies": 0}
    done = []
    signal.signal(signal.SIGTERM, lambda *_: done.append(1))
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", a.port))
    listener.listen(1)
    listener.settimeout(0.1)
    out = Out()
    mav = mavlink.MAVLink(out, srcSystem=1, srcComponent=1)
    print("ready", flush=True)
    while not done:
        try:
            sock, _ = listener.accept()
        except socket.timeout:
            continue
        sock.settimeout(0.1)
        ws = WSConnection(ConnectionType.SERVER)
        parser = mavlink.MAVLink(None)
        closed = False
        while not done and not closed:
            try:
                data = sock.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                break
            if not data:
                break
            ws.receive_data(data)
            reply = b""
            for event in ws.events():
                if isinstance(event, Request):
                    headers = {k.decode().lower(): v.decode() for k, v in event.extra_headers}
                    given = headers.get("authorization")
                    truth["authorization"].append(given)
                    want = None
                    if a.auth:
                        want = "Basic " + base64.b64encode(a.auth.encode()).decode()
                    status = a.status or (401 if want and given != want else None)
                    if status:
                        truth["refused"] += 1
                        reply += ws.send(RejectConnection(status_code=status))
                        closed = True
                    else:
                        truth["accepted"] += 1
                        reply += ws.send(AcceptConnection())
                elif isinstance(event, CloseConnection):
                    reply += ws.send(event.response())
                    closed = True
                elif isinstance(event, BytesMessage):
                    for msg in parser.parse_buffer(bytes(event.data)) or []:
                        if msg.get_type() != "PING" or msg.target_system != 0:
                            continue
                        truth["ping_requests"] += 1
                        mav.ping_send(msg.time_usec, msg.seq, msg.get_srcSystem(),
                                      msg.get_srcComponent())
                        reply += ws.send(BytesMessage(data=out.data))
                        out.data = b""
                        truth["replies"] += 1
                        if a.text_after and truth["replies"] == a.text_after:
                            reply += ws.send(TextMessage(data='{"header":{},"message":{}}'))
                        if a.close_after and truth["replies"] == a.close_after:
                            reply += ws.send(CloseConnection(code=1001, reason="going away"))
                            closed = True
            if reply:
                try:
                    sock.sendall(reply)
                except OSError:
                    break
        sock.close()
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    sys.exit(main())
