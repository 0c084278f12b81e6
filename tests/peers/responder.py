#!/usr/bin/env python3
"""A MAVLink responder written with pymavlink: the third-party peer that
mavping's integration tests measure against.

It answers PING requests (targets 0/0) as PX4 does, and can drop or
duplicate chosen sequence numbers, send junk datagrams or corrupt frames,
or behave like ArduPilot (HEARTBEAT and TIMESYNC only, no PING).
With --radio-status it also plays a telemetry radio injecting RADIO_STATUS
into the same stream from its own ids (SiK: 51/68), one report from the
schedule before each reply, so every report reaches the pinger before the
reply that follows it.
Prints one JSON line of ground truth on exit (SIGTERM/SIGINT or --count).
"""
import argparse
import json
import os
import random
import select
import signal
import socket
import sys
import time


class Udp6In:
    """pymavlink has no IPv6 sockets: this gives its MAVLink encoder and
    parser one, answering the last peer heard as pymavlink's udpin does."""

    def __init__(self, host, port, mavlink, sysid, compid):
        self.sock = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)
        self.sock.bind((host, port))
        self.peer = None
        self.pending = []
        self.mav = mavlink.MAVLink(self, srcSystem=sysid, srcComponent=compid)

    def write(self, data):
        if self.peer is not None:
            self.sock.sendto(data, self.peer)

    def recv_match(self, blocking=True, timeout=None):
        if not self.pending:
            ready, _, _ = select.select([self.sock], [], [], timeout)
            if not ready:
                return None
            data, self.peer = self.sock.recvfrom(65535)
            self.pending = self.mav.parse_buffer(data) or []
        return self.pending.pop(0) if self.pending else None


def parse_set(text):
    return {int(x) for x in text.split(",") if x.strip()} if text else set()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpout:127.0.0.1:14550, "
                    "tcpin:127.0.0.1:5760, /dev/pts/3; or udpin:[::1]:PORT (IPv6)")
    ap.add_argument("--sysid", type=int, default=1)
    ap.add_argument("--compid", type=int, default=1)
    ap.add_argument("--mavlink1", action="store_true", help="reply in MAVLink 1")
    ap.add_argument("--drop", default="", help="PING seqs not to answer, e.g. 2,5")
    ap.add_argument("--dup", default="", help="PING seqs to answer twice")
    ap.add_argument("--drop-every", type=int, default=0,
                    help="also drop every PING whose seq is a multiple of N (long soaks)")
    ap.add_argument("--dup-every", type=int, default=0,
                    help="also answer twice every PING whose seq is 1 more than a multiple of N")
    ap.add_argument("--delay-ms", type=float, default=0.0, help="delay every reply")
    ap.add_argument("--junk-before", default="", help="PING seqs whose reply is preceded by junk")
    ap.add_argument("--bad-crc", default="", help="PING seqs answered with a corrupted frame only")
    ap.add_argument("--no-ping", action="store_true", help="like ArduPilot: never answer PING")
    ap.add_argument("--autopilot", type=int, default=12, help="MAV_AUTOPILOT in HEARTBEAT (12 PX4, 3 ArduPilot)")
    ap.add_argument("--heartbeat-hz", type=float, default=10.0)
    ap.add_argument("--baud", type=int, default=57600)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--radio-status", default="",
                    help="RADIO_STATUS schedule, one report per PING request: "
                    "'rssi,remrssi,txbuf,noise,remnoise,rxerrors,fixed;...'")
    ap.add_argument("--radio-id", default="51/68", help="sysid/compid the radio sends as")
    args = ap.parse_args()

    if not args.mavlink1:
        os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil  # imported after MAVLINK20 is set

    rng = random.Random(args.seed)
    if args.connection.startswith("udpin:["):
        host, port = args.connection[len("udpin:["):].split("]:")
        mavutil.set_dialect("common")
        conn = Udp6In(host, int(port), mavutil.mavlink, args.sysid, args.compid)
    else:
        conn = mavutil.mavlink_connection(
            args.connection,
            source_system=args.sysid,
            source_component=args.compid,
            baud=args.baud,
            dialect="common",
        )
    mav = conn.mav
    radio_schedule = [tuple(int(v) for v in r.split(",")) for r in args.radio_status.split(";") if r]
    radio = None
    if radio_schedule:
        rsys, rcomp = (int(v) for v in args.radio_id.split("/"))
        # A second encoder on the same link: the radio's frames share the
        # stream (and its order) with the autopilot's, as on a real radio.
        radio = mavutil.mavlink.MAVLink(conn, srcSystem=rsys, srcComponent=rcomp)
    drop, dup = parse_set(args.drop), parse_set(args.dup)
    junk_before, bad_crc = parse_set(args.junk_before), parse_set(args.bad_crc)
    truth = {"ping_requests": 0, "replies": 0, "dropped": 0, "duplicated": 0,
             "junk": 0, "junk_bytes": 0, "bad_crc": 0, "radio_status": 0}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def heartbeat():
        mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_QUADROTOR, args.autopilot, 0, 0, 0)

    def write_raw(data):
        conn.write(data)

    heartbeat()
    print("ready", flush=True)
    next_hb = time.monotonic()
    while running:
        now = time.monotonic()
        if now >= next_hb:
            heartbeat()
            next_hb = now + 1.0 / args.heartbeat_hz
        try:
            msg = conn.recv_match(blocking=True, timeout=0.02)
        except Exception as e:  # the link under test went away (pty closed)
            print(f"responder: link lost: {e}", file=sys.stderr)
            break
        if msg is None:
            continue
        if msg.get_type() != "PING" or args.no_ping:
            continue
        if msg.target_system != 0 or msg.target_component != 0:
            continue  # a reply to someone else, not a request
        truth["ping_requests"] += 1
        seq = msg.seq
        if radio is not None and truth["radio_status"] < len(radio_schedule):
            radio.radio_status_send(*radio_schedule[truth["radio_status"]])
            truth["radio_status"] += 1
        if seq in drop or (args.drop_every and seq % args.drop_every == 0):
            truth["dropped"] += 1
            continue
        if args.delay_ms:
            time.sleep(args.delay_ms / 1000.0)
        src_sys, src_comp = msg.get_srcSystem(), msg.get_srcComponent()
        reply = mav.ping_encode(msg.time_usec, seq, src_sys, src_comp)
        if seq in junk_before:
            junk = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 60)))
            write_raw(junk)
            truth["junk"] += 1
            truth["junk_bytes"] += len(junk)
        if seq in bad_crc:
            data = bytearray(reply.pack(mav))
            data[-1] ^= 0xFF
            write_raw(bytes(data))
            truth["bad_crc"] += 1
            continue
        mav.send(reply)
        truth["replies"] += 1
        if seq in dup or (args.dup_every and seq % args.dup_every == 1):
            mav.send(mav.ping_encode(msg.time_usec, seq, src_sys, src_comp))
            truth["duplicated"] += 1
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
