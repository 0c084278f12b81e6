#!/usr/bin/env python3
"""A vehicle behind a mavlink2rest WebSocket (wsproto, as ws_peer.py), for
mavping's m2r:// tests: every message a JSON text as mavlink2rest 1.0
writes it, and what it takes read as mavlink2rest reads it.

  m2r_peer.py PORT [--drop P] [--seed S] [--heartbeat-hz H]
                   [--autopilot N] [--junk N] [--unknown N]

What mavlink2rest sends (src/websocket_manager.rs, src/data.rs): the
`mavlink` crate's serde form of {"header": MavHeader, "message":
MavMessage}, through serde_json::to_value (keys sorted) and
to_string_pretty (two-space indent); the message's "type" is its name,
enums are {"type": NAME} objects, bit flags "A | B" strings. What it
takes: the same JSON; it answers each text with the Rust result of
sending the message, "Ok(LEN)", or "Could not convert input message."
when the text is no message it can read. The path is /v1/ws/mavlink; a
?filter=REGEX query picks messages by name (all when absent).

The vehicle is 1/1 (ArduSub by default: MAV_AUTOPILOT 3): it sends
HEARTBEAT at --heartbeat-hz, answers PING requests (target 0/0) and
TIMESYNC requests (tc1 0), and drops each request's answer with
probability --drop, seeded. --junk N texts that are no message and
--unknown N messages of a type no dialect has go first, when a client
connects.

One client at a time. Prints "ready"; on SIGTERM one JSON line of truth:
requests, replies and dropped per kind, texts it could not convert, the
junk and unknown messages sent and the junk's bytes.
"""
import argparse
import json
import os
import random
import re
import select
import signal
import socket
import sys
import time
from urllib.parse import parse_qs

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402
from wsproto import ConnectionType, WSConnection  # noqa: E402
from wsproto.events import (  # noqa: E402
    AcceptConnection, CloseConnection, Ping, RejectConnection, Request, TextMessage)

PATH = "/v1/ws/mavlink"
# Every enum entry's value by name (names are unique across enums).
ENUM_VALUES = {e.name: value for entries in mavlink.enums.values()
               for value, e in entries.items()}


class Out:
    def __init__(self):
        self.data = b""

    def write(self, data):
        self.data += data


def as_mavlink2rest(sysid, compid, seq, message):
    """One message as mavlink2rest writes it (serde_json: keys sorted, pretty)."""
    header = {"system_id": sysid, "component_id": compid, "sequence": seq}
    return json.dumps({"header": header, "message": message}, indent=2, sort_keys=True)


def field_value(cls, name, value):
    """A JSON field as pymavlink wants it: enums from {"type": NAME}, flags
    from "A | B"; None when the form is not the crate's."""
    enum = cls.fieldenums_by_name.get(name)
    if enum is None:
        return value
    if cls.fielddisplays_by_name.get(name) == "bitmask":
        if not isinstance(value, str):
            return None
        flags = [f.strip() for f in value.split("|") if f.strip()]
        if any(f not in ENUM_VALUES for f in flags):
            return None
        bits = 0
        for f in flags:
            bits |= ENUM_VALUES[f]
        return bits
    if not isinstance(value, dict) or value.get("type") not in ENUM_VALUES:
        return None
    return ENUM_VALUES[value["type"]]


