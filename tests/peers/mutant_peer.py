#!/usr/bin/env python3
"""A responder (pymavlink) that hides each PING reply among mutated copies
of itself, seeded, and reports what it sent as ground truth (issue 21).

For every PING request but the last it sends the true reply and COPIES
(default 8) mutated copies of it, in random order: over UDP each as its
own datagram; over TCP or a serial port (a pty) one after another in the
byte stream, written in 1 to 3 pieces cut at random. Each copy is one of:
  flip       1-3 distinct bit flips
  cut        the first 1..len-1 bytes
  junk       1-20 bytes drawn from {0xFD, 0xFE, random} before the whole frame
  length     a random length byte (the same as the true one: a whole copy)
  random     1-300 random bytes
  lone_fd    a lone 0xFD before the frame, its last CRC byte flipped
A junk-prefixed copy, and a random length byte equal to the true one, hold
the whole frame: an intact copy, which mavping must count as a duplicate.
The last request (--count) gets its reply alone, so mavping, which stops
once every request is answered, has read every copy before it.

Mutants can, by a 16-bit CRC collision (1 in 65,536 for each start byte
whose header is right), hold or splice into a valid frame that is none of
the intact copies, e.g. a cut copy whose claimed CRC lands in the next
copy. Such a frame overlaps the copy it runs into, and no scanner can
deliver both. The peer checks every exchange's bytes (on a stream with
the tail of the bytes before them) with pymavlink's CRC and dialect, and
draws the mutants again when a valid frame other than the intact copies
turns up; `redrawn` counts those.

Prints "ready", then one JSON line of ground truth on SIGTERM: requests,
replies, intact (extra whole copies), mutants, per-kind counts, redrawn,
bytes, and `copies`: {seq: whole copies beyond the first} for each seq that
had any.
"""
import argparse
import json
import random
import re
import signal
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav2
from pymavlink.generator.mavcrc import x25crc

KINDS = ("flip", "cut", "junk", "length", "random", "lone_fd")
START = re.compile(b"[\xfd\xfe]")
MAX_FRAME = 280


class Out:
    def __init__(self):
        self.buf = bytearray()

    def write(self, b):
        self.buf += b


def valid_frames(buf, since):
    """(start, end) of every CRC-valid frame of a message pymavlink's
    dialect knows, whole in buf and ending after `since`. Lengths are not
    checked: a superset of what any scanner accepts."""
    found = []
    for m in START.finditer(buf):
        i = m.start()
        if buf[i] == 0xFE:
            if i + 6 > len(buf):
                continue
            header, msgid, sig = 6, buf[i + 5], 0
        else:
            if i + 10 > len(buf) or buf[i + 2] > 1:
                continue
            header = 10
            msgid = buf[i + 7] | buf[i + 8] << 8 | buf[i + 9] << 16
            sig = 13 * buf[i + 2]
        end = i + header + buf[i + 1] + 2 + sig
        if end > len(buf) or end <= since or msgid not in mav2.mavlink_map:
            continue
        crc_at = i + header + buf[i + 1]
        crc = x25crc(buf[i + 1:crc_at])
        crc.accumulate(bytes([mav2.mavlink_map[msgid].crc_extra]))
        if crc.crc == buf[crc_at] | buf[crc_at + 1] << 8:
            found.append((i, end))
    return found


