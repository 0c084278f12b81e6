#!/usr/bin/env python3
"""A vehicle written with pymavlink that sends the same frames over two (or
more) UDP links to one ground station, each link with its own faults, for
mavping's "two links to one vehicle" report (issue 41). mavping listens on
the N ports (`mavping --passive udp:127.0.0.1:P1 udp:127.0.0.1:P2 ...`);
this peer sends to them, one plain UDP socket (its own source port) per link.

  --to HOST:PORT      a link's ground port; give it once per link (N >= 2)
  --drop PCT          a link's loss, percent (default 0)
  --delay-ms MS       a link's one-way delay (default 0)
  --jitter-ms MS      a link's jitter: each copy waits a further
                      uniform(0, MS) ms (default 0)
                      Each of these three is given in link order, once per
                      link, or once for every link, or not at all.
  --rate HZ           vehicle ticks per second (default 50)
  --duration S        how long it sends (default 10)
  --start-after S     wait before the first frame, so the ground is
                      listening (default 1.0)
  --seed N            the fault plan's seed (default 0)
  --sysid/--compid    its ids (default 1/1)

Frames, MAVLink 2, built like a vehicle's: every tick an ATTITUDE
(time_boot_ms from a monotonic clock started with the script), every 10th
tick (from tick 0) a GLOBAL_POSITION_INT after it, and once a second (ticks
0, rate, 2*rate, ... in tick time) a HEARTBEAT before it. Each frame is
packed ONCE, so it has one packet sequence number (0, 1, ... 255, 0, ...)
and one byte string, and those very bytes go out on every link that does
not drop it, each after that link's delay (+ jitter).

The fault plan is reproducible from --seed alone: random.Random(seed)
draws, frame by frame and within a frame link by link, one number per
(frame, link), always, whatever the link's loss (so one link's --drop does
not change another link's plan); the copy is dropped if it is < PCT/100.
Jitter comes from its own random.Random(f"{seed}/jitter"), drawn in the
same order, so adding jitter leaves the drop plan as it was.

A frame's copy on a link is due at the frame's build time plus the link's
delay + jitter; copies are held in a heap of (due, order) and each is sent
when due. Without jitter a link's copies keep their order (any delay); with
jitter they may not, and the truth says so.

On exit (after --duration, or on SIGTERM/SIGINT) it stops building frames,
sends every copy still held when due, then prints one JSON line of ground
truth on stdout (before it only "ready", once its sockets are open, as the
other peers here; logs go to stderr) and exits 0.
A second SIGTERM/SIGINT abandons the copies still held: they are not
counted as sent but as "abandoned".

  frames               frames built
  links[k]             to, drop_pct, delay_ms, jitter_ms;
                       sent      copies it sent (an error on sendto counts
                                 in send_errors, not here);
                       dropped   copies the plan dropped;
                       dropped_between  of them, those between its first
                                 and its last copy sent: what its sequence
                                 alone can count lost;
                       only      frames it sent and no other link sent;
                       first     frames whose copy on it was due first among
                                 the links that sent the frame: the least
                                 delay + jitter; a tie goes to the link given
                                 first on the command line (lowest index), so
                                 every frame sent on any link is "first" on
                                 exactly one link (sum = frames -
                                 lost_on_every_link);
                       lag_p50_ms, lag_max_ms  its copies' lag behind
                                 the first copy as really sent, over the
                                 frames two links sent (0 where first)
                       reordered copies it sent after a copy of a later
                                 frame (0 without jitter);
                       abandoned, send_errors (0 normally)
  lost_on_every_link   frames no link sent
  lost_on_every_link_between  of those, the ones between the first and
                       the last frame any link sent
  sent_on_every_link   frames every link sent
  reordered            whether any link reordered
  seq_wraps            times the sequence number went 255 -> 0
  first_seq, last_seq  the first and last frame's sequence (null if none)
  by_type              frames built per message name
"""
import argparse
import heapq
import json
import os
import random
import signal
import socket
import sys
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402


def log(*parts):
    print("two_link_vehicle:", *parts, file=sys.stderr, flush=True)


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
    return host, int(port)


