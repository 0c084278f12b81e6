#!/usr/bin/env python3
"""A 1,000-parameter download against `mavping respond` on loopback, by
mavping's `--probe params` and by MAVProxy's `param fetch`, in the same
run: the time each download takes and the CPU each client spends on it.

  transfers.py MAVPING MAVPROXY [--params 1000] [--downloads 5]
               [--rates 1000,20000]
  (bash scripts/bench.sh --transfers builds and runs it)

For each `--transfer-rate` (the responder's frames a second), one
responder serves both clients in turn: mavping makes the downloads in one
run (`-c N`, each timed by its own `time_to_100_ms`; CPU from
getrusage of the child), then MAVProxy, started once and past its own
fetch at connect, is typed `param fetch` N times, each timed from the
typing to its "Received N parameters" line, its CPU read from
/proc/PID/stat around them. Prints one JSON line per rate.
"""
import argparse
import json
import os
import queue
import resource
import socket
import statistics
import subprocess
import sys
import threading
import time


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def cpu_s(pid):
    """The process's user + system CPU seconds, from /proc."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    return (int(fields[11]) + int(fields[12])) / ticks


def respond(mavping, port, params, rate):
    p = subprocess.Popen(
        [mavping, "respond", "--params", str(params), "--transfer-rate", str(rate),
         f"udpin:127.0.0.1:{port}"],
        stdout=subprocess.PIPE, text=True)
    p.stdout.readline()
    return p


def mavping_downloads(mavping, port, downloads):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    run = subprocess.run(
        [mavping, "--probe", "params", "-c", str(downloads), "-W", "1s", "--json",
         f"udpout:127.0.0.1:{port}"],
        capture_output=True, text=True, timeout=600)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    downloads_ = [json.loads(l) for l in run.stdout.splitlines()]
    ended = [d for d in downloads_ if d.get("type") == "transfer"]
    times = [d["time_to_100_ms"] / 1e3 for d in ended if d["time_to_100_ms"] is not None]
    complete = sum(d["ending"] == "complete" for d in ended)
    return {"seconds_p50": statistics.median(times), "seconds": times,
            "complete": complete, "cpu_s_per_download": cpu / downloads}


def mavproxy_downloads(mavproxy, port, params, downloads):
    p = subprocess.Popen(
        [mavproxy, f"--master=udpout:127.0.0.1:{port}", "--target-system=1",
         "--target-component=1", "--nowait"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
        text=True, cwd=os.environ.get("TMPDIR", "/tmp"))
    lines = queue.Queue()
    threading.Thread(target=lambda: [lines.put(l) for l in p.stdout], daemon=True).start()
    done = f"Received {params} parameters"

    def wait(text, limit=300):
        end = time.time() + limit
        while time.time() < end:
            try:
                if text in lines.get(timeout=1):
                    return True
            except queue.Empty:
                pass
        return False

    try:
        if not wait(done):
            raise SystemExit("bench/transfers.py: MAVProxy never fetched the parameters")
        times, cpu0 = [], cpu_s(p.pid)
        for _ in range(downloads):
            start = time.monotonic()
            p.stdin.write("param fetch\n")
            p.stdin.flush()
            if not wait(done):
                raise SystemExit("bench/transfers.py: a MAVProxy param fetch did not end")
            times.append(time.monotonic() - start)
        cpu = cpu_s(p.pid) - cpu0
    finally:
        p.kill()
        p.wait()
    return {"seconds_p50": statistics.median(times), "seconds": times,
            "cpu_s_per_download": cpu / downloads}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mavping")
    ap.add_argument("mavproxy")
    ap.add_argument("--params", type=int, default=1000)
    ap.add_argument("--downloads", type=int, default=5)
    ap.add_argument("--rates", default="1000,20000")
    a = ap.parse_args()
    # MAVProxy runs in a scratch directory (its logs): absolute paths.
    a.mavping, a.mavproxy = os.path.abspath(a.mavping), os.path.abspath(a.mavproxy)
    for rate in map(int, a.rates.split(",")):
        port = free_port()
        responder = respond(a.mavping, port, a.params, rate)
        try:
            ours = mavping_downloads(a.mavping, port, a.downloads)
            theirs = mavproxy_downloads(a.mavproxy, port, a.params, a.downloads)
        finally:
            responder.terminate()
            served = responder.communicate(timeout=30)[0].strip().splitlines()
        print(json.dumps({"transfer_rate": rate, "params": a.params,
                          "mavping": ours, "mavproxy": theirs,
                          "respond": served[-1] if served else ""}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
