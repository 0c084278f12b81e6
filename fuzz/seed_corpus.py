#!/usr/bin/env python3
"""Writes the committed seed corpus for the fuzz targets: real MAVLink v1,
v2 and signed frames made by pymavlink (the third-party encoder), alone,
back to back, behind junk and truncated. Run with the venv's python:
    .venv/bin/python fuzz/seed_corpus.py
"""
import os
import struct

from pymavlink.dialects.v20 import ardupilotmega as mav2
from pymavlink.dialects.v10 import ardupilotmega as mav1

HERE = os.path.dirname(os.path.abspath(__file__))


class Sink:
    def write(self, _b):
        pass


def encoder(v1=False, sysid=1, compid=1, key=None):
    m = (mav1 if v1 else mav2).MAVLink(Sink(), srcSystem=sysid, srcComponent=compid)
    if key is not None:
        m.signing.secret_key = key
        m.signing.link_id = 1
        m.signing.timestamp = 1_000_000
        m.signing.sign_outgoing = True
    return m


def frames():
    v1 = encoder(v1=True)
    v2 = encoder()
    signed = encoder(key=bytes(range(32)))
    out = {}
    out["v1_ping"] = v1.ping_encode(123456, 7, 255, 190).pack(v1)
    out["v2_ping"] = v2.ping_encode(123456, 7, 255, 190).pack(v2)
    out["v2_timesync"] = v2.timesync_encode(555, 999).pack(v2)
    out["v2_heartbeat"] = v2.heartbeat_encode(2, 12, 0, 0, 4).pack(v2)
    out["v2_signed_ping"] = signed.ping_encode(42, 8, 255, 190).pack(signed)
    out["v2_signed_heartbeat"] = signed.heartbeat_encode(2, 3, 0, 0, 4).pack(signed)
    out["v2_command_ack"] = v2.command_ack_encode(512, 0).pack(v2)
    out["v2_radio_status"] = v2.radio_status_encode(200, 190, 90, 40, 40, 3, 0).pack(v2)
    return out


def main():
    f = frames()
    seeds = dict(f)
    seeds["mixed"] = f["v1_ping"] + f["v2_ping"] + f["v2_signed_ping"] + f["v2_timesync"]
    seeds["junk_then_frames"] = b"\x00\xfe\x33\xfd\x01junk" + f["v2_ping"] + b"\xfe" + f["v1_ping"]
    seeds["truncated_then_frame"] = f["v2_heartbeat"][:9] + f["v2_ping"]
    bad = bytearray(f["v2_ping"])
    bad[-1] ^= 0xFF
    seeds["bad_crc_then_frame"] = bytes(bad) + f["v1_ping"]
    # An unknown message id (0xEEEEEE) lined up with a real frame.
    seeds["unknown_id"] = bytes([0xFD, 2, 0, 0, 0, 1, 1, 0xEE, 0xEE, 0xEE, 0xAA, 0xBB, 0, 0]) + f["v2_ping"]
    # A length that lies: claims 255 bytes, a real frame follows.
    seeds["lying_length"] = bytes([0xFE, 255, 0, 1, 1, 4]) + f["v2_ping"] * 3
    os.makedirs(os.path.join(HERE, "seeds/scanner"), exist_ok=True)
    for name, data in seeds.items():
        # The target reads a split count and split sizes first.
        for splits in (b"\x00", b"\x03\x04\x00\x10"):
            tag = "whole" if splits == b"\x00" else "split"
            with open(os.path.join(HERE, "seeds/scanner", f"{name}_{tag}"), "wb") as fh:
                fh.write(splits + data)
    # Matcher: timeout, capacity, first-seq byte, then (op, arg) pairs.
    os.makedirs(os.path.join(HERE, "seeds/matcher"), exist_ok=True)
    ops = {
        "send_reply_expire": bytes([10, 16, 4]) + bytes([0x10, 0, 0x11, 0, 0x11, 0, 0x13, 0]),
        "dup_late_stale": bytes([1, 8, 2]) + bytes([0x00, 0, 0x01, 1, 0x01, 1, 0xF3, 0, 0x01, 1, 0x09, 2, 0x01, 0xFC]),
        "overfull_ring": bytes([200, 2, 9]) + bytes([0x10, 0] * 10 + [0x11, 0x04, 0x12, 0x09]),
    }
    for name, data in ops.items():
        with open(os.path.join(HERE, "seeds/matcher", name), "wb") as fh:
            fh.write(data)
    print(f"{len(seeds) * 2} scanner seeds, {len(ops)} matcher seeds")


if __name__ == "__main__":
    main()
