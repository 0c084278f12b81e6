#!/usr/bin/env python3
"""The C2 link report's figures of a telemetry log, computed without
mavping: the truth `mavping --report c2 tlog:LOG` is held against.

    c2_truth.py LOG.tlog [--up-within 2] [--distance-band 500]
                [--failsafe direction=up|down,message=heartbeat|timesync|any,
                            timeout=S[,long-timeout=S][,rate=HZ]] ...

Prints one JSON object. The log is walked record by record (8-byte
big-endian stamp in microseconds, then one MAVLink frame) as
tlog_crc_census.py does, each frame's CRC checked against pymavlink's
ardupilotmega dialect (MAVLink 2 build), and the frames the rule needs
decoded by pymavlink.

The rule (issue 44):
- Time 0 is the stamp of the first record whose frame's CRC checks (bytes
  before it are junk); the log ends at its last record's stamp (a record
  whose CRC fails, lined up with the others, included).
- Vehicle frames: every CRC-valid frame (and every frame of an id this
  dialect lacks: no CRC to check, and mavping's dialect may know it) from a
  source that is not a radio (compid 68 or 240) and not a ground station
  (a sysid that sent a HEARTBEAT of MAV_TYPE_GCS, from that HEARTBEAT on,
  any of its components).
- The link is up at t while a vehicle frame came within the last
  UP_WITHIN (at time 0 as if one had just come). A gap g > UP_WITHIN
  between consecutive vehicle frames (or from time 0 to the first) is an
  outage of g - UP_WITHIN from the earlier + UP_WITHIN; a last vehicle
  frame older than UP_WITHIN at the end leaves an open outage to the end.
- Bands by outage duration: <1s, 1-3s, 3-10s, 10-30s, >30s (>= 30).
- Distance: slant range (haversine on a 6371008.8 m sphere, and the
  altitude difference) from the origin: the first usable position
  (GLOBAL_POSITION_INT not at 0/0; a source that never sends one: GPS_RAW_INT
  with fix >= 2), replaced by HOME_POSITION when one comes. The time from a
  vehicle frame to the next (and the outage in it) goes to the band of the
  last distance known at the earlier one.
- A failsafe: deliveries d1 < d2 < ...; it trips when the time since the
  last delivery (or time 0) exceeds TIMEOUT, at last + TIMEOUT, and
  clears at the next delivery; a trip is long when the wait also exceeds
  the long timeout. The closest call is the longest wait (from time 0 or
  the last delivery to the next delivery) that did not trip, at the
  delivery that ended it.
  direction=down: the vehicle frames of the message (heartbeat, timesync,
  any) as received. direction=up: the ground station's own recorded frames
  of the message, each delivered when the link was up (by the rule) at its
  record; a log with none of them: messages at the rate from time 0 (0,
  1/rate, ... up to the end), each delivered when the link was up then.

Times are computed in integer microseconds and printed in seconds.
"""
import argparse
import json
import math
import os
import struct
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink.dialects.v20 import ardupilotmega as dialect  # noqa: E402
from pymavlink.generator.mavcrc import x25crc  # noqa: E402

RADIO_COMPIDS = (68, 240)
MAV_TYPE_GCS = 6
HEARTBEAT, TIMESYNC = 0, 111
GLOBAL_POSITION_INT, GPS_RAW_INT, HOME_POSITION = 33, 24, 242
EARTH_RADIUS_M = 6371008.8
# A stamp this far past the latest is no record's (pymavlink's bound).
PLAUSIBLE_US = 3 * 24 * 3600 * 1_000_000
BANDS = [("<1s", 0, 1_000_000), ("1-3s", 1_000_000, 3_000_000),
         ("3-10s", 3_000_000, 10_000_000), ("10-30s", 10_000_000, 30_000_000),
         (">30s", 30_000_000, None)]
MESSAGES = {"heartbeat": HEARTBEAT, "timesync": TIMESYNC, "any": None}


def frame_len(buf, at):
    if at + 3 > len(buf):
        return None
    stx, plen, incompat = buf[at], buf[at + 1], buf[at + 2]
    if stx == 0xFE:
        return 8 + plen
    if stx == 0xFD and incompat & ~1 == 0:
        return 12 + plen + (13 if incompat & 1 else 0)
    return None


