#!/usr/bin/env python3
"""A ground station's read-only transfers written with pymavlink: the
baseline mavping's --probe params/mission/ftp are held against, and the
smoke test of tests/peers/mavsdk_vehicle.py.

  transfer_client.py udpout:127.0.0.1:P [--params] [--mission] [--ftp PATH]

Sends a HEARTBEAT first (as a ground station does), then, in order:

params   PARAM_REQUEST_LIST; every PARAM_VALUE counted by param_index
         until none has come for --idle seconds (the first pass); then
         each missing index re-requested by PARAM_REQUEST_READ, one at a
         time, up to --tries times, --timeout seconds each.
mission  MISSION_REQUEST_LIST -> MISSION_COUNT, then MISSION_REQUEST_INT
         for each item (re-sent after --timeout, up to --tries), then
         MISSION_ACK. Read-only: no upload, no clear.
ftp      ResetSessions, OpenFileRO PATH, BurstReadFile from 0 until the
         burst says complete, ReadFile for what is still missing,
         TerminateSession. Read-only: never writes, creates or removes.

Prints one JSON line: per transfer what arrived, what was missing on the
first pass, what the re-requests asked and got, times, and what the
vehicle did (PARAM_VALUE copies, index 65535, burst packet sizes...).
"""
import argparse
import hashlib
import json
import socket
import struct
import sys
import time

PARAM_VALUE, MISSION_COUNT, MISSION_ITEM_INT, MISSION_ACK, FTP = 22, 44, 73, 47, 110
OP_TERMINATE, OP_RESET, OP_OPEN_RO, OP_READ, OP_BURST = 1, 2, 4, 5, 15
OP_ACK, OP_NAK = 128, 129
FTP_DATA = 239


class Link:
    """The connection and a receive that never blocks past a deadline."""

    def __init__(self, url, sysid, compid, target):
        from pymavlink import mavutil
        self.m = mavutil.mavlink_connection(url, source_system=sysid, source_component=compid,
                                            dialect="common")
        # MAVSDK sends a whole parameter list in one burst: at loopback
        # speed the default buffer (~256 datagrams) overflows and the
        # kernel drops what no relay counted.
        self.m.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
        self.mav = self.m.mav
        self.ts, self.tc = target
        self.other = {}

    def recv(self, until, types):
        """The next message of one of `types` before `until`, or None;
        others are counted by type."""
        while True:
            left = until - time.monotonic()
            if left <= 0:
                return None
            msg = self.m.recv_match(blocking=True, timeout=min(left, 0.05))
            if msg is None:
                continue
            t = msg.get_msgId()
            if t in types:
                return msg
            self.other[msg.get_type()] = self.other.get(msg.get_type(), 0) + 1


def params(link, a):
    t0 = time.monotonic()
    got, copies, count, odd = {}, 0, None, 0
    first_at = last_at = None
    link.mav.param_request_list_send(link.ts, link.tc)
    until = t0 + a.first_wait
    while (msg := link.recv(until, {PARAM_VALUE})) is not None:
        now = time.monotonic() - t0
        first_at = first_at if first_at is not None else now
        last_at = now
        until = time.monotonic() + a.idle
        if msg.param_index == 65535 or msg.param_index >= msg.param_count:
            odd += 1
            continue
        count = msg.param_count
        copies += msg.param_index in got
        got.setdefault(msg.param_index, (msg.param_id, msg.param_type, msg.param_value))
    first_pass = len(got)
    missing = sorted(set(range(count or 0)) - set(got))
    sent = answered = 0
    for i in missing:
        for _ in range(a.tries):
            link.mav.param_request_read_send(link.ts, link.tc, b"", i)
            sent += 1
            until = time.monotonic() + a.timeout
            while (msg := link.recv(until, {PARAM_VALUE})) is not None:
                if msg.param_index == i:
                    break
            if msg is not None:
                answered += 1
                got[i] = (msg.param_id, msg.param_type, msg.param_value)
                break
    done = time.monotonic() - t0
    return {"count": count, "first_pass": first_pass, "missing_first_pass": len(missing),
            "missing_indices": missing, "rerequests": sent, "rerequests_answered": answered,
            "received": len(got), "copies": copies, "index_out_of_range": odd,
            "first_value_s": first_at, "first_pass_last_s": last_at, "seconds": done,
            "first_pass_per_s": (first_pass / (last_at - first_at)) if first_pass > 1 and last_at > first_at else None,
            "names": [got[i][0] for i in sorted(got)[:3]],
            "types": sorted({v[1] for v in got.values()})}


def mission(link, a):
    t0 = time.monotonic()
    msg, count_tries = None, 0
    while msg is None and count_tries < a.tries:
        link.mav.mission_request_list_send(link.ts, link.tc, 0)
        count_tries += 1
        msg = link.recv(time.monotonic() + a.timeout, {MISSION_COUNT})
    if msg is None:
        return {"count": None, "count_requests": count_tries}
    count, items, retries, sent, first = msg.count, {}, 0, 0, None
    for seq in range(count):
        for k in range(a.tries):
            retries += k > 0
            sent += 1
            link.mav.mission_request_int_send(link.ts, link.tc, seq, 0)
            until = time.monotonic() + a.timeout
            while (item := link.recv(until, {MISSION_ITEM_INT})) is not None:
                if item.seq == seq:
                    break
            if item is not None:
                items[seq] = item
                break
    link.mav.mission_ack_send(link.ts, link.tc, 0, 0)
    if 0 in items:
        it = items[0]
        first = {"frame": it.frame, "command": it.command, "current": it.current,
                 "autocontinue": it.autocontinue, "x": it.x, "y": it.y, "z": it.z,
                 "target": [it.target_system, it.target_component]}
    return {"count": count, "count_requests": count_tries, "received": len(items),
            "item_requests": sent, "retries": retries, "seconds": time.monotonic() - t0, "first_item": first,
            "last_seq": max(items) if items else None}


