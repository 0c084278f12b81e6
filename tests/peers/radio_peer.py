#!/usr/bin/env python3
"""A telemetry radio, written with pymavlink: it sends RADIO_STATUS as one
kind of radio does (its ids, its rate, its companions, each field on its
own scale), encoding physical figures it knows, so a test can check that
mavping names the kind and converts each figure back to what was encoded.

Kinds, as their firmware sends them:
  sik        SiK / RFD900: 51/68, no HEARTBEAT; rssi/noise on the Si1000
             scale (raw = (dBm + 127) * 1.9), rxerrors/fixed counting.
  sik-pairs  SiK 2013-2016: each report twice, as RADIO (166) and then
             RADIO_STATUS (109), one packet sequence number for both.
  radio-only SiK before 2013 (and openLRSng): RADIO (166) only.
  mlrs       mLRS ground module: HEARTBEAT from 51/68 (MAV_TYPE_GENERIC,
             MAV_AUTOPILOT_INVALID) and RADIO_STATUS with rssi_i8_to_ap's
             scale (-120..-50 dBm as 0..254), noise = 10 - SNR,
             remnoise 255, rxerrors/fixed 0, txbuf 100.
  elrs       ExpressLRS receiver in MAVLink mode: 255/68 at 100 Hz,
             rssi = (uint8)(LQ * 2.55), remrssi = -uplink dBm, noise = SNR
             as int8, remnoise/rxerrors/fixed 0.
  esp        mavesp8266: the vehicle's sysid, compid 240; rssi the WiFi
             RSSI as int8, remnoise the % of the vehicle's messages lost,
             rxerrors the % of the ground's.

It listens (udpin) and starts once it hears mavping's HEARTBEAT, sends
--count reports at the kind's rate (then nothing), and on SIGTERM prints
one JSON line of ground truth: the raw fields of every report and the
figures they encode.
"""
import argparse
import json
import os
import signal
import time

RATE = {"sik": 2.0, "sik-pairs": 2.0, "radio-only": 2.0, "mlrs": 2.0, "elrs": 100.0, "esp": 2.0}
IDS = {"sik": (51, 68), "sik-pairs": (51, 68), "radio-only": (51, 68), "mlrs": (51, 68),
       "elrs": (255, 68), "esp": (1, 240)}


def sik_raw(dbm):
    """SiK's scale: dBm = raw / 1.9 - 127. The figures below are chosen so
    that (dBm + 127) * 1.9 is whole: they come back exactly."""
    raw = (dbm + 127) * 19 / 10
    assert raw == int(raw), dbm
    return int(raw)


def mlrs_raw(dbm):
    """mLRS's rssi_i8_to_ap, in integer arithmetic as it does it."""
    if dbm > -50:
        return 254
    if dbm < -120:
        return 0
    r = dbm + 120
    return (r * 254 + 35) // 70


