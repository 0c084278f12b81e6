#!/usr/bin/env python3
"""Generates a large telemetry log for scripts/bench-tlog.sh: a vehicle's
telemetry (HEARTBEAT 1 Hz, SYS_STATUS 2 Hz, GLOBAL_POSITION_INT 10 Hz,
VFR_HUD 10 Hz, the rest ATTITUDE) at RATE frames a second for SECONDS,
1 frame in 100 lost, packed by pymavlink (each message kind packed once
per sequence number, so a 200 MB log takes seconds, not hours).

    tlog_gen.py OUT.tlog --seconds S --rate HZ [--stamps us|ms|mavproxy]

Stamps: "us" a clock's microseconds with the jitter of a real receiver
(their low bits vary), "ms" QGroundControl's whole milliseconds,
"mavproxy" MAVProxy's link number 0 in the low bits.
"""
import argparse
import os
import random
import struct

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--seconds", type=float, required=True)
    ap.add_argument("--rate", type=float, default=50.0)
    ap.add_argument("--stamps", default="us", choices=["us", "ms", "mavproxy"])
    args = ap.parse_args()
    mav = mavutil.mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    kinds = [
        lambda: mav.attitude_encode(123456, 0.1, 0.2, 0.3, 0.01, 0.02, 0.03),
        lambda: mav.global_position_int_encode(123456, 473977418, 85455939, 100000,
                                               50000, 10, 20, 30, 9000),
        lambda: mav.vfr_hud_encode(12.5, 12.1, 90, 55, 100.0, 0.5),
        lambda: mav.sys_status_encode(0x3f, 0x3f, 0x3f, 500, 12400, 1200, 80, 0, 0, 0,
                                      0, 0, 0),
        lambda: mav.heartbeat_encode(2, 3, 81, 4, 4),
    ]
    packed = {}
    for k, encode in enumerate(kinds):
        for seq in range(256):
            mav.seq = seq
            packed[(k, seq)] = bytes(encode().pack(mav))
    rng = random.Random(1)
    frames = int(args.seconds * args.rate)
    step = 1e6 / args.rate
    t0 = 1_764_500_000_000_000
    per_second = int(args.rate)
    out = []
    with open(args.out, "wb") as f:
        for n in range(frames):
            i = n % per_second
            kind = 4 if i == 0 else 3 if i % (per_second // 2 or 1) == 1 else (
                1 if i % 5 == 2 else 2 if i % 5 == 3 else 0)
            if rng.random() < 0.01:
                continue
            us = t0 + int(n * step)
            if args.stamps == "us":
                us += rng.randrange(400)
            elif args.stamps == "ms":
                us = us // 1000 * 1000
            else:
                us &= ~3
            out.append(struct.pack(">Q", us) + packed[(kind, n % 256)])
            if len(out) >= 100_000:
                f.write(b"".join(out))
                out = []
        f.write(b"".join(out))


if __name__ == "__main__":
    main()
