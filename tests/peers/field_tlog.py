#!/usr/bin/env python3
"""Writes a telemetry log shaped like the real ground stations' logs in
shared/tlogs (QGroundControl's batches and whole-ms stamps, its own
frames logged in part, two senders behind one id, damaged and unknown
frames, outages that wrap the 8-bit counter, a reboot, a SiK radio,
MAVProxy's link bits), frames packed by pymavlink's own encoder
(ardupilotmega dialect), with its ground truth beside it. For mavping's
`tlog:` tests (tests/it/field_logs.rs).

    field_tlog.py OUT.tlog [--truth TRUTH.json] [scenario options]
    field_tlog.py --shape LOG...   (a log's stamps: equal ones, pauses,
                                    batches; to compare with real logs)

A record is 8 bytes of big-endian µs since the Unix epoch, then one raw
frame. Scenarios combine; everything random comes from --seed. Each
counter starts at a number of its own, as a sender running before the
log began (--duration s of it, default 60; --start-us: its start).

The link side (the vehicle 1/1 at --rate frames/s, a realistic
ArduPilot mix with a HEARTBEAT each second; the sources below on the
vehicle's sysid; the radio) reaches the logger with a few ms of latency:

  --batched            QGroundControl on a link that delivers in batches
                       (shared/tlogs/vtol.tlog): stamps are whole ms, a
                       batch about every --batch-pause s (default 1.05)
                       plus its own spread, its frames in clusters of
                       equal stamps (as in vtol.tlog: median cluster 3,
                       mean 4.7; a batch spans ~140 ms). A batch holds
                       every frame that reached the logger since the last
                       one: no number goes missing across a pause.
  --stamps us|ms       plain µs (default) or QGroundControl's ms x 1000
                       (the default with --batched)
  --lose LIST          frames lost on the link, by the n-th frame a source
                       numbers (from 0): N, N-M, N+K (K frames from N);
                       next to a batch pause K (1-based): <pK (the last
                       frame before it), >pK (the first after), <pK:n and
                       >pK:n (n frames). [S/C@] names another source than
                       1/1 (its first counter).
  --silence START:LEN[,...]  outages of the vehicle (s): it numbers frames
                       and none reaches the log (the radio and the ground
                       station go on)
  --delayed START:LEN[,...]  pauses after which the vehicle's frames come
                       in one burst, none missing (delayed, not lost)
  --reboot AT          the vehicle 1/1 restarts at AT s: ~1 s of nothing,
                       then its sequence restarts at 0 (STATUSTEXT, then
                       PARAM_VALUE, as ArduPilot's SITL in
                       shared/tlogs/flight_logs.tlog)
  --radio              a SiK radio's RADIO_STATUS from 51/68 at 1 Hz
  --two-counters S/C   a vehicle-side component with two programs under
                       one id, each with its own counter, frames taking
                       turns (A, B, A, B ...) at 20 frames/s, a few losses
                       in each (--two-counter-losses N per counter), B's
                       numbers --two-counter-offset (100) ahead of A's
  --damage S/C:MSGNAME:SHARE  (repeatable) that share of the source's
                       written MSGNAME frames with both CRC bytes flipped
                       (the header whole); a source that is not otherwise
                       there is made a companion component sending
                       HEARTBEAT at 1 Hz and MSGNAME at 10 Hz
  --unknown S/C:N      (repeatable) N frames of message id 60045
                       (MLRS_RADIO_LINK_STATS, unknown to the dialect) in
                       the source's stream, each taking a number of its
                       sequence, a made-up payload, a CRC computed with a
                       CRC_EXTRA of 0x5A: whole frames, not CRC failures
  --mavlink1           the vehicle 1/1 in MAVLink 1 (as vtol.tlog)

The ground station's own frames, logged when it sends them:

  --gcs [S/C]          (S/C 255/190 unless given) HEARTBEAT (type 6 GCS,
                       autopilot 8 INVALID) at 1 Hz and MANUAL_CONTROL at
                       ~25 Hz, numbered by one counter of which only some
                       frames are logged (about every 13th number is spent
                       on a frame the log never sees)
  --gcs-second-counter REQUEST_DATA_STREAM from the same id every 0.5 s,
                       one for each of 7 streams, numbered 1..7 again and
                       again by a small counter of its own, for
                       --gcs-second-rounds (5) rounds, as in
                       qgc_ardusub_2023-04-18.tlog (two senders behind one
                       id: regular backward jumps)
  --mavproxy-links     MAVProxy's stamps: (usec & ~3) | link, link 3 for
                       what the ground station sent, 0 for the rest

The truth (JSON to --truth; on stdout with --print or without --truth):
  sources["S/C"]   sent (numbered), written (records), good (a whole CRC
                   and a known id: what a reader delivers), lost (on the
                   link, exact: lost_frames, lost_seqs, lost_near_pauses),
                   silenced (numbered in an outage), delayed, damaged and
                   unknown_id (by message id, and _total), not_logged
                   (a ground station's numbers spent on frames it did not
                   log: not_logged_seqs), by_msg (good frames by id),
                   first_us/last_us, role; where two counters share the
                   id, counters["S/C:A"] and ["S/C:B"] with the same
                   figures each (the source's are their sums)
  outages          per --silence and --delayed pause, per counter on the
                   vehicle's side: frames numbered in it (and mod 256),
                   written, any_missing, the last number before and the
                   first after, apparent_gap_mod_256 (what the sequence
                   alone shows) and log_pause_s; a burst's stamps
  reboots          when, the numbers before and after (0), the pause
  batches          (--batched) count, records per batch, cut-offs, and
                   per counter every pause across which a number is
                   missing ([batch, numbers]): only planned losses
  records, first_us, last_us, span_s (good records, as a reader dates
                   them: link bits cleared), stamps (whole_ms, low_bits,
                   equal_consecutive), totals
  pymavlink        pymavlink's own reading of the file written: good
                   frames per source (as mavloss.py counts them, the radio
                   apart), BAD_DATA, UNKNOWN_60045; pymavlink_agrees: it
                   read what the truth says was written
"""
import argparse
import inspect
import json
import math
import os
import random
import struct
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

mavlink = mavutil.mavlink

