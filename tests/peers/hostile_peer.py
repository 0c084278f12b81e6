#!/usr/bin/env python3
"""A hostile MAVLink responder (pymavlink): it answers every PING request
as 1/1, once and in time, but surrounds its replies with everything a bad
link or an untrusted peer can send, and counts what it sent.

Per request i (mavping's n-th request, counted here):
  i % 6 == 0  a bad-CRC PING datagram first (no start byte after its own)
  i % 6 == 1  an unknown message id frame (0xEEEEEE) in its own datagram
  i % 6 == 2  a v1 start byte whose length (255) lies, then the reply in the
              same datagram or write (the reply must still be found at once)
  i % 6 == 3  the reply is MAVLink 2 *signed* (a key mavping does not have)
  i % 6 == 4  the reply is MAVLink 1 (v1/v2 mixed)
  i % 4 == 0  a reply echoing a wrong time_usec for this seq, sent first
  i % 4 == 1  a reply for a seq never sent (seq + 1,000,000)
  i % 5 == 0  a reply claiming 7/1 (an id that never answers) with a wrong
              time_usec: stale for 7/1, never received
TIMESYNC requests get their reply, and every 3rd one first a reply echoing
a wrong ts1.
Serial mode (--serial DEV): one byte stream; the replies and junk are cut
into pieces written separately (frames split across reads), and a
truncated frame (first 9 bytes of a HEARTBEAT) precedes every 3rd reply.
Prints "ready", then one JSON line of ground truth on SIGTERM.
"""
import argparse
import json
import os
import signal
import socket
import sys
import time

from pymavlink.dialects.v20 import common as mav2
from pymavlink.dialects.v10 import common as mav1

STX = (0xFD, 0xFE)


class Out:
    def __init__(self):
        self.buf = bytearray()

    def write(self, b):
        self.buf += b


def encoder(module, sysid=1, compid=1, key=None):
    out = Out()
    m = module.MAVLink(out, srcSystem=sysid, srcComponent=compid)
    if key is not None:
        m.signing.secret_key = key
        m.signing.link_id = 3
        m.signing.timestamp = 1
        m.signing.sign_outgoing = True
    return m


def bad_crc_frame():
    """A PING frame with a wrong CRC and no start byte after its first."""
    m = encoder(mav2)
    t = 1
    while True:
        frame = bytearray(m.ping_encode(t, 1, 255, 190).pack(m))
        frame[-1] ^= 0x55
        if not any(b in STX for b in frame[1:]):
            return bytes(frame)
        t += 1


def unknown_frame():
    # v2, payload 2, msgid 0xEEEEEE: no dialect knows it.
    return bytes([0xFD, 2, 0, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE, 0x11, 0x22, 0x33, 0x44])


LYING = bytes([0xFE, 0xFF, 0x00, 0x01, 0x01, 0x04])  # claims 255 bytes


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int)
    ap.add_argument("--serial")
    ap.add_argument("--baud", type=int, default=57600)
    ap.add_argument("--log", help="serial mode: append every byte written here")
    args = ap.parse_args()

    v2 = encoder(mav2)
    v1 = encoder(mav1)
    signed = encoder(mav2, key=bytes(range(32)))
    spoof = encoder(mav2, sysid=7)
    truth = dict(requests=0, replies=0, signed=0, v1=0, bad_crc=0, damaged=0, unknown_id=0, lying=0,
                 wrong_time=0, unsent_seq=0, spoofed=0, skipped_bytes=0, truncated_sent=0,
                 timesync_requests=0, wrong_ts1=0)
    bad = bad_crc_frame()
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))

    if args.serial:
        import serial
        port = serial.Serial(args.serial, args.baud, timeout=0.05)
        parser = encoder(mav2)

        def recv():
            data = port.read(256)
            return parser.parse_buffer(data) or [] if data else []

        log = open(args.log, "wb") if args.log else None

        def send(datagrams):
            if log:
                log.write(b"".join(datagrams))
                log.flush()
            # One stream: each piece split in two writes with a pause, so
            # mavping reads frames in parts.
            for d in datagrams:
                half = max(1, len(d) // 2)
                port.write(d[:half])
                port.flush()
                time.sleep(0.002)
                port.write(d[half:])
                port.flush()
    else:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(("127.0.0.1", args.port))
        sock.settimeout(0.05)
        parser = encoder(mav2)
        peer = [None]

        def recv():
            try:
                data, peer[0] = sock.recvfrom(65535)
            except (socket.timeout, InterruptedError):
                return []
            return parser.parse_buffer(data) or []

        def send(datagrams):
            for d in datagrams:
                sock.sendto(d, peer[0])

    print("ready", flush=True)
    while not stop:
        try:
            msgs = recv()
        except InterruptedError:
            continue
        for msg in msgs:
            if msg.get_type() == "TIMESYNC" and msg.tc1 == 0:
                # TIMESYNC: the reply, and before every 3rd one a reply
                # echoing a wrong ts1 (targets 0/0, as ArduPilot sends).
                j = truth["timesync_requests"]
                truth["timesync_requests"] += 1
                out = []
                if j % 3 == 0:
                    out.append(v2.timesync_encode(12345, msg.ts1 + 7).pack(v2))
                    truth["wrong_ts1"] += 1
                out.append(v2.timesync_encode(time.monotonic_ns(), msg.ts1).pack(v2))
                truth["replies"] += 1
                send(out)
                continue
            if msg.get_type() != "PING" or msg.target_system != 0:
                continue
            i = truth["requests"]
            truth["requests"] += 1
            ts, tc = msg.get_srcSystem(), msg.get_srcComponent()
            out = []
            if i % 4 == 0:
                out.append(v2.ping_encode(msg.time_usec ^ 0x5A5A, msg.seq, ts, tc).pack(v2))
                truth["wrong_time"] += 1
            if i % 4 == 1:
                out.append(v2.ping_encode(msg.time_usec, (msg.seq + 1_000_000) % 2**32, ts, tc).pack(v2))
                truth["unsent_seq"] += 1
            if i % 5 == 0:
                out.append(spoof.ping_encode(msg.time_usec + 1, msg.seq, ts, tc).pack(spoof))
                truth["spoofed"] += 1
            kind = i % 6
            if kind == 0:
                out.append(bad)
                if args.serial:
                    # On the stream a cut HEARTBEAT follows it (i % 3 == 0):
                    # nothing shows it whole, so it is junk.
                    truth["bad_crc"] += 1
                    truth["skipped_bytes"] += len(bad)
                else:
                    # A datagram of its own: a whole frame failing its CRC.
                    truth["damaged"] += 1
            elif kind == 1:
                out.append(unknown_frame())
                truth["unknown_id"] += 1
            if kind == 3:
                reply = signed.ping_encode(msg.time_usec, msg.seq, ts, tc).pack(signed)
                truth["signed"] += 1
            elif kind == 4:
                reply = v1.ping_encode(msg.time_usec, msg.seq, ts, tc).pack(v1)
                truth["v1"] += 1
            else:
                reply = v2.ping_encode(msg.time_usec, msg.seq, ts, tc).pack(v2)
            if kind == 2:
                reply = LYING + reply
                truth["lying"] += 1
                truth["skipped_bytes"] += len(LYING)
            if args.serial and i % 3 == 0:
                hb = v2.heartbeat_encode(2, 12, 0, 0, 4).pack(v2)
                out.append(hb[:9])
                truth["truncated_sent"] += 1
            out.append(reply)
            truth["replies"] += 1
            send(out)
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
