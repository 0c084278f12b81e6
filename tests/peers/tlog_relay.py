#!/usr/bin/env python3
"""Two radio links in one process, for mavping's `tlog:` tests: takes the
frames a pymavlink vehicle sends over UDP and forwards each to two
addresses (MAVProxy's two masters), dropping the ones the plan says on
each link, so MAVProxy hears one vehicle on two links that lose
differently.

    tlog_relay.py VEHICLE_PORT LINK0_PORT LINK1_PORT --drop0 N,... --drop1 N,...

N counts the vehicle's datagrams (one frame each, pymavlink writes a frame
a datagram), from 0. It sends the vehicle a HEARTBEAT each second (a
vehicle listening with udpin learns where to send from it), prints
"ready", and on SIGTERM one JSON line: datagrams heard, forwarded and
dropped per link.
"""
import argparse
import json
import os
import select
import signal
import socket
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def numbers(text):
    return {int(x) for x in text.split(",") if x.strip()} if text else set()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("vehicle", type=int)
    ap.add_argument("link0", type=int)
    ap.add_argument("link1", type=int)
    ap.add_argument("--drop0", default="")
    ap.add_argument("--drop1", default="")
    args = ap.parse_args()
    drops = [numbers(args.drop0), numbers(args.drop1)]
    links = [("127.0.0.1", args.link0), ("127.0.0.1", args.link1)]
    vehicle = ("127.0.0.1", args.vehicle)
    # One socket toward the vehicle, one per link: each link is a peer of
    # its own to MAVProxy.
    up = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    up.bind(("127.0.0.1", 0))
    down = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in links]
    for s in down:
        s.bind(("127.0.0.1", 0))
    mav = mavutil.mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
    heartbeat = mav.heartbeat_encode(mavutil.mavlink.MAV_TYPE_GCS,
                                     mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    truth = {"heard": 0, "forwarded": [0, 0], "dropped": [0, 0]}
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print("ready", flush=True)
    next_beat = 0.0
    while not stop:
        now = time.monotonic()
        if now >= next_beat:
            up.sendto(heartbeat.pack(mav), vehicle)
            next_beat = now + 1.0
        try:
            ready, _, _ = select.select([up] + down, [], [], 0.05)
        except InterruptedError:
            continue
        for s in ready:
            data = s.recv(65536)
            if s is not up:
                continue  # MAVProxy's own frames: the vehicle needs none
            n = truth["heard"]
            truth["heard"] += 1
            for k, addr in enumerate(links):
                if n in drops[k]:
                    truth["dropped"][k] += 1
                else:
                    down[k].sendto(data, addr)
                    truth["forwarded"][k] += 1
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