START_US = 1_764_500_000_000_000
VEHICLE = (1, 1)
RADIO = (51, 68)
UNKNOWN_ID = 60045
UNKNOWN_CRC_EXTRA = 0x5A

# ArduPilot's streams, as in vtol.tlog (each about 4 Hz at ~115 frames/s);
# a HEARTBEAT each second besides.
ARDUPILOT_MIX = [
    "SYS_STATUS", "SYSTEM_TIME", "GPS_RAW_INT", "RAW_IMU", "SCALED_PRESSURE",
    "ATTITUDE", "LOCAL_POSITION_NED", "GLOBAL_POSITION_INT", "RC_CHANNELS_RAW",
    "SERVO_OUTPUT_RAW", "MISSION_CURRENT", "NAV_CONTROLLER_OUTPUT", "RC_CHANNELS",
    "VFR_HUD", "SCALED_IMU2", "POWER_STATUS", "TERRAIN_REPORT", "MEMINFO", "AHRS",
    "SIMSTATE", "HWSTATUS", "WIND", "AHRS2", "AHRS3", "EKF_STATUS_REPORT",
    "VIBRATION", "BATTERY_STATUS", "TIMESYNC",
]
# After a reboot, as flight_logs.tlog's SITL: STATUSTEXT, PARAM_VALUEs,
# TIMESYNC, HEARTBEAT, then the parameter download.
BOOT_MIX = ["STATUSTEXT", "PARAM_VALUE", "PARAM_VALUE", "TIMESYNC", "HEARTBEAT"] + \
    ["PARAM_VALUE"] * 6 + ["STATUSTEXT"] + ["PARAM_VALUE"] * 12 + ["STATUSTEXT"] + \
    ["PARAM_VALUE"] * 10
REBOOT_OFF_S = 1.0
GCS_HEARTBEAT_HZ = 1.0
GCS_MANUAL_HZ = 25.0
GCS_SKIP_EVERY = 13
GCS_SECOND_PERIOD_S = 0.5
# MAV_DATA_STREAM: RAW_SENSORS, EXTENDED_STATUS, RC_CHANNELS, POSITION,
# EXTRA1, EXTRA2, EXTRA3.
GCS_STREAMS = [1, 2, 3, 6, 10, 11, 12]
RADIO_HZ = 1.0
COMPANION_HZ = 10.0
TWO_COUNTER_HZ = 20.0


def key(ids):
    return "%d/%d" % ids


def parse_ids(text):
    """'SYS/COMP' (argparse turns a ValueError into one line of usage)."""
    s, c = text.split("/")
    ids = int(s), int(c)
    if not all(0 <= x <= 255 for x in ids):
        raise ValueError(text)
    return ids


def spans(text):
    """'START:LEN,...' in seconds."""
    out = []
    for part in (text or "").split(","):
        if part.strip():
            a, b = part.split(":")
            if float(b) <= 0:
                raise ValueError(part)
            out.append((float(a), float(b)))
    return out


def make_msg(msg_name, **values):
    """A message of the dialect by name, every field zero (or empty)
    unless given."""
    cls = getattr(mavlink, "MAVLink_%s_message" % msg_name.lower())
    args = []
    for i, field in enumerate(cls.fieldnames):
        if field in values:
            args.append(values[field])
            continue
        length = cls.array_lengths[cls.ordered_fieldnames.index(field)]
        ftype = cls.fieldtypes[i]
        if ftype == "char":
            args.append(b"")
        elif length:
            args.append([0.0 if ftype in ("float", "double") else 0] * length)
        elif ftype in ("float", "double"):
            args.append(0.0)
        else:
            args.append(0)
    return cls(*args)


class Frame:
    """One frame a counter numbered: when it was sent, when it reached the
    logger, its bytes and what became of it."""

    __slots__ = ("src", "counter", "index", "seq", "msg_id", "name", "t", "arrival",
                 "data", "fate", "link", "batched", "stamp", "delayed", "near", "batch")

    def __init__(self, src, counter, index, seq, msg_id, name, t, data, batched):
        self.src = src
        self.counter = counter
        self.index = index
        self.seq = seq
        self.msg_id = msg_id
        self.name = name
        self.t = t
        self.arrival = t
        self.data = data
        # written, lost, silenced, not_logged (a ground station's frame it
        # never logged); damaged and unknown are written too.
        self.fate = "written"
        self.link = 0
        self.batched = batched
        self.stamp = None
        self.delayed = False
        self.near = None
        self.batch = None


class Counter:
    """A sender's sequence counter: numbers frames in the order sent."""

    def __init__(self, ids, label, version=2):
        self.ids = ids
        self.label = label
        self.version = version
        self.mav = mavlink.MAVLink(None, srcSystem=ids[0], srcComponent=ids[1])
        self.frames = []
        # Numbers 1..cycle, again and again (QGroundControl's
        # REQUEST_DATA_STREAM); else 0..255.
        self.cycle = None

    def step(self, seq):
        """The number after `seq`."""
        return seq % self.cycle + 1 if self.cycle else (seq + 1) % 256

    def number(self, t, name, msg, batched):
        seq = self.mav.seq
        if name == "UNKNOWN":
            data = unknown_frame(self.mav, seq)
            msg_id = UNKNOWN_ID
        else:
            data = bytes(msg.pack(self.mav, force_mavlink1=self.version == 1))
            if self.version == 1:
                data = mavlink1_as_sent(data, msg)
            msg_id = msg.get_msgId()
        self.mav.seq = self.step(seq)
        f = Frame(key(self.ids), self.label, len(self.frames), seq, msg_id, name, t, data, batched)
        self.frames.append(f)
        return f


def base_len(cls):
    """A message's payload without its extension fields (the arguments of
    the class with a default)."""
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    nbase = sum(1 for p in params if p.default is inspect.Parameter.empty)
    size = 0
    for i in range(nbase):
        # native_format starts with '<'.
        size += struct.calcsize("<" + chr(cls.native_format[i + 1])) * max(1, cls.array_lengths[i])
    return size


