#!/usr/bin/env python3
"""Writes a telemetry log with pymavlink (its `mavlogfile`, opened with
`mavutil.mavlink_connection(PATH, write=True)`), frames packed by
pymavlink's own encoder, with faults planned frame by frame, and prints
one JSON line of ground truth. For mavping's `tlog:` tests.

    tlog_writer.py OUT.tlog PLAN_JSON

The plan:
  start_us     the first stamp (µs since the Unix epoch)
  stamps       "us" (a clock's µs), "ms" (QGroundControl: ms x 1000),
               "pymavlink" (usec & ~3), "mavproxy" ((usec & ~3) | link)
  sources      each: sysid, compid, rate (ATTITUDE per second; a
               HEARTBEAT each second besides), frames (numbered), version
               (1 or 2), signed (MAVLink 2 signing), phase_us, and faults
               by frame number (the n-th frame it numbers, from 0):
                 drop [n...]      numbered, never written (a gap)
                 dup [n...]       written twice
                 swap [n...]      held back, written after frame n+1
                 silence [[n,k]]  after frame n, k frames numbered and
                                  none written, in their time (a silence)
               clock {"offset_ms", "ppm"}: ATTITUDE's time_boot_ms off
                 the plan's time; queue {"start_us", "rise_us", "peak_us"}:
                 each frame written that much after it was sent, growing
                 to the peak over the rise and draining as fast
               links (mavproxy stamps): {"LINK": {"drop": [n...],
                 "delay_us": d}}: the frame is written once per link,
                 less that link's drops; plain: true stamps the source's
                 frames with a clock's µs (MAVProxy logs what its outputs
                 send so), whatever the plan's stamps
  exchanges    each: kind ("timesync", "ping", "command"), requester and
               responder [sysid, compid], count requests period_us apart
               from phase_us, each answered rtt_us + rtt_step_us * (k % 10)
               after it (link: [request link, reply link] for mavproxy
               stamps), command (its id), and by request number k:
                 drop [k...]      never answered (unanswered)
                 dup [k...]       answered twice, 1 ms apart
                 late [k...]      answered after late_us (unanswered, late)
                 retransmit {k: n} (commands) sent n more times retry_us
                                  apart (confirmation 1..n), answered
                                  after the last
                 orphan [k...]    the reply written, the request not
               The truth per exchange: its exact counts and every RTT.
               position: {"every": k, "lat0", "lon0", "alt0_m",
                 "north_mps", "climb_mps", "message": "global" or "gps"}:
                 every k-th frame (not a HEARTBEAT) is a GLOBAL_POSITION_INT
                 (or GPS_RAW_INT, 3D fix) of a vehicle moving north and up
                 at those speeds from (lat0, lon0, alt0_m); "home_frame": n
                 makes frame n a HOME_POSITION at (lat0, lon0, alt0_m)
               link_node: {"every": k, "received0", "received_step",
                 "lost0", "lost_step", "parse0", "parse_step", "reboot_at": m}:
                 every k-th frame (not a HEARTBEAT) is a LINK_NODE_STATUS, the
                 m-th (from 0) with messages_received received0 + m x step
                 (mod 2^32; lost likewise; rx_parse_err mod 2^16), its boot
                 clock 3,600,000 ms + m s; from report reboot_at on the node
                 has rebooted: its clock 700 ms + (m - reboot_at) s, each
                 counter (m - reboot_at + 1) x step (messages_sent: 40 a
                 report). The truth: the reports
                 written, and what each counter grew by between the first
                 and the last written (after a reboot its new value counts)
               radio: {"rxerrors0": e, "rxerrors_step": d}: the source is a
                 radio: every frame a RADIO_STATUS, rssi 200 less
                 rssi_drop_per_s (default 1) a second, rxerrors e + d per report (mod 65536), no HEARTBEAT;
                 or with "figures": {rssi, remrssi, noise, remnoise[, txbuf]}
                 those figures, and "spans": [{from_us, to_us, figures...}]
                 others from from_us to to_us (a radio losing its link, or
                 hearing interference, while the vehicle is silent); every
                 report written is in the truth's "reports" as
                 [t_us, rssi, remrssi, noise, remnoise]
  window_us    per window of this many µs of the frames' time (the first
               frame at 0): numbered and written frames, the last written
               position's true distance, the radio's reports and rxerrors
               growth, in the truth's "windows" (distances from the first
               position written, its (north_m, up_m) in "first_fix")
  junk         [[r, hex]]: those bytes after the r-th record written
  cut          bytes cut off the end (a last record cut short)

Stamps are arrival times: a swapped frame is stamped after the frame it
follows, a duplicate 1 ms after its first copy. The truth per source (and
per link) counts what was numbered and what was written.
"""
import heapq
import json
import math
import os
import random
import struct
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

