#!/usr/bin/env python3
"""MAVSDK's servers behind fault_relay.py, downloaded by transfer_client.py:
checks that what the ground side missed is exactly what the relay
dropped, the figure mavping's transfer probes will be held to.

  transfer_check.py [--params 1000] [--mission 50] [--seed 7] [--drop 0.1]

The relay drops --drop of PARAM_VALUE (22) and MISSION_ITEM_INT (73) only
(--down-ids 22,73), nothing on the uplink. What is comparable:
- the first pass: MAVSDK sends the list once, in index order, so the n-th
  PARAM_VALUE through the relay is index n: the indices missing after the
  first pass are exactly the relay's dropped_nth_by_msgid["22"] below
  param_count (the rest are answers to re-requests);
- the whole download: every PARAM_REQUEST_READ is answered once, so the
  relay's dropped_by_msgid["22"] = missing on the first pass + re-requests
  whose answer did not come; its frames_by_msgid["22"] = param_count +
  re-requests;
- the mission: one MISSION_ITEM_INT per MISSION_REQUEST_INT, so the
  relay's frames_by_msgid["73"] = the client's item requests, and its
  dropped_by_msgid["73"] = item requests - items received.
The client gives up an index after --tries requests (default 10 here): at
30 % loss 3 tries lose a few (0.3^3 of the missing), and the "all
received" checks fail, rightly, while the identities hold. Its re-request
timeout is 0.2 s: MAVSDK's mission server stops answering an item that
has cost it 5 sends and 0.5 s timeouts, which a 0.5 s client reaches at
20 % loss (then the mission identities fail too: items requested after
that are never answered).
And nothing dropped in a kernel (kernel_dropped 0), or the counts miss
frames. Prints one JSON line (the three truths and the checks) and exits
1 if a check fails.
"""
import argparse
import json
import os
import signal
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def start(args):
    p = subprocess.Popen([sys.executable, *args], stdout=subprocess.PIPE, text=True)
    first = p.stdout.readline().strip()
    if first != "ready":
        p.kill()
        raise SystemExit(f"transfer_check.py: {args[0]} did not start: {first!r}")
    return p, p.stdout.readline().strip()


def stop(p):
    p.send_signal(signal.SIGTERM)
    out, _ = p.communicate(timeout=30)
    return json.loads(out.strip().splitlines()[-1])


def checks(client, relay, n, m):
    pc, src = client["params"], relay["down"]["1/1"]
    nth = src.get("dropped_nth_by_msgid", {}).get("22", [])
    dropped = src.get("dropped_by_msgid", {})
    frames = src.get("frames_by_msgid", {})
    unanswered = pc["rerequests"] - pc["rerequests_answered"]
    out = {
        "param_count": pc["count"] == n,
        "all_params_received": pc["received"] == n,
        "first_pass_missing_are_the_dropped": pc["missing_indices"] == [k for k in nth if k < n],
        "dropped_22_is_missing_plus_unanswered":
            dropped.get("22", 0) == pc["missing_first_pass"] + unanswered,
        "frames_22_is_count_plus_rerequests": frames.get("22", 0) == n + pc["rerequests"],
        "kernel_dropped_none": relay["kernel_dropped"] == {"ground": 0, "vehicles": [0]},
    }
    if m:
        mc = client["mission"]
        out["mission_received"] = mc["received"] == m
        out["frames_73_is_item_requests"] = frames.get("73", 0) == mc["item_requests"]
        out["dropped_73_is_requests_unanswered"] = \
            dropped.get("73", 0) == mc["item_requests"] - mc["received"]
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--params", type=int, default=1000)
    ap.add_argument("--mission", type=int, default=50)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--drop", type=float, default=0.1)
    ap.add_argument("--tries", type=int, default=10, help="the client's, per index or item")
    ap.add_argument("--timeout", type=float, default=0.2, help="the client's, per request")
    a = ap.parse_args()
    vehicle, facts = start([os.path.join(HERE, "mavsdk_vehicle.py"), "--params", str(a.params),
                            "--mission", str(a.mission), "--file-size", "0"])
    port = json.loads(facts)["port"]
    relay, relay_port = start([os.path.join(HERE, "fault_relay.py"), "--vehicle",
                               f"127.0.0.1:{port}", "--seed", str(a.seed), "--drop-down",
                               str(a.drop), "--down-ids", "22,73"])
    try:
        what = ["--params"] + (["--mission"] if a.mission else [])
        run = subprocess.run([sys.executable, os.path.join(HERE, "transfer_client.py"),
                              f"udpout:127.0.0.1:{relay_port}", "--tries", str(a.tries),
                              "--timeout", str(a.timeout), *what],
                             capture_output=True, text=True, timeout=600)
        client = json.loads(run.stdout)
    finally:
        relay_truth = stop(relay)
        vehicle_truth = stop(vehicle)
    result = checks(client, relay_truth, a.params, a.mission)
    src = relay_truth["down"]["1/1"]
    print(json.dumps({"checks": result, "client": client,
                      "relay": {k: src[k] for k in ("frames_by_msgid", "dropped_by_msgid")},
                      "relay_kernel_dropped": relay_truth["kernel_dropped"],
                      "vehicle": vehicle_truth}), flush=True)
    return 0 if all(result.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
