#!/usr/bin/env python3
"""A vehicle written with pymavlink that asks the ground its clock
questions and stamps its telemetry, for mavping's tests of answering
(issue 40): once it has heard the ground's HEARTBEAT, for --duration
seconds it sends

  TIMESYNC requests (tc1 = 0, ts1 = its clock in ns) at --timesync-hz, as
      ArduPilot does to time the link to its ground station;
  PING requests to all (targets 0/0) at --ping-hz, as PX4 streams them;
  ATTITUDE at --attitude-hz and SYSTEM_TIME at --system-time-hz, stamped
      by its clock (ms since it "booted": --boot-s before it started).

It answers the ground's TIMESYNC requests (tc1 its clock in ns), and with
--answer-ping its PING requests, once each. It counts every reply it gets
to its own requests: a TIMESYNC reply is one with tc1 != 0 (pymavlink's
TIMESYNC has no targets), matched by its ts1 to one of its requests (a
second for the same ts1 is a duplicate; a ts1 it never sent is unknown),
a PING reply one to its ids, matched by its seq likewise. On SIGTERM it prints one JSON line of that truth, with the ids the
replies came from.
"""
import argparse
import json
import os
import select
import signal
import time


class ClockVehicle:
    def __init__(self, m, mavlink, boot_s):
        self.m = m
        self.mavlink = mavlink
        self.start = time.monotonic() - boot_s
        self.heard_heartbeat = False
        self.timesync_sent = set()
        self.ping_sent = set()
        self.timesync_answered = set()
        self.ping_answered = set()
        self.truth = {"timesync_requests": 0, "timesync_replies": 0, "timesync_duplicates": 0,
                      "timesync_unknown": 0, "ping_requests": 0, "ping_replies": 0,
                      "ping_duplicates": 0, "ping_unknown": 0, "reply_from": [],
                      "answered_timesync": 0, "answered_ping": 0}

    def clock_ns(self):
        return int((time.monotonic() - self.start) * 1e9)

    def ours(self, msg):
        return (msg.target_system, msg.target_component) == (self.m.mav.srcSystem,
                                                              self.m.mav.srcComponent)

    def replied_by(self, msg):
        source = [msg.get_srcSystem(), msg.get_srcComponent()]
        if source not in self.truth["reply_from"]:
            self.truth["reply_from"].append(source)

    def count_reply(self, kind, key, sent, answered, msg):
        """A reply to one of our requests: new, a duplicate, or unknown."""
        self.replied_by(msg)
        if key not in sent:
            self.truth[kind + "_unknown"] += 1
        elif key in answered:
            self.truth[kind + "_duplicates"] += 1
        else:
            answered.add(key)
            self.truth[kind + "_replies"] += 1

    def take(self, msg, answer_ping):
        kind = msg.get_type()
        mav = self.m.mav
        if kind == "HEARTBEAT":
            self.heard_heartbeat = True
        elif kind == "TIMESYNC" and msg.tc1 == 0:
            mav.timesync_send(self.clock_ns(), msg.ts1)
            self.truth["answered_timesync"] += 1
        elif kind == "TIMESYNC":
            # This dialect's TIMESYNC has no targets: a reply is told by
            # tc1 != 0 and matched by its ts1, as ArduPilot does.
            self.count_reply("timesync", msg.ts1, self.timesync_sent, self.timesync_answered, msg)
        elif kind == "PING" and (msg.target_system, msg.target_component) == (0, 0):
            if answer_ping:
                mav.ping_send(msg.time_usec, msg.seq, msg.get_srcSystem(), msg.get_srcComponent())
                self.truth["answered_ping"] += 1
        elif kind == "PING" and self.ours(msg):
            self.count_reply("ping", msg.seq, self.ping_sent, self.ping_answered, msg)

    def drain(self, answer_ping):
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                return
            if msg.get_type() != "BAD_DATA":
                self.take(msg, answer_ping)

    def send_timesync_request(self):
        ts1 = self.clock_ns()
        self.timesync_sent.add(ts1)
        self.m.mav.timesync_send(0, ts1)
        self.truth["timesync_requests"] += 1

    def send_ping_request(self):
        seq = self.truth["ping_requests"]
        self.ping_sent.add(seq)
        self.m.mav.ping_send(self.clock_ns() // 1000, seq, 0, 0)
        self.truth["ping_requests"] += 1

    def send_attitude(self):
        ms = (self.clock_ns() // 1_000_000) % 2**32
        self.m.mav.attitude_send(ms, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0)

    def send_system_time(self):
        ms = (self.clock_ns() // 1_000_000) % 2**32
        self.m.mav.system_time_send(int(time.time() * 1e6), ms)


def wait(m, seconds):
    port = getattr(m, "port", None)
    fd = port.fileno() if port is not None else m.fd
    try:
        select.select([fd], [], [], max(0.0, seconds))
    except InterruptedError:
        pass


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--timesync-hz", type=float, default=5.0)
    ap.add_argument("--ping-hz", type=float, default=5.0)
    ap.add_argument("--attitude-hz", type=float, default=0.0)
    ap.add_argument("--system-time-hz", type=float, default=0.0)
    ap.add_argument("--boot-s", type=float, default=100.0, help="its clock at start")
    ap.add_argument("--answer-ping", action="store_true", help="answer PING requests, as PX4")
    args = ap.parse_args()
    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(args.connection, source_system=args.sysid,
                                   source_component=args.compid)
    v = ClockVehicle(m, mavutil.mavlink, args.boot_s)
    print("ready", flush=True)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    deadline = time.monotonic() + 30
    while not v.heard_heartbeat and time.monotonic() < deadline and not stop:
        v.drain(args.answer_ping)
        wait(m, 0.02)
    streams = [(hz, send) for hz, send in [
        (args.timesync_hz, v.send_timesync_request), (args.ping_hz, v.send_ping_request),
        (args.attitude_hz, v.send_attitude), (args.system_time_hz, v.send_system_time)]
        if hz > 0]
    begin = time.monotonic()
    due = [begin for _ in streams]
    while not stop and time.monotonic() < begin + args.duration:
        now = time.monotonic()
        for k, (hz, send) in enumerate(streams):
            if now >= due[k]:
                send()
                due[k] += 1.0 / hz
        v.drain(args.answer_ping)
        wait(m, min(due) - time.monotonic() if due else 0.02)
    # Replies still on their way are counted until SIGTERM.
    while not stop:
        v.drain(args.answer_ping)
        wait(m, 0.05)
    v.drain(args.answer_ping)
    print(json.dumps(v.truth), flush=True)


if __name__ == "__main__":
    main()