def mavlink1_as_sent(data, msg):
    """A MAVLink 1 frame as the C library (ArduPilot) sends it: the
    payload without extension fields. pymavlink's force_mavlink1 keeps
    them, a length no MAVLink 1 frame of the message has."""
    n = base_len(type(msg))
    if data[1] == n:
        return data
    body = bytearray(data[:6 + n])
    body[1] = n
    crc = mavutil.mavlink.x25crc(bytes(body[1:]))
    crc.accumulate(bytes([msg.crc_extra]))
    return bytes(body) + struct.pack("<H", crc.crc)


def unknown_frame(mav, seq):
    """A whole MAVLink 2 frame of an id the dialect does not know: a
    made-up 18-byte payload, its CRC with a CRC_EXTRA of our own."""
    payload = bytes((seq * 7 + i * 13) % 256 for i in range(18))
    header = struct.pack("<BBBBBBBHB", 0xFD, len(payload), 0, 0, seq, mav.srcSystem,
                         mav.srcComponent, UNKNOWN_ID & 0xFFFF, UNKNOWN_ID >> 16)
    crc = mavutil.mavlink.x25crc(header[1:] + payload)
    crc.accumulate(bytes([UNKNOWN_CRC_EXTRA]))
    return header + payload + struct.pack("<H", crc.crc)


def vehicle_msg(name, t_boot, k, rng):
    """A plausible message of the vehicle: its clock since boot, a position,
    a heartbeat of an armed ArduPilot plane."""
    ms = int(t_boot * 1000)
    if name == "HEARTBEAT":
        return make_msg(name, type=mavlink.MAV_TYPE_FIXED_WING,
                        autopilot=mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base_mode=217,
                        custom_mode=10, system_status=4, mavlink_version=3)
    if name == "STATUSTEXT":
        return make_msg(name, severity=6, text=b"ArduPlane V4.5.7 (boot %d)" % k)
    if name == "PARAM_VALUE":
        return make_msg(name, param_id=b"PARAM_%04d" % k, param_value=float(k), param_type=9,
                        param_count=1200, param_index=k)
    if name == "TIMESYNC":
        return make_msg(name, tc1=0, ts1=int(t_boot * 1e9))
    if name == "GLOBAL_POSITION_INT":
        return make_msg(name, time_boot_ms=ms, lat=int(-35.36 * 1e7), lon=int(149.16 * 1e7),
                        alt=584000 + int(t_boot * 100), relative_alt=int(t_boot * 100))
    if name == "GPS_RAW_INT":
        return make_msg(name, time_usec=int(t_boot * 1e6), fix_type=3, lat=int(-35.36 * 1e7),
                        lon=int(149.16 * 1e7), alt=584000, eph=90, epv=150,
                        satellites_visible=14)
    if name == "ATTITUDE":
        return make_msg(name, time_boot_ms=ms, roll=0.01 * math.sin(t_boot),
                        pitch=0.02, yaw=rng.uniform(-3, 3))
    if name == "SYSTEM_TIME":
        return make_msg(name, time_unix_usec=int(1_764_500_000e6 + t_boot * 1e6),
                        time_boot_ms=ms)
    if name == "VFR_HUD":
        return make_msg(name, airspeed=18.0, groundspeed=17.5, heading=90, throttle=45,
                        alt=100.0, climb=0.1)
    if name == "SYS_STATUS":
        return make_msg(name, voltage_battery=12600, current_battery=1500,
                        battery_remaining=80, load=300)
    cls = getattr(mavlink, "MAVLink_%s_message" % name.lower())
    values = {}
    if "time_boot_ms" in cls.fieldnames:
        values["time_boot_ms"] = ms
    return make_msg(name, **values)


