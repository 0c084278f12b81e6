#!/usr/bin/env python3
"""A pymavlink system that answers like ArduPilot: HEARTBEAT (autopilot
ArduPilot) and TIMESYNC only, never PING. Its TIMESYNC clock (tc1) is ns since
it started, and replies carry no target fields (pymavlink's common dialect,
like ArduPilot, leaves them out).

Can drop chosen requests (by arrival order, from 0) and delay every reply.
With --clock unix its TIMESYNC clock is the wall clock (time.time_ns())
plus --offset-s: the truth a bound on the offset is held against.
Prints one JSON line of ground truth on SIGTERM/SIGINT, including the true
offset of its clock against the wall clock (what mavping's ts1 counts).
"""
import argparse
import json
import os
import signal
import sys
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--drop", default="", help="request numbers (from 0) not to answer")
    ap.add_argument("--delay-ms", type=float, default=0.0)
    ap.add_argument("--clock", choices=["boot", "unix"], default="boot",
                    help="boot: ns since start (as ArduPilot); unix: the wall clock")
    ap.add_argument("--offset-s", type=float, default=0.0, help="added to the unix clock")
    ap.add_argument("--autopilot", type=int, default=3,
                    help="its HEARTBEAT's autopilot (3 ArduPilot; 12 hides it as PX4)")
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                      source_component=args.compid, dialect="common")
    mav = conn.mav
    drop = {int(x) for x in args.drop.split(",") if x.strip()}
    start = time.monotonic_ns()

    offset_ns = int(round(args.offset_s * 1e9))

    def clock():
        if args.clock == "unix":
            return time.time_ns() + offset_ns
        return time.monotonic_ns() - start + 1

    truth = {"timesync_requests": 0, "replies": 0, "dropped": 0, "ping_ignored": 0}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    hb = lambda: mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_QUADROTOR,
                                    args.autopilot, 0, 0, 0)
    hb()
    print("ready", flush=True)
    next_hb = time.monotonic() + 1.0
    while running:
        if time.monotonic() >= next_hb:
            hb()
            next_hb += 1.0
        msg = conn.recv_match(blocking=True, timeout=0.02)
        if msg is None:
            continue
        kind = msg.get_type()
        if kind == "PING":
            truth["ping_ignored"] += 1
            continue
        if kind != "TIMESYNC" or msg.tc1 != 0:
            continue
        n = truth["timesync_requests"]
        truth["timesync_requests"] += 1
        if n in drop:
            truth["dropped"] += 1
            continue
        if args.delay_ms:
            time.sleep(args.delay_ms / 1000.0)
        # ArduPilot reads its clock as it answers.
        mav.timesync_send(clock(), msg.ts1)
        truth["replies"] += 1
    # Theirs minus ours, read back to back at exit (exact for --clock unix).
    truth["offset_ns"] = offset_ns if args.clock == "unix" else clock() - time.time_ns()
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