import link_node  # noqa: E402

mavlink = mavutil.mavlink


EARTH_RADIUS_M = 6371008.8


def position_msg(mav, pos, t):
    """The vehicle's position at t µs, and (north_m, up_m) from its start."""
    north = pos.get("north_mps", 0) * t / 1e6
    up = pos.get("climb_mps", 0) * t / 1e6
    lat = int(round((pos["lat0"] + math.degrees(north / EARTH_RADIUS_M)) * 1e7))
    lon = int(round(pos["lon0"] * 1e7))
    alt = int(round((pos["alt0_m"] + up) * 1000))
    if pos.get("message") == "gps":
        msg = mav.gps_raw_int_encode(int(t), 3, lat, lon, alt, 100, 100, 0, 0, 10)
    else:
        msg = mav.global_position_int_encode(int(t / 1000), lat, lon, alt, int(up * 1000),
                                             0, 0, 0, 0)
    return msg, (north, up)


def radio_msg(mav, radio, t, n):
    """A report at t µs, its rxerrors, and (planned figures) the figures."""
    rxerrors = (radio.get("rxerrors0", 0) + n * radio.get("rxerrors_step", 0)) % 65536
    if "figures" in radio:
        f = dict(radio["figures"])
        for span in radio.get("spans", []):
            if span["from_us"] <= t < span["to_us"]:
                f.update({k: v for k, v in span.items() if k not in ("from_us", "to_us")})
        msg = mav.radio_status_encode(f["rssi"], f["remrssi"], f.get("txbuf", 80), f["noise"],
                                      f["remnoise"], rxerrors, 0)
        return msg, rxerrors, [int(t), f["rssi"], f["remrssi"], f["noise"], f["remnoise"]]
    rssi = max(0, 200 - int(radio.get("rssi_drop_per_s", 1) * t / 1e6))
    return mav.radio_status_encode(rssi, 190, 80, 40, 41, rxerrors, 0), rxerrors, None


def link_node_msg(mav, spec, m):
    """The m-th LINK_NODE_STATUS of a node planned by `spec`."""
    reboot = spec.get("reboot_at")
    if reboot is not None and m >= reboot:
        since = m - reboot + 1
        t_ms = 700 + (m - reboot) * 1000
        received, lost, parse = (since * spec.get(k, 0) for k in
                                 ("received_step", "lost_step", "parse_step"))
        sent = since * 40
    else:
        t_ms = 3_600_000 + m * 1000
        received = spec.get("received0", 0) + m * spec.get("received_step", 0)
        lost = spec.get("lost0", 0) + m * spec.get("lost_step", 0)
        parse = spec.get("parse0", 0) + m * spec.get("parse_step", 0)
        sent = m * 40
    cls = link_node.install(mavlink)
    return cls(timestamp=t_ms, tx_buf=90, rx_buf=100, tx_rate=1200, rx_rate=640,
               rx_parse_err=parse % 2**16, messages_sent=sent,
               messages_received=received % 2**32, messages_lost=lost % 2**32)


