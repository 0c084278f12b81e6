#!/usr/bin/env python3
"""A UDP relay between a ground side (mavping, MAVProxy) and one or more
vehicles that drops, duplicates and reorders MAVLink frames in each
direction by a seeded plan, and counts exactly what it did: the ground
truth mavping's per-direction figures are held against. Raw sockets, no
pymavlink: it reads only frame headers (and PING payloads, to tell
requests and replies apart).

  fault_relay.py --vehicle 127.0.0.1:V1 [--vehicle 127.0.0.1:V2] \\
      --seed 7 --drop-up 0.1 --dup-up 0.03 --drop-down 0.05 --dup-down 0.03 \\
      --reorder-down 0.02 [--requests N] [--down-ids 22,73,110]

Prints "ready", then the UDP port it listens on for the ground side (it
answers whoever sent last there, as a router's UDP server does). Every
frame mavping sends goes to every vehicle, each with its own fate; every
frame a vehicle sends goes to the ground side.

The plan: each stream (uplink to vehicle i; downlink of source
sysid/compid) has its own random sequence seeded by --seed and the
stream's name, three draws a frame whatever happens to it, so the k-th
frame of a stream always meets the same fate. A stream's first frame is
always delivered (a sequence count starts at the first frame it sees: a
drop before it shows nowhere). Per frame: dropped with --drop-*; else,
downlink, held back with --reorder-down (it goes after the source's next
frame, or after 200 ms); and a frame that goes is sent twice with
--dup-*.

--down-ids 22,73,110: the downlink plan (drop, dup, reorder) meets only
frames of these message ids (here PARAM_VALUE, MISSION_ITEM_INT,
FILE_TRANSFER_PROTOCOL); the others go down once, untouched, and take no
draw, so the k-th PARAM_VALUE of a source meets the same fate however
many HEARTBEATs came between. A source's index-based figures
(distinct_forwarded, last_forwarded_index, dropped_after_last) then
number its planned frames only; "untouched" counts the others.

--requests N (a probe run): once N PING requests have come from the
ground side and the vehicles have answered every copy forwarded to them,
the downlink closes (nothing more forwarded or counted), so the counts
are exactly what the prober can have seen: it received everything the
relay forwarded before that, and nothing after.

--cut START+LENGTH[,START+LENGTH...] (seconds, after the relay's first
forwarded frame, e.g. 3+2.5,9+1): during each window every frame in
either direction is dropped on arrival (before the plan, which it takes
no draw of). The truth then has "cut": the windows, how many frames each
direction lost to them, and the time (s after that first frame) and
message id of every frame forwarded down, in order, copies included:
the deliveries a C2 report's outages and failsafe replay are held to;
and the sequence number of every PING request it cut ("requests_cut";
those forwarded are in the uplink's "requests" with their fates).

On SIGTERM, one JSON line: per downlink source, frames from the vehicle,
forwarded (copies included), dropped, dropped after the last forwarded
frame (no later frame shows those gaps), duplicated, reordered, PING
replies and how many of them were dropped, frames and drops by message id
("frames_by_msgid", "dropped_by_msgid": {"22": 9}) and which of a message
id's frames were dropped, numbered from 0 among that id's frames from the
source ("dropped_nth_by_msgid": {"22": [4, 10, ...]}: a vehicle that
sends its parameter list in index order, once, as MAVSDK does, numbers
the first pass's PARAM_VALUEs by param_index); per vehicle on the uplink,
frames, dropped, duplicated, dropped after the last forwarded frame, and
every PING request's fate: its copies forwarded, its replies forwarded
and dropped ([seq, copies, replies forwarded, replies dropped], in the
order the requests came), and the first replies that went down after the
reply to a later request. "kernel_dropped": datagrams the kernel
dropped before the relay could read them (SO_RXQ_OVFL; a MAVSDK parameter
list comes in one burst): the ground socket's, and each vehicle socket's.
The kernel tells a drop with the next datagram it queues after it (a
vehicle's 1 Hz HEARTBEAT brings it). Anything but 0 there means the counts
above miss frames.
"""
import argparse
import json
import random
import select
import signal
import socket
import sys
import time

