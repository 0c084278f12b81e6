#!/usr/bin/env python3
"""A vehicle written with pymavlink that streams telemetry, for mavping's
passive tests: HEARTBEAT at 1 Hz and ATTITUDE at --rate, every frame
numbered by pymavlink's own sequence counter, with faults chosen by frame
number (the n-th telemetry frame it numbers, from 0):

  --drop N,M,...   number the frame, do not send it (a gap)
  --dup N,...      send the frame twice (a duplicate)
  --swap N,...     hold frame N back and send it after frame N+1
  --silence N:K    after frame N, number K frames and send none (a silence
                   of K frames, K > 255 aliases in a wrapping counter)

It answers every PING request (targets 0/0 or its own ids) at once, as
PX4 does, from its first frame to its last: the reply is numbered in the
same sequence as its telemetry (so a test through a lossy relay sees
replies and telemetry lost alike). With --radio-hz it also plays the SiK
radio beside it: RADIO_STATUS from 51/68, numbered by the radio's own
sequence, as a radio injects it, while the stream lasts.

With --link-node-status it counts what it receives by each sender's packet
sequence (`link_node.SeqCount`: received, lost) and sends LINK_NODE_STATUS
at 1 Hz from its first heard HEARTBEAT, as PX4 does, in its own sequence:
"honest" says those counts, "no-loss" says the same received and 0 lost
(a vehicle whose count contradicts the link). Its truth then has every
report it sent ("link_node": "reports", and its final count).

It sends to the peer it has heard (udpin: waits for a HEARTBEAT, as a
vehicle behind a router does) for --frames frames, then prints one JSON
line of ground truth and goes on answering PINGs until SIGTERM. Frames
dropped or silenced after the last one sent would leave no gap, so the
last frame is always sent.
"""
import argparse
import json
import os
import select
import signal
import sys
import time

import link_node


def numbers(text):
    return {int(x) for x in text.split(",") if x.strip()} if text else set()