class Vehicle:
    """Builds the frames: packs each once and numbers it."""

    def __init__(self, sysid, compid):
        self.mav = mavutil.mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self.boot = time.monotonic()
        self.seqs = []
        self.by_type = {}

    def pack(self, msg):
        buf = msg.pack(self.mav)
        self.seqs.append(self.mav.seq)
        self.by_type[msg.get_type()] = self.by_type.get(msg.get_type(), 0) + 1
        self.mav.seq = (self.mav.seq + 1) % 256
        return buf

    def tick(self, i, rate):
        """The frames of tick i, in the order they go out."""
        ms = int((time.monotonic() - self.boot) * 1000) % 2**32
        m = mavutil.mavlink
        frames = []
        # Once a second in tick time: ticks where the second count changes.
        if i == 0 or int(i / rate) != int((i - 1) / rate):
            frames.append(self.pack(m.MAVLink_heartbeat_message(
                m.MAV_TYPE_QUADROTOR, m.MAV_AUTOPILOT_ARDUPILOTMEGA,
                m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 0, m.MAV_STATE_ACTIVE, 3)))
        t = ms / 1000.0
        frames.append(self.pack(m.MAVLink_attitude_message(
            ms, 0.1 * (t % 3), 0.05, (t % 6.0) - 3.0, 0.01, 0.02, 0.03)))
        if i % 10 == 0:
            frames.append(self.pack(m.MAVLink_global_position_int_message(
                ms, -353632610 + i, 1491652370, 584000, 10000 + i % 1000, 5, -3, 0, 9000)))
        return frames


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--to", action="append", default=[], required=True,
                    help="HOST:PORT of one link's ground port; once per link (N >= 2)")
    ap.add_argument("--drop", action="append", type=float, default=[],
                    help="a link's loss in percent, in link order")
    ap.add_argument("--delay-ms", action="append", type=float, default=[],
                    help="a link's delay in ms, in link order")
    ap.add_argument("--jitter-ms", action="append", type=float, default=[],
                    help="a link's jitter in ms (uniform 0..MS added), in link order")
    ap.add_argument("--rate", type=float, default=50.0, help="ticks per second")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--start-after", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    args = ap.parse_args()

    n = len(args.to)
    if n < 2:
        raise SystemExit("give --to at least twice (one per link)")
    if args.rate <= 0:
        raise SystemExit("--rate must be > 0")
    targets = [address(t) for t in args.to]
    drop = per_link("drop", args.drop, n, 0.0)
    delay = per_link("delay-ms", args.delay_ms, n, 0.0)
    jitter = per_link("jitter-ms", args.jitter_ms, n, 0.0)
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(n)]
    plan_rng = random.Random(args.seed)
    jitter_rng = random.Random(f"{args.seed}/jitter")

    vehicle = Vehicle(args.sysid, args.compid)
    links = [{"to": args.to[k], "drop_pct": drop[k], "delay_ms": delay[k],
              "jitter_ms": jitter[k], "sent": 0, "dropped": 0, "only": 0, "first": 0,
              "reordered": 0, "abandoned": 0, "send_errors": 0} for k in range(n)]
    # Per frame: {link: offset in s} of the copies planned, then those sent.
    planned = []
    sent_on = []
    latest = [-1] * n  # per link, the latest frame index it has sent
    held = []  # (due, order, link, frame index, bytes)
    sent_at = {}  # frame index -> {link: when its copy was really sent}
    order = 0

    signals = []

    def stop(*_):
        signals.append(True)  # logged outside the handler

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def send_due(now):
        while held and held[0][0] <= now:
            _, _, k, f, buf = heapq.heappop(held)
            try:
                socks[k].sendto(buf, targets[k])
            except OSError as e:
                links[k]["send_errors"] += 1
                log(f"link {k}: sendto {args.to[k]}: {e}")
                continue
            links[k]["sent"] += 1
            sent_on[f].add(k)
            sent_at.setdefault(f, {})[k] = time.monotonic()
            if f < latest[k]:
                links[k]["reordered"] += 1
            latest[k] = max(latest[k], f)

    def nap(until):
        """Sleep until `until` or a signal, in short steps."""
        left = until - time.monotonic()
        if left > 0:
            time.sleep(min(left, 0.05))

    print("ready", flush=True)
    log(f"{n} links to {', '.join(args.to)}; first frame in {args.start_after}s")
    wake = time.monotonic() + args.start_after
    while not signals and time.monotonic() < wake:
        nap(wake)

    begin = time.monotonic()
    tick = 0
    while not signals:
        now = time.monotonic()
        tick_at = begin + tick / args.rate
        if tick / args.rate >= args.duration:
            break
        if now >= tick_at:
            for buf in vehicle.tick(tick, args.rate):
                f = len(planned)
                offsets = {}
                for k in range(n):
                    lost = plan_rng.random() < drop[k] / 100.0
                    extra = jitter_rng.uniform(0.0, jitter[k]) if jitter[k] > 0 else 0.0
                    if lost:
                        links[k]["dropped"] += 1
                        continue
                    offsets[k] = (delay[k] + extra) / 1000.0
                    order += 1
                    heapq.heappush(held, (tick_at + offsets[k], order, k, f, buf))
                planned.append(offsets)
                sent_on.append(set())
            tick += 1
            send_due(time.monotonic())
            continue
        send_due(now)
        nap(min(tick_at, held[0][0]) if held else tick_at)

    why = "on a signal" if signals else "after --duration"
    log(f"stopped {why}: built {len(planned)} frames; flushing {len(held)} copies")
    while held and len(signals) < 2:
        now = time.monotonic()
        send_due(now)
        if held:
            nap(held[0][0])
    if held:
        log(f"stopped again: abandoning {len(held)} copies still held")
    for _, _, k, _, _ in held:
        links[k]["abandoned"] += 1

    # What a link's own sequence can count: the frames missing between its
    # first and its last copy (drops before or after them leave no gap).
    for k, link in enumerate(links):
        on_k = [f for f, sent in enumerate(sent_on) if k in sent]
        link["dropped_between"] = (on_k[-1] - on_k[0] + 1 - len(on_k)) if on_k else 0
    lost_everywhere = sent_everywhere = 0
    for offsets, sent in zip(planned, sent_on):
        if not sent:
            lost_everywhere += 1
            continue
        if len(sent) == n:
            sent_everywhere += 1
        if len(sent) == 1:
            links[next(iter(sent))]["only"] += 1
        # Least offset first; a tie goes to the lowest link index.
        links[min(sent, key=lambda k: (offsets[k], k))]["first"] += 1

    # Each link's lag behind the first copy, as really sent (the schedule
    # slips under load): over the frames two links sent, 0 where first.
    lags = [[] for _ in links]
    for when in sent_at.values():
        if len(when) > 1:
            first = min(when.values())
            for k, t in when.items():
                lags[k].append((t - first) * 1e3)
    for k, link in enumerate(links):
        got = sorted(lags[k])
        pick = lambda q: got[min(len(got) - 1, int(q * len(got)))] if got else None
        link["lag_p50_ms"], link["lag_max_ms"] = pick(0.5), (got[-1] if got else None)
    # As a link alone, the merged stream sees no loss before its first
    # frame or after its last.
    on_any = [f for f, sent in enumerate(sent_on) if sent]
    between = sent_on[on_any[0] : on_any[-1] + 1] if on_any else []
    lost_between = sum(1 for sent in between if not sent)
    seqs = vehicle.seqs
    truth = {
        "frames": len(planned),
        "links": links,
        "lost_on_every_link": lost_everywhere,
        "lost_on_every_link_between": lost_between,
        "sent_on_every_link": sent_everywhere,
        "reordered": any(link["reordered"] for link in links),
        "seq_wraps": sum(1 for a, b in zip(seqs, seqs[1:]) if b < a),
        "first_seq": seqs[0] if seqs else None,
        "last_seq": seqs[-1] if seqs else None,
        "by_type": vehicle.by_type,
        "seed": args.seed,
    }
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