def link_node_truth(spec, written):
    """What each counter grew by between the first and last report
    written: per pair of reports written in turn, the steps between them,
    or after a reboot between them the counter's new value."""
    reboot = spec.get("reboot_at")
    grown = {"received": 0, "lost": 0, "parse": 0}
    reboots = 0
    for a, b in zip(written, written[1:]):
        periods = b - a
        if reboot is not None and a < reboot <= b:
            periods = b - reboot + 1
            reboots += 1
        for k in grown:
            grown[k] += periods * spec.get(k + "_step", 0)
    return {"written": written, "reboots": reboots, **{k + "_grown": v for k, v in grown.items()}}


def boot_ms(src, t):
    """ATTITUDE's time_boot_ms of a frame sent at `t` (µs of the plan):
    the vehicle's clock, `clock: {"offset_ms", "ppm"}` off ours."""
    clock = src.get("clock", {})
    ms = t * (1 + clock.get("ppm", 0) * 1e-6) / 1000 + clock.get("offset_ms", 0)
    return int(ms) % 2**32


def queued_us(src, t):
    """How late a frame sent at `t` reaches the log: `queue: {"start_us",
    "rise_us", "peak_us"}` grows from 0 to its peak over its rise from its
    start, then drains as fast (the truth an age is held to)."""
    q = src.get("queue")
    if q is None or t <= q["start_us"]:
        return 0
    x = (t - q["start_us"]) / q["rise_us"]
    return q["peak_us"] * (x if x <= 1 else max(0.0, 2 - x))


def frames_of(src, mav):
    """(time_us, frame number, bytes, facts) of every frame the source
    numbers; facts: a position's (north_m, up_m) or a report's rxerrors."""
    period = 1e6 / src["rate"]
    t = src.get("phase_us", 0)
    next_hb = t
    n = 0
    pos = src.get("position")
    radio = src.get("radio")
    node = src.get("link_node")
    reports = 0
    while n < src["frames"]:
        facts = None
        if radio is not None:
            msg, rxerrors, figures = radio_msg(mav, radio, t, n)
            facts = {"rxerrors": rxerrors, "figures": figures}
        elif node is not None and n % node["every"] == 0:
            msg = link_node_msg(mav, node, reports)
            facts = {"link_node": reports}
            reports += 1
        elif t >= next_hb:
            msg = mav.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR,
                                       mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
            next_hb += 1e6
        elif pos is not None and n == pos.get("home_frame"):
            msg = mav.home_position_encode(int(round(pos["lat0"] * 1e7)),
                                           int(round(pos["lon0"] * 1e7)),
                                           int(round(pos["alt0_m"] * 1000)),
                                           0, 0, 0, [1, 0, 0, 0], 0, 0, 0)
            facts = {"home": True}
        elif pos is not None and n % pos["every"] == 0:
            msg, (north, up) = position_msg(mav, pos, t)
            facts = {"north_m": north, "up_m": up}
        else:
            msg = mav.attitude_encode(boot_ms(src, t), 0.1, 0.2, 0.3, 0.01, 0.02, 0.03)
        data = msg.pack(mav, force_mavlink1=src.get("version", 2) == 1)
        mav.seq = (mav.seq + 1) % 256
        yield int(t + queued_us(src, t)), n, bytes(data), facts
        n += 1
        t += period


def mav_for(src):
    mav = mavlink.MAVLink(None, srcSystem=src["sysid"], srcComponent=src["compid"])
    if src.get("signed"):
        mav.signing.secret_key = bytes(range(32))
        mav.signing.link_id = 1
        mav.signing.timestamp = 1
        mav.signing.sign_outgoing = True
    return mav


