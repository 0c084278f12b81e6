#!/usr/bin/env python3
"""mavping's end-to-end benchmark (run through scripts/bench.sh).

Everything is measured in one run on this machine, side by side, and
reported as figures and ratios (absolute times depend on CPU placement;
see FIELD-NOTES). CPU time of the pinger comes from wait4(2) (the
kernel's nanosecond run time, summed over its threads), of a responder
from /proc/PID/task/*/schedstat; peak RSS from GNU time, which reports the
child's own pages.

    run.py [--quick] [--binary PATH]

The passive rows (--passive at 100,000 frames/s) come from passive.py,
which also runs alone.

--binary benches another build of mavping (an older one, for a before and
after table): the same script, the same machine, the same responder code
as that build.
"""
import json
import os

import passive
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARGS = sys.argv[1:]
MAVPING = (os.path.abspath(ARGS[ARGS.index("--binary") + 1]) if "--binary" in ARGS
           else os.path.join(ROOT, "target", "release", "mavping"))
FLOOR = os.path.join(ROOT, "target", "release", "examples", "wake_floor")
# The portable path (what Windows and macOS get), built by bench.sh with
# --features portable into its own target directory.
PORTABLE = os.path.join(ROOT, "target", "portable", "release", "mavping")
PY = sys.executable
QUICK = "--quick" in ARGS
TRIAL_S = 2 if QUICK else 3
PACED_S = 4 if QUICK else 10
LONG_S = 30 if QUICK else 120
LINKS_S = 10 if QUICK else 30
LINKS = 100


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_rusage(cmd, timeout=600):
    """Runs a command; returns (stdout, stderr, peak RSS KiB, CPU s, wall s).
    GNU time reports the child's own peak RSS (wait4's ru_maxrss would
    include the forked Python parent's pages from before exec); wait4 on
    GNU time gives the CPU time of it and its child, to the nanosecond
    (GNU time's own share is well under a millisecond)."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.monotonic()
        p = subprocess.Popen(["/usr/bin/time", "-f", "TIME %M", *cmd], stdout=out, stderr=err)
        try:
            _, status, usage = os.wait4(p.pid, 0)
        except BaseException:
            p.kill()
            raise
        p.returncode = os.waitstatus_to_exitcode(status)
        wall = time.monotonic() - t0
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    lines = stderr.rstrip().splitlines()
    rss = int(lines[-1].split()[1])
    return stdout, "\n".join(lines[:-1]), rss, usage.ru_utime + usage.ru_stime, wall


def task_cpu(pid):
    """CPU time of a running process so far (s), summed over its threads."""
    total = 0
    for tid in os.listdir(f"/proc/{pid}/task"):
        with open(f"/proc/{pid}/task/{tid}/schedstat") as f:
            total += int(f.read().split()[0])
    return total / 1e9


class Responder:
    """`mavping respond` on a UDP port: its own count of replies is the
    ground truth the pinger's figures are held against."""

    def __init__(self):
        self.port = free_port()
        self.p = subprocess.Popen([MAVPING, "respond", f"udpin:127.0.0.1:{self.port}"],
                                  stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.p.stdout.readline()

    def cpu(self):
        return task_cpu(self.p.pid)

    def stop(self):
        """Stops it; how many replies it says it sent."""
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(timeout=10)
        truth = self.p.stdout.read()
        return int(truth.split(" replies sent")[0].split(", ")[-1]) if " replies sent" in truth else None


def mavping_json(args, responder, binary=None):
    out, err, rss, cpu, wall = run_rusage(
        [binary or MAVPING, "--json", "-q", *args, f"udpout:127.0.0.1:{responder.port}"])
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


def wake_floor(rate, seconds):
    """CPU per send (µs) of the least a pinger waking once per send can do
    here (examples/wake_floor.rs), in the same run."""
    out = subprocess.run([FLOOR, str(rate), str(seconds)], capture_output=True, text=True,
                         timeout=120).stdout
    return json.loads(out.strip().splitlines()[-1])["cpu_per_send_us"]


def pymavlink_rate(rate, responder):
    out = subprocess.run([PY, os.path.join(ROOT, "bench", "pymavlink_pinger.py"),
                          f"udpout:127.0.0.1:{responder.port}", "--rate", str(rate),
                          "--duration", str(TRIAL_S)], capture_output=True, text=True,
                         timeout=120).stdout
    return json.loads(out.strip().splitlines()[-1])


def fmt(x, unit=""):
    return "-" if x is None else f"{x:,.1f}{unit}"


def per_ping_us(cpu, s):
    return cpu / max(1, s["requests"]) * 1e6


def exact_run(rows, rate, label):
    """`-c` requests at `rate` (10 s worth) against a fresh responder:
    counts held against the responder's own, CPU of both ends."""
    resp = Responder()
    before = resp.cpu()
    count = rate * 10
    s, r, rss, cpu, _ = mavping_json(["--rate", str(rate), "-c", str(count), "-W", "1s"], resp)
    respond_cpu = resp.cpu() - before
    replies = resp.stop()
    exact = r is not None and replies == r["received"] + r["late"] + r["duplicate"]
    rows.append((f"{label} for 10 s: sent / received / lost",
                 f"{r['sent']:,} / {r['received']:,} / {r['lost']:,}" if r else "no reply",
                 f"responder sent {replies:,}" if replies is not None else "",
                 "exact" if exact else "MISMATCH"))
    if r:
        rows.append((f"{label}: RTT p50 / p99 (µs)",
                     f"{r['rtt_us']['p50']:,.1f} / {r['rtt_us']['p99']:,.1f}", "", ""))
    rows.append((f"{label}: CPU per PING (µs), achieved rate", f"{per_ping_us(cpu, s):.2f}",
                 f"{s['schedule']['achieved_rate_hz']:,.0f}/s", ""))
    rows.append((f"{label}: `respond` CPU per reply (µs)",
                 f"{respond_cpu / max(1, replies or 0) * 1e6:.2f}", "", ""))
    print(f"bench: {label} done", flush=True)


def hundred_links(rows):
    """LINKS udpout links at 1 Hz in one process, each to its own
    `mavping respond` (a listening responder answers at most 64 peers, and
    each link needs its own address)."""
    peers = [Responder() for _ in range(LINKS)]
    try:
        links = [f"udpout:127.0.0.1:{p.port}" for p in peers]
        out, err, rss, cpu, wall = run_rusage([MAVPING, "-q", "-c", str(LINKS_S), "-i", "1", *links])
    finally:
        for p in peers:
            p.stop()
    answered = out.count(f"{LINKS_S} received")
    rows.append((f"{LINKS} links at 1 Hz for {LINKS_S} s: CPU (% of a core)", f"{100 * cpu / wall:.2f}",
                 f"{answered} of {LINKS} links answered every PING", f"peak RSS {rss:,} KiB"))
    print("bench: 100 links done", flush=True)


def portable_rows(rows, resp):
    """The portable path beside the Linux one, the same runs in turn: RTT
    and CPU per PING at 100 Hz and 1 kHz."""
    if not os.path.exists(PORTABLE):
        print(f"bench: no {PORTABLE}: the portable rows are skipped", flush=True)
        return
    for rate, name in [(100, "100 Hz"), (1000, "1 kHz")]:
        runs = {}
        for label, binary in [("linux", MAVPING), ("portable", PORTABLE)]:
            s, r, rss, cpu, _ = mavping_json(
                ["--rate", str(rate), "-w", f"{PACED_S}s", "-W", "1s"], resp, binary)
            runs[label] = (s, r, cpu)
        (ls, lr, lcpu), (ps, pr, pcpu) = runs["linux"], runs["portable"]
        rows.append((f"portable path: RTT p50 / p99 at {name} (µs)",
                     f"{pr['rtt_us']['p50']:.0f} / {pr['rtt_us']['p99']:.0f}",
                     f"{lr['rtt_us']['p50']:.0f} / {lr['rtt_us']['p99']:.0f} (Linux path)",
                     f"{pr['rtt_us']['p50'] / lr['rtt_us']['p50']:.2f}x"))
        rows.append((f"portable path: send lateness p50 / p99 at {name} (µs)",
                     f"{ps['schedule']['lateness_p50_us']:.1f} / {ps['schedule']['lateness_p99_us']:.1f}",
                     f"{ls['schedule']['lateness_p50_us']:.1f} / {ls['schedule']['lateness_p99_us']:.1f}"
                     " (Linux path)", ""))
        rows.append((f"portable path: CPU per PING at {name} (µs), sent / received",
                     f"{per_ping_us(pcpu, ps):.1f}, {pr['sent']:,} / {pr['received']:,}",
                     f"{per_ping_us(lcpu, ls):.1f}, {lr['sent']:,} / {lr['received']:,} (Linux path)",
                     f"{per_ping_us(pcpu, ps) / per_ping_us(lcpu, ls):.1f}x"))
        print(f"bench: portable path at {name} done", flush=True)


def print_rows(rows):
    head = ("figure", "mavping", "baseline", "ratio")
    print("| " + " | ".join(head) + " |")
    print("|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


def main():
    rows = []
    if "--portable" in ARGS:
        resp = Responder()
        try:
            portable_rows(rows, resp)
        finally:
            if resp.p.poll() is None:
                resp.stop()
        print(f"\nload average {os.getloadavg()[0]:.2f} (1-minute; {os.cpu_count()} CPUs)\n")
        print_rows(rows)
        return
    load_start = os.getloadavg()
    resp = Responder()
    try:
        print(f"bench: machine {os.cpu_count()} CPUs, load average {load_start[0]:.2f}; "
              f"trials {TRIAL_S} s; mavping {MAVPING}", flush=True)

        # 1. Measurement overhead at 1 kHz: mavping vs irtt, same machine, same run.
        s, r, rss, cpu, _ = mavping_json(["--rate", "1000", "-w", "10s", "-W", "1s"], resp)
        mp = r["rtt_us"]
        ir = irtt_1ms()
        irtt = lambda x: fmt(x) + " (irtt)" if x is not None else "-"  # noqa: E731
        rows.append(("RTT p50 at 1 kHz (µs)", fmt(mp["p50"]), irtt(ir and ir["p50_us"]),
                     fmt(ir and mp["p50"] / ir["p50_us"], "x")))
        rows.append(("RTT p99 at 1 kHz (µs)", fmt(mp["p99"]), irtt(ir and ir["p99_us"]),
                     fmt(ir and mp["p99"] / ir["p99_us"], "x")))
        print("bench: 1 kHz vs irtt done", flush=True)

        # 2. Pacing: how late sends go out and what the waiting costs.
        for rate, name in [(100, "100 Hz"), (1000, "1 kHz"), (10000, "10 kHz")]:
            s, r, rss, cpu, wall = mavping_json(
                ["--rate", str(rate), "-w", f"{PACED_S}s", "-W", "1s"], resp)
            sched = s["schedule"]
            rows.append((f"send lateness p50 / p99 at {name} (µs)",
                         f"{sched['lateness_p50_us']:.1f} / {sched['lateness_p99_us']:.1f}", "", ""))
            rows.append((f"achieved rate at {name} (/s)", f"{sched['achieved_rate_hz']:,.2f}", "",
                         f"{100 * (sched['achieved_rate_hz'] / rate - 1):+.3f}%"))
            floor = wake_floor(rate, PACED_S)
            rows.append((f"CPU per PING at {name} (µs)", f"{per_ping_us(cpu, s):.1f}",
                         f"{floor:.1f} (wake floor)", f"{per_ping_us(cpu, s) / floor:.1f}x"))
            print(f"bench: {name} done", flush=True)
        portable_rows(rows, resp)

        # 3. Highest clean rate (< 0.1 % loss): mavping vs the pymavlink pinger.
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
        for rate in [50000, 100000, 150000, 200000, 250000, 300000, 350000, 400000]:
            s, r, rss, cpu, _ = mavping_json(["--rate", str(rate), "-w", f"{TRIAL_S}s", "-W", "1s"], resp)
            ach = s["schedule"]["achieved_rate_hz"]
            print(f"bench: mavping {rate}/s: lost {r and r['lost']} of {r and r['sent']}, "
                  f"achieved {ach:,.0f}/s, p50 {fmt(r and r['rtt_us']['p50'])} µs, "
                  f"CPU/ping {per_ping_us(cpu, s):.2f} µs", flush=True)
            if clean(s, r) and ach >= 0.99 * rate:
                best_mp = rate
            else:
                break
        rows.append(("highest clean rate, < 0.1 % loss (/s)", f"{best_mp:,}", f"{best_py:,} (pymavlink)",
                     fmt(best_py and best_mp / best_py, "x")))
        resp.stop()

        # 4. 150k and 300k PINGs/s for 10 s, exact accounting against the responder.
        exact_run(rows, 150000, "150k/s")
        exact_run(rows, 300000, "300k/s")

        # 5. Many links in one process.
        hundred_links(rows)

        # 5b. Listening: --passive at 100k frames/s (bench/passive.py).
        rows.extend(passive.rows(MAVPING, QUICK))

        # 6. Memory: peak RSS of a short and a long run at 10 kHz; per responder.
        resp = Responder()
        peaks = []
        for secs in (10, LONG_S):
            s, r, rss, cpu, _ = mavping_json(["--rate", "10000", "-w", f"{secs}s", "-W", "1s"], resp)
            peaks.append(rss)
        rows.append((f"peak RSS at 10 kHz, 10 s vs {LONG_S} s (KiB)", f"{peaks[0]:,} vs {peaks[1]:,}", "",
                     f"{peaks[1] - peaks[0]:+,} KiB"))
        out, err, rss, cpu, wall = run_rusage(
            [MAVPING, "-q", "-c", "5000", "-i", "1ms", "sim:?responders=1000&clock=virtual"])
        one, _, rss1, _, _ = run_rusage([MAVPING, "-q", "-c", "5000", "-i", "1ms", "sim:?responders=1&clock=virtual"])
        rows.append(("peak RSS, `sim:` with 1 vs 1000 responders (KiB)", f"{rss1:,} vs {rss:,}", "",
                     f"{(rss - rss1) / 999:.1f} KiB per responder"))

        # 7. Start-up: `mavping -c 1` against the local responder.
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
        if resp.p.poll() is None:
            resp.stop()

    load_end = os.getloadavg()
    print(f"\nload average at start {load_start[0]:.2f}, at end {load_end[0]:.2f} "
          f"(1-minute; {os.cpu_count()} CPUs)\n")
    print_rows(rows)


if __name__ == "__main__":
    main()