PING = 4
HOLD_S = 0.2
# Linux: ancillary data on each datagram with the socket's count of
# datagrams dropped for want of buffer space.
SO_RXQ_OVFL = getattr(socket, "SO_RXQ_OVFL", 40)
RCVBUF = 4 << 20


def counted_socket():
    """A UDP socket with a large buffer that reports the kernel's drops."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RCVBUF)
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
    except OSError:
        pass
    sock.bind(("127.0.0.1", 0))
    return sock


def receive(sock):
    """(data, addr, kernel drop count so far or None)."""
    data, anc, _, addr = sock.recvmsg(65535, socket.CMSG_SPACE(4))
    dropped = None
    for level, kind, value in anc:
        if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL and len(value) >= 4:
            dropped = int.from_bytes(value[:4], sys.byteorder)
    return data, addr, dropped


def frames_of(data):
    """Splits a datagram into MAVLink 1/2 frames: [(bytes, header)] with
    header (seq, sysid, compid, msgid, payload); bytes that are no frame
    come as one piece with header None."""
    out, i = [], 0
    while i < len(data):
        magic = data[i]
        if magic == 0xFD and i + 10 <= len(data):
            n = data[i + 1]
            end = i + 10 + n + 2 + (13 if data[i + 2] & 1 else 0)
            seq, sysid, compid = data[i + 4], data[i + 5], data[i + 6]
            msgid = data[i + 7] | data[i + 8] << 8 | data[i + 9] << 16
            payload = data[i + 10:i + 10 + n]
        elif magic == 0xFE and i + 6 <= len(data):
            n = data[i + 1]
            end = i + 6 + n + 2
            seq, sysid, compid, msgid = data[i + 2], data[i + 3], data[i + 4], data[i + 5]
            payload = data[i + 6:i + 6 + n]
        else:
            out.append((data[i:], None))
            return out
        if end > len(data):
            out.append((data[i:], None))
            return out
        out.append((data[i:end], (seq, sysid, compid, msgid, payload)))
        i = end
    return out


def ping_fields(payload):
    """(seq, target_system, target_component) of a PING payload (MAVLink 2
    trims trailing zeros)."""
    p = bytes(payload).ljust(14, b"\0")
    return int.from_bytes(p[8:12], "little"), p[12], p[13]


class Plan:
    """The fates of one stream's frames, by frame number."""

    def __init__(self, seed, name, drop, dup, hold):
        self.rng = random.Random(f"{seed}/{name}")
        self.drop, self.dup, self.hold = drop, dup, hold
        self.index = 0

    def next(self):
        """(index, fate, doubled): fate is "drop", "hold" or "go"."""
        d, h, u = self.rng.random(), self.rng.random(), self.rng.random()
        k = self.index
        self.index += 1
        if k == 0:
            return k, "go", False
        if d < self.drop:
            return k, "drop", False
        return k, ("hold" if h < self.hold else "go"), u < self.dup


class DownSource:
    """What the relay did to one source's frames on their way down."""

    def __init__(self, plan):
        self.plan = plan
        self.frames = self.forwarded = self.duplicated = self.reordered = 0
        self.dropped = []
        self.seen = set()
        self.highest = -1
        self.held = None  # (index, data, doubled, release_at, reply)
        self.replies = self.replies_dropped = 0
        self.untouched = 0
        self.frames_by_msgid = {}
        self.dropped_by_msgid = {}

    def truth(self):
        after_last = sum(1 for k in self.dropped if k > self.highest)
        return {"frames": self.frames, "forwarded": self.forwarded,
                "dropped": len(self.dropped), "dropped_after_last": after_last,
                "duplicated": self.duplicated, "reordered": self.reordered,
                "distinct_forwarded": len(self.seen), "last_forwarded_index": self.highest,
                "replies": self.replies, "replies_dropped": self.replies_dropped,
                "untouched": self.untouched,
                "frames_by_msgid": {str(k): v for k, v in sorted(self.frames_by_msgid.items())},
                "dropped_by_msgid": {str(k): len(v) for k, v in sorted(self.dropped_by_msgid.items())},
                "dropped_nth_by_msgid": {str(k): v for k, v in sorted(self.dropped_by_msgid.items())}}


