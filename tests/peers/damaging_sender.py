#!/usr/bin/env python3
"""Sends ATTITUDE frames packed by pymavlink from one or more sources, each
frame a datagram of its own, and breaks the CRC of every k-th frame of a
source (both CRC bytes flipped): frames that arrive whole but damaged. When
done, prints one JSON line of ground truth and exits.

    damaging_sender.py udpout:HOST:PORT --source SYSID:K[:heartbeat] [--source ...]
                       [--frames N] [--rate HZ]

A source given ":heartbeat" sends HEARTBEATs (a quadrotor, PX4) instead.

Truth per source "sysid/1": sent (every frame numbered and sent), damaged
(those sent with a broken CRC), good (sent - damaged).
"""
import argparse
import json
import os
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("link")
    ap.add_argument("--source", action="append", required=True, help="SYSID:K, K: every k-th frame damaged")
    ap.add_argument("--frames", type=int, default=200, help="frames per source")
    ap.add_argument("--rate", type=float, default=100.0, help="frames per second per source")
    args = ap.parse_args()

    conn = mavutil.mavlink_connection(args.link, source_system=1, source_component=1)
    sources = []
    for spec in args.source:
        sysid, every, *kind = spec.split(":")
        mav = mavutil.mavlink.MAVLink(conn, srcSystem=int(sysid), srcComponent=1)
        sources.append((int(sysid), int(every), kind == ["heartbeat"], mav))
    truth = {f"{s}/1": {"sent": 0, "damaged": 0, "good": 0} for s, _, _, _ in sources}
    print("ready", flush=True)
    start = time.monotonic()
    for n in range(args.frames):
        for sysid, every, heartbeat, mav in sources:
            if heartbeat:
                msg = mav.heartbeat_encode(2, 12, 0, 0, 4)
            else:
                msg = mav.attitude_encode(n * 10, 0.1, 0.2, 0.3, 0.01, 0.02, 0.03)
            frame = bytearray(msg.pack(mav))
            # pack() numbers the frame with mav.seq; send() would step it.
            mav.seq = (mav.seq + 1) % 256
            t = truth[f"{sysid}/1"]
            t["sent"] += 1
            if n % every == every - 1:
                frame[-1] ^= 0xFF
                frame[-2] ^= 0xFF
                t["damaged"] += 1
            else:
                t["good"] += 1
            conn.write(bytes(frame))
        delay = start + (n + 1) / args.rate - time.monotonic()
        if delay > 0:
            time.sleep(delay)
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
