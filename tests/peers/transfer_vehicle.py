#!/usr/bin/env python3
"""A vehicle that serves a parameter list, a mission and a file with
faults it plans and counts: the truth a download probe's figures are held
against. pymavlink, MAVLink 2, system 1 component 1, answers PING and TIMESYNC.

  transfer_vehicle.py PORT [--params N] [--mission N] [--file-size B]
      [--seed S] [--drop-list P] [--stop-list-after I] [--drop-reads P]
      [--drop-items P] [--drop-burst P] [--ignore params,mission,ftp]

Listens on udpin 127.0.0.1:PORT and answers whoever sent last. Prints
"ready". The faults, each drawn from one seeded random stream in the
order the frames go:
  --drop-list P         each PARAM_VALUE of the list dropped with P
  --stop-list-after I   the list ends after index I (the rest never sent
                        with it, as a vehicle that stopped sending)
  --drop-reads P        each answer to PARAM_REQUEST_READ dropped with P
  --drop-items P        the answer to each item's first request dropped
                        with P (a request sent again is always answered)
  --drop-burst P        each packet of an FTP burst dropped with P
  --ignore KINDS        never answer these requests at all
  --lose-open-ack       the first OpenFileRO's ACK is lost (the session
                        is open all the same); an open while one is open
                        gets NAK Fail, as ArduPilot's one session does
The file at /vehicle.bin holds bytes (i * 7 + 3) % 251; other paths get
NAK FileNotFound.

On SIGTERM, one JSON line: per kind what was served and dropped:
list_sent, list_dropped (by index), reads, reads_dropped, items_sent,
items_dropped, burst_packets, burst_dropped, burst_bytes_dropped, reads
of the file and its terminations.
"""
import argparse
import json
import random
import signal
import struct
import sys
import time

from pymavlink import mavutil

PATH = "/vehicle.bin"
ACK, NAK = 128, 129
TERMINATE, RESET, OPEN_RO, READ, BURST = 1, 2, 4, 5, 15
EOF, FILE_NOT_FOUND, INVALID_SESSION = 6, 10, 4
CHUNK = 239


