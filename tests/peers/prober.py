#!/usr/bin/env python3
"""A pymavlink pinger, TIMESYNC requester and commander, used against
`mavping respond`: sends known requests, then checks every reply with
pymavlink's own decoding. Prints "ready", then one JSON line of findings
when done (it exits by itself).
"""
import argparse
import json
import os
import sys
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection")
    ap.add_argument("--sysid", type=int, default=250)
    ap.add_argument("--compid", type=int, default=190)
    ap.add_argument("--responder", default="1/1", help="expected SYS/COMP of the replies")
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--interval", type=float, default=0.005)
    ap.add_argument("--baud", type=int, default=57600)
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    rsys, rcomp = (int(x) for x in args.responder.split("/"))
    conn = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                      source_component=args.compid, baud=args.baud,
                                      dialect="common")
    mav = conn.mav
    f = {"ping_sent": 0, "ping_ok": 0, "ping_bad": 0, "timesync_sent": 0,
         "timesync_ok": 0, "timesync_bad": 0, "commands_sent": 0, "acks_ok": 0,
         "acks_bad": 0, "heartbeats": 0, "other_source": 0, "tc1_rising": True}
    pings, syncs = {}, set()
    last_tc1 = [0]

    def check(msg):
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        if (msg.get_srcSystem(), msg.get_srcComponent()) != (rsys, rcomp):
            f["other_source"] += 1
            return
        if kind == "HEARTBEAT":
            f["heartbeats"] += 1
        elif kind == "PING":
            ok = (msg.seq in pings and pings[msg.seq] == msg.time_usec
                  and (msg.target_system, msg.target_component) == (args.sysid, args.compid))
            f["ping_ok" if ok else "ping_bad"] += 1
        elif kind == "TIMESYNC":
            ok = msg.tc1 != 0 and msg.ts1 in syncs
            if msg.tc1 <= last_tc1[0]:
                f["tc1_rising"] = False
            last_tc1[0] = msg.tc1
            f["timesync_ok" if ok else "timesync_bad"] += 1
        elif kind == "COMMAND_ACK":
            ok = (msg.command == mavutil.mavlink.MAV_CMD_REQUEST_MESSAGE
                  and (msg.target_system, msg.target_component) == (args.sysid, args.compid))
            f["acks_ok" if ok else "acks_bad"] += 1

    def drain(until):
        while time.monotonic() < until:
            msg = conn.recv_match(blocking=True, timeout=0.005)
            if msg is not None:
                check(msg)

    # Our HEARTBEAT first: a udpin responder learns where we are from it.
    mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    print("ready", flush=True)
    drain(time.monotonic() + 0.1)
    for i in range(args.count):
        t = 1_000_000 + i * 7
        pings[i] = t
        mav.ping_send(t, i, 0, 0)
        f["ping_sent"] += 1
        ts1 = time.time_ns() + i
        syncs.add(ts1)
        mav.timesync_send(0, ts1)
        f["timesync_sent"] += 1
        drain(time.monotonic() + args.interval)
    # A command and its retransmission: both must be acknowledged.
    for confirmation in (0, 1):
        mav.command_long_send(rsys, rcomp, mavutil.mavlink.MAV_CMD_REQUEST_MESSAGE,
                              confirmation, 0, 0, 0, 0, 0, 0, 0)
        f["commands_sent"] += 1
        drain(time.monotonic() + args.interval)
    drain(time.monotonic() + 0.5)
    # The responder's HEARTBEAT comes at 1 Hz: on a fast machine the run
    # above ends before the first one reaches us, so wait for it (bounded).
    deadline = time.monotonic() + 2.0
    while f["heartbeats"] == 0 and time.monotonic() < deadline:
        drain(time.monotonic() + 0.05)
    print(json.dumps(f), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