class Uplink:
    """What the relay did to the ground side's frames on their way to one
    vehicle, and the fate of every PING request."""

    def __init__(self, addr, plan):
        self.addr, self.plan = addr, plan
        self.sock = counted_socket()
        self.kernel_dropped = 0
        self.frames = self.dropped = self.duplicated = 0
        # Frame numbers dropped, and the last forwarded: a drop after it
        # leaves no gap the vehicle can see.
        self.dropped_at = []
        self.last_forwarded = -1
        self.requests = []  # [seq] in arrival order
        self.fate = {}  # seq -> [copies forwarded, replies forwarded, replies dropped]
        self.index = {}  # seq -> its place in `requests`
        self.outstanding = 0  # copies forwarded not yet answered
        self.highest_answered = -1
        self.replies_out_of_order = 0  # first replies after a later request's
        self.sources = set()

    def answered(self, seq):
        """A copy of the reply to `seq` went down."""
        fate = self.fate[seq]
        fate[1] += 1
        if fate[1] == 1:
            k = self.index[seq]
            self.replies_out_of_order += k < self.highest_answered
            self.highest_answered = max(self.highest_answered, k)

    def truth(self):
        reqs = [[s, *self.fate[s]] for s in self.requests]
        return {"vehicle": f"{self.addr[0]}:{self.addr[1]}", "sources": sorted(self.sources),
                "frames": self.frames, "dropped": self.dropped, "duplicated": self.duplicated,
                "dropped_after_last": sum(1 for k in self.dropped_at if k > self.last_forwarded),
                "requests": reqs, "unanswered_copies": self.outstanding,
                "replies_out_of_order": self.replies_out_of_order,
                "kernel_dropped": self.kernel_dropped}


class Cuts:
    """The --cut windows, timed from the first frame forwarded."""

    def __init__(self, windows):
        self.windows = windows
        self.origin = None
        self.up = self.down = 0
        self.requests = []  # the seq of every PING request cut
        self.forwarded_down = []  # [seconds, msgid]

    def now(self):
        """Seconds since the first frame forwarded (the first call starts
        the clock: the caller is about to forward one)."""
        now = time.monotonic()
        if self.origin is None:
            self.origin = now
        return now - self.origin

    def drops(self, up):
        """Whether a frame arriving now falls in a window (counted)."""
        if self.origin is None:
            return False
        t = time.monotonic() - self.origin
        if any(start <= t < start + length for start, length in self.windows):
            if up:
                self.up += 1
            else:
                self.down += 1
            return True
        return False

    def truth(self):
        return {"windows": self.windows, "dropped_up": self.up, "dropped_down": self.down,
                "requests_cut": self.requests, "forwarded_down": self.forwarded_down}