def header(frame):
    """(sysid, compid, msgid, header length)."""
    if frame[0] == 0xFE:
        return frame[3], frame[4], frame[5], 6
    return frame[5], frame[6], frame[7] | frame[8] << 8 | frame[9] << 16, 10


def crc_ok(frame, msgid, hlen):
    end = hlen + frame[1]
    crc = x25crc(bytes(frame[1:end]))
    crc.accumulate(struct.pack("B", dialect.mavlink_map[msgid].crc_extra))
    return crc.crc == struct.unpack("<H", bytes(frame[end:end + 2]))[0]


def records(data):
    """(stamp_us, sysid, compid, msgid, frame, known) of every whole
    frame whose CRC checks or whose id the dialect lacks; a byte at a
    time past what is no record, as tlog_crc_census.py walks."""
    at = 0
    while at + 8 < len(data):
        n = frame_len(data, at + 8)
        if n is None or at + 8 + n > len(data):
            at += 1
            continue
        stamp = struct.unpack(">Q", data[at:at + 8])[0]
        frame = data[at + 8:at + 8 + n]
        sysid, compid, msgid, hlen = header(frame)
        known = msgid in dialect.mavlink_map
        yield stamp, sysid, compid, msgid, frame, known and crc_ok(frame, msgid, hlen), known
        at += 8 + n


def decode(parser, frame):
    return parser.decode(bytearray(frame))


def slant(a, b):
    """Metres between (lat, lon, alt_m) a and b."""
    la1, lo1, la2, lo2 = map(math.radians, (a[0], a[1], b[0], b[1]))
    h = (math.sin((la2 - la1) / 2) ** 2
         + math.cos(la1) * math.cos(la2) * math.sin((lo2 - lo1) / 2) ** 2)
    ground = 2 * EARTH_RADIUS_M * math.asin(min(1.0, math.sqrt(h)))
    return math.hypot(ground, b[2] - a[2])


class Walk:
    """The log's vehicle frames, the ground station's, and the distances."""

    def __init__(self):
        self.start = self.end = None
        self.vehicle = []  # (t_us, msgid, distance at it or None)
        self.gcs_frames = []  # (t_us, msgid, index of the next vehicle frame)
        self.gcs_sysids = set()
        self.sources = {}
        self.origin = None
        # The last distance known (computed at each position), and the
        # source whose positions are read: the first to give one.
        self.distance = None
        self.positioned_by = None
        self.global_seen = False
        self.unknown = 0
        self.bad_crc = 0
        self.implausible = 0

    def read(self, data):
        parser = dialect.MAVLink(None)
        parser.robust_parsing = True
        for stamp, sysid, compid, msgid, frame, ok, known in records(data):
            if self.start is None and not ok:
                # Junk before the first good frame (flight_logs.tlog
                # starts with some): the log starts at that frame.
                continue
            if self.start is None:
                self.start = self.end = stamp
            if not self.start <= stamp <= self.end + PLAUSIBLE_US:
                self.implausible += 1
                continue
            self.end = max(self.end, stamp)
            if known and not ok:
                self.bad_crc += 1
                continue
            self.unknown += not known
            t = stamp - self.start
            if msgid == HEARTBEAT and known:
                if decode(parser, frame).type == MAV_TYPE_GCS:
                    self.gcs_sysids.add(sysid)
            if sysid in self.gcs_sysids:
                self.gcs_frames.append((t, msgid, len(self.vehicle)))
                continue
            if compid in RADIO_COMPIDS:
                continue
            key = f"{sysid}/{compid}"
            self.sources[key] = self.sources.get(key, 0) + 1
            if known:
                self.position_from(parser, key, msgid, frame)
            self.vehicle.append((t, msgid, self.distance))
        return self

    def position_from(self, parser, key, msgid, frame):
        if msgid not in (GLOBAL_POSITION_INT, GPS_RAW_INT, HOME_POSITION):
            return
        if self.positioned_by not in (None, key):
            return
        if msgid == GLOBAL_POSITION_INT:
            m = decode(parser, frame)
            if (m.lat, m.lon) != (0, 0):
                self.positioned_by = key
                self.global_seen = True
                self.place((m.lat / 1e7, m.lon / 1e7, m.alt / 1e3))
        elif msgid == GPS_RAW_INT and not self.global_seen:
            m = decode(parser, frame)
            if m.fix_type >= 2:
                self.positioned_by = key
                self.place((m.lat / 1e7, m.lon / 1e7, m.alt / 1e3))
        elif msgid == HOME_POSITION:
            m = decode(parser, frame)
            self.positioned_by = key
            self.origin = (m.latitude / 1e7, m.longitude / 1e7, m.altitude / 1e3)

    def place(self, pos):
        if self.origin is None:
            self.origin = pos
        self.distance = slant(self.origin, pos)


