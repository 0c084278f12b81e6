#!/usr/bin/env python3
"""BASELINE for the passive rows of scripts/bench.sh: pymavlink's mavutil
listening on UDP and counting what it receives as MAVProxy and mavloss do
(mavutil.post_message: mav_count, mav_loss), with the same 4 MiB receive
buffer mavping asks for. Ends 0.5 s after the stream stops, or DURATION
after it started; prints one JSON line: frames parsed, pymavlink's loss
figure, and its own CPU time from its first frame on.

    pymavlink_listener.py PORT DURATION
"""
import json
import os
import resource
import select
import socket
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def cpu_s():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    port, duration = int(sys.argv[1]), float(sys.argv[2])
    m = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255)
    m.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    print("ready", flush=True)
    fd = m.port.fileno()
    end = before = None
    while end is None or time.monotonic() < end:
        if not select.select([fd], [], [], 0.5)[0]:
            if end is not None:
                break
            continue
        # Drain what is waiting (at a high rate it never is drained: the
        # deadline is checked as it goes).
        while m.recv_msg() is not None:
            if end is None:
                before, end = cpu_s(), time.monotonic() + duration
            elif time.monotonic() >= end:
                break
    print(json.dumps({"received": m.mav_count, "loss": m.mav_loss,
                      "cpu_s": cpu_s() - before if before is not None else 0.0}),
          flush=True)


if __name__ == "__main__":
    main()
