#!/usr/bin/env python3
"""Weeks of monitoring in minutes: mavping on the simulated link's virtual
clock (sim:?clock=virtual), checked against the link's own ground truth.
Run by scripts/sim-soak.sh, which builds the release binary; see there.

For each case it runs `mavping --json -q -v -Q 1h` with a --first-seq that
makes the PING seq wrap past 2^32 inside the run, reads the interim events
as they come (one per simulated hour) and samples mavping's RSS at each,
then checks, per responder, every count against the truth the link logs
(`sim truth 1/1: answered=.. dropped=..`), and that the RSS at the end of
the run is the RSS after the first simulated hour within 1 MiB.
"""
import json
import subprocess
import sys
import threading
import time

U32 = 2**32
RSS_SLACK_KB = 1024

CASES = {
    # A week at 10 Hz, two responders, an outage of 45 s every 6 h.
    "week": {
        "count": 7 * 86_400 * 10,
        "interval": "100ms",
        "timeout": "1s",
        "first_seq": U32 - 3_000_000,
        "link": "sim:?responders=2&delay=20ms&jitter=5ms&loss=1%&dup=0.5%&reorder=1%&hold=50ms"
                "&spike=0.1%&spike_delay=3s&outage=30m+45s&outage_every=6h&seed=17&clock=virtual",
    },
    # A day at 1 kHz, an outage of 5 s every 3 h.
    "day": {
        "count": 86_400 * 1_000,
        "interval": "1ms",
        "timeout": "200ms",
        "first_seq": U32 - 40_000_000,
        "link": "sim:?responders=1&delay=2ms&jitter=1ms&loss=1%&dup=1%&reorder=2%&hold=20ms"
                "&spike=0.05%&spike_delay=400ms&outage=20m+5s&outage_every=3h&seed=11&clock=virtual",
    },
    # Three hours at 1 kHz: the day's faults, for a quick look.
    "hours": {
        "count": 3 * 3_600 * 1_000,
        "interval": "1ms",
        "timeout": "200ms",
        "first_seq": U32 - 5_000_000,
        "link": "sim:?responders=1&delay=2ms&jitter=1ms&loss=1%&dup=1%&reorder=2%&hold=20ms"
                "&spike=0.05%&spike_delay=400ms&outage=20m+5s&outage_every=1h&seed=11&clock=virtual",
    },
}


def rss_kb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def truth_of(stderr):
    """{responder: {key: value}} from the `sim truth` lines."""
    out = {}
    for line in stderr.splitlines():
        if "sim truth " not in line:
            continue
        rest = line.split("sim truth ", 1)[1]
        who, fields = rest.split(":", 1)
        out[who] = {k: int(v) for k, v in
                    (p.split("=") for p in fields.split() if "=" in p and p.split("=")[1].isdigit())}
    return out


class Checks:
    def __init__(self):
        self.failed = False

    def eq(self, name, expected, actual):
        ok = expected == actual
        self.failed |= not ok
        print(f"  {'ok  ' if ok else 'FAIL'} {name:<44} {actual}" + ("" if ok else f" (expected {expected})"))

    def true(self, name, ok, detail):
        self.failed |= not ok
        print(f"  {'ok  ' if ok else 'FAIL'} {name:<44} {detail}")