def outages(walk, up_us):
    """[(start_us, duration_us, silence_us, open, distance)] by the rule."""
    out = []
    last, last_d = 0, None
    for t, _, d in walk.vehicle:
        if t - last > up_us:
            out.append((last + up_us, t - last - up_us, t - last, False, last_d))
        last, last_d = t, d
    end = walk.end - walk.start
    if end - last > up_us:
        out.append((last + up_us, end - last - up_us, end - last, True, last_d))
    return out


def up_at(walk, up_us, t, next_vehicle):
    """Whether the link was up at t, a record coming before the vehicle
    frame of index next_vehicle."""
    last = walk.vehicle[next_vehicle - 1][0] if next_vehicle > 0 else 0
    return t - last <= up_us


def band_of(us):
    for name, lo, hi in BANDS:
        if us >= lo and (hi is None or us < hi):
            return name
    raise AssertionError(us)


def distance_bands(walk, up_us, width):
    """{band index: [observed_us, down_us, outages]}: each gap between two
    vehicle frames (and from the last to the end) goes to the band of the
    distance known at the earlier."""
    bands = {}
    ends = [t for t, _, _ in walk.vehicle[1:]] + [walk.end - walk.start]
    for (t0, _, d), t1 in zip(walk.vehicle, ends):
        if d is None or t1 <= t0:
            continue
        b = bands.setdefault(int(d // width), [0, 0, 0])
        b[0] += t1 - t0
        if t1 - t0 > up_us:
            b[1] += t1 - t0 - up_us
            b[2] += 1
    return bands


def replay(deliveries, end, timeout, long_timeout):
    """The failsafe rule played on delivery times (us, increasing)."""
    trips, closest = [], None
    last = 0
    for d in deliveries:
        wait = d - last
        if wait > timeout:
            trips.append({"at_s": s(last + timeout), "lasted_s": s(wait - timeout),
                          "open": False,
                          "long": long_timeout is not None and wait > long_timeout})
        elif closest is None or wait > closest[0]:
            closest = (wait, d)
        last = d
    if end - last > timeout:
        trips.append({"at_s": s(last + timeout), "lasted_s": s(end - last - timeout),
                      "open": True,
                      "long": long_timeout is not None and end - last > long_timeout})
    return {"trips": len(trips), "long_trips": sum(t["long"] for t in trips),
            "trip_list": trips,
            "closest_wait_s": s(closest[0]) if closest else None,
            "closest_margin_s": s(timeout - closest[0]) if closest else None,
            "closest_at_s": s(closest[1]) if closest else None}


def failsafe(walk, up_us, spec):
    direction, message = spec["direction"], spec["message"]
    timeout, long_timeout = spec["timeout"], spec.get("long-timeout")
    want = MESSAGES[message]
    end = walk.end - walk.start
    basis = "received"
    if direction == "down":
        played = [(t, True) for t, m, _ in walk.vehicle if want is None or m == want]
    else:
        basis = "recorded"
        played = [(t, up_at(walk, up_us, t, k)) for t, m, k in walk.gcs_frames
                  if want is None or m == want]
    if direction == "up" and not played:
        # No message of the ground station's in the log: sent at the
        # rate from time 0, delivered while the link was up.
        basis = "downlink"
        period = round(1e6 / spec["rate"])
        times = [t for t, _, _ in walk.vehicle]
        played, k = [], 0
        for t in range(0, end + 1, period):
            # The frames up to t, one at t included.
            while k < len(times) and times[k] <= t:
                k += 1
            played.append((t, up_at(walk, up_us, t, k)))
    deliveries = [t for t, ok in played if ok]
    out = {"direction": direction, "message": message, "basis": basis,
           "timeout_s": s(timeout),
           "long_timeout_s": s(long_timeout) if long_timeout is not None else None,
           "messages": len(played), "delivered": len(deliveries)}
    out.update(replay(deliveries, end, timeout, long_timeout))
    return out


def s(us):
    return us / 1e6


def report(walk, up_us, width, specs):
    duration = walk.end - walk.start
    outs = outages(walk, up_us)
    down = sum(o[1] for o in outs)
    bands = []
    for name, _, _ in BANDS:
        inside = [o[1] for o in outs if band_of(o[1]) == name]
        bands.append({"band": name, "count": len(inside), "total_s": s(sum(inside))})
    gaps = [b - a for (a, _, _), (b, _, _) in zip(walk.vehicle, walk.vehicle[1:])]
    dist = distance_bands(walk, up_us, width)
    return {
        "up_within_s": s(up_us), "distance_band_m": width,
        "duration_s": s(duration), "down_s": s(down),
        "availability_pct": 100.0 * (1 - down / duration) if walk.vehicle and duration else None,
        "frames": len(walk.vehicle),
        "sources": walk.sources, "gcs_sysids": sorted(walk.gcs_sysids),
        "gcs_frames": len(walk.gcs_frames), "unknown_id_frames": walk.unknown,
        "bad_crc_frames": walk.bad_crc, "implausible_stamps": walk.implausible,
        "first_vehicle_s": s(walk.vehicle[0][0]) if walk.vehicle else None,
        "longest_silence_s": s(max(gaps)) if gaps else None,
        "outages": {
            "count": len(outs), "total_s": s(down), "bands": bands,
            "list": [{"start_s": s(a), "duration_s": s(b), "silence_s": s(c), "open": o,
                      "distance_m": d} for a, b, c, o, d in outs]},
        "distance": [{"from_m": k * width, "to_m": (k + 1) * width, "observed_s": s(v[0]),
                      "down_s": s(v[1]),
                      "availability_pct": 100.0 * (1 - v[1] / v[0]) if v[0] else None,
                      "outages": v[2]} for k, v in sorted(dist.items())],
        "failsafes": [failsafe(walk, up_us, spec) for spec in specs],
    }


def micros(text):
    value = float(text.rstrip("s"))
    if value < 0:
        raise argparse.ArgumentTypeError(f"negative: {text}")
    return round(value * 1e6)


def failsafe_spec(text):
    """direction=up|down,message=heartbeat|timesync|any,timeout=S
    [,long-timeout=S][,rate=HZ]"""
    spec = {"direction": "up", "message": "heartbeat", "rate": 1.0}
    try:
        for pair in text.split(","):
            key, value = pair.split("=")
            if key in ("timeout", "long-timeout"):
                spec[key] = micros(value)
            elif key == "rate":
                spec[key] = float(value)
            elif key in ("direction", "message"):
                spec[key] = value
            else:
                raise ValueError(key)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: {failsafe_spec.__doc__}") from None
    if spec["direction"] not in ("up", "down") or spec["message"] not in MESSAGES \
            or "timeout" not in spec:
        raise argparse.ArgumentTypeError(f"{text!r}: {failsafe_spec.__doc__}")
    return spec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("--up-within", type=micros, default=2_000_000, metavar="SECONDS")
    ap.add_argument("--distance-band", type=float, default=500.0, metavar="METRES")
    ap.add_argument("--failsafe", type=failsafe_spec, action="append", default=[],
                    metavar="direction=D,message=M,timeout=S[,long-timeout=S][,rate=HZ]")
    args = ap.parse_args()
    with open(args.log, "rb") as f:
        walk = Walk().read(f.read())
    if walk.start is None:
        print(f"{args.log}: no records", file=sys.stderr)
        return 1
    print(json.dumps(report(walk, args.up_within, args.distance_band, args.failsafe)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