def convert(text, mav):
    """A text as mavlink2rest's ws_callback reads it: (header, pymavlink
    message), or None for "Could not convert input message."."""
    try:
        doc = json.loads(text)
        header, message = doc["header"], doc["message"]
        ids = (header["system_id"], header["component_id"], header["sequence"])
        cls = mavlink.mavlink_map[getattr(mavlink, "MAVLINK_MSG_ID_" + message["type"])]
    except (ValueError, KeyError, TypeError, AttributeError):
        return None
    values = []
    for name in cls.fieldnames:
        key = "mavtype" if name == "type" else name  # the crate's name for it
        if key not in message:
            return None
        value = field_value(cls, name, message[key])
        if value is None:
            return None
        values.append(value)
    try:
        msg = cls(*values)
        msg.pack(mav)  # in range, or it raises
    except Exception:  # noqa: BLE001 (struct.error, ValueError: not a message)
        return None
    return ids, msg


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port", type=int)
    ap.add_argument("--drop", type=float, default=0.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--heartbeat-hz", type=float, default=10.0)
    ap.add_argument("--autopilot", type=int, default=3)
    ap.add_argument("--junk", type=int, default=0)
    ap.add_argument("--unknown", type=int, default=0)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    truth = {"ping_requests": 0, "ping_replies": 0, "ping_dropped": 0,
             "timesync_requests": 0, "timesync_replies": 0, "timesync_dropped": 0,
             "texts": 0, "not_converted": 0, "junk": 0, "junk_bytes": 0, "unknown": 0,
             "refused": 0}
    done = []
    signal.signal(signal.SIGTERM, lambda *_: done.append(1))
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", a.port))
    listener.listen(1)
    listener.settimeout(0.1)
    mav = mavlink.MAVLink(Out(), srcSystem=1, srcComponent=1)
    seq = [0]
    print("ready", flush=True)

    def vehicle(message, ws, pattern):
        """One message from the vehicle, if the client's filter takes it."""
        if not pattern.search(message["type"]):
            return b""
        text = as_mavlink2rest(1, 1, seq[0], message)
        seq[0] = (seq[0] + 1) % 256
        return ws.send(TextMessage(data=text))

    def heartbeat():
        return {"type": "HEARTBEAT", "custom_mode": 19, "mavtype": {"type": "MAV_TYPE_SUBMARINE"},
                "autopilot": {"type": mavlink.enums["MAV_AUTOPILOT"][a.autopilot].name},
                "base_mode": "MAV_MODE_FLAG_CUSTOM_MODE_ENABLED",
                "system_status": {"type": "MAV_STATE_STANDBY"}, "mavlink_version": 3}

    def answer(ids, msg):
        """The vehicle's answer to a request, or None."""
        kind = msg.get_type()
        if kind == "PING" and msg.target_system == 0 and msg.target_component == 0:
            reply = {"type": "PING", "time_usec": msg.time_usec, "seq": msg.seq,
                     "target_system": ids[0], "target_component": ids[1]}
        elif kind == "TIMESYNC" and msg.tc1 == 0:
            reply = {"type": "TIMESYNC", "tc1": time.monotonic_ns(), "ts1": msg.ts1,
                     "target_system": ids[0], "target_component": ids[1]}
        else:
            return None
        name = kind.lower()
        truth[name + "_requests"] += 1
        if rng.random() < a.drop:
            truth[name + "_dropped"] += 1
            return None
        truth[name + "_replies"] += 1
        return reply

    while not done:
        try:
            sock, _ = listener.accept()
        except socket.timeout:
            continue
        # A reply is a few hundred bytes: Nagle would hold it back.
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        ws = WSConnection(ConnectionType.SERVER)
        pattern = None
        closed = False
        parts = []
        next_hb = time.monotonic()
        while not done and not closed:
            out = b""
            if pattern is not None and time.monotonic() >= next_hb:
                out += vehicle(heartbeat(), ws, pattern)
                next_hb = time.monotonic() + 1.0 / a.heartbeat_hz
            if out:
                try:
                    sock.sendall(out)
                except OSError:
                    break
            ready, _, _ = select.select([sock], [], [], 0.01)
            if not ready:
                continue
            try:
                data = sock.recv(65536)
            except OSError:
                break
            if not data:
                break
            ws.receive_data(data)
            reply = b""
            for event in ws.events():
                if isinstance(event, Request):
                    path, _, query = event.target.partition("?")
                    if path != PATH:
                        truth["refused"] += 1
                        reply += ws.send(RejectConnection(status_code=404))
                        closed = True
                        continue
                    regex = parse_qs(query).get("filter", [".*"])[0]
                    pattern = re.compile(regex)
                    reply += ws.send(AcceptConnection())
                    for i in range(a.junk):
                        junk = "junk %d: not a MAVLink message" % i
                        truth["junk"] += 1
                        truth["junk_bytes"] += len(junk.encode())
                        reply += ws.send(TextMessage(data=junk))
                    for i in range(a.unknown):
                        truth["unknown"] += 1
                        text = as_mavlink2rest(1, 1, 0, {"type": "NO_DIALECT_HAS_THIS", "n": i})
                        reply += ws.send(TextMessage(data=text))
                elif isinstance(event, CloseConnection):
                    reply += ws.send(event.response())
                    closed = True
                elif isinstance(event, Ping):
                    reply += ws.send(event.response())
                elif isinstance(event, TextMessage):
                    parts.append(event.data)
                    if not event.message_finished:
                        continue
                    text, parts = "".join(parts), []
                    truth["texts"] += 1
                    converted = convert(text, mav)
                    if converted is None:
                        truth["not_converted"] += 1
                        reply += ws.send(TextMessage(data="Could not convert input message."))
                        continue
                    ids, msg = converted
                    length = len(msg.pack(mav))
                    # mavlink2rest's answer to the sender: the write's result.
                    reply += ws.send(TextMessage(data="Ok(%d)" % length))
                    message = answer(ids, msg)
                    if message is not None:
                        reply += vehicle(message, ws, pattern)
            if reply:
                try:
                    sock.sendall(reply)
                except OSError:
                    break
        sock.close()
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    sys.exit(main())