def run_case(mavping, name, case, checks):
    args = [mavping, "--json", "-q", "-v", "-Q", "1h", "-c", str(case["count"]),
            "-i", case["interval"], "-W", case["timeout"], "--first-seq", str(case["first_seq"]),
            case["link"]]
    print(f"== {name}: {case['count']:,} PINGs every {case['interval']}, timeout {case['timeout']}, "
          f"first seq {case['first_seq']}")
    print(f"   {' '.join(args[1:-1])} '{case['link']}'")
    started = time.monotonic()
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    err = []
    reader = threading.Thread(target=lambda: err.append(proc.stderr.read()))
    reader.start()
    peak = [0]

    def sample():
        while proc.poll() is None:
            peak[0] = max(peak[0], rss_kb(proc.pid))
            time.sleep(0.5)

    sampler = threading.Thread(target=sample)
    sampler.start()
    interims, summary = [], None
    for line in proc.stdout:
        event = json.loads(line)
        if event["type"] == "interim":
            interims.append((event["t_s"], rss_kb(proc.pid), event))
        elif event["type"] == "summary":
            summary = event
    proc.wait()
    wall = time.monotonic() - started
    reader.join()
    sampler.join()
    stderr = err[0] if err else ""
    if summary is None:
        print(f"  FAIL no summary (exit {proc.returncode}):\n{stderr[-2000:]}")
        checks.failed = True
        return None
    truth = truth_of(stderr)
    requests = summary["requests"]
    checks.eq("requests", case["count"], requests)
    checks.true("PING seq wrapped past 2^32 in the run", case["first_seq"] + requests > U32,
                f"first {case['first_seq']}, last {(case['first_seq'] + requests - 1) % U32}")
    frames = summary["frames"]["frames"]
    checks.true("MAVLink packet seq wrapped (frames > 256)", frames > 256, f"{frames:,} frames")
    checks.eq("in flight at the end", 0, summary["in_flight"])
    checks.eq("responders with ground truth", len(summary["responders"]), len(truth))
    for r in summary["responders"]:
        who = f"{r['responder']['sysid']}/{r['responder']['compid']}"
        t = truth.get(who, {})
        print(f"  {who} truth: " + " ".join(f"{k}={v:,}" for k, v in t.items()))
        print(f"  {who} mavping: " + " ".join(
            f"{k}={r[k]:,}" for k in ("not_charged", "sent", "received", "lost", "late", "duplicate",
                                      "out_of_order", "stale", "in_flight")))
        before = t.get("dropped_before_first", -1)
        checks.eq(f"[{who}] answered = requests", requests, t.get("answered"))
        checks.eq(f"[{who}] not charged = dropped before first", before, r["not_charged"])
        checks.eq(f"[{who}] sent = answered - before first", t.get("answered", 0) - before, r["sent"])
        checks.eq(f"[{who}] received = delivered", t.get("delivered"), r["received"])
        checks.eq(f"[{who}] lost = dropped (in window) + spiked",
                  t.get("dropped", 0) - before + t.get("spiked", 0), r["lost"])
        checks.eq(f"[{who}] late = spiked replies that arrived", t.get("spiked_arrived"), r["late"])
        checks.eq(f"[{who}] duplicate = copies that arrived", t.get("duplicates_arrived"), r["duplicate"])
        checks.eq(f"[{who}] stale", 0, r["stale"])
        checks.true(f"[{who}] outages lost exchanges", t.get("outage", 0) > 0, f"{t.get('outage', 0):,}")
        checks.eq(f"[{who}] not charged + sent + in flight", requests,
                  r["not_charged"] + r["sent"] + r["in_flight"])
    first = next((i for i in interims if i[0] >= 3600), None)
    # The last interim comes with the end of the run; mavping may have
    # exited before it was read: the last one read while it ran.
    last = next((i for i in reversed(interims) if i[1] > 0), None)
    if first and last:
        grew = last[1] - first[1]
        checks.true(f"RSS at {last[0] / 3600:.0f} h = RSS at 1 h ± {RSS_SLACK_KB} kB",
                    abs(grew) <= RSS_SLACK_KB,
                    f"{first[1]:,} kB -> {last[1]:,} kB ({grew:+,} kB), peak {peak[0]:,} kB")
    else:
        checks.true("RSS sampled at interims", False, f"{len(interims)} interims")
    simulated = summary["duration_s"]
    print(f"  simulated {simulated / 86400:.2f} days in {wall:.0f} s of wall time "
          f"({requests / wall:,.0f} PINGs/s, {simulated / wall:,.0f} x real time); "
          f"{len(interims)} interim summaries")
    return wall


def main():
    mavping, names = sys.argv[1], sys.argv[2:] or ["week", "day"]
    checks = Checks()
    for name in names:
        if name not in CASES:
            sys.exit(f"unknown case {name}; cases: {', '.join(CASES)}")
        run_case(mavping, name, CASES[name], checks)
    if checks.failed:
        print("sim soak: FAILED")
        return 1
    print("sim soak: all counts equal the ground truth, memory flat")
    return 0


if __name__ == "__main__":
    sys.exit(main())