def report(kind, i):
    """The i-th report: (raw fields, the figures they encode)."""
    if kind in ("sik", "sik-pairs", "radio-only"):
        rssi, remrssi = [(-87, -97), (-97, -107), (-77, -87)][i % 3]
        noise, remnoise = -117, -107 - 10 * (i % 2)
        raw = dict(rssi=sik_raw(rssi), remrssi=sik_raw(remrssi), txbuf=90 - i,
                   noise=sik_raw(noise), remnoise=sik_raw(remnoise),
                   rxerrors=100 + 3 * i, fixed=7 + i)
        return raw, dict(rssi_dbm=rssi, remrssi_dbm=remrssi, noise_dbm=noise,
                         remnoise_dbm=remnoise, fade_margin_db=rssi - noise,
                         remote_fade_margin_db=remrssi - remnoise)
    if kind == "mlrs":
        rssi, remrssi, snr = [(-85, -90, 7), (-101, -96, -2), (-60, -66, 12)][i % 3]
        raw = dict(rssi=mlrs_raw(rssi), remrssi=mlrs_raw(remrssi), txbuf=100,
                   noise=max(0, min(127, 10 - snr)), remnoise=255, rxerrors=0, fixed=0)
        # SNR over 10 dB is sent as 0: it comes back as 10.
        return raw, dict(rssi_dbm=rssi, remrssi_dbm=remrssi, snr_db=min(snr, 10))
    if kind == "elrs":
        lq, uplink, snr = [(100, -67, 9), (98, -71, 6), (60, -95, -3), (20, -104, -8)][i % 4]
        raw = dict(rssi=int(lq * 2.55), remrssi=-uplink, txbuf=95, noise=snr & 0xFF,
                   remnoise=0, rxerrors=0, fixed=0)
        return raw, dict(link_quality_pct=lq, remrssi_dbm=uplink, snr_db=snr)
    if kind == "esp":
        wifi, vehicle_lost, gcs_lost = [(-61, 2, 0), (-70, 5, 1), (-58, 0, 3)][i % 3]
        raw = dict(rssi=wifi & 0xFF, remrssi=0, txbuf=40, noise=0, remnoise=vehicle_lost,
                   rxerrors=gcs_lost, fixed=0)
        return raw, dict(rssi_dbm=wifi, vehicle_lost_pct=vehicle_lost, gcs_lost_pct=gcs_lost)
    raise SystemExit(f"unknown kind {kind}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("connection", help="pymavlink connection string, e.g. udpin:127.0.0.1:14550")
    ap.add_argument("--kind", required=True, choices=sorted(RATE))
    ap.add_argument("--count", type=int, default=5, help="reports to send")
    ap.add_argument("--late-heartbeat", action="store_true",
                    help="mlrs: its first HEARTBEAT only after its first report")
    args = ap.parse_args()

    os.environ["MAVLINK20"] = "1"
    from pymavlink import mavutil  # imported after MAVLINK20 is set

    sysid, compid = IDS[args.kind]
    conn = mavutil.mavlink_connection(args.connection, source_system=sysid,
                                      source_component=compid, dialect="ardupilotmega")
    mav = conn.mav
    truth = {"kind": args.kind, "id": [sysid, compid], "reports": 0, "messages": 0,
             "raw": [], "encoded": []}
    running = True

    def stop(*_):
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    print("ready", flush=True)

    # Start once mavping is heard (its HEARTBEAT): nothing is lost before.
    while running and conn.recv_match(blocking=True, timeout=0.05) is None:
        pass
    period = 1.0 / RATE[args.kind]
    next_at = time.monotonic()
    # A late HEARTBEAT: after the first report (sent at once, below).
    next_heartbeat = next_at + (period / 2 if args.late_heartbeat else 0)
    sent = 0
    while running:
        now = time.monotonic()
        if args.kind == "mlrs" and now >= next_heartbeat:
            # mLRS's MAVLink component: a HEARTBEAT from the radio's ids.
            mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GENERIC,
                               mavutil.mavlink.MAV_AUTOPILOT_INVALID,
                               mavutil.mavlink.MAV_MODE_FLAG_SAFETY_ARMED, 0,
                               mavutil.mavlink.MAV_STATE_ACTIVE)
            next_heartbeat = now + 1.0
        if sent < args.count and now >= next_at:
            raw, encoded = report(args.kind, sent)
            fields = (raw["rssi"], raw["remrssi"], raw["txbuf"], raw["noise"],
                      raw["remnoise"], raw["rxerrors"], raw["fixed"])
            if args.kind in ("sik-pairs", "radio-only"):
                seq = mav.seq
                mav.radio_send(*fields)
                truth["messages"] += 1
                if args.kind == "sik-pairs":
                    mav.seq = seq  # the same sequence number, as SiK did
                    mav.radio_status_send(*fields)
                    truth["messages"] += 1
            else:
                mav.radio_status_send(*fields)
                truth["messages"] += 1
            truth["raw"].append(raw)
            truth["encoded"].append(encoded)
            truth["reports"] += 1
            sent += 1
            next_at += period
        conn.recv_match(blocking=True, timeout=0.002)
    print(json.dumps(truth), flush=True)


if __name__ == "__main__":
    main()
