#!/usr/bin/env python3
"""A ground station written with pymavlink that records a telemetry log
with pymavlink's own logger (`mavfile.setup_logfile`: every frame it
receives, stamped `usec & ~3`), for mavping's `tlog:` tests.

    tlog_recorder.py CONNECTION OUT.tlog

It sends a HEARTBEAT each second (a vehicle listening with udpin learns
where to send from it), prints "ready", records until SIGTERM, then closes
the log and prints one JSON line: the frames it recorded.
"""
import contextlib
import json
import os
import signal
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def main():
    connection, path = sys.argv[1], sys.argv[2]
    # pymavlink's TCP client prints its retries ("Connection refused
    # sleeping") on stdout, where the test reads "ready": send them to stderr.
    with contextlib.redirect_stdout(sys.stderr):
        m = mavutil.mavlink_connection(connection, source_system=255, source_component=190)
    m.setup_logfile(path)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    print("ready", flush=True)
    recorded = 0
    next_beat = 0.0
    while not stop:
        now = time.monotonic()
        if now >= next_beat:
            m.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS,
                                 mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            next_beat = now + 1.0
        msg = m.recv_msg()
        if msg is None:
            time.sleep(0.001)
        elif msg.get_type() != "BAD_DATA":
            recorded += 1
    m.logfile.close()
    print(json.dumps({"recorded": recorded}), flush=True)


if __name__ == "__main__":
    main()