class Vehicle:
    """The connection, its sequence counter and the ground truth."""

    def __init__(self, m, mavutil, radio_hz, link_node_mode=None):
        self.m = m
        self.mavutil = mavutil
        self.start = time.monotonic()
        self.truth = {"numbered": 0, "sent": 0, "dropped": 0, "duplicated": 0, "swapped": 0,
                      "silenced": 0, "heartbeats": 0, "replies": 0, "radio": 0}
        self.heard_heartbeat = False
        # The radio numbers its own frames: a MAVLink encoder of its own
        # writing through the same connection.
        self.radio = mavutil.mavlink.MAVLink(m, srcSystem=ord("3"), srcComponent=ord("D"))
        self.radio_period = 1.0 / radio_hz if radio_hz > 0 else None
        self.next_radio = 0.0
        self.link_node_mode = link_node_mode
        self.next_link_node = None
        self.uplink = link_node.SeqCount()
        self.rx_bytes = 0
        if link_node_mode is not None:
            self.LinkNodeStatus = link_node.install(mavutil.mavlink)
            self.truth["link_node"] = {"mode": link_node_mode, "reports": []}

    def encode(self, msg):
        """The frame of `msg` with the next sequence number. pack() stamps
        the current number and send() would step it: step it here, so a
        frame is numbered whether it is sent or not."""
        data = msg.pack(self.m.mav)
        self.m.mav.seq = (self.m.mav.seq + 1) % 256
        self.truth["numbered"] += 1
        return data

    def telemetry(self, kind):
        mav, mavlink = self.m.mav, self.mavutil.mavlink
        if kind == "hb":
            msg = mav.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR,
                                       mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
        else:
            ms = int((time.monotonic() - self.start) * 1000)
            msg = mav.attitude_encode(ms, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0)
        return self.encode(msg)

    def send(self, data):
        self.m.write(data)
        self.truth["sent"] += 1

    def send_link_node_status(self, now):
        """Its own count of the link, at 1 Hz."""
        self.next_link_node += 1.0
        if self.next_link_node < now:
            self.next_link_node = now + 1.0
        lost = self.uplink.lost if self.link_node_mode == "honest" else 0
        report = {"timestamp": int((now - self.start) * 1000), "tx_buf": 95, "rx_buf": 100,
                  "tx_rate": 0, "rx_rate": self.rx_bytes, "rx_parse_err": 0,
                  "tx_overflows": 0, "rx_overflows": 0,
                  "messages_sent": (self.truth["sent"] + 1) % 2**32,
                  "messages_received": self.uplink.received % 2**32,
                  "messages_lost": lost % 2**32}
        self.rx_bytes = 0
        self.send(self.encode(self.LinkNodeStatus(**report)))
        self.truth["link_node"]["reports"].append(report)

    def serve(self, until):
        """Answers what arrives until `until` (monotonic seconds), and
        sends the radio's RADIO_STATUS and its LINK_NODE_STATUS when due."""
        while True:
            now = time.monotonic()
            if self.next_link_node is not None and now >= self.next_link_node:
                self.send_link_node_status(now)
            if self.radio_period is not None and self.heard_heartbeat and now >= self.next_radio:
                self.next_radio += self.radio_period
                if self.next_radio < now:
                    self.next_radio = now + self.radio_period
                self.radio.radio_status_send(180, 170, 90, 40, 35, 0, 0)
                self.truth["radio"] += 1
            self.answer_waiting()
            if now >= until:
                return
            wait = until - now
            if self.radio_period is not None and self.heard_heartbeat:
                wait = min(wait, max(0.0, self.next_radio - now))
            if self.next_link_node is not None:
                wait = min(wait, max(0.0, self.next_link_node - now))
            # tcpin has no port until a client connects: wait on its listener.
            port = getattr(self.m, "port", None)
            fd = port.fileno() if port is not None else self.m.fd
            try:
                select.select([fd], [], [], wait)
            except InterruptedError:
                pass

    def answer_waiting(self):
        ours = (self.m.mav.srcSystem, self.m.mav.srcComponent)
        while True:
            msg = self.m.recv_match(blocking=False)
            if msg is None:
                return
            kind = msg.get_type()
            if kind == "BAD_DATA":
                continue
            self.uplink.frame((msg.get_srcSystem(), msg.get_srcComponent()), msg.get_seq())
            self.rx_bytes += len(msg.get_msgbuf())
            if kind == "HEARTBEAT" and not self.heard_heartbeat:
                self.heard_heartbeat = True
                self.next_radio = time.monotonic()
                if self.link_node_mode is not None:
                    self.next_link_node = self.next_radio
            elif kind == "PING" and (msg.target_system, msg.target_component) in [(0, 0), ours]:
                reply = self.m.mav.ping_encode(msg.time_usec, msg.seq, msg.get_srcSystem(),
                                               msg.get_srcComponent())
                self.send(self.encode(reply))
                self.truth["replies"] += 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550 "
                    "or /dev/pts/3")
    ap.add_argument("--baud", type=int, default=57600, help="for a serial device")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--rate", type=float, default=100.0, help="ATTITUDE per second")
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--drop", default="")
    ap.add_argument("--dup", default="")
    ap.add_argument("--swap", default="")
    ap.add_argument("--silence", default="", help="N:K")
    ap.add_argument("--radio-hz", type=float, default=0.0,
                    help="also RADIO_STATUS from 51/68 this often (a SiK radio)")
    ap.add_argument("--link-node-status", choices=["honest", "no-loss"], default=None,
                    help="count the uplink by sequence and say so in LINK_NODE_STATUS at 1 Hz")
    args = ap.parse_args()
    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil

    m = mavutil.mavlink_connection(args.connection, baud=args.baud, source_system=args.sysid,
                                   source_component=args.compid)
    v = Vehicle(m, mavutil, args.radio_hz, args.link_node_status)
    drop, dup, swap = numbers(args.drop), numbers(args.dup), numbers(args.swap)
    silence_after, silence_len = (None, 0)
    if args.silence:
        n, k = args.silence.split(":")
        silence_after, silence_len = int(n), int(k)
    print("ready", flush=True)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    # A vehicle behind a router sends once it has been heard from (udpin
    # learns where its peer is from what arrives).
    deadline = time.monotonic() + 30
    while not v.heard_heartbeat and time.monotonic() < deadline and not stop:
        v.serve(time.monotonic() + 0.05)
    held = None
    period = 1.0 / args.rate
    start = time.monotonic()
    next_heartbeat = 0.0
    due = start
    frame = 0
    while frame < args.frames and not stop:
        kind = "hb" if time.monotonic() - start >= next_heartbeat else "att"
        if kind == "hb":
            next_heartbeat += 1.0
            v.truth["heartbeats"] += 1
        data = v.telemetry(kind)
        last = frame == args.frames - 1
        if frame in drop and not last:
            v.truth["dropped"] += 1
        elif frame in swap and not last:
            held = data
            v.truth["swapped"] += 1
        else:
            v.send(data)
            if frame in dup:
                v.send(data)
                v.truth["duplicated"] += 1
            if held is not None:
                v.send(held)
                held = None
        if frame == silence_after:
            for _ in range(silence_len):
                v.telemetry("att")
                v.truth["silenced"] += 1
            due += silence_len * period
        frame += 1
        due += period
        v.serve(due)
    # The radio goes quiet with the vehicle, so a count taken after the
    # stream holds all of it.
    v.radio_period = None
    if "link_node" in v.truth:
        v.truth["link_node"].update(received=v.uplink.received, lost=v.uplink.lost)
    print(json.dumps(v.truth), flush=True)
    while not stop:
        v.serve(time.monotonic() + 0.2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
