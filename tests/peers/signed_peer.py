#!/usr/bin/env python3
"""A MAVLink 2 responder that signs with pymavlink's own signing code, for
mavping's signing tests (tests/signing.rs).

With --key it signs every reply and checks every request with pymavlink's
signature check; unsigned requests are refused (allow_unsigned_callback
answers no) unless --allow-unsigned. Chosen PING seqs can be answered in
ways a signing peer must refuse:
  --forge SEQS    reply signed with another key (a forger without the key)
  --unsigned SEQS reply not signed at all
  --replay SEQS   reply sent, then its exact bytes sent again (a replay)
Sends no HEARTBEAT unless --heartbeat-hz, so a pinger's counts are exact.
It acknowledges COMMAND_LONG addressed to it (MAV_RESULT_ACCEPTED), once
pymavlink's check has accepted the frame.

--clock-offset SECONDS shifts its signing clock: every frame it signs is
stamped at least the wall clock plus SECONDS (a vehicle whose clock is
ahead, or behind when negative), so its clock runs at the wall clock's
rate. pymavlink's own check then refuses a new stream of ours more than a
minute behind that clock, as MAVLink 2 signing says; its truth has the
last signature timestamp it sent ("last_timestamp", 10 µs units since
2015; with --stamps every one, "stamps") and the refused COMMAND_LONGs
("rejected_commands").
Prints one JSON line of ground truth on exit (SIGTERM/SIGINT).
"""
import argparse
import hashlib
import json
import os
import signal
import sys
import time


EPOCH_2015 = 1420070400


def secret(text):
    """64 hex characters are the key; anything else is a passphrase hashed
    as MAVProxy's `signing setup` does."""
    if len(text) == 64:
        try:
            return bytes.fromhex(text)
        except ValueError:
            pass
    return hashlib.sha256(text.encode()).digest()


def parse_set(text):
    return {int(x) for x in text.split(",") if x.strip()} if text else set()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550")
    ap.add_argument("--key", required=True, help="signing key: 64 hex characters or a passphrase")
    ap.add_argument("--link-id", type=int, default=3)
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--allow-unsigned", action="store_true",
                    help="accept requests whatever their signature (checks nothing)")
    ap.add_argument("--forge", default="", help="PING seqs answered signed with a wrong key")
    ap.add_argument("--unsigned", default="", help="PING seqs answered unsigned")
    ap.add_argument("--replay", default="", help="PING seqs whose signed reply is sent twice")
    ap.add_argument("--heartbeat-hz", type=float, default=0.0)
    ap.add_argument("--stamps", action="store_true",
                    help="list every signature timestamp sent in the truth")
    ap.add_argument("--clock-offset", type=float, default=0.0,
                    help="seconds added to the wall clock its signatures are stamped by")
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil  # imported after MAVLINK20 is set

    conn = mavutil.mavlink_connection(
        args.connection,
        source_system=args.sysid,
        source_component=args.compid,
        dialect="common",
    )
    key = secret(args.key)
    wrong_key = hashlib.sha256(b"not the key").digest()
    def clock_now():
        """The shifted wall clock, as a signing timestamp."""
        return int((time.time() + args.clock_offset - EPOCH_2015) * 100_000)

    conn.setup_signing(
        key,
        sign_outgoing=True,
        allow_unsigned_callback=lambda _mav, _msgid: args.allow_unsigned,
        initial_timestamp=clock_now(),
        link_id=args.link_id,
    )
    mav = conn.mav
    forge, unsigned, replay = parse_set(args.forge), parse_set(args.unsigned), parse_set(args.replay)
    truth = {"ping_requests": 0, "replies": 0, "forged": 0, "unsigned": 0, "replayed": 0,
             "rejected_frames": 0, "rejected_pings": 0, "rejected_commands": 0, "commands": 0,
             "acks": 0, "last_timestamp": None}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def write(reply):
        # pymavlink adds one unit a frame and otherwise stands still: a
        # vehicle's clock runs on.
        mav.signing.timestamp = max(mav.signing.timestamp, clock_now())
        data = reply.pack(mav)
        if mav.signing.sign_outgoing:
            truth["last_timestamp"] = mav.signing.timestamp - 1
            if args.stamps:
                truth.setdefault("stamps", []).append(truth["last_timestamp"])
        conn.write(data)
        mav.seq = (mav.seq + 1) % 256
        return data

    print("ready", flush=True)
    next_hb = time.monotonic()
    while running:
        now = time.monotonic()
        if args.heartbeat_hz > 0 and now >= next_hb:
            write(mav.heartbeat_encode(mavutil.mavlink.MAV_TYPE_QUADROTOR, 12, 0, 0, 0))
            next_hb = now + 1.0 / args.heartbeat_hz
        msg = conn.recv_match(blocking=True, timeout=0.02)
        if msg is None:
            continue
        if msg.get_type() == "BAD_DATA":
            # pymavlink refused it: bad or missing signature, or a replay.
            if "signature" in str(getattr(msg, "reason", "")):
                truth["rejected_frames"] += 1
                data = bytes(msg.data)
                if len(data) > 9 and data[0] == 0xFD and data[7] == 4:
                    truth["rejected_pings"] += 1
                if len(data) > 9 and data[0] == 0xFD and data[7] == 76:
                    truth["rejected_commands"] += 1
            continue
        if msg.get_type() == "COMMAND_LONG" and msg.target_system == args.sysid:
            truth["commands"] += 1
            write(mav.command_ack_encode(msg.command, mavutil.mavlink.MAV_RESULT_ACCEPTED, 0, 0,
                                         msg.get_srcSystem(), msg.get_srcComponent()))
            truth["acks"] += 1
            continue
        if msg.get_type() != "PING" or msg.target_system != 0 or msg.target_component != 0:
            continue
        truth["ping_requests"] += 1
        seq = msg.seq
        reply = mav.ping_encode(msg.time_usec, seq, msg.get_srcSystem(), msg.get_srcComponent())
        if seq in forge:
            mav.signing.secret_key = wrong_key
            write(reply)
            mav.signing.secret_key = key
            truth["forged"] += 1
        elif seq in unsigned:
            mav.signing.sign_outgoing = False
            write(reply)
            mav.signing.sign_outgoing = True
            truth["unsigned"] += 1
        else:
            data = write(reply)
            truth["replies"] += 1
            if seq in replay:
                conn.write(data)
                truth["replayed"] += 1
    truth["sig_count"] = mav.signing.sig_count
    truth["badsig_count"] = mav.signing.badsig_count
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