def window_truth(truth, window_us, t):
    """The truth of the window at t µs, made on first use."""
    windows = truth.setdefault("windows", {})
    return windows.setdefault(str(int(t // window_us)), {
        "numbered": 0, "written": 0, "distance_m": None, "ground_m": None,
        "reports": 0, "rxerrors_last": None})


def plan_source(src, out, truth_of, window_us=None):
    """Puts the source's writes on `out`: (time_us, order, link, bytes)."""
    drop = set(src.get("drop", []))
    dup = set(src.get("dup", []))
    swap = set(src.get("swap", []))
    silences = {n: k for n, k in src.get("silence", [])}
    links = src.get("links") or {"0": {}}
    truth = truth_of(src)
    held = None
    skip_until = -1
    for t, n, data, facts in frames_of(src, mav_for(src)):
        truth["numbered"] += 1
        win = window_truth(truth, window_us, t) if window_us else {}
        win["numbered"] = win.get("numbered", 0) + 1
        if n <= skip_until:
            truth["silenced"] += 1
            continue
        if n in silences:
            skip_until = n + silences[n]
        last = n == src["frames"] - 1
        if n in drop and not last:
            truth["dropped"] += 1
            continue
        if n in swap and not last:
            held = (n, data)
            truth["swapped"] += 1
            continue
        if facts and "link_node" in facts:
            truth.setdefault("link_node_written", []).append(facts["link_node"])
        if facts and facts.get("figures") is not None:
            truth.setdefault("reports", []).append(facts["figures"])
        if window_us:
            win["written"] += 1
            if facts and "home" in facts:
                truth["first_fix"] = (0.0, 0.0)
                truth["home"] = True
            if facts and "north_m" in facts:
                # From the first position written (or home, from when it
                # is written), as a ground station has it.
                n0, u0 = truth.setdefault("first_fix", (facts["north_m"], facts["up_m"]))
                win["ground_m"] = facts["north_m"] - n0
                win["distance_m"] = math.hypot(facts["north_m"] - n0, facts["up_m"] - u0)
            if facts and "rxerrors" in facts:
                win["reports"] += 1
                win["rxerrors_last"] = facts["rxerrors"]
        writes = [(t, n, data)]
        if n in dup:
            writes.append((t + 1000, n, data))
            truth["duplicated"] += 1
        if held is not None:
            writes.append((t + 500, held[0], held[1]))
            held = None
        for link, spec in links.items():
            lt = truth["links"].setdefault(link, {"written": 0, "dropped": 0})
            for wt, wn, wdata in writes:
                if wn in set(spec.get("drop", [])):
                    lt["dropped"] += 1
                    continue
                lt["written"] += 1
                out.append((wt + spec.get("delay_us", 0), int(link), src, wdata))
        truth["written"] += len(writes)


def plan_exchange(ex, out, mavs):
    """Puts an exchange's requests and replies on `out`; its truth."""
    req_id, resp_id = tuple(ex["requester"]), tuple(ex["responder"])
    for ids in (req_id, resp_id):
        if ids not in mavs:
            mavs[ids] = mavlink.MAVLink(None, srcSystem=ids[0], srcComponent=ids[1])
    req, resp = mavs[req_id], mavs[resp_id]
    kind = ex["kind"]
    req_link, reply_link = ex.get("link", [0, 0])
    drop, dup, late = (set(ex.get(k, [])) for k in ("drop", "dup", "late"))
    orphan = set(ex.get("orphan", []))
    retransmit = {int(k): n for k, n in ex.get("retransmit", {}).items()}
    truth = {"kind": kind, "requester": "%d/%d" % req_id, "responder": "%d/%d" % resp_id,
             "requests": 0, "repeats": 0, "matched": 0, "after_retransmission": 0,
             "unanswered": 0, "late": 0, "duplicate": 0, "no_request": 0, "rtts_us": []}

    def emit(mav, msg, t, link):
        # Packed when written, so each system numbers its frames in time
        # order.
        out.append((int(t), link, None, (mav, msg)))

    for k in range(ex["count"]):
        t = ex.get("phase_us", 0) + k * ex["period_us"]
        ts1 = 1_700_000_000_000_000_000 + t * 1000 + k
        attempts = 1 + retransmit.get(k, 0)
        if k not in orphan:
            truth["requests"] += 1
            for i in range(attempts):
                at = t + i * ex.get("retry_us", 1_000_000)
                if kind == "timesync":
                    msg = req.timesync_encode(0, ts1)
                elif kind == "ping":
                    msg = req.ping_encode(1_000_000 + t, k, 0, 0)
                else:
                    msg = req.command_long_encode(resp_id[0], resp_id[1], ex["command"], i,
                                                  0, 0, 0, 0, 0, 0, 0)
                emit(req, msg, at, req_link)
            truth["repeats"] += attempts - 1
        last = t + (attempts - 1) * ex.get("retry_us", 1_000_000)
        if k in drop:
            truth["unanswered"] += 1
            continue
        rtt = ex["late_us"] if k in late else ex["rtt_us"] + ex.get("rtt_step_us", 0) * (k % 10)
        if kind == "timesync":
            msg = resp.timesync_encode(123_456 + k, ts1)
        elif kind == "ping":
            msg = resp.ping_encode(1_000_000 + t, k, req_id[0], req_id[1])
        else:
            msg = resp.command_ack_encode(ex["command"], 0, 0, 0, req_id[0], req_id[1])
        copies = 2 if k in dup else 1
        for c in range(copies):
            emit(resp, msg, last + rtt + c * 1000, reply_link)
        if k in orphan:
            truth["no_request"] += copies
        elif k in late:
            truth["unanswered"] += 1
            truth["late"] += copies
        else:
            truth["matched"] += 1
            truth["duplicate"] += copies - 1
            truth["after_retransmission"] += attempts > 1
            truth["rtts_us"].append(rtt)
    return truth


def stamp(plan, src, t_us, link, rng):
    us = plan["start_us"] + t_us
    kind = plan.get("stamps", "us")
    if src is not None and src.get("plain"):
        return us | rng.randrange(4)
    if kind == "ms":
        return (us // 1000) * 1000
    if kind == "pymavlink":
        return us & ~3
    if kind == "mavproxy":
        return (us & ~3) | link
    return us


def main():
    path, plan = sys.argv[1], json.loads(sys.argv[2])
    rng = random.Random(7)
    truths = {}

    def truth_of(src):
        key = "%d/%d" % (src["sysid"], src["compid"])
        return truths.setdefault(key, {"numbered": 0, "written": 0, "dropped": 0,
                                       "duplicated": 0, "swapped": 0, "silenced": 0,
                                       "links": {}})

    writes = []
    for src in plan.get("sources", []):
        plan_source(src, writes, truth_of, plan.get("window_us"))
        if "link_node" in src:
            truth = truth_of(src)
            truth["link_node"] = link_node_truth(src["link_node"],
                                                 truth.pop("link_node_written", []))
    mavs = {}
    exchanges = [plan_exchange(ex, writes, mavs) for ex in plan.get("exchanges", [])]
    # In time order; equal times in the order planned.
    order = [(t, i, link, src, data) for i, (t, link, src, data) in enumerate(writes)]
    heapq.heapify(order)
    junk = {r: bytes.fromhex(h) for r, h in plan.get("junk", [])}
    # pymavlink's log writer needs the file to exist to take it for a log.
    open(path, "wb").close()
    log = mavutil.mavlink_connection(path, write=True)
    records = 0
    junk_bytes = 0
    size = 0
    last_len = 0
    while order:
        t, _, link, src, data = heapq.heappop(order)
        if isinstance(data, tuple):
            mav, msg = data
            data = bytes(msg.pack(mav))
            mav.seq = (mav.seq + 1) % 256
        record = struct.pack(">Q", stamp(plan, src, t, link, rng)) + data
        log.write(record)
        size += len(record)
        last_len = len(record)
        records += 1
        if records in junk:
            log.write(junk[records])
            junk_bytes += len(junk[records])
            size += len(junk[records])
    log.close()
    cut = plan.get("cut", 0)
    if cut:
        with open(path, "r+b") as f:
            f.truncate(size - cut)
    print(json.dumps({"sources": truths, "exchanges": exchanges, "records": records, "junk_bytes": junk_bytes,
                      "cut": cut, "last_record_len": last_len}), flush=True)


if __name__ == "__main__":
    main()
