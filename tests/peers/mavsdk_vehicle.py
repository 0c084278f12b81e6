#!/usr/bin/env python3
"""A vehicle made of MAVSDK's own C++ servers (the `mavsdk` package on
PyPI, a ctypes binding around libcmavsdk.so), driven from Python: the
third-party peer mavping's transfer probes are tested against.

  mavsdk_vehicle.py [--port P] [--params N] [--mission M] [--file-size B]

It is an autopilot (MAVSDK's autopilot configuration: sysid 1, compid 1)
listening on udpin://127.0.0.1:P (P 0: a free port), so mavping's
`udpout:127.0.0.1:P` reaches it. It serves, with MAVSDK's plugins:
  --params N     param_server: N parameters, index i named MP_I%04d (even
                 i, INT32, value 7*i) or MP_F%04d (odd i, REAL32, i + 0.5)
  --mission M    mission_raw_server: M waypoints (MAV_CMD_NAV_WAYPOINT,
                 frame 6, x = 473977420 + 100 i, y = 85455940 + 100 i,
                 z = 10 + i), uploaded at start by a second, in-process
                 MAVSDK (a ground station, 245/190) over a connection of
                 its own: the server only serves what was uploaded to it
  --file-size B  ftp_server: a temporary root holding mavping.bin, B bytes,
                 byte k = k mod 251
Prints "ready", then one JSON line: the port, the FTP path to name, the
file's size and sha256, the counts. On SIGTERM it prints one JSON line of
what it served (from the plugins: the parameters retrieve_all_params
holds, the mission the server accepted, the file) and exits 0. Without the
`mavsdk` package it exits 2 with one line.

What MAVSDK 4.1.0 does (measured with tests/peers/transfer_client.py on
loopback; the probes are designed by these):
- PARAM_VALUE: param_count N; every index once on the first pass (no
  copies, no index 65535), the whole list in one burst as fast as the
  socket takes it: a receiver that is slow or keeps the default 208 KiB
  SO_RCVBUF loses the tail in its own kernel (1000 parameters: 256
  arrived). Integers are sent as MAV_PARAM_TYPE_INT32 (6) in the bytewise
  encoding (the int's bits in param_value's float), floats as REAL32 (9).
  Logs "Sending not extended message" once per value (silenced here).
  Rate: 5000 parameters in 0.15 s (33,000/s) to a raw socket with an
  8 MiB buffer; pymavlink's parser keeps up with ~40,000/s. Index order
  is the order provide_param_* was called in.
- PARAM_REQUEST_READ by index and by name both answered (one PARAM_VALUE
  with the right index); an index out of range gets PARAM_ERROR (msgid
  345) with target 0/0, error 1.
- No HEARTBEAT needed first: a request from an unknown sender is
  answered, to that sender's address. MAVSDK sends HEARTBEAT at 1 Hz and
  one PING *request*
  (target 0/0, seq 0) to a component it discovers: a prober must not
  take it for a reply. It forgets a sender after 3 s without its
  HEARTBEAT ("Heartbeats ... timed out") and goes on answering it.
- MISSION_REQUEST_LIST with no mission uploaded: MISSION_COUNT 0, sent
  again every 0.5 s until a MISSION_ACK (5 tries); so the peer uploads.
  With one: MISSION_COUNT (target = the requester), one MISSION_ITEM_INT
  per MISSION_REQUEST_INT (target the requester, mission_type 0, fields
  as uploaded); 500 items in 0.05 s, one request at a time. Its
  download gives up (no more answers, "mission_request_int: retries
  exceeded") once an item has cost 5: each send of it and each 0.5 s
  without a request count. A client that re-requests after 0.5 s loses
  the mission at 20 % item loss; after 0.1-0.3 s it gets it all (30 %
  loss, 10 tries). Re-requests are answered with the same item.
- Two MAVSDKs both start listening on one UDP port (its bind shares
  the port; seen, not read in its source): this peer
  checks the port is free first.
- PING: a request (target 0/0) is answered at once (target = the sender);
  one targeted at 1/1 is not (it is a reply). TIMESYNC (tc1 0) is not
  answered: latency beside a transfer against MAVSDK is PING's.
- FTP: ResetSessions and OpenFileRO acked (session 0, data = the u32 file
  size; one session: a second open is acked again); a missing file is
  NAK FileNotFound (10). BurstReadFile is supported: 150 packets of 239
  bytes per burst (35,850 bytes; the last packet of the file short),
  burst_complete on the last, each reply's seq one more, paced ~2 ms a
  packet (~117 KB/s on loopback: a 1 MB file in 28 bursts, 8.6 s); a
  burst at or past the end is NAK EOF (6). ReadFile of more bytes than
  remain is NAK Fail (1), not a short read; of more than 239, NAK
  InvalidDataSize (3); at the end, NAK EOF (6); after TerminateSession,
  NAK Fail (1).
"""
import argparse
import hashlib
import json
import os
import signal
import socket
import sys
import tempfile
import threading

FILE_NAME = "mavping.bin"


def load_mavsdk():
    try:
        import mavsdk
        from mavsdk.plugins import ftp_server, mission_raw, mission_raw_server, param_server
    except ImportError as e:
        print(f"mavsdk_vehicle.py: the mavsdk package (4.1.0) is missing: {e}", file=sys.stderr)
        sys.exit(2)
    return mavsdk, param_server, mission_raw_server, mission_raw, ftp_server


