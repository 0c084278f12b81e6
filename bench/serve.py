#!/usr/bin/env python3
"""`mavping serve` at fleet scale (run through scripts/bench-serve.sh).

1. Continuous links: a server with 1 link (the baseline) and one with N
   links (default 100), each at 1 Hz against `mavping respond` peers over
   UDP loopback. Over the same window it reads each server's CPU time
   (utime + stime from /proc) and RSS, and checks every link's counts at
   /metrics. Memory per link is (RSS(N) - RSS(1)) / (N - 1).
2. Concurrent probes: P (default 50) /probe requests of 10 PINGs each sent
   at once, each with a 5 s scrape timeout; every answer must be a success
   with 10 requests decided within that timeout.

Python standard library only; figures are printed, nothing is asserted
beyond the correctness of the answers.
"""
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAVPING = os.environ.get("MAVPING", os.path.join(ROOT, "target", "release", "mavping"))
WINDOW_S = float(os.environ.get("WINDOW", "60"))
LINKS = int(os.environ.get("LINKS", "100"))
PROBES = int(os.environ.get("PROBES", "50"))
# `mavping respond` answers at most 64 peers on one socket.
LINKS_PER_RESPONDER = 25
TICK = os.sysconf("SC_CLK_TCK")


def free_port(kind=socket.SOCK_DGRAM):
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Process:
    def __init__(self, args, ready_prefix=None):
        self.p = subprocess.Popen(args, stdout=subprocess.DEVNULL if ready_prefix else subprocess.PIPE,
                                  stderr=subprocess.PIPE if ready_prefix else subprocess.DEVNULL,
                                  text=True)
        self.line = (self.p.stderr if ready_prefix else self.p.stdout).readline().strip()
        if ready_prefix and not self.line.startswith(ready_prefix):
            sys.exit(f"bench: {args[:2]} did not start: {self.line}")
        if ready_prefix:
            # Drain stderr so a chatty server never blocks on it.
            threading.Thread(target=self.p.stderr.read, daemon=True).start()

    def cpu_s(self):
        fields = open(f"/proc/{self.p.pid}/stat").read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / TICK

    def rss_kib(self):
        for line in open(f"/proc/{self.p.pid}/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    def stop(self):
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(timeout=10)


def responder():
    port = free_port()
    return Process([MAVPING, "respond", f"udpin:127.0.0.1:{port}"]), port


def serve(config_text, *args):
    path = tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False)
    path.write(config_text)
    path.close()
    server = Process([MAVPING, "serve", "--listen", "127.0.0.1:0", "--config", path.name, *args],
                     ready_prefix="mavping: serving")
    os.unlink(path.name)
    server.addr = re.search(r"http://([^/]+)/", server.line).group(1)
    return server


def get(addr, path, timeout_s=None):
    request = urllib.request.Request(f"http://{addr}{path}")
    if timeout_s:
        request.add_header("X-Prometheus-Scrape-Timeout-Seconds", str(timeout_s))
    with urllib.request.urlopen(request, timeout=60) as r:
        return r.status, r.read().decode()


def samples(text, name):
    """{labels text: value} of every sample called `name`."""
    out = {}
    for line in text.splitlines():
        if line.startswith(name + "{") or line.startswith(name + " "):
            series, value = line.rsplit(" ", 1)
            out[series[len(name):]] = float(value)
    return out


def links_config(n, ports):
    text = ""
    for i in range(n):
        text += (f'[[link]]\nlink = "udpout:127.0.0.1:{ports[i // LINKS_PER_RESPONDER]}"\n'
                 f'name = "link-{i}"\nrate = 1\n')
    return text


