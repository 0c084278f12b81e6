#!/usr/bin/env python3
"""Walks a telemetry log's records (8-byte big-endian stamp, then one MAVLink
frame) with pymavlink's ardupilotmega dialect (MAVLink 2 build), checks
each frame's CRC against pymavlink's CRC_EXTRA, and prints one JSON line
of per-source figures: the truth mavping's damaged-frame tests compare with.

    tlog_crc_census.py LOG.tlog

Per source "sysid/compid":
  good      frames whose CRC checks (what pymavlink counts as packets)
  damaged   frames of an id the dialect knows whose CRC fails
  unknown   frames of an id the dialect does not know
  damaged_ids  {id: count} of the damaged frames
  lost      numbers missing from the sequence of all its frames, damaged
            ones included: sum of ((seq - previous) mod 256) - 1, a
            repeated number (difference 0) left out
And for the whole log: records, junk_bytes (bytes where no record starts:
the walk moves a byte at a time until a stamp and a whole frame start),
and damaged_runs: damaged records right after another damaged record.
"""
import json
import os
import struct
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import ardupilotmega as dialect  # noqa: E402
from pymavlink.generator.mavcrc import x25crc  # noqa: E402


def frame_len(buf, at):
    """The length a frame header at buf[at] claims, or None."""
    if at + 3 > len(buf):
        return None
    stx, plen, incompat = buf[at], buf[at + 1], buf[at + 2]
    if stx == 0xFE:
        return 8 + plen
    if stx == 0xFD and incompat & ~1 == 0:
        return 12 + plen + (13 if incompat & 1 else 0)
    return None


def header(frame):
    if frame[0] == 0xFE:
        return frame[2], frame[3], frame[4], frame[5], 6
    msgid = frame[7] | frame[8] << 8 | frame[9] << 16
    return frame[4], frame[5], frame[6], msgid, 10


def crc_ok(frame, msgid, hlen):
    end = hlen + frame[1]
    crc = x25crc(bytes(frame[1:end]))
    crc.accumulate(struct.pack("B", dialect.mavlink_map[msgid].crc_extra))
    return crc.crc == struct.unpack("<H", bytes(frame[end:end + 2]))[0]


def census(data):
    sources = {}
    totals = {"records": 0, "junk_bytes": 0, "damaged_runs": 0}
    at, last_damaged = 0, False
    while at + 8 < len(data):
        n = frame_len(data, at + 8)
        if n is None or at + 8 + n > len(data):
            totals["junk_bytes"] += 1
            at += 1
            continue
        frame = data[at + 8:at + 8 + n]
        seq, sysid, compid, msgid, hlen = header(frame)
        s = sources.setdefault(f"{sysid}/{compid}",
                               {"good": 0, "damaged": 0, "unknown": 0, "damaged_ids": {},
                                "lost": 0, "last_seq": None})
        if s["last_seq"] is not None and (seq - s["last_seq"]) % 256:
            s["lost"] += (seq - s["last_seq"]) % 256 - 1
        s["last_seq"] = seq
        damaged = False
        if msgid not in dialect.mavlink_map:
            s["unknown"] += 1
        elif crc_ok(frame, msgid, hlen):
            s["good"] += 1
        else:
            damaged = True
            s["damaged"] += 1
            s["damaged_ids"][str(msgid)] = s["damaged_ids"].get(str(msgid), 0) + 1
            totals["damaged_runs"] += int(last_damaged)
        last_damaged = damaged
        totals["records"] += 1
        at += 8 + n
    for s in sources.values():
        del s["last_seq"]
    totals["sources"] = sources
    return totals


def main():
    with open(sys.argv[1], "rb") as f:
        data = f.read()
    print(json.dumps(census(data), sort_keys=True), flush=True)


if __name__ == "__main__":
    main()