def mutate(rng, frame, kind):
    """One mutated copy: (bytes, offset of a whole copy of frame in it or None)."""
    if kind == "flip":
        m = bytearray(frame)
        for bit in rng.sample(range(8 * len(frame)), rng.randint(1, 3)):
            m[bit // 8] ^= 1 << (bit % 8)
        return bytes(m), None
    if kind == "cut":
        return frame[:rng.randint(1, len(frame) - 1)], None
    if kind == "junk":
        junk = bytes(rng.choice((0xFD, 0xFE, rng.randrange(256))) for _ in range(rng.randint(1, 20)))
        return junk + frame, len(junk)
    if kind == "length":
        m = bytearray(frame)
        m[1] = rng.randrange(256)
        return bytes(m), (0 if m[1] == frame[1] else None)
    if kind == "random":
        return bytes(rng.randrange(256) for _ in range(rng.randint(1, 300))), None
    m = bytearray(b"\xfd" + frame)
    m[-1] ^= 0xFF
    return bytes(m), None


def exchange(rng, frame, copies):
    """The true reply and `copies` mutants, shuffled: [(bytes, whole-copy
    offset or None, kind)]."""
    pieces = [(frame, 0, "true")]
    for _ in range(copies):
        kind = rng.choice(KINDS)
        data, at = mutate(rng, frame, kind)
        pieces.append((data, at, kind))
    rng.shuffle(pieces)
    return pieces


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, help="UDP: answer datagrams sent to this port")
    ap.add_argument("--tcp", type=int, help="TCP: accept one client on this port")
    ap.add_argument("--serial", help="a serial device (a pty)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--copies", type=int, default=8)
    ap.add_argument("--count", type=int, required=True, help="requests mavping sends")
    args = ap.parse_args()

    rng = random.Random(args.seed)
    mav = mav2.MAVLink(Out(), srcSystem=1, srcComponent=1)
    parser = mav2.MAVLink(Out())
    truth = dict(requests=0, replies=0, intact=0, mutants=0, redrawn=0, bytes=0,
                 kinds={k: 0 for k in KINDS}, copies={})
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    stream = args.port is None
    tail = b""

    if args.serial:
        import serial
        port = serial.Serial(args.serial, 57600, timeout=0.05)

        def recv():
            return port.read(4096)

        def write(data):
            port.write(data)
            port.flush()
    elif args.tcp:
        server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind(("127.0.0.1", args.tcp))
        server.listen(1)
        conn = [None]

        def recv():
            if conn[0] is None:
                server.settimeout(0.05)
                try:
                    conn[0] = server.accept()[0]
                except (socket.timeout, InterruptedError):
                    return b""
                conn[0].setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                conn[0].settimeout(0.05)
            try:
                return conn[0].recv(4096)
            except (socket.timeout, InterruptedError):
                return b""

        def write(data):
            conn[0].sendall(data)
    else:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(("127.0.0.1", args.port))
        sock.settimeout(0.05)
        peer = [None]

        def recv():
            try:
                data, peer[0] = sock.recvfrom(65535)
            except (socket.timeout, InterruptedError):
                return b""
            return data

    def clean(pieces, before, frame):
        """True when the bytes hold no valid frame but the intact copies."""
        if stream:
            buf = before + b"".join(p for p, _, _ in pieces)
            intended, at = set(), len(before)
            for data, whole, _ in pieces:
                if whole is not None:
                    intended.add((at + whole, at + whole + len(frame)))
                at += len(data)
            return all(f in intended for f in valid_frames(buf, len(before)))
        # A datagram meant to hold no whole frame (whole is None) is clean
        # only if none passes as one.
        return all(
            all(whole is not None and f == (whole, whole + len(frame))
                for f in valid_frames(data, 0))
            for data, whole, _ in pieces
        )

    print("ready", flush=True)
    while not stop:
        try:
            data = recv()
        except InterruptedError:
            continue
        for msg in (parser.parse_buffer(data) or []) if data else []:
            if msg.get_type() != "PING" or msg.target_system != 0:
                continue
            last = truth["requests"] == args.count - 1
            truth["requests"] += 1
            frame = bytes(mav.ping_encode(msg.time_usec, msg.seq, msg.get_srcSystem(),
                                          msg.get_srcComponent()).pack(mav))
            pieces = [(frame, 0, "true")] if last else exchange(rng, frame, args.copies)
            while not clean(pieces, tail, frame):
                truth["redrawn"] += 1
                if last:
                    # Nothing to draw again: move the reply on by a byte.
                    pieces = [(b"\x00", None, "pad")] + pieces
                else:
                    pieces = exchange(rng, frame, args.copies)
            whole = sum(1 for _, at, _ in pieces if at is not None)
            truth["replies"] += 1
            truth["intact"] += whole - 1
            if whole > 1:
                truth["copies"][str(msg.seq)] = whole - 1
            for _, _, kind in pieces:
                if kind in truth["kinds"]:
                    truth["kinds"][kind] += 1
                    truth["mutants"] += 1
            if stream:
                out = b"".join(p for p, _, _ in pieces)
                cuts = sorted(rng.sample(range(1, len(out)), min(len(out) - 1, rng.randint(0, 2))))
                for a, b in zip([0] + cuts, cuts + [len(out)]):
                    write(out[a:b])
                tail = (tail + out)[-(MAX_FRAME - 1):]
                truth["bytes"] += len(out)
            else:
                for p, _, _ in pieces:
                    sock.sendto(p, peer[0])
                    truth["bytes"] += len(p)
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
