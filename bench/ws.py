#!/usr/bin/env python3
"""RTT and CPU per PING over ws:// beside UDP and TCP, to one `mavping
respond` listening on udpin:, tcpin: and wsin: at once, in the same run.

  ws.py MAVPING [--count 5000] [--rate 1000] [--trials 3]

For each trial and link, `mavping -c COUNT --rate RATE --json -q LINK`:
its RTT p50/p99 from the summary, its CPU (user + system, getrusage of the
child) divided by the PINGs. Prints one JSON line per link with the median
of the trials, and the responder's counts line.
"""
import argparse
import json
import resource
import socket
import statistics
import subprocess
import sys


def free_port(kind):
    s = socket.socket(socket.AF_INET, kind)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def run(mavping, link, count, rate):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([mavping, "-c", str(count), "--rate", str(rate), "--json", "-q", link],
                         capture_output=True, text=True, timeout=600)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    summary = [json.loads(l) for l in out.stdout.splitlines() if '"type":"summary"' in l][0]
    r = summary["responders"][0]
    return {"received": r["received"], "lost": r["lost"], "p50_us": r["rtt_us"]["p50"],
            "p99_us": r["rtt_us"]["p99"], "cpu_us_per_ping": cpu * 1e6 / count}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mavping")
    ap.add_argument("--count", type=int, default=5000)
    ap.add_argument("--rate", type=int, default=1000)
    ap.add_argument("--trials", type=int, default=3)
    a = ap.parse_args()
    udp, tcp, ws = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_STREAM), free_port(socket.SOCK_STREAM)
    responder = subprocess.Popen(
        [a.mavping, "respond", f"udpin:127.0.0.1:{udp}", f"tcpin:127.0.0.1:{tcp}",
         f"wsin:127.0.0.1:{ws}"], stdout=subprocess.PIPE, text=True)
    responder.stdout.readline()
    links = {"udp": f"udpout:127.0.0.1:{udp}", "tcp": f"tcp:127.0.0.1:{tcp}",
             "ws": f"ws://127.0.0.1:{ws}/"}
    results = {k: [] for k in links}
    try:
        for _ in range(a.trials):
            for name, link in links.items():
                results[name].append(run(a.mavping, link, a.count, a.rate))
    finally:
        responder.terminate()
        counts = responder.communicate(timeout=30)[0].strip().splitlines()
    for name, trials in results.items():
        med = {k: statistics.median(t[k] for t in trials) for k in trials[0]}
        print(json.dumps({"link": name, "count": a.count, "rate": a.rate, "trials": a.trials,
                          "median": med, "each": trials}), flush=True)
    print(json.dumps({"respond": counts[-1] if counts else ""}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
