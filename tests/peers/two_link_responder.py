#!/usr/bin/env python3
"""A vehicle written with pymavlink, reached by two (or more) UDP links,
that answers TIMESYNC requests and sends every reply on ALL its links, as
a vehicle behind mavlink-router (or MAVProxy with several outputs) does,
with seeded per-link loss each way: a ground station sending requests on
link A hears the replies on link A and on link B. It is the ground truth
for mavping's request/reply matrix (issue 41: "requests out on one link,
replies heard on each link ... with RTT and loss per (out-link, in-link)").

  --listen HOST:PORT  a link's socket, bound there; give it once per link
                      (N >= 2). mavping reaches it with udpout:HOST:PORT.
  --drop-up PCT       a link's uplink loss, percent: requests arriving on
                      it dropped before the vehicle sees them (default 0)
  --drop-down PCT     a link's downlink loss, percent: each reply copy on
                      it dropped (default 0)
  --delay-ms MS       a link's reply delay: each reply copy on it is sent
                      MS after the request arrived (default 0)
                      Each of these three is given in link order, once per
                      link, or once for every link, or not at all.
  --seed N            the drop plan's seed (default 0)
  --sysid/--compid    its ids (default 1/1)
  --heartbeat-hz HZ   a HEARTBEAT on every link whose peer is known, HZ
                      times a second (default 1; 0 for none); heartbeats
                      are never dropped
  --boot-s S          its clock at start, seconds (default 100)
  --ping              answer PING requests (targets 0/0) too: the reply
                      (time_usec and seq echoed, targets the requester's
                      ids) is routed, dropped and counted as a TIMESYNC
                      reply is

Each socket's peer is the address its last datagram came from (mavping's
udpout socket). Every MAVLink frame arriving on a link is parsed by that
link's own parser; all but TIMESYNC requests (tc1 == 0) are ignored.

A request is answered with TIMESYNC tc1 = its clock in ns (monotonic, plus
--boot-s), ts1 = the request's ts1. The reply is packed ONCE (MAVLink 2),
so it has one sequence number and one byte string, and those very bytes go
out on every link that does not drop it. A request whose ts1 it has already
answered is not answered again: it counts in "repeats".

The drop plan is reproducible from --seed alone. The i-th request to
arrive on link a (i = 0, 1, ..., repeats and up-dropped ones included)
draws from its own random.Random(f"{seed}/{a}/{i}"): one number for its
uplink drop (dropped if < PCT/100), then, if the vehicle answers it (not
up-dropped, not a repeat), one per link in link order for that reply's
downlink drops, always, whatever the links' loss. So the plan depends only
on each link's own arrival order (UDP keeps it on one host), not on how the
links' requests interleave, which a scheduler's stall can change (one
random.Random(seed) for all arrivals made the plan differ run to run).
A reply copy not dropped is held until due (arrival + the link's delay)
and then sent to the link's peer; if that link has no peer yet it is
counted in no_peer and not sent.

On SIGTERM/SIGINT (mavping's run ends first, then the test stops the
peer) it stops at once: copies still held are not sent but counted as
"abandoned". It prints one JSON line of ground truth on stdout (before it
only "ready", once its sockets are open; logs go to stderr) and exits 0:

  links[k]   listen, drop_up_pct, drop_down_pct, delay_ms;
             requests_received  TIMESYNC requests that arrived on it
                                (before the uplink drop, repeats included);
             requests_dropped   of them, up-dropped;
             replies_sent       reply copies sent on it;
             replies_dropped    reply copies the plan dropped on it;
             no_peer            reply copies not sent: no peer known yet;
             abandoned          copies still held at the signal;
             send_errors        copies whose sendto failed (not sent);
             heartbeats_sent, ignored (frames that were not requests);
             ts1_low_bits       the requests by their ts1's low four bits
                                (MAVProxy's `ping` puts its out-link
                                there), {"BITS": count}
  cells[a][b]  requests: requests that arrived on link a and were
             answered (the same for every b); replies: of their reply
             copies, those really sent on link b
  answered   requests answered in total (sum over a of cells[a][0].requests)
  repeats    requests not answered since their ts1 already was
  seed
"""
import argparse
import heapq
import json
import os
import random
import select
import signal
import socket
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def log(*parts):
    print("two_link_responder:", *parts, file=sys.stderr, flush=True)


def per_link(name, values, n, default):
    """A per-link option: given once per link, once for all, or not at all."""
    if not values:
        return [default] * n
    if len(values) == 1:
        return values * n
    if len(values) != n:
        raise SystemExit(f"--{name} given {len(values)} times for {n} links")
    return values