class Relay:
    def __init__(self, args):
        self.args = args
        self.ground = counted_socket()
        self.ground_kernel_dropped = 0
        self.down_ids = args.down_ids
        self.peer = None
        self.ours = tuple(int(x) for x in args.ours.split("/"))
        self.up = []
        for i, v in enumerate(args.vehicle):
            host, port = v.rsplit(":", 1)
            self.up.append(Uplink((host, int(port)), Plan(args.seed, f"up/{i}", args.drop_up,
                                                          args.dup_up, 0.0)))
        self.down = {}
        self.requests_seen = 0
        self.closed_at = None
        self.close_forced = False
        self.after_close = 0
        self.no_peer = 0
        self.unparsed = 0
        self.cuts = Cuts(args.cut) if args.cut else None

    def send_down(self, frame, msgid):
        """One copy of a frame to the ground side (timed, with --cut)."""
        self.ground.sendto(frame, self.peer)
        if self.cuts is not None:
            self.cuts.forwarded_down.append([round(self.cuts.now(), 6), msgid])

    def from_ground(self, data):
        for frame, header in frames_of(data):
            if self.cuts is not None:
                if self.cuts.drops(up=True):
                    if header is not None and header[3] == PING:
                        seq, ts, tc = ping_fields(header[4])
                        if (ts, tc) == (0, 0):
                            self.cuts.requests.append(seq)
                    continue
                self.cuts.now()
            request = None
            if header is None:
                self.unparsed += 1
            elif header[3] == PING:
                seq, ts, tc = ping_fields(header[4])
                if (ts, tc) == (0, 0):
                    request = seq
                    self.requests_seen += 1
            for link in self.up:
                self.uplink(link, frame, request)

    def uplink(self, link, frame, request):
        k, fate, doubled = link.plan.next()
        link.frames += 1
        copies = 0
        if fate == "drop":
            link.dropped += 1
            link.dropped_at.append(k)
        else:
            link.last_forwarded = k
            copies = 2 if doubled else 1
            link.duplicated += copies - 1
            for _ in range(copies):
                link.sock.sendto(frame, link.addr)
        if request is not None:
            link.index.setdefault(request, len(link.requests))
            link.requests.append(request)
            link.fate.setdefault(request, [0, 0, 0])[0] += copies
            link.outstanding += copies

    def from_vehicle(self, link, data):
        for frame, header in frames_of(data):
            if header is None:
                self.unparsed += 1
                continue
            seq, sysid, compid, msgid, payload = header
            key = f"{sysid}/{compid}"
            link.sources.add(key)
            reply = None
            if msgid == PING:
                rseq, ts, tc = ping_fields(payload)
                if (ts, tc) == self.ours and rseq in link.fate:
                    reply = rseq
                    link.outstanding -= 1
            if self.closed_at is not None:
                self.after_close += 1
                continue
            if self.peer is None:
                self.no_peer += 1
                continue
            if self.cuts is not None and self.cuts.drops(up=False):
                continue
            src = self.down.get(key)
            if src is None:
                a = self.args
                src = self.down[key] = DownSource(Plan(a.seed, f"down/{key}", a.drop_down,
                                                       a.dup_down, a.reorder_down))
            self.downlink(src, link, frame, msgid, reply)
        self.maybe_close()

    def downlink(self, src, link, frame, msgid, reply):
        nth = src.frames_by_msgid.get(msgid, 0)
        src.frames_by_msgid[msgid] = nth + 1
        if self.down_ids is not None and msgid not in self.down_ids:
            src.frames += 1
            src.untouched += 1
            src.replies += reply is not None
            self.send_down(frame, msgid)
            src.forwarded += 1
            if reply is not None:
                link.answered(reply)
            return
        k, fate, doubled = src.plan.next()
        src.frames += 1
        src.replies += reply is not None
        if fate == "drop":
            src.dropped.append(k)
            src.dropped_by_msgid.setdefault(msgid, []).append(nth)
            if reply is not None:
                src.replies_dropped += 1
                link.fate[reply][2] += 1
            return
        if fate == "hold" and src.held is None:
            src.held = (k, frame, doubled, time.monotonic() + HOLD_S, link, reply, msgid)
            return
        self.forward(src, k, frame, doubled, link, reply, msgid)
        self.release(src)

    def forward(self, src, k, frame, doubled, link, reply, msgid):
        for _ in range(2 if doubled else 1):
            self.send_down(frame, msgid)
            src.forwarded += 1
            if k in src.seen:
                src.duplicated += 1
            elif k < src.highest:
                src.reordered += 1
            src.seen.add(k)
            src.highest = max(src.highest, k)
            if reply is not None:
                link.answered(reply)

    def release(self, src, now=None):
        if src.held is not None and (now is None or now >= src.held[3]):
            k, frame, doubled, _, link, reply, msgid = src.held
            src.held = None
            self.forward(src, k, frame, doubled, link, reply, msgid)

    def maybe_close(self, force=False):
        n = self.args.requests
        if n is None or self.closed_at is not None or self.requests_seen < n:
            return
        if force or all(link.outstanding <= 0 for link in self.up):
            for src in self.down.values():
                self.release(src)
            self.closed_at = time.monotonic()
            self.close_forced = force

    def run(self, until):
        socks = {self.ground: None, **{link.sock: link for link in self.up}}
        last_request = None
        while until.running:
            now = time.monotonic()
            held = [s.held[3] for s in self.down.values() if s.held is not None]
            timeout = max(0.0, min([0.05, *[h - now for h in held]]))
            try:
                ready, _, _ = select.select(list(socks), [], [], timeout)
            except InterruptedError:
                ready = []
            for sock in ready:
                data, addr, dropped = receive(sock)
                if sock is self.ground:
                    self.ground_kernel_dropped = dropped or self.ground_kernel_dropped
                    self.peer = addr
                    self.from_ground(data)
                else:
                    link = socks[sock]
                    link.kernel_dropped = dropped or link.kernel_dropped
                    self.from_vehicle(link, data)
            now = time.monotonic()
            for src in self.down.values():
                if self.closed_at is None:
                    self.release(src, now)
            # A vehicle that never answers some copy must not hold the
            # downlink open for ever: close after 3 s, and say so.
            if self.args.requests is not None and self.requests_seen >= self.args.requests:
                last_request = last_request or now
                if now - last_request > 3.0:
                    self.maybe_close(force=True)

    def truth(self):
        extra = {"cut": self.cuts.truth()} if self.cuts is not None else {}
        return {**extra, "down": {k: s.truth() for k, s in sorted(self.down.items())},
                "up": [link.truth() for link in self.up],
                "requests_seen": self.requests_seen,
                "closed": self.closed_at is not None, "close_forced": self.close_forced,
                "after_close": self.after_close, "before_peer": self.no_peer,
                "unparsed": self.unparsed,
                "kernel_dropped": {"ground": self.ground_kernel_dropped,
                                   "vehicles": [link.kernel_dropped for link in self.up]}}


