#!/usr/bin/env python3
"""A pinger that signs with pymavlink's own signing code and then replays
its captured requests, for mavping's signing tests (tests/it/signing.rs):
a replayed signed request must not be answered.

Prints "ready", sends --count signed PING requests (seq 0, 1, ...) --interval apart,
keeping each request's exact bytes as they went on the wire; then sends
the captured bytes of --replay seqs again, verbatim (a replay attack by
someone who recorded the link), and waits --linger seconds for replies.
Prints one JSON line: requests and replays sent, and the replies seen per
seq (each checked with pymavlink's signature check).
"""
import argparse
import json
import os
import sys
import time

from signed_peer import secret  # the key as signed_peer.py reads it


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpout:127.0.0.1:14550")
    ap.add_argument("--key", required=True)
    ap.add_argument("--link-id", type=int, default=2)
    ap.add_argument("--count", type=int, default=5)
    ap.add_argument("--interval", type=float, default=0.05)
    ap.add_argument("--replay", default="", help="seqs whose captured request is sent again")
    ap.add_argument("--linger", type=float, default=0.5)
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil  # imported after MAVLINK20 is set

    conn = mavutil.mavlink_connection(args.connection, source_system=250, source_component=190,
                                      dialect="common")
    conn.setup_signing(secret(args.key), sign_outgoing=True,
                       allow_unsigned_callback=lambda _mav, _msgid: False, link_id=args.link_id)
    mav = conn.mav
    print("ready", flush=True)
    captured = {}
    replies = {}

    def drain(until):
        while True:
            left = until - time.monotonic()
            if left <= 0:
                return
            msg = conn.recv_match(type="PING", blocking=True, timeout=left)
            if msg is None:
                continue
            if msg.target_system == 250 and msg.target_component == 190:
                replies[msg.seq] = replies.get(msg.seq, 0) + 1

    for seq in range(args.count):
        data = mav.ping_encode(int(time.time() * 1e6), seq, 0, 0).pack(mav)
        conn.write(data)
        mav.seq = (mav.seq + 1) % 256
        captured[seq] = data
        drain(time.monotonic() + args.interval)
    replayed = 0
    for seq in (int(x) for x in args.replay.split(",") if x.strip()):
        conn.write(captured[seq])
        replayed += 1
        drain(time.monotonic() + args.interval)
    drain(time.monotonic() + args.linger)
    print(json.dumps({"requests": args.count, "replayed": replayed,
                      "replies": {str(k): v for k, v in sorted(replies.items())}}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
