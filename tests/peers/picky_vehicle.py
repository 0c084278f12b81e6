#!/usr/bin/env python3
"""A pymavlink vehicle that ignores some ground stations, for mavping's
"why the vehicle ignores us" tests (tests/it/ignored.rs). It sends
HEARTBEAT at --heartbeat-hz from its first frame (to the peer it has heard:
udpin waits for one), and acknowledges COMMAND_LONG addressed to it
(MAV_RESULT_ACCEPTED, the ACK addressed to the sender), except:

  --gcs-sysid N  it accepts commands from system N only, as ArduPilot with
                 SYSID_MYGCS=N and SYSID_ENFORCE=1; others are counted and
                 ignored. Its ground station N is on another link of the
                 same router: with every HEARTBEAT it answers that
                 station's SET_MESSAGE_INTERVAL and PING (a COMMAND_ACK and a
                 PING reply addressed to N/190), so what we hear shows
                 whom it answers.
  --mavlink1     it speaks MAVLink 1 only (MAVLINK20 unset) and, as a
                 MAVLink 1 stack, reads no MAVLink 2 frame (pymavlink's
                 parser would): each is counted as unread.

Prints "ready", then on SIGTERM one JSON line of ground truth: commands
acknowledged and ignored (by sender), MAVLink 2 frames it could not read,
HEARTBEATs, and frames addressed to its ground station ("to_gcs").
"""
import argparse
import json
import os
import signal
import sys
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--gcs-sysid", type=int, default=None)
    ap.add_argument("--mavlink1", action="store_true")
    ap.add_argument("--heartbeat-hz", type=float, default=5.0)
    args = ap.parse_args()

    if args.mavlink1:
        os.environ.pop("MAVLINK20", None)
    else:
        os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil  # imported after MAVLINK20 is set

    conn = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                      source_component=args.compid, dialect="common")
    mav = conn.mav
    truth = {"acks": 0, "ignored": {}, "unread_v2": 0, "unread_commands": 0, "heartbeats": 0, "to_gcs": 0}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    print("ready", flush=True)
    next_hb = None
    while running:
        now = time.monotonic()
        if next_hb is not None and now >= next_hb:
            mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_QUADROTOR,
                               mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
            truth["heartbeats"] += 1
            if args.gcs_sysid is not None:
                n = truth["heartbeats"]
                mav.command_ack_send(mavutil.mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                                     mavutil.mavlink.MAV_RESULT_ACCEPTED, 0, 0,
                                     args.gcs_sysid, 190)
                mav.ping_send(int(time.time() * 1e6), n, args.gcs_sysid, 190)
                truth["to_gcs"] += 2
            next_hb = now + 1.0 / args.heartbeat_hz
        msg = conn.recv_match(blocking=True, timeout=0.02)
        if msg is None:
            continue
        if next_hb is None:
            # A peer is known: the stream begins.
            next_hb = now
        if msg.get_type() == "BAD_DATA":
            continue
        if args.mavlink1 and bytes(msg.get_msgbuf()[:1]) == b"\xfd":
            # pymavlink's parser reads both; a MAVLink 1 stack reads none.
            truth["unread_v2"] += 1
            if msg.get_type() == "COMMAND_LONG":
                truth["unread_commands"] += 1
            continue
        if msg.get_type() != "COMMAND_LONG" or msg.target_system != args.sysid:
            continue
        src = msg.get_srcSystem()
        if args.gcs_sysid is not None and src != args.gcs_sysid:
            truth["ignored"][str(src)] = truth["ignored"].get(str(src), 0) + 1
            continue
        if args.mavlink1:
            # MAVLink 1 has no room for the ACK's target (an extension).
            mav.command_ack_send(msg.command, mavutil.mavlink.MAV_RESULT_ACCEPTED)
        else:
            mav.command_ack_send(msg.command, mavutil.mavlink.MAV_RESULT_ACCEPTED, 0, 0,
                                 src, msg.get_srcComponent())
        truth["acks"] += 1
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