def measure_links(n, ports):
    server = serve(links_config(n, ports))
    time.sleep(5)  # every link open and answered; the heap settled
    cpu0, t0, rss0 = server.cpu_s(), time.monotonic(), server.rss_kib()
    time.sleep(WINDOW_S)
    cpu1, t1 = server.cpu_s(), time.monotonic()
    rss = server.rss_kib()
    _, metrics = get(server.addr, "/metrics")
    server.stop()
    sent = samples(metrics, "mavping_sent_total")
    received = samples(metrics, "mavping_received_total")
    lost = samples(metrics, "mavping_lost_total")
    up = samples(metrics, "mavping_link_up")
    return {
        "links": n,
        "cpu_pct": 100.0 * (cpu1 - cpu0) / (t1 - t0),
        "rss_kib": rss,
        "rss_start_kib": rss0,
        "responders": len(sent),
        "up": sum(up.values()),
        "sent": sum(sent.values()),
        "received": sum(received.values()),
        "lost": sum(lost.values()),
    }


def concurrent_probes(port):
    server = serve(f'allow = ["udpout:127.0.0.1:*"]\nmax_concurrent = {max(PROBES, 16)}\n')
    results = [None] * PROBES
    barrier = threading.Barrier(PROBES)

    def one(i):
        barrier.wait()
        t0 = time.monotonic()
        status, body = get(server.addr, f"/probe?target=udpout:127.0.0.1:{port}&count=10&interval=100ms",
                           timeout_s=5)
        results[i] = (status, time.monotonic() - t0, body)

    threads = [threading.Thread(target=one, args=(i,)) for i in range(PROBES)]
    t0 = time.monotonic()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.monotonic() - t0
    server.stop()
    ok = 0
    for status, elapsed, body in results:
        success = samples(body, "mavping_probe_success").get("", 0)
        requests = samples(body, "mavping_probe_requests").get("", 0)
        in_flight = samples(body, "mavping_probe_in_flight").get("", 1)
        received = sum(samples(body, "mavping_probe_received").values())
        if status == 200 and success == 1 and requests == 10 and in_flight == 0 and received == 10 \
                and elapsed < 5:
            ok += 1
    durations = sorted(r[1] for r in results)
    return ok, durations, wall


def main():
    responders = [responder() for _ in range((LINKS + LINKS_PER_RESPONDER - 1) // LINKS_PER_RESPONDER)]
    ports = [port for _, port in responders]
    print(f"mavping serve benchmark: {LINKS} continuous links at 1 Hz, window {WINDOW_S:.0f} s; "
          f"{PROBES} concurrent probes")
    print(f"binary: {MAVPING}; {os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.2f}")
    base = measure_links(1, ports)
    fleet = measure_links(LINKS, ports)
    print()
    print("| links | CPU (% of one core) | RSS at window start → end (KiB) | responders at /metrics "
          "| links up | sent | received | lost |")
    print("|---|---|---|---|---|---|---|---|")
    for r in (base, fleet):
        print(f"| {r['links']} | {r['cpu_pct']:.2f} | {r['rss_start_kib']:,} → {r['rss_kib']:,} "
              f"| {r['responders']} | {r['up']:.0f} "
              f"| {r['sent']:,.0f} | {r['received']:,.0f} | {r['lost']:,.0f} |")
    per_link = (fleet["rss_kib"] - base["rss_kib"]) / (LINKS - 1)
    print(f"\nmemory per link: {per_link:.1f} KiB (RSS difference / {LINKS - 1}); "
          f"CPU per link: {(fleet['cpu_pct'] - base['cpu_pct']) / (LINKS - 1):.4f} % of a core")
    for p, _ in responders:
        p.stop()

    probe_responder, port = responder()
    ok, durations, wall = concurrent_probes(port)
    probe_responder.stop()
    print(f"\n{PROBES} concurrent /probe requests of 10 PINGs 100 ms apart, scrape timeout 5 s: "
          f"{ok}/{PROBES} answered in time with 10/10 replies; "
          f"answer time min/median/max {durations[0]:.3f}/{durations[len(durations) // 2]:.3f}/"
          f"{durations[-1]:.3f} s, all {PROBES} in {wall:.3f} s")


if __name__ == "__main__":
    main()
