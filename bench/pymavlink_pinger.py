#!/usr/bin/env python3
"""BASELINE, not mavping: a PING client written with pymavlink, the best a
Python MAVLink tool does. Sends PINGs at RATE per second for DURATION
seconds to a responder, then prints one JSON line: sent, received, loss,
RTT p50/p99 in microseconds. Pacing: every due request is sent at each
millisecond tick (what a Python loop can do)."""
import argparse
import json
import os
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection")
    ap.add_argument("--rate", type=float, default=1000)
    ap.add_argument("--duration", type=float, default=3)
    ap.add_argument("--timeout", type=float, default=1.0)
    a = ap.parse_args()
    conn = mavutil.mavlink_connection(a.connection, source_system=254, source_component=190, dialect="common")
    mav = conn.mav
    sent_at = {}
    rtts = []
    interval = 1.0 / a.rate
    start = time.monotonic()
    n = 0
    end = start + a.duration
    while True:
        now = time.monotonic()
        if now >= end + a.timeout:
            break
        while now < end and start + n * interval <= now:
            sent_at[n] = time.monotonic()
            mav.ping_send(int(time.time() * 1e6), n, 0, 0)
            n += 1
        msg = conn.recv_match(type="PING", blocking=False)
        while msg is not None:
            t = time.monotonic()
            if msg.target_system == 254 and msg.seq in sent_at:
                rtts.append(t - sent_at.pop(msg.seq))
            msg = conn.recv_match(type="PING", blocking=False)
        if not rtts and n == 0:
            time.sleep(0.0005)
    rtts.sort()
    k = len(rtts)
    pct = lambda q: rtts[min(k - 1, int(q * k))] * 1e6 if k else None  # noqa: E731
    print(json.dumps({"sent": n, "received": k, "loss": (n - k) / n if n else 0,
                      "p50_us": pct(0.5), "p99_us": pct(0.99)}))


if __name__ == "__main__":
    main()
