#!/usr/bin/env python3
"""A pymavlink client of `mavping respond`'s transfers, for what MAVProxy
does not ask: a parameter read by name and by an unknown name or index,
a mission item past the end and a MISSION_ACK, a mission upload (which a
read-only server refuses), FTP's file-not-found, a second session while
one is open, a ReadFile past the end, a write, a ListDirectory, and a
BurstReadFile read to the end as a client would, reading each gap again
by ReadFile.

  respond_client.py PORT

It talks to udpout:127.0.0.1:PORT as 255/190 and prints one JSON line:
what each request drew (message names and their fields).
"""
import json
import struct
import sys
import time

from pymavlink import mavutil

TIMEOUT = 10.0


def conn(port):
    m = mavutil.mavlink_connection("udpout:127.0.0.1:%d" % port,
                                   source_system=255, source_component=190)
    m.mav.heartbeat_send(6, 8, 0, 0, 0)
    m.wait_heartbeat(timeout=TIMEOUT)
    return m


def replies(m, types, quiet=0.5):
    """Every message of `types` until none came for `quiet` seconds."""
    got = []
    end = time.time() + TIMEOUT
    last = time.time()
    while time.time() < end and time.time() - last < quiet:
        msg = m.recv_match(type=types, blocking=True, timeout=0.05)
        if msg is not None:
            got.append(msg)
            last = time.time()
    return got


def params(m):
    out = {}
    for name, index in [("by_name", (b"MAVPING_0042", -1)),
                        ("by_index", (b"", 41)),
                        ("unknown_name", (b"SYSID_THISMAV", -1)),
                        ("unknown_index", (b"", 30000))]:
        m.mav.param_request_read_send(1, 1, index[0], index[1])
        got = replies(m, ["PARAM_VALUE"])
        out[name] = [[p.param_id, p.param_value, p.param_type, p.param_index,
                      p.param_count] for p in got]
    return out


def mission(m):
    out = {}
    m.mav.mission_request_list_send(1, 1, 0)
    out["count"] = [c.count for c in replies(m, ["MISSION_COUNT"])]
    m.mav.mission_request_int_send(1, 1, 2, 0)
    out["item_2"] = [[i.seq, i.command, i.frame, i.x, i.y, i.z]
                     for i in replies(m, ["MISSION_ITEM_INT"])]
    m.mav.mission_request_int_send(1, 1, 500, 0)
    out["past_end"] = [a.type for a in replies(m, ["MISSION_ACK", "MISSION_ITEM_INT"])]
    m.mav.mission_ack_send(1, 1, 0, 0)
    m.mav.mission_request_list_send(1, 1, 1)
    out["fence_count"] = [c.count for c in replies(m, ["MISSION_COUNT"])]
    m.mav.mission_count_send(1, 1, 3, 0)
    out["upload"] = [a.type for a in replies(m, ["MISSION_ACK", "MISSION_REQUEST",
                                                 "MISSION_REQUEST_INT"])]
    return out


class Ftp:
    def __init__(self, m):
        self.m = m
        self.seq = 0

    def send(self, session, opcode, size=0, offset=0, data=b""):
        hdr = struct.pack("<HBBBBBBI", self.seq, session, opcode, size, 0, 0, 0, offset)
        self.seq = (self.seq + 1) % 65536
        payload = list(hdr + data) + [0] * (251 - 12 - len(data))
        self.m.mav.file_transfer_protocol_send(0, 1, 1, payload)

    def replies(self, quiet=0.5):
        out = []
        for msg in replies(self.m, ["FILE_TRANSFER_PROTOCOL"], quiet):
            p = bytes(msg.payload)
            seq, session, opcode, size, req, burst, _, offset = struct.unpack("<HBBBBBBI", p[:12])
            out.append({"seq": seq, "session": session, "opcode": opcode, "size": size,
                        "req": req, "burst_complete": burst, "offset": offset,
                        "data": list(p[12:12 + size])})
        return out

    def one(self, session, opcode, size=0, offset=0, data=b""):
        self.send(session, opcode, size, offset, data)
        got = self.replies()
        return [[r["opcode"], r["data"][:4] if r["opcode"] == 129 or r["size"] <= 4
                 else r["size"]] for r in got]


def ftp(m):
    f = Ftp(m)
    out = {}
    path = b"/mavping.bin"
    out["missing"] = f.one(3, 4, len(b"/nothing"), 0, b"/nothing")
    out["open"] = f.one(3, 4, len(path), 0, path)
    out["second_session"] = f.one(4, 4, len(path), 0, path)
    out["read_past_end"] = f.one(3, 5, 239, 10_000_000)
    out["write"] = f.one(3, 6, len(b"/x"), 0, b"/x")
    out["list"] = [bytes(r["data"]).decode() if r["opcode"] == 128 else r["opcode"]
                   for r in (f.send(3, 3, 1, 0, b"/") or f.replies())]
    # The whole file by bursts, each gap read again by ReadFile.
    data = {}
    offset = 0
    size = None
    bursts = 0
    while size is None:
        f.send(3, 15, 239, offset)
        bursts += 1
        got = f.replies()
        for r in got:
            if r["opcode"] == 128:
                data[r["offset"]] = bytes(r["data"])
                offset = max(offset, r["offset"] + r["size"])
            elif r["data"][:1] == [6]:
                size = r["offset"]
        if not got:
            break
    gaps = [o for o in range(0, size or 0, 239) if o not in data]
    for o in gaps:
        f.send(3, 5, 239, o)
        for r in f.replies():
            if r["opcode"] == 128:
                data[r["offset"]] = bytes(r["data"])
    blob = b"".join(data[o] for o in sorted(data))
    out["file"] = {"size": size, "bytes": len(blob), "bursts": bursts,
                   "gaps": len(gaps), "blob_hex_head": blob[:8].hex()}
    with open(sys.argv[2], "wb") as fh:
        fh.write(blob)
    out["terminate"] = f.one(3, 1)
    out["after_terminate"] = f.one(3, 5, 239, 0)
    return out


def main():
    m = conn(int(sys.argv[1]))
    result = {"params": params(m), "mission": mission(m), "ftp": ftp(m)}
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
