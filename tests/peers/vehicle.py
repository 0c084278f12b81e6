#!/usr/bin/env python3
"""A vehicle written with pymavlink that streams telemetry, for mavping's
passive tests: HEARTBEAT at 1 Hz and ATTITUDE at --rate, every frame
numbered by pymavlink's own sequence counter, with faults chosen by frame
number (the n-th frame it numbers, from 0):

  --drop N,M,...   number the frame, do not send it (a gap)
  --dup N,...      send the frame twice (a duplicate)
  --swap N,...     hold frame N back and send it after frame N+1
  --silence N:K    after frame N, number K frames and send none (a silence
                   of K frames, K > 255 aliases in a wrapping counter)

It sends to the mavping it has heard (udpin: waits for mavping's
HEARTBEAT) for --frames frames, then prints one JSON line of ground truth
and waits for SIGTERM. Frames dropped or silenced after the last one sent
would leave no gap, so the last frame is always sent.
"""
import argparse
import json
import os
import signal
import sys
import time


def numbers(text):
    return {int(x) for x in text.split(",") if x.strip()} if text else set()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--rate", type=float, default=100.0, help="ATTITUDE per second")
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--drop", default="")
    ap.add_argument("--dup", default="")
    ap.add_argument("--swap", default="")
    ap.add_argument("--silence", default="", help="N:K")
    args = ap.parse_args()
    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                   source_component=args.compid)
    drop, dup, swap = numbers(args.drop), numbers(args.dup), numbers(args.swap)
    silence_after, silence_len = (None, 0)
    if args.silence:
        n, k = args.silence.split(":")
        silence_after, silence_len = int(n), int(k)
    print("ready", flush=True)
    # udpin learns where mavping is from its HEARTBEAT.
    while m.recv_match(type="HEARTBEAT", blocking=True, timeout=30) is None:
        pass
    truth = {"numbered": 0, "sent": 0, "dropped": 0, "duplicated": 0, "swapped": 0,
             "silenced": 0, "heartbeats": 0}
    held = None
    period = 1.0 / args.rate
    next_heartbeat = 0.0
    start = time.monotonic()
    frame = 0

    def encode(kind):
        if kind == "hb":
            msg = m.mav.heartbeat_encode(mavutil.mavlink.MAV_TYPE_QUADROTOR,
                                         mavutil.mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
        else:
            msg = m.mav.attitude_encode(int((time.monotonic() - start) * 1000), 0.1, 0.2, 0.3,
                                        0.0, 0.0, 0.0)
        # pack() stamps the current sequence number and send() would step
        # it: step it here, so a frame is numbered whether sent or not.
        data = msg.pack(m.mav)
        m.mav.seq = (m.mav.seq + 1) % 256
        return data

    def send(data):
        m.write(data)
        truth["sent"] += 1

    while frame < args.frames:
        now = time.monotonic() - start
        kind = "hb" if now >= next_heartbeat else "att"
        if kind == "hb":
            next_heartbeat += 1.0
            truth["heartbeats"] += 1
        data = encode(kind)
        truth["numbered"] += 1
        last = frame == args.frames - 1
        if frame in drop and not last:
            truth["dropped"] += 1
        elif frame in swap and not last:
            held = data
            truth["swapped"] += 1
        else:
            send(data)
            if frame in dup:
                send(data)
                truth["duplicated"] += 1
            if held is not None:
                send(held)
                held = None
        if frame == silence_after:
            for _ in range(silence_len):
                encode("att")
                truth["numbered"] += 1
                truth["silenced"] += 1
            time.sleep(silence_len * period)
        frame += 1
        time.sleep(period)
    print(json.dumps(truth), flush=True)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    while True:
        time.sleep(1)


if __name__ == "__main__":
    main()