def free_port(port=0):
    """A UDP port nobody holds: MAVSDK's bind shares a taken port, so a second
    vehicle on a taken port would start without a word and share it."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        s.bind(("127.0.0.1", port))
    except OSError as e:
        raise SystemExit(f"mavsdk_vehicle.py: UDP port {port}: {e.strerror}") from None
    port = s.getsockname()[1]
    s.close()
    return port


def param(i):
    """(name, is_int, value) of parameter i."""
    if i % 2 == 0:
        return f"MP_I{i:04d}", True, 7 * i
    return f"MP_F{i:04d}", False, i + 0.5


def waypoints(sdk_items, m):
    return [sdk_items.MissionItem(seq=i, frame=6, command=16, current=int(i == 0), autocontinue=1,
                                  param1=0.0, param2=1.0, param3=0.0, param4=0.0,
                                  x=473977420 + 100 * i, y=85455940 + 100 * i, z=10.0 + i,
                                  mission_type=0)
            for i in range(m)]


def file_bytes(size):
    return bytes(k % 251 for k in range(size))


class Vehicle:
    def __init__(self, args):
        self.args = args
        mavsdk, self.ps_mod, self.mrs_mod, self.mr_mod, self.ftp_mod = load_mavsdk()
        self.mavsdk = mavsdk
        # Its Warn line per PARAM_VALUE would drown the test's stderr.
        mavsdk.log_subscribe(self.log)
        self.port = free_port(args.port)
        cfg = mavsdk.Configuration.create_with_component_type(mavsdk.ComponentType.AUTOPILOT)
        self.sdk = mavsdk.Mavsdk(cfg)
        self.connect(f"udpin://127.0.0.1:{self.port}")
        self.component = self.sdk.server_component()
        self.accepted = None
        self.incoming = threading.Event()
        self.root = tempfile.mkdtemp(prefix="mavsdk_vehicle.")

    def log(self, level, msg, _file, _line):
        quiet = "not extended message" in msg or level < self.mavsdk.LogLevel.WARN
        if not quiet:
            print(f"mavsdk: {level.name} {msg}", file=sys.stderr, flush=True)
        return True

    def connect(self, url):
        result = self.sdk.add_any_connection(url)
        if result != self.mavsdk.ConnectionResult.SUCCESS:
            raise SystemExit(f"mavsdk_vehicle.py: {url}: {result.name}")

    def serve_params(self, n):
        self.params = self.ps_mod.ParamServer(self.component)
        for i in range(n):
            name, is_int, value = param(i)
            if is_int:
                self.params.provide_param_int(name, value)
            else:
                self.params.provide_param_float(name, value)

    def serve_mission(self, m):
        """Uploads m waypoints to our own mission_raw_server from a second
        MAVSDK over a second connection, so mavping's port carries only
        mavping's traffic."""
        self.mission = self.mrs_mod.MissionRawServer(self.component)
        self.mission.subscribe_incoming_mission(self.on_incoming)
        if m == 0:
            return
        q = free_port()
        self.connect(f"udpin://127.0.0.1:{q}")
        gcs_cfg = self.mavsdk.Configuration.create_with_component_type(
            self.mavsdk.ComponentType.GROUND_STATION)
        gcs = self.mavsdk.Mavsdk(gcs_cfg)
        try:
            if gcs.add_any_connection(f"udpout://127.0.0.1:{q}") != self.mavsdk.ConnectionResult.SUCCESS:
                raise SystemExit("mavsdk_vehicle.py: the uploader cannot connect")
            autopilot = gcs.first_autopilot(10.0)
            if autopilot is None:
                raise SystemExit("mavsdk_vehicle.py: the uploader saw no autopilot in 10 s")
            self.mr_mod.MissionRaw(autopilot).upload_mission(waypoints(self.mr_mod, m))
            if not self.incoming.wait(10.0) or self.accepted != m:
                raise SystemExit(f"mavsdk_vehicle.py: the server accepted {self.accepted} of {m} items")
        finally:
            gcs.destroy()

    def on_incoming(self, result, plan, _user):
        if result == self.mrs_mod.MissionRawServerResult.SUCCESS:
            self.accepted = len(plan.mission_items)
        self.incoming.set()

    def serve_file(self, size):
        self.ftp = self.ftp_mod.FtpServer(self.component)
        data = file_bytes(size)
        with open(os.path.join(self.root, FILE_NAME), "wb") as f:
            f.write(data)
        self.ftp.set_root_dir(self.root)
        self.sha256 = hashlib.sha256(data).hexdigest()

    def facts(self):
        a = self.args
        return {"port": self.port, "sysid": 1, "compid": 1, "params": a.params,
                "mission": a.mission, "ftp_path": f"/{FILE_NAME}", "file_size": a.file_size,
                "sha256": self.sha256, "root": self.root}

    def served(self):
        every = self.params.retrieve_all_params()
        return {"params": len(every.int_params) + len(every.float_params),
                "int_params": len(every.int_params), "float_params": len(every.float_params),
                "mission_accepted": self.accepted, "file_size": self.args.file_size,
                "sha256": self.sha256}

    def close(self):
        path = os.path.join(self.root, FILE_NAME)
        if os.path.exists(path):
            os.unlink(path)
        os.rmdir(self.root)
        self.sdk.destroy()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, default=0, help="UDP port to listen on (0: a free one)")
    ap.add_argument("--params", type=int, default=100)
    ap.add_argument("--mission", type=int, default=10)
    ap.add_argument("--file-size", type=int, default=10000)
    args = ap.parse_args()
    if args.params < 0 or args.mission < 0 or args.file_size < 0:
        print("mavsdk_vehicle.py: counts must be >= 0", file=sys.stderr)
        return 2
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    v = Vehicle(args)
    try:
        v.serve_params(args.params)
        v.serve_mission(args.mission)
        v.serve_file(args.file_size)
        print("ready", flush=True)
        print(json.dumps(v.facts()), flush=True)
        while not stop.wait(0.2):
            pass
        print(json.dumps(v.served()), flush=True)
    finally:
        v.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
