#!/usr/bin/env python3
"""mavping's end-to-end benchmark (run through scripts/bench.sh).

Everything is measured in one run on this machine, side by side, and
reported as figures and ratios (absolute times depend on CPU placement;
see FIELD-NOTES). Per child process, peak RSS and CPU time come from
wait4(2), so they are exact for that process alone.
"""
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAVPING = os.path.join(ROOT, "target", "release", "mavping")
PY = sys.executable
QUICK = "--quick" in sys.argv
TRIAL_S = 2 if QUICK else 3
LONG_S = 30 if QUICK else 120


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_rusage(cmd, timeout=600):
    """Runs a command; returns (stdout, stderr, peak RSS KiB, CPU s, wall s).
    GNU time reports the child's own figures (wait4's ru_maxrss would
    include the forked Python parent's pages from before exec)."""
    t0 = time.monotonic()
    p = subprocess.run(["/usr/bin/time", "-f", "TIME %M %U %S", *cmd], capture_output=True,
                       text=True, timeout=timeout)
    wall = time.monotonic() - t0
    lines = p.stderr.rstrip().splitlines()
    _, rss, user, system = lines[-1].split()
    return p.stdout, "\n".join(lines[:-1]), int(rss), float(user) + float(system), wall


class Responder:
    """`mavping respond` on a UDP port, the same responder for every pinger."""

    def __init__(self):
        self.port = free_port()
        self.p = subprocess.Popen([MAVPING, "respond", f"udpin:127.0.0.1:{self.port}"],
                                  stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.p.stdout.readline()

    def stop(self):
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(timeout=10)


def mavping_json(args, responder):
    out, err, rss, cpu, wall = run_rusage(
        [MAVPING, "--json", "-q", *args, f"udpout:127.0.0.1:{responder.port}"])
    s = json.loads(out.strip().splitlines()[-1])
    r = s["responders"][0] if s["responders"] else None
    return s, r, rss, cpu, wall


def clean(s, r):
    return r is not None and r["lost"] <= 0.001 * max(1, r["sent"]) and r["sent"] > 0


def irtt_1ms():
    if not shutil.which("irtt"):
        return None
    port = free_port()
    server = subprocess.Popen(["irtt", "server", "-i", "0", "-b", f"127.0.0.1:{port}"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.3)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "irtt.json")
        subprocess.run(["irtt", "client", "-Q", "-i", "1ms", "-d", "10s", "-o", path,
                        f"127.0.0.1:{port}"], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        data = json.load(open(path))
    server.terminate()
    server.wait()
    rtts = sorted(rt["delay"]["rtt"] for rt in data["round_trips"]
                  if "delay" in rt and "rtt" in rt["delay"])
    n = len(rtts)
    return {"p50_us": rtts[n // 2] / 1e3, "p99_us": rtts[int(n * 0.99)] / 1e3, "n": n}


def pymavlink_rate(rate, responder):
    out = subprocess.run([PY, os.path.join(ROOT, "bench", "pymavlink_pinger.py"),
                          f"udpout:127.0.0.1:{responder.port}", "--rate", str(rate),
                          "--duration", str(TRIAL_S)], capture_output=True, text=True,
                         timeout=120).stdout
    return json.loads(out.strip().splitlines()[-1])


def fmt(x, unit=""):
    return "-" if x is None else f"{x:,.1f}{unit}"


def main():
    rows = []
    resp = Responder()
    try:
        print(f"bench: machine {os.cpu_count()} CPUs; trials {TRIAL_S} s; mavping {MAVPING}",
              flush=True)

        # 1. Measurement overhead at 1 kHz: mavping vs irtt, same machine, same run.
        s, r, rss, cpu, _ = mavping_json(["--rate", "1000", "-w", "10s", "-W", "1s"], resp)
        mp = r["rtt_us"]
        sched = s["schedule"]
        ir = irtt_1ms()
        rows.append(("RTT p50 at 1 kHz (µs)", fmt(mp["p50"]), fmt(ir and ir["p50_us"]),
                     fmt(ir and mp["p50"] / ir["p50_us"], "x")))
        rows.append(("RTT p99 at 1 kHz (µs)", fmt(mp["p99"]), fmt(ir and ir["p99_us"]),
                     fmt(ir and mp["p99"] / ir["p99_us"], "x")))
        rows.append(("send lateness p50/p99 at 1 kHz (µs)",
                     f"{sched['lateness_p50_us']:.1f} / {sched['lateness_p99_us']:.1f}", "", ""))
        rows.append(("achieved rate at 1 kHz (/s)", f"{sched['achieved_rate_hz']:.2f}", "",
                     f"{100 * (sched['achieved_rate_hz'] / 1000 - 1):+.3f}%"))
        rows.append(("CPU per PING at 1 kHz (µs)", fmt(cpu / max(1, s["requests"]) * 1e6), "", ""))
        print("bench: 1 kHz done", flush=True)

        s, r, rss, cpu, _ = mavping_json(["--rate", "10000", "-w", f"{TRIAL_S}s", "-W", "1s"], resp)
        sched = s["schedule"]
        rows.append(("send lateness p50/p99 at 10 kHz (µs)",
                     f"{sched['lateness_p50_us']:.1f} / {sched['lateness_p99_us']:.1f}", "", ""))
        rows.append(("achieved rate at 10 kHz (/s)", f"{sched['achieved_rate_hz']:.1f}", "",
                     f"{100 * (sched['achieved_rate_hz'] / 10000 - 1):+.3f}%"))

        # 2. Highest clean rate (< 0.1 % loss): mavping vs the pymavlink pinger.
        best_py = 0
        for rate in [2000, 5000, 10000, 20000, 30000, 50000]:
            p = pymavlink_rate(rate, resp)
            print(f"bench: pymavlink {rate}/s: loss {p['loss']:.4f}, p50 {fmt(p['p50_us'])} µs",
                  flush=True)
            if p["loss"] <= 0.001 and p["sent"] >= 0.97 * rate * TRIAL_S:
                best_py = rate
            else:
                break
        best_mp = 0
        for rate in [50000, 100000, 150000, 200000, 300000, 400000]:
            s, r, rss, cpu, _ = mavping_json(["--rate", str(rate), "-w", f"{TRIAL_S}s", "-W", "1s"], resp)
            ach = s["schedule"]["achieved_rate_hz"]
            print(f"bench: mavping {rate}/s: lost {r and r['lost']} of {r and r['sent']}, "
                  f"achieved {ach:,.0f}/s, p50 {fmt(r and r['rtt_us']['p50'])} µs, "
                  f"CPU/ping {cpu / max(1, s['requests']) * 1e6:.2f} µs", flush=True)
            if clean(s, r) and ach >= 0.99 * rate:
                best_mp = rate
            else:
                break
        rows.append(("highest clean rate, < 0.1 % loss (/s)", f"{best_mp:,}", f"{best_py:,} (pymavlink)",
                     fmt(best_py and best_mp / best_py, "x")))

        # 3. 150k PINGs/s for 10 s, exact accounting against the responder.
        resp.stop()
        resp = Responder()
        s, r, rss, cpu, _ = mavping_json(["--rate", "150000", "-c", "1500000", "-W", "1s"], resp)
        resp.stop()
        truth = resp.p.stdout.read()
        replies = int(truth.split(" replies sent")[0].split(", ")[-1]) if " replies sent" in truth else None
        rows.append(("150k/s for 10 s: sent / received / lost",
                     f"{r['sent']:,} / {r['received']:,} / {r['lost']:,}",
                     f"responder sent {replies:,}" if replies is not None else "",
                     "exact" if replies == r["received"] + r["late"] + r["duplicate"] else "MISMATCH"))
        rows.append(("150k/s: RTT p50 / p99 (µs)", f"{r['rtt_us']['p50']:.1f} / {r['rtt_us']['p99']:.1f}",
                     "", ""))
        rows.append(("150k/s: CPU per PING (µs), achieved rate",
                     f"{cpu / s['requests'] * 1e6:.2f}", f"{s['schedule']['achieved_rate_hz']:,.0f}/s", ""))
        resp = Responder()

        # 4. Memory: peak RSS of a short and a long run at 10 kHz.
        peaks = []
        for secs in (10, LONG_S):
            s, r, rss, cpu, _ = mavping_json(["--rate", "10000", "-w", f"{secs}s", "-W", "1s"], resp)
            peaks.append(rss)
        rows.append((f"peak RSS at 10 kHz, 10 s vs {LONG_S} s (KiB)", f"{peaks[0]:,} vs {peaks[1]:,}", "",
                     f"{peaks[1] - peaks[0]:+,} KiB"))
        out, err, rss, cpu, wall = run_rusage(
            [MAVPING, "-q", "-c", "5000", "-i", "1ms", "sim:?responders=1000&clock=virtual"])
        one, _, rss1, _, _ = run_rusage([MAVPING, "-q", "-c", "5000", "-i", "1ms", "sim:?responders=1&clock=virtual"])
        rows.append(("peak RSS, sim with 1 vs 1000 responders (KiB)", f"{rss1:,} vs {rss:,}", "",
                     f"{(rss - rss1) / 1000:.1f} KiB per responder"))

        # 5. Start-up: `mavping -c 1` against the local responder.
        walls = []
        for _ in range(20):
            t0 = time.monotonic()
            subprocess.run([MAVPING, "-q", "-c", "1", f"udpout:127.0.0.1:{resp.port}"],
                           stdout=subprocess.DEVNULL, check=True)
            walls.append((time.monotonic() - t0) * 1e3)
        walls.sort()
        rows.append(("`mavping -c 1` wall time, median of 20 (ms)", f"{walls[10]:.1f}", "",
                     f"max {walls[-1]:.1f}"))
    finally:
        resp.stop()

    w = [max(len(r[i]) for r in rows + [("figure", "mavping", "baseline", "ratio")]) for i in range(4)]
    print()
    for row in [("figure", "mavping", "baseline", "ratio")] + rows:
        print("  ".join(c.ljust(w[i]) for i, c in enumerate(row)))


if __name__ == "__main__":
    main()