class Writer:
    def __init__(self, args):
        self.a = args
        self.rng = random.Random(args.seed)
        self.counters = []
        self.damage = {}   # (src, name) -> share
        self.unknown = {}  # src -> count
        self.batches = []

    def counter(self, ids, label=None, version=2, first_seq=None):
        """A new counter; it starts where a sender running before the log
        began would be (any number), unless told."""
        c = Counter(ids, label or key(ids), version)
        c.mav.seq = self.rng.randrange(256) if first_seq is None else first_seq
        self.counters.append(c)
        return c

    # --- what is sent ---

    def vehicle(self):
        a = self.a
        period = 1.0 / a.rate
        c = self.counter(VEHICLE, version=1 if a.mavlink1 else 2)
        extra = [name for (src, name) in self.damage if src == key(VEHICLE)
                 and name not in ARDUPILOT_MIX and name != "HEARTBEAT"]
        mix = ARDUPILOT_MIX + extra
        unknown = self.unknown.get(key(VEHICLE), 0)
        total = int(a.duration * a.rate)
        unknown_at = set(int((i + 0.5) * total / unknown) for i in range(unknown)) if unknown else set()
        reboot = a.reboot
        boot_at = 0.0 - self.rng.uniform(100, 200)  # booted before the log starts
        boot_k = None
        next_hb = 0.0
        k_mix = 0
        i = 0
        t = 0.0
        self.reboots = []
        while t < a.duration:
            t = i * period + self.rng.uniform(0, 0.3 * period)
            i += 1
            if t >= a.duration:
                break
            if reboot is not None and t >= reboot:
                # Off for about a second; on again numbering from 0.
                if not self.reboots:
                    back = reboot + REBOOT_OFF_S + self.rng.uniform(0.0, 0.05)
                    self.reboots.append({"at_s": reboot, "back_s": back,
                                         "last_seq_before": c.frames[-1].seq if c.frames else None,
                                         "frames_before": len(c.frames)})
                if t < back:
                    continue
                c.mav.seq = 0
                boot_at = back
                boot_k = 0
                next_hb = back + 1.0
                reboot = None
            if boot_k is not None and boot_k < len(BOOT_MIX):
                name = BOOT_MIX[boot_k]
                boot_k += 1
            elif len(c.frames) in unknown_at:
                name = "UNKNOWN"
                unknown_at.discard(len(c.frames))
            elif t >= next_hb:
                name = "HEARTBEAT"
                next_hb += 1.0
            else:
                name = mix[k_mix % len(mix)]
                k_mix += 1
            msg = None if name == "UNKNOWN" else vehicle_msg(name, t - boot_at, len(c.frames), self.rng)
            c.number(t, name, msg, batched=True)
        self.vehicle_counter = c

    def periodic(self, c, schedule, batched):
        """Numbers a counter's frames: schedule is [(t, name, msg)] in any
        order; unknown-id frames are spread through it."""
        schedule.sort(key=lambda x: x[0])
        # A source's unknown-id frames go to its (first) counter.
        unknown = self.unknown.get(key(c.ids), 0) if c.label in (key(c.ids), key(c.ids) + ":A") else 0
        n = len(schedule)
        unknown_at = set(int((i + 0.5) * n / unknown) for i in range(unknown)) if unknown else set()
        for j, (t, name, msg) in enumerate(schedule):
            if j in unknown_at:
                c.number(t, "UNKNOWN", None, batched)
            c.number(t, name, msg, batched)

    def ticks(self, hz, phase, jitter=0.0):
        t = phase
        out = []
        while t < self.a.duration:
            out.append(t + self.rng.uniform(0, jitter))
            t += 1.0 / hz
        return out

    def companion(self, ids, names):
        c = self.counter(ids)
        sched = [(t, "HEARTBEAT", make_msg("HEARTBEAT", type=mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
                                          autopilot=mavlink.MAV_AUTOPILOT_INVALID,
                                          mavlink_version=3))
                 for t in self.ticks(1.0, self.rng.uniform(0, 1))]
        for name in names:
            if name == "HEARTBEAT":
                continue
            for t in self.ticks(COMPANION_HZ, self.rng.uniform(0, 0.1), 0.002):
                msg = (make_msg(name, time_boot_ms=int(t * 1000), min_distance=20,
                                max_distance=5000, current_distance=150 + int(50 * math.sin(t)),
                                type=1, id=1, orientation=25, covariance=255)
                       if name == "DISTANCE_SENSOR" else vehicle_msg(name, t + 300, 0, self.rng))
                sched.append((t, name, msg))
        self.periodic(c, sched, batched=True)

    def two_counters(self, ids):
        a_ = self.counter(ids, key(ids) + ":A")
        # B runs --two-counter-offset numbers ahead of A (programs started
        # at different times).
        b_ = self.counter(ids, key(ids) + ":B",
                          first_seq=(a_.mav.seq + self.a.two_counter_offset) % 256)
        hb_a = make_msg("HEARTBEAT", type=mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
                        autopilot=mavlink.MAV_AUTOPILOT_INVALID, mavlink_version=3)
        next_hb = 0.3
        sa, sb = [], []
        for j, t in enumerate(self.ticks(TWO_COUNTER_HZ, 0.013, 0.003)):
            if j % 2 == 0:
                if t >= next_hb:
                    sa.append((t, "HEARTBEAT", hb_a))
                    next_hb += 1.0
                else:
                    sa.append((t, "VISION_POSITION_ESTIMATE",
                               make_msg("VISION_POSITION_ESTIMATE", usec=int(t * 1e6),
                                        x=0.1 * t, y=0.0, z=-1.0)))
            else:
                sb.append((t, "NAMED_VALUE_FLOAT",
                           make_msg("NAMED_VALUE_FLOAT", time_boot_ms=int(t * 1000),
                                    name=b"depth", value=float(j))))
        self.periodic(a_, sa, batched=True)
        self.periodic(b_, sb, batched=True)
        # A few losses in each counter: singles and a run of two.
        for c in (a_, b_):
            n = len(c.frames)
            for _ in range(self.a.two_counter_losses):
                k = self.rng.randrange(5, n - 5)
                run = 2 if self.rng.random() < 0.3 else 1
                for f in c.frames[k:k + run]:
                    f.fate = "lost"

    def radio(self):
        c = self.counter(RADIO)
        sched = []
        for j, t in enumerate(self.ticks(RADIO_HZ, self.rng.uniform(0.1, 0.9), 0.01)):
            sched.append((t, "RADIO_STATUS",
                          make_msg("RADIO_STATUS", rssi=180 - j % 7, remrssi=175 - j % 5,
                                   txbuf=95, noise=40, remnoise=42, rxerrors=j // 10, fixed=j // 30)))
        self.periodic(c, sched, batched=True)

    def gcs(self, ids):
        c = self.counter(ids, key(ids) + ":A" if self.a.gcs_second_counter else key(ids))
        hb = make_msg("HEARTBEAT", type=mavlink.MAV_TYPE_GCS, autopilot=mavlink.MAV_AUTOPILOT_INVALID,
                      mavlink_version=3)
        sched = [(t, "HEARTBEAT", hb) for t in self.ticks(GCS_HEARTBEAT_HZ, self.rng.uniform(0, 1))]
        for t in self.ticks(GCS_MANUAL_HZ, self.rng.uniform(0, 0.04), 0.004):
            sched.append((t, "MANUAL_CONTROL",
                          make_msg("MANUAL_CONTROL", target=VEHICLE[0], x=0, y=0, z=500, r=0,
                                   buttons=0)))
        self.periodic(c, sched, batched=False)
        # QGroundControl spends numbers on frames it does not log: about
        # every 13th.
        for f in c.frames:
            if f.index > 0 and self.rng.random() < 1.0 / GCS_SKIP_EVERY:
                f.fate = "not_logged"
        self.gcs_counter = c
        if self.a.gcs_second_counter:
            # As in qgc_ardusub_2023-04-18.tlog: REQUEST_DATA_STREAM every
            # 0.5 s, one of 7 streams each, numbered 1..7 by a small
            # counter of its own, for --gcs-second-rounds rounds.
            b = self.counter(ids, key(ids) + ":B", first_seq=1)
            b.cycle = len(GCS_STREAMS)
            sched = []
            t = self.rng.uniform(0.5, 0.8)
            for j in range(self.a.gcs_second_rounds * len(GCS_STREAMS)):
                if t >= self.a.duration:
                    break
                sched.append((t, "REQUEST_DATA_STREAM",
                              make_msg("REQUEST_DATA_STREAM", target_system=VEHICLE[0],
                                       target_component=VEHICLE[1],
                                       req_stream_id=GCS_STREAMS[j % len(GCS_STREAMS)],
                                       req_message_rate=4, start_stop=1)))
                t += GCS_SECOND_PERIOD_S + self.rng.uniform(-0.01, 0.02)
            self.periodic(b, sched, batched=False)

    # --- what happens to it ---

    def arrivals(self):
        """When each frame reaches the logger: a few ms after it was sent;
        a delayed stretch comes in one burst at its end."""
        for c in self.counters:
            last = -1.0
            for f in c.frames:
                if f.batched:
                    f.arrival = f.t + self.rng.uniform(0.002, 0.006)
                else:
                    f.arrival = f.t + self.rng.uniform(0.0, 0.001)
                if f.src.split("/")[0] == str(VEHICLE[0]) and f.batched:
                    for start, length in self.a.delayed:
                        if start <= f.t < start + length:
                            f.arrival = start + length + 0.003
                            f.delayed = True
                f.arrival = max(f.arrival, last + 1e-5)
                last = f.arrival
                # MAVProxy's link 3: what the ground station sent itself
                # (the frames not on the link).
                f.link = 0 if f.batched else 3

    def silences(self):
        for c in self.counters:
            if c.ids[0] != VEHICLE[0]:
                continue
            for f in c.frames:
                for start, length in self.a.silence:
                    # Nothing reaches the log in an outage: a frame planned
                    # lost in it is silenced like the rest.
                    if start <= f.t < start + length:
                        f.fate = "silenced"

    def make_batches(self):
        """Batch write times: frames that reached the logger up to a batch's
        cut-off are written at its time, spread in clusters."""
        a = self.a
        batched = sorted((f for c in self.counters for f in c.frames if f.batched
                          and f.fate not in ("lost", "silenced")), key=lambda f: f.arrival)
        rng = self.rng
        s = rng.uniform(0.15, 0.9)   # the first batch's write time
        i = 0
        k = 0
        while i < len(batched):
            cut = s - rng.uniform(0.001, 0.004)
            members = []
            while i < len(batched) and batched[i].arrival <= cut:
                members.append(batched[i])
                i += 1
            ms = int(s * 1000)
            first_ms = ms
            left = 0
            # Some batches come tight, some spread (vtol.tlog: a batch's
            # stamps span 142 ms at the median, 340 ms at p90).
            scale = math.exp(rng.gauss(math.log(0.8), 0.7))
            for f in members:
                if left == 0:
                    if f is not members[0]:
                        ms += max(1, int(round(self.increment_ms() * scale)))
                    left = self.cluster_size()
                f.stamp = ms
                f.batch = k + 1
                left -= 1
            k += 1
            self.batches.append({"index": k, "cut_s": cut, "first_ms": first_ms, "last_ms": ms})
            pause = a.batch_pause + (rng.uniform(-0.25, -0.05) if rng.random() < 0.05
                                     else rng.uniform(-0.03, 0.06))
            s = ms / 1000.0 + pause
        self.pauses = self.batches[:-1]

    def cluster_size(self):
        # vtol.tlog: median 3, mean 4.7, p90 11, at most 26.
        return min(26, 1 + int(math.log(1 - self.rng.random()) / math.log(1 - 1 / 5.0)))

    def increment_ms(self):
        # vtol.tlog's steps between clusters: median 1 ms, p75 4, p90 16,
        # p95 34, p99 77.
        r = self.rng.random()
        if r < 0.58:
            return 1
        if r < 0.78:
            return self.rng.randint(2, 4)
        if r < 0.91:
            return self.rng.randint(5, 16)
        if r < 0.955:
            return self.rng.randint(17, 34)
        if r < 0.993:
            return self.rng.randint(35, 77)
        return self.rng.randint(78, 200)

    def losses(self):
        """--lose: frames lost on the link."""
        for item in (self.a.lose or "").split(","):
            if item.strip():
                try:
                    chosen, near = self.lose_item(item.strip())
                except (ValueError, IndexError, StopIteration):
                    sys.exit("field_tlog.py: --lose %s: not a frame of a source in this log "
                             "(N, N-M, N+K, <pK[:n], >pK[:n], [S/C@])" % item)
                for f in chosen:
                    if f.fate == "written":
                        f.fate = "lost"
                        f.near = near

    def lose_item(self, item):
        """The frames one --lose item names, and the pause it is next to."""
        ids = VEHICLE
        if "@" in item:
            who, item = item.split("@")
            ids = parse_ids(who)
        c = next(x for x in self.counters if x.ids == ids)
        if item[0] in "<>":
            if not self.a.batched:
                sys.exit("field_tlog.py: --lose %s: pauses are --batched's" % item)
            side, rest = item[0], item[2:]
            pause, n = (rest.split(":") + ["1"])[:2]
            pause, n = int(pause), int(n)
            if not 1 <= pause < len(self.batches):
                raise IndexError(pause)
            cut = self.batches[pause - 1]["cut_s"]
            if side == "<":
                return [f for f in c.frames if f.arrival <= cut][-n:], ("before", pause)
            return [f for f in c.frames if f.arrival > cut][:n], ("after", pause)
        if "-" in item:
            lo, hi = map(int, item.split("-"))
            return c.frames[lo:hi + 1], None
        if "+" in item:
            lo, n = map(int, item.split("+"))
            return c.frames[lo:lo + n], None
        return [c.frames[int(item)]], None

    def damages(self):
        for (src, name), share in self.damage.items():
            frames = [f for c in self.counters if key(c.ids) == src for f in c.frames
                      if f.name == name and f.fate == "written"]
            n = int(round(share * len(frames)))
            for f in self.rng.sample(frames, n):
                f.fate = "damaged"
                d = bytearray(f.data)
                d[-2] ^= 0xFF
                d[-1] ^= 0xFF
                f.data = bytes(d)

    def stamps(self):
        a = self.a
        for c in self.counters:
            for f in c.frames:
                if f.fate in ("lost", "silenced", "not_logged"):
                    continue
                if f.batched and a.batched:
                    us = a.start_us + f.stamp * 1000
                else:
                    us = a.start_us + int(round(f.arrival * 1e6))
                    if a.stamps == "ms":
                        us = us // 1000 * 1000
                if a.mavproxy_links:
                    us = (us & ~3) | f.link
                f.stamp = us

    # --- out ---

    def write(self, path):
        written = sorted((f for c in self.counters for f in c.frames
                          if f.fate in ("written", "damaged")),
                         key=lambda f: (f.stamp, f.arrival))
        open(path, "wb").close()
        log = mavutil.mavlink_connection(path, write=True)
        for f in written:
            log.write(struct.pack(">Q", f.stamp) + f.data)
        log.close()
        return written


def counter_truth(c):
    frames = c.frames
    good = [f for f in frames if f.fate == "written" and f.name != "UNKNOWN"]
    lost = [f for f in frames if f.fate == "lost"]
    t = {
        "sent": len(frames),
        "written": sum(1 for f in frames if f.fate in ("written", "damaged")),
        "good": len(good),
        "lost": len(lost),
        "lost_frames": [f.index for f in lost],
        "lost_seqs": [f.seq for f in lost],
        "lost_near_pauses": [{"frame": f.index, "seq": f.seq, "side": f.near[0], "pause": f.near[1]}
                             for f in lost if f.near],
        "damaged": {},
        "unknown_id": {},
        "silenced": sum(1 for f in frames if f.fate == "silenced"),
        "not_logged": sum(1 for f in frames if f.fate == "not_logged"),
        "not_logged_seqs": [f.seq for f in frames if f.fate == "not_logged"],
        "delayed": sum(1 for f in frames if f.delayed and f.fate != "lost"),
        "first_seq": frames[0].seq if frames else None,
        "last_seq": frames[-1].seq if frames else None,
        "by_msg": {},
    }
    for f in frames:
        if f.fate == "damaged":
            t["damaged"][str(f.msg_id)] = t["damaged"].get(str(f.msg_id), 0) + 1
        if f.fate == "written" and f.name == "UNKNOWN":
            t["unknown_id"][str(f.msg_id)] = t["unknown_id"].get(str(f.msg_id), 0) + 1
    for f in good:
        t["by_msg"][str(f.msg_id)] = t["by_msg"].get(str(f.msg_id), 0) + 1
    # Steps between consecutive frames of this counter in the log that are
    # not the counter's next number (a lost or unlogged frame between).
    logged = [f for f in frames if f.fate in ("written", "damaged")]
    t["logged_seq_gaps"] = sum(1 for x, y in zip(logged, logged[1:]) if y.seq != c.step(x.seq))
    if c.cycle:
        t["cycle"] = [1, c.cycle]
    return t


def seq_across(frames, start, end):
    """What a reader sees of a counter across a pause: the last frame
    logged that was sent before `start`, the first logged from `end` on
    (for a delayed pause, `end` is its start: the burst's first frame),
    their numbers and stamps."""
    logged = [f for f in frames if f.fate in ("written", "damaged")]
    before = [f for f in logged if f.t < start]
    after = [f for f in logged if f.t >= end]
    e = {"last_seq_before": before[-1].seq if before else None,
         "first_seq_after": after[0].seq if after else None}
    if before and after:
        # The sequence alone shows (after - before - 1) mod 256 missing.
        e["apparent_gap_mod_256"] = (after[0].seq - before[-1].seq - 1) % 256
        e["log_pause_s"] = ((after[0].stamp & ~3) - (before[-1].stamp & ~3)) / 1e6
    return e


def outage_truth(counters, spans_, kind):
    """Per silence or delayed pause, per counter on the vehicle's side:
    the frames it numbered in it (and modulo 256), how many reached the
    log, whether any number went missing."""
    out = []
    for start, length in spans_:
        entry = {"kind": kind, "start_s": start, "length_s": length, "counters": {}}
        for c in counters:
            if c.ids[0] != VEHICLE[0]:
                continue
            inside = [f for f in c.frames if start <= f.t < start + length]
            e = {
                "numbered": len(inside),
                "numbered_mod_256": len(inside) % 256,
                "written": sum(1 for f in inside if f.fate in ("written", "damaged")),
                "any_missing": any(f.fate in ("lost", "silenced") for f in inside),
                "lost_in_it": sum(1 for f in inside if f.fate == "lost"),
            }
            e.update(seq_across(c.frames, start, start if kind == "delayed" else start + length))
            if kind == "delayed":
                burst = [f.stamp & ~3 for f in inside if f.delayed and f.fate != "lost"]
                if burst:
                    e["burst_first_us"] = min(burst)
                    e["burst_last_us"] = max(burst)
            entry["counters"][c.label] = e
        out.append(entry)
    return out


def pymavlink_reading(path):
    """pymavlink's own reading, as mavloss.py counts: good frames per
    source (the radio apart), and BAD_DATA."""
    log = mavutil.mavlink_connection(path, dialect="ardupilotmega")
    per = {}
    radio = 0
    bad = 0
    reasons = {}
    unknown = {}
    while True:
        m = log.recv_match()
        if m is None:
            break
        if m.get_type() == "BAD_DATA":
            bad += 1
            reason = " ".join(str(getattr(m, "reason", "")).split(" ")[:3])
            reasons[reason] = reasons.get(reason, 0) + 1
            continue
        ids = (m.get_srcSystem(), m.get_srcComponent())
        if m.get_type().startswith("UNKNOWN_"):
            # pymavlink hands an unknown id over as UNKNOWN_<id> (its
            # header not kept: 0/0), counted in no loss figure.
            unknown[m.get_type()] = unknown.get(m.get_type(), 0) + 1
            continue
        if m.get_msgId() < 0:
            continue
        if ids == RADIO:
            radio += 1
            continue
        per[key(ids)] = per.get(key(ids), 0) + 1
    return {"sources": per, "radio": radio, "bad_data": bad, "bad_data_reasons": reasons,
            "unknown": unknown}


def shape(path):
    """A log's shape, by a plain walk over its records: how often
    consecutive stamps are equal, the pauses over 0.5 s, the frames
    between them (a batch), the spread of a batch's stamps and the
    clusters of equal stamps in it."""
    data = open(path, "rb").read()
    stamps = []
    i = 0
    while i + 11 <= len(data):
        stx = data[i + 8]
        if stx == 0xFD:
            n = 12 + data[i + 9] + (13 if data[i + 10] & 1 else 0)
        elif stx == 0xFE:
            n = 8 + data[i + 9]
        else:
            i += 1
            continue
        stamps.append(struct.unpack(">Q", data[i:i + 8])[0] & ~3)
        i += 8 + n
    gaps = [(b - a) / 1e6 for a, b in zip(stamps, stamps[1:])]
    cuts = [0] + [k + 1 for k, g in enumerate(gaps) if g > 0.5] + [len(stamps)]
    batches = [stamps[a:b] for a, b in zip(cuts, cuts[1:])]
    clusters = []
    for b in batches:
        run = 1
        for x, y in zip(b, b[1:]):
            if x == y:
                run += 1
            else:
                clusters.append(run)
                run = 1
        clusters.append(run)

    def q(values, *qs):
        v = sorted(values)
        return [round(v[int(x * (len(v) - 1))], 3) for x in qs] if v else []

    pauses = [g for g in gaps if g > 0.5]
    return {
        "file": os.path.basename(path),
        "records": len(stamps),
        "span_s": (stamps[-1] - stamps[0]) / 1e6 if stamps else 0,
        "whole_ms": all(x % 1000 == 0 for x in stamps),
        "equal_consecutive_share": round(sum(1 for g in gaps if g == 0) / max(1, len(gaps)), 3),
        "pauses_over_0_5_s": len(pauses),
        "pause_s_p10_p50_p90_max": q(pauses, 0.1, 0.5, 0.9, 1.0),
        "frames_per_batch_p10_p50_p90": q([len(b) for b in batches], 0.1, 0.5, 0.9),
        "batch_spread_ms_p50_p90": q([(b[-1] - b[0]) / 1000 for b in batches], 0.5, 0.9),
        "equal_stamp_cluster_mean": round(sum(clusters) / max(1, len(clusters)), 2),
    }


def positive(text):
    x = float(text)
    if not x > 0:
        raise argparse.ArgumentTypeError("%r is not above 0" % text)
    return x


def damage_arg(text):
    """S/C:MSGNAME:SHARE"""
    try:
        src, name, share = text.split(":")
        parse_ids(src)
        share = float(share)
    except ValueError:
        raise argparse.ArgumentTypeError("%r is not S/C:MSGNAME:SHARE" % text)
    if not hasattr(mavlink, "MAVLink_%s_message" % name.lower()):
        raise argparse.ArgumentTypeError("%r: no message %s in the dialect" % (text, name))
    if not 0 <= share <= 1:
        raise argparse.ArgumentTypeError("%r: the share is from 0 to 1" % text)
    return src, name.upper(), share


def unknown_arg(text):
    """S/C:N"""
    try:
        src, n = text.split(":")
        parse_ids(src)
        n = int(n)
    except ValueError:
        raise argparse.ArgumentTypeError("%r is not S/C:N" % text)
    if n < 0:
        raise argparse.ArgumentTypeError("%r: N is a count" % text)
    return src, n


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out")
    p.add_argument("--truth")
    p.add_argument("--print", action="store_true", help="the truth on stdout too")
    p.add_argument("--seed", type=int, default=38)
    p.add_argument("--duration", type=positive, default=60.0)
    p.add_argument("--rate", type=positive, default=115.0)
    p.add_argument("--start-us", type=int, default=START_US)
    p.add_argument("--batched", action="store_true")
    p.add_argument("--batch-pause", type=positive, default=1.05)
    p.add_argument("--stamps", choices=["us", "ms"])
    p.add_argument("--lose")
    p.add_argument("--silence", type=spans, default=[])
    p.add_argument("--delayed", type=spans, default=[])
    p.add_argument("--reboot", type=positive)
    p.add_argument("--radio", action="store_true")
    p.add_argument("--two-counters", type=parse_ids)
    p.add_argument("--two-counter-losses", type=int, default=3)
    p.add_argument("--two-counter-offset", type=int, default=100)
    p.add_argument("--damage", type=damage_arg, action="append", default=[])
    p.add_argument("--unknown", type=unknown_arg, action="append", default=[])
    p.add_argument("--mavlink1", action="store_true")
    p.add_argument("--gcs", type=parse_ids, nargs="?", const=(255, 190))
    p.add_argument("--gcs-second-counter", action="store_true")
    p.add_argument("--gcs-second-rounds", type=int, default=5)
    p.add_argument("--mavproxy-links", action="store_true")
    a = p.parse_args()
    if a.stamps is None:
        a.stamps = "ms" if a.batched else "us"
    if a.batched and a.stamps != "ms":
        p.error("--batched is QGroundControl's: whole-ms stamps")
    if a.gcs_second_counter and a.gcs is None:
        p.error("--gcs-second-counter goes with --gcs")
    if a.mavlink1 and any(src == key(VEHICLE) for src, _ in a.unknown):
        p.error("--unknown 1/1: id 60045 needs MAVLink 2 (--mavlink1)")
    return a


def plan(a):
    """Every frame of every sender, numbered, and what becomes of it."""
    w = Writer(a)
    for src, name, share in a.damage:
        w.damage[(src, name)] = share
    for src, n in a.unknown:
        w.unknown[src] = w.unknown.get(src, 0) + n
    w.vehicle()
    gcs_key = key(a.gcs) if a.gcs else None
    known = {key(VEHICLE), key(RADIO), gcs_key, key(a.two_counters) if a.two_counters else None}
    # A source named by --damage or --unknown and nothing else is a
    # companion component of its own.
    companions = {}
    for (src, name) in w.damage:
        if src not in known:
            companions.setdefault(src, []).append(name)
    for src in w.unknown:
        if src not in known:
            companions.setdefault(src, [])
    for src, names in sorted(companions.items()):
        w.companion(parse_ids(src), names)
    if a.two_counters:
        w.two_counters(a.two_counters)
    if a.radio:
        w.radio()
    if gcs_key:
        w.gcs(a.gcs)
    w.arrivals()
    w.silences()
    if a.batched:
        # Losses next to pauses need the batches; the batches are cut by
        # arrival, so a loss does not move them.
        w.make_batches()
    w.losses()
    w.damages()
    w.stamps()
    return w, gcs_key


def source_truths(w, written, a, gcs_key):
    """The truth per source: its counters' figures added up (and kept
    apart where two counters share the id)."""
    sources = {}
    for c in w.counters:
        s = sources.setdefault(key(c.ids), {"counters": {}})
        s["counters"][c.label] = counter_truth(c)
    for src, s in sources.items():
        cts = list(s["counters"].values())
        for k in ("sent", "written", "good", "lost", "silenced", "not_logged", "delayed"):
            s[k] = sum(ct[k] for ct in cts)
        for k in ("damaged", "unknown_id", "by_msg"):
            merged = {}
            for ct in cts:
                for mid, n in ct[k].items():
                    merged[mid] = merged.get(mid, 0) + n
            s[k] = merged
        s["damaged_total"] = sum(s["damaged"].values())
        s["unknown_id_total"] = sum(s["unknown_id"].values())
        if len(cts) == 1:
            for k in ("lost_frames", "lost_seqs", "lost_near_pauses", "not_logged_seqs",
                      "first_seq", "last_seq", "logged_seq_gaps"):
                s[k] = cts[0][k]
            del s["counters"]
        else:
            s["lost_seqs"] = sorted(x for ct in cts for x in ct["lost_seqs"])
        mine = [f.stamp for f in written if f.src == src]
        s["first_us"] = min(mine) if mine else None
        s["last_us"] = max(mine) if mine else None
        s["role"] = ("vehicle" if src == key(VEHICLE) else "radio" if src == key(RADIO)
                     else "gcs" if src == gcs_key else "two_counters"
                     if a.two_counters and src == key(a.two_counters) else "companion")
        if s["role"] == "gcs":
            s["logged"] = s["written"]
            s["numbered"] = s["sent"]
        s["version"] = 1 if (src == key(VEHICLE) and a.mavlink1) else 2
    return sources


def batch_truth(w, written, a):
    """The batches: records in each, cut-offs, and per counter every pause
    across which a number is missing ([batch, numbers]): none but where a
    loss was planned (an outage or a reboot aside)."""
    records = [0] * len(w.batches)
    for f in written:
        if f.batch:
            records[f.batch - 1] += 1
    missing = {}
    for c in w.counters:
        logged = [f for f in c.frames if f.fate in ("written", "damaged") and f.batch]
        for x, y in zip(logged, logged[1:]):
            if y.batch == x.batch:
                continue
            gap = (y.seq - x.seq - 1) % 256
            outage = any(x.t < start + length and y.t >= start
                         for start, length in a.silence + a.delayed)
            reboot = w.reboots and x.t < w.reboots[0]["back_s"] <= y.t
            if gap and not outage and not reboot:
                missing.setdefault(c.label, []).append([x.batch, gap])
    return {
        "count": len(w.batches),
        "pause_s": a.batch_pause,
        "records": records,
        "cuts_us": [a.start_us + int(b["cut_s"] * 1e6) for b in w.batches],
        "missing_across_pauses": missing,
    }


def reboot_truth(w):
    if not w.reboots:
        return []
    r = w.reboots[0]
    frames = w.vehicle_counter.frames
    after = [f for f in frames if f.t >= r["back_s"]]
    r["first_msgs_after"] = [f.name for f in after[:3]]
    # Off: it numbers nothing; on again from 0.
    r["numbered_while_off"] = 0
    r["frames_after"] = len(after)
    r.update(seq_across(frames, r["at_s"], r["back_s"]))
    return w.reboots


def log_truth(w, written, a, gcs_key):
    # The records a reader takes (a good CRC, a known id), dated as it
    # dates them: MAVProxy's link bits cleared (a 4 µs grid).
    good = [f for f in written if f.fate == "written" and f.name != "UNKNOWN"]
    stamps = [f.stamp & ~3 for f in good]
    sources = source_truths(w, written, a, gcs_key)
    truth = {
        "writer": "field_tlog.py",
        "argv": sys.argv[1:],
        "seed": a.seed,
        "pymavlink_version": getattr(__import__("pymavlink"), "__version__", None),
        "records": len(written),
        "first_stamp": good[0].stamp if good else None,
        "first_us": stamps[0] if stamps else None,
        "last_us": stamps[-1] if stamps else None,
        "span_s": (stamps[-1] - stamps[0]) / 1e6 if stamps else 0.0,
        "stamps": {"kind": "mavproxy" if a.mavproxy_links else a.stamps,
                   "whole_ms": all(f.stamp % 1000 == 0 for f in good),
                   "equal_consecutive": sum(1 for x, y in zip(stamps, stamps[1:]) if x == y),
                   "low_bits": [sum(1 for f in good if f.stamp & 3 == b) for b in range(4)]},
        "sources": sources,
        "outages": outage_truth(w.counters, a.silence, "silence")
        + outage_truth(w.counters, a.delayed, "delayed"),
        "reboots": reboot_truth(w),
        "totals": {k: sum(s[k] for s in sources.values())
                   for k in ("sent", "written", "good", "lost", "silenced", "not_logged")},
    }
    truth["totals"]["damaged"] = sum(s["damaged_total"] for s in sources.values())
    truth["totals"]["unknown_id"] = sum(s["unknown_id_total"] for s in sources.values())
    if a.batched:
        truth["batches"] = batch_truth(w, written, a)
    return truth


def check_with_pymavlink(truth, path):
    """pymavlink reads the log back: it must find what the truth says was
    written."""
    py = pymavlink_reading(path)
    sources = truth["sources"]
    expect = {src: s["good"] for src, s in sources.items() if src != key(RADIO) and s["good"]}
    truth["pymavlink"] = py
    truth["pymavlink_agrees"] = (
        py["sources"] == expect
        and py["radio"] == sources.get(key(RADIO), {}).get("good", 0)
        and py["bad_data"] == truth["totals"]["damaged"]
        and sum(py["unknown"].values()) == truth["totals"]["unknown_id"])
    if not truth["pymavlink_agrees"]:
        print("field_tlog.py: pymavlink reads %s, the truth is %s" % (py, expect), file=sys.stderr)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--shape":
        for path in sys.argv[2:]:
            print(json.dumps(shape(path)))
        return
    a = parse_args()
    w, gcs_key = plan(a)
    written = w.write(a.out)
    truth = log_truth(w, written, a, gcs_key)
    check_with_pymavlink(truth, a.out)
    if a.truth:
        with open(a.truth, "w") as f:
            f.write(json.dumps(truth, indent=1, sort_keys=True) + "\n")
    if a.print or not a.truth:
        print(json.dumps(truth, sort_keys=True), flush=True)


if __name__ == "__main__":
    main()