class UntilSignalled:
    def __init__(self):
        self.running = True
        signal.signal(signal.SIGTERM, self.stop)
        signal.signal(signal.SIGINT, self.stop)

    def stop(self, *_):
        self.running = False


def msgids(text):
    try:
        ids = {int(x) for x in text.split(",") if x.strip()}
    except ValueError:
        raise argparse.ArgumentTypeError(f"not message ids: {text!r}") from None
    return ids or None


def windows(text):
    """START+LENGTH[,...] in seconds."""
    out = []
    for part in text.split(","):
        try:
            start, length = (float(x) for x in part.split("+"))
        except ValueError:
            raise argparse.ArgumentTypeError(f"not START+LENGTH: {part!r}") from None
        if start < 0 or length <= 0:
            raise argparse.ArgumentTypeError(f"not START+LENGTH: {part!r}")
        out.append([start, length])
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vehicle", action="append", required=True, help="HOST:PORT, repeatable")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--drop-up", type=float, default=0.0)
    ap.add_argument("--dup-up", type=float, default=0.0)
    ap.add_argument("--drop-down", type=float, default=0.0)
    ap.add_argument("--dup-down", type=float, default=0.0)
    ap.add_argument("--reorder-down", type=float, default=0.0)
    ap.add_argument("--requests", type=int, default=None,
                    help="close the downlink once this many PINGs are answered")
    ap.add_argument("--ours", default="250/190", help="the prober's sysid/compid")
    ap.add_argument("--down-ids", type=msgids, default=None, metavar="ID,ID",
                    help="message ids the downlink plan applies to (others pass untouched)")
    ap.add_argument("--cut", type=windows, default=None, metavar="START+LENGTH,...",
                    help="drop both directions in these windows (s after the first frame)")
    args = ap.parse_args()
    relay = Relay(args)
    until = UntilSignalled()
    print("ready", flush=True)
    print(relay.ground.getsockname()[1], flush=True)
    relay.run(until)
    print(json.dumps(relay.truth()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