def address(spec):
    host, port = spec.rsplit(":", 1)
    return host.strip("[]"), int(port)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--listen", action="append", default=[], required=True,
                    help="HOST:PORT of one link's socket; once per link (N >= 2)")
    ap.add_argument("--drop-up", action="append", type=float, default=[],
                    help="a link's request loss in percent, in link order")
    ap.add_argument("--drop-down", action="append", type=float, default=[],
                    help="a link's reply loss in percent, in link order")
    ap.add_argument("--delay-ms", action="append", type=float, default=[],
                    help="a link's reply delay in ms, in link order")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--heartbeat-hz", type=float, default=1.0)
    ap.add_argument("--boot-s", type=float, default=100.0, help="its clock at start")
    ap.add_argument("--ping", action="store_true",
                    help="answer PING requests too, routed as TIMESYNC replies are")
    args = ap.parse_args()

    n = len(args.listen)
    if n < 2:
        raise SystemExit("give --listen at least twice (one per link)")
    drop_up = per_link("drop-up", args.drop_up, n, 0.0)
    drop_down = per_link("drop-down", args.drop_down, n, 0.0)
    delay = per_link("delay-ms", args.delay_ms, n, 0.0)

    m = mavutil.mavlink
    # The encoder; one parser per link, so a link's bytes never meet another's.
    mav = m.MAVLink(None, srcSystem=args.sysid, srcComponent=args.compid)
    parsers = []
    socks = []
    for spec in args.listen:
        host, port = address(spec)
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        s = socket.socket(family, socket.SOCK_DGRAM)
        s.bind((host, port))
        s.setblocking(False)
        socks.append(s)
        p = m.MAVLink(None, srcSystem=args.sysid, srcComponent=args.compid)
        p.robust_parsing = True
        parsers.append(p)
    peers = [None] * n
    boot_ns = time.monotonic_ns() - int(args.boot_s * 1e9)

    links = [{"listen": args.listen[k], "drop_up_pct": drop_up[k],
              "drop_down_pct": drop_down[k], "delay_ms": delay[k],
              "requests_received": 0, "requests_dropped": 0, "replies_sent": 0,
              "replies_dropped": 0, "no_peer": 0, "abandoned": 0, "send_errors": 0,
              "heartbeats_sent": 0, "ignored": 0, "ts1_low_bits": {}} for k in range(n)]
    cells = [[{"requests": 0, "replies": 0} for _ in range(n)] for _ in range(n)]
    answered_ts1 = set()
    counts = {"answered": 0, "repeats": 0}
    held = []  # (due, order, out-link, in-link, bytes)
    order = 0

    signals = []

    def stop(*_):
        signals.append(True)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def pack(msg):
        buf = msg.pack(mav)
        mav.seq = (mav.seq + 1) % 256
        return buf

    def send(k, buf):
        try:
            socks[k].sendto(buf, peers[k])
            return True
        except OSError as e:
            links[k]["send_errors"] += 1
            log(f"link {k}: sendto {peers[k]}: {e}")
            return False

    def send_due(now):
        while held and held[0][0] <= now:
            _, _, b, a, buf = heapq.heappop(held)
            if peers[b] is None:
                links[b]["no_peer"] += 1
            elif send(b, buf):
                links[b]["replies_sent"] += 1
                cells[a][b]["replies"] += 1

    def reply_to(msg, link):
        """The reply to a request on `link`, and what tells it from others."""
        if msg.get_type() == "PING":
            reply = m.MAVLink_ping_message(msg.time_usec, msg.seq,
                                           msg.get_srcSystem(), msg.get_srcComponent())
            return reply, ("ping", msg.time_usec, msg.seq)
        bits = str(msg.ts1 & 0xF)
        link["ts1_low_bits"][bits] = link["ts1_low_bits"].get(bits, 0) + 1
        clock = time.monotonic_ns() - boot_ns
        return m.MAVLink_timesync_message(clock, msg.ts1), ("timesync", msg.ts1)

    def request(a, msg, arrived):
        nonlocal order
        link = links[a]
        rng = random.Random(f"{args.seed}/{a}/{link['requests_received']}")
        link["requests_received"] += 1
        reply, key = reply_to(msg, link)
        if rng.random() < drop_up[a] / 100.0:
            link["requests_dropped"] += 1
            return
        if key in answered_ts1:
            counts["repeats"] += 1
            return
        answered_ts1.add(key)
        counts["answered"] += 1
        for b in range(n):
            cells[a][b]["requests"] += 1
        buf = pack(reply)
        for b in range(n):
            if rng.random() < drop_down[b] / 100.0:
                links[b]["replies_dropped"] += 1
                continue
            order += 1
            heapq.heappush(held, (arrived + delay[b] / 1000.0, order, b, a, buf))

    def receive(a):
        while True:
            try:
                data, peer = socks[a].recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError as e:
                log(f"link {a}: recvfrom: {e}")
                return
            arrived = time.monotonic()
            peers[a] = peer
            for msg in parsers[a].parse_buffer(data) or []:
                timesync = msg.get_type() == "TIMESYNC" and msg.tc1 == 0
                ping = (args.ping and msg.get_type() == "PING"
                        and msg.target_system == 0 and msg.target_component == 0)
                if timesync or ping:
                    request(a, msg, arrived)
                else:
                    links[a]["ignored"] += 1

    def heartbeat():
        buf = None
        for k in range(n):
            if peers[k] is None:
                continue
            if buf is None:
                buf = pack(m.MAVLink_heartbeat_message(
                    m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                    m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0, m.MAV_STATE_ACTIVE, 3))
            if send(k, buf):
                links[k]["heartbeats_sent"] += 1

    print("ready", flush=True)
    log(f"{n} links on {', '.join(args.listen)}; seed {args.seed}")
    period = 1.0 / args.heartbeat_hz if args.heartbeat_hz > 0 else None
    next_beat = time.monotonic()
    while not signals:
        now = time.monotonic()
        if period is not None and now >= next_beat:
            heartbeat()
            next_beat += period
            if next_beat < now:
                next_beat = now + period
        send_due(now)
        wake = [0.05]
        if held:
            wake.append(held[0][0] - now)
        if period is not None:
            wake.append(next_beat - now)
        try:
            ready, _, _ = select.select(socks, [], [], max(0.0, min(wake)))
        except InterruptedError:
            continue
        for a, s in enumerate(socks):
            if s in ready:
                receive(a)
        send_due(time.monotonic())

    for _, _, b, _, _ in held:
        links[b]["abandoned"] += 1
    log(f"stopped on a signal: answered {counts['answered']}, abandoned {len(held)} copies")
    truth = {"links": links, "cells": cells, "answered": counts["answered"],
             "repeats": counts["repeats"], "seed": args.seed}
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
