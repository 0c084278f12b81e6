#!/usr/bin/env python3
"""BASELINE for the passive rows of scripts/bench.sh: pymavlink's mavutil
listening on UDP and counting what it receives as MAVProxy and mavloss do
(mavutil.post_message: mav_count, mav_loss), with the same 4 MiB receive
buffer mavping asks for. Ends 0.5 s after the stream stops, or DURATION
after it started; prints one JSON line: frames parsed, pymavlink's loss
figure, and its own CPU time from its first frame on.

With several ports, one mavutil connection a port in one process, as
MAVProxy holds one for each of its masters: the figures are their sums
(mavutil matches no frame across them).

    pymavlink_listener.py PORT[,PORT...] DURATION
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
    ports, duration = [int(p) for p in sys.argv[1].split(",")], float(sys.argv[2])
    conns = {}
    for port in ports:
        m = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255)
        m.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        conns[m.port.fileno()] = m
    print("ready", flush=True)
    end = before = None
    while end is None or time.monotonic() < end:
        ready = select.select(list(conns), [], [], 0.5)[0]
        if not ready:
            if end is not None:
                break
            continue
        for fd in ready:
            m = conns[fd]
            # Drain what is waiting (at a high rate it never is drained: the
            # deadline is checked as it goes); with several ports, at most
            # a batch from each in turn, or the first would starve the rest.
            taken = 0
            while m.recv_msg() is not None:
                taken += 1
                if end is None:
                    before, end = cpu_s(), time.monotonic() + duration
                elif time.monotonic() >= end or (len(conns) > 1 and taken >= 64):
                    break
    print(json.dumps({"received": sum(m.mav_count for m in conns.values()),
                      "loss": sum(m.mav_loss for m in conns.values()),
                      "cpu_s": cpu_s() - before if before is not None else 0.0}),
          flush=True)

if __name__ == "__main__":
    main()