class Ftp:
    """The FILE_TRANSFER_PROTOCOL payload: seq, session, opcode, size,
    req_opcode, burst_complete, offset, data."""

    def __init__(self, link):
        self.link, self.seq, self.session = link, 0, 0

    def send(self, opcode, size=0, offset=0, data=b""):
        self.seq = (self.seq + 1) & 0xFFFF
        head = struct.pack("<HBBBBBxI", self.seq, self.session, opcode, size, 0, 0, offset)
        self.link.mav.file_transfer_protocol_send(0, self.link.ts, self.link.tc,
                                                  list((head + data).ljust(251, b"\0")))

    def recv(self, until):
        msg = self.link.recv(until, {FTP})
        if msg is None:
            return None
        p = bytes(msg.payload)
        seq, session, opcode, size, req, burst_complete, offset = struct.unpack_from("<HBBBBBxI", p)
        return {"seq": seq, "session": session, "opcode": opcode, "size": size, "req": req,
                "complete": burst_complete, "offset": offset, "data": p[12:12 + size]}

    def call(self, opcode, a, size=0, offset=0, data=b""):
        for _ in range(a.tries):
            self.send(opcode, size, offset, data)
            until = time.monotonic() + a.timeout
            while (r := self.recv(until)) is not None:
                if r["req"] == opcode:
                    return r
        return None


def ftp(link, a):
    t0 = time.monotonic()
    f = Ftp(link)
    out = {"path": a.ftp}
    r = f.call(OP_RESET, a)
    out["reset"] = r and r["opcode"]
    path = a.ftp.encode()
    r = f.call(OP_OPEN_RO, a, len(path), 0, path)
    if r is None or r["opcode"] != OP_ACK:
        out["open"] = r and {"opcode": r["opcode"], "data": list(r["data"])}
        return out
    f.session = r["session"]
    size = struct.unpack("<I", r["data"][:4].ljust(4, b"\0"))[0]
    out["size"] = size
    have, sizes, bursts, naks, stray = {}, {}, 0, [], 0
    offset = 0
    while offset < size:
        f.send(OP_BURST, FTP_DATA, offset)
        bursts += 1
        until = time.monotonic() + a.timeout
        while (r := f.recv(until)) is not None:
            until = time.monotonic() + a.timeout
            if r["req"] != OP_BURST:
                stray += 1
                continue
            if r["opcode"] == OP_NAK:
                naks.append(list(r["data"][:2]))
                break
            have[r["offset"]] = r["data"]
            sizes[r["size"]] = sizes.get(r["size"], 0) + 1
            if r["complete"]:
                break
        top = max((o + len(d) for o, d in have.items()), default=0)
        if top <= offset:
            break
        offset = top
    first_pass = sum(len(d) for d in have.values())
    reads = 0
    pos = 0
    while pos < size:
        chunk = have.get(pos)
        if chunk:
            pos += len(chunk)
            continue
        r = f.call(OP_READ, a, min(FTP_DATA, size - pos), pos)
        reads += 1
        if r is None or r["opcode"] != OP_ACK or not r["data"]:
            break
        have[pos] = r["data"]
    f.call(OP_TERMINATE, a)
    blob = b"".join(have[o] for o in sorted(have))
    out.update({"bursts": bursts, "burst_packet_sizes": sizes, "naks": naks,
                "first_pass_bytes": first_pass, "reads": reads, "received": len(blob),
                "sha256": hashlib.sha256(blob).hexdigest(), "stray": stray,
                "seconds": time.monotonic() - t0})
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpout:127.0.0.1:14550")
    ap.add_argument("--ids", default="250/190", help="our sysid/compid")
    ap.add_argument("--target", default="1/1", help="the vehicle's sysid/compid")
    ap.add_argument("--params", action="store_true")
    ap.add_argument("--mission", action="store_true")
    ap.add_argument("--ftp", metavar="PATH", help="read this file by MAVLink FTP")
    ap.add_argument("--no-heartbeat", action="store_true", help="do not send a HEARTBEAT first")
    ap.add_argument("--first-wait", type=float, default=3.0,
                    help="seconds to wait for the first PARAM_VALUE")
    ap.add_argument("--idle", type=float, default=0.5,
                    help="the first pass ends after this long without a PARAM_VALUE")
    ap.add_argument("--timeout", type=float, default=0.2,
                    help="per request, seconds (MAVSDK's mission server gives up an item "
                    "after 5 of its own sends and 0.5 s timeouts together: re-request sooner)")
    ap.add_argument("--tries", type=int, default=3)
    a = ap.parse_args()
    ids = [int(x) for x in a.ids.split("/")]
    link = Link(a.connection, ids[0], ids[1], tuple(int(x) for x in a.target.split("/")))
    if not a.no_heartbeat:
        link.mav.heartbeat_send(6, 8, 0, 0, 0)
    out = {}
    if a.params:
        out["params"] = params(link, a)
    if a.mission:
        out["mission"] = mission(link, a)
    if a.ftp:
        out["ftp"] = ftp(link, a)
    out["other"] = link.other
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
