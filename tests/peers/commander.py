#!/usr/bin/env python3
"""A pymavlink system that acknowledges COMMAND_LONG addressed to it only on
a chosen attempt (by the `confirmation` field: attempt k has k-1), or never.
Prints one JSON line of ground truth on SIGTERM/SIGINT.
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
    ap.add_argument("--ack-on", type=int, default=1, help="acknowledge attempt N (1-based)")
    ap.add_argument("--never", action="store_true", help="never acknowledge")
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                      source_component=args.compid, dialect="common")
    mav = conn.mav
    truth = {"commands": 0, "acks": 0, "by_confirmation": {}, "commands_ids": []}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_QUADROTOR,
                       mavutil.mavlink.MAV_AUTOPILOT_PX4, 0, 0, 0)
    print("ready", flush=True)
    while running:
        msg = conn.recv_match(type="COMMAND_LONG", blocking=True, timeout=0.02)
        if msg is None:
            continue
        if msg.target_system != args.sysid or msg.target_component not in (0, args.compid):
            continue
        truth["commands"] += 1
        key = str(msg.confirmation)
        truth["by_confirmation"][key] = truth["by_confirmation"].get(key, 0) + 1
        if msg.command not in truth["commands_ids"]:
            truth["commands_ids"].append(msg.command)
        if args.never or msg.confirmation != args.ack_on - 1:
            continue
        mav.command_ack_send(msg.command, mavutil.mavlink.MAV_RESULT_ACCEPTED, 0, 0,
                             msg.get_srcSystem(), msg.get_srcComponent())
        truth["acks"] += 1
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