def file_byte(i):
    return (i * 7 + 3) % 251


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("port", type=int)
    ap.add_argument("--params", type=int, default=300)
    ap.add_argument("--mission", type=int, default=20)
    ap.add_argument("--file-size", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--drop-list", type=float, default=0.0)
    ap.add_argument("--stop-list-after", type=int, default=None)
    ap.add_argument("--drop-reads", type=float, default=0.0)
    ap.add_argument("--drop-items", type=float, default=0.0)
    ap.add_argument("--drop-burst", type=float, default=0.0)
    ap.add_argument("--ignore", default="")
    ap.add_argument("--lose-open-ack", action="store_true")
    a = ap.parse_args()
    ignore = set(filter(None, a.ignore.split(",")))
    rng = random.Random(a.seed)
    m = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{a.port}", source_system=1, source_component=1
    )
    m.mav.WIRE_PROTOCOL_VERSION = "2.0"
    truth = {
        "list_sent": 0, "list_dropped": [], "reads": 0, "reads_dropped": 0,
        "items_sent": 0, "items_dropped": 0, "items_requested": 0,
        "burst_packets": 0, "burst_dropped": 0, "burst_bytes_dropped": 0,
        "file_reads": 0, "terminated": 0, "mission_acks": 0,
        "opens": 0, "open_acks_lost": 0, "opens_refused": 0, "resets": 0,
    }
    done = []
    signal.signal(signal.SIGTERM, lambda *_: done.append(1))
    asked = set()  # mission items asked for once already
    session_open = False
    print("ready", flush=True)
    last_beat = 0.0

    def value(i):
        m.mav.param_value_send(f"MAVPING_{i:04d}".encode(), float(i), 9, a.params, i)

    def ftp(seq, opcode, req, size, offset, data, session=0, complete=0):
        payload = struct.pack("<HBBBBBxI", seq, session, opcode, size, req, complete, offset)
        payload += bytes(data) + bytes(251 - 12 - len(data))
        m.mav.file_transfer_protocol_send(0, 0, 0, payload)

    def nak(seq, req, error):
        ftp(seq, NAK, req, 1, 0, [error])

    def chunk(offset):
        n = max(0, min(CHUNK, a.file_size - offset))
        return [file_byte(offset + i) for i in range(n)]

    while not done:
        now = time.time()
        if now - last_beat > 1:
            m.mav.heartbeat_send(2, 3, 0, 0, 0)
            last_beat = now
        msg = m.recv_match(blocking=True, timeout=0.05)
        if msg is None:
            continue
        t = msg.get_type()
        if t == "TIMESYNC" and msg.tc1 == 0:
            m.mav.timesync_send(time.monotonic_ns(), msg.ts1)
        elif t == "PING" and msg.target_system == 0:
            m.mav.ping_send(msg.time_usec, msg.seq, msg.get_srcSystem(), msg.get_srcComponent())
        elif t == "PARAM_REQUEST_LIST" and "params" not in ignore:
            end = a.params if a.stop_list_after is None else min(a.params, a.stop_list_after + 1)
            for i in range(end):
                if rng.random() < a.drop_list:
                    truth["list_dropped"].append(i)
                    continue
                value(i)
                truth["list_sent"] += 1
                time.sleep(0.0002)
        elif t == "PARAM_REQUEST_READ" and "params" not in ignore:
            truth["reads"] += 1
            if rng.random() < a.drop_reads:
                truth["reads_dropped"] += 1
            elif 0 <= msg.param_index < a.params:
                value(msg.param_index)
        elif t == "MISSION_REQUEST_LIST" and "mission" not in ignore:
            m.mav.mission_count_send(msg.get_srcSystem(), msg.get_srcComponent(), a.mission, 0)
        elif t in ("MISSION_REQUEST_INT", "MISSION_REQUEST") and "mission" not in ignore:
            truth["items_requested"] += 1
            first = msg.seq not in asked
            asked.add(msg.seq)
            if first and rng.random() < a.drop_items:
                truth["items_dropped"] += 1
                continue
            m.mav.mission_item_int_send(
                msg.get_srcSystem(), msg.get_srcComponent(), msg.seq, 6, 16, 0, 1,
                0, 0, 0, 0, 473977420 + msg.seq, 85455940, 30.0, 0)
            truth["items_sent"] += 1
        elif t == "MISSION_ACK":
            truth["mission_acks"] += 1
            asked.clear()
        elif t == "FILE_TRANSFER_PROTOCOL" and "ftp" not in ignore:
            p = bytes(msg.payload)
            seq, session, opcode, size, _req, _c, offset = struct.unpack("<HBBBBBxI", p[:12])
            if opcode == OPEN_RO:
                path = p[12:12 + size].split(b"\0")[0].decode(errors="replace")
                if path != PATH:
                    nak(seq + 1, OPEN_RO, FILE_NOT_FOUND)
                    continue
                truth["opens"] += 1
                if session_open and a.lose_open_ack:
                    truth["opens_refused"] += 1
                    nak(seq + 1, OPEN_RO, 1)  # Fail: the one session is held
                    continue
                session_open = True
                if a.lose_open_ack and truth["open_acks_lost"] == 0:
                    truth["open_acks_lost"] += 1
                    continue
                ftp(seq + 1, ACK, OPEN_RO, 4, 0, list(struct.pack("<I", a.file_size)))
            elif opcode == BURST and session_open:
                at, n = offset, seq
                while at < a.file_size:
                    data = chunk(at)
                    last = at + len(data) >= a.file_size
                    n += 1
                    truth["burst_packets"] += 1
                    if rng.random() < a.drop_burst:
                        truth["burst_dropped"] += 1
                        truth["burst_bytes_dropped"] += len(data)
                    else:
                        ftp(n, ACK, BURST, len(data), at, data, complete=int(last))
                    at += len(data)
                    time.sleep(0.0002)
            elif opcode == READ and session_open:
                truth["file_reads"] += 1
                data = chunk(offset)
                if not data:
                    nak(seq + 1, READ, EOF)
                else:
                    ftp(seq + 1, ACK, READ, len(data), offset, data[:size or CHUNK])
            elif opcode in (TERMINATE, RESET):
                truth["terminated" if opcode == TERMINATE else "resets"] += 1
                session_open = False
                ftp(seq + 1, ACK, opcode, 0, 0, [])
            elif not session_open:
                nak(seq + 1, opcode, INVALID_SESSION)
    truth["list_dropped_count"] = len(truth["list_dropped"])
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    sys.exit(main())
