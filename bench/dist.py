#!/usr/bin/env python3
"""What the size-tuned `dist` profile costs (run through
scripts/bench-dist.sh): the shipped static build (opt-level "s") beside
the same build at opt-level 3, the same runs in turn, interleaved over
rounds so that the machine's drift falls on both alike.

    dist.py SHIPPED OPT3 TLOG [--rounds N]

Per build and round: 1 kHz for 5 s (RTT p50, CPU per PING), 150k PINGs/s
for 5 s against `mavping respond` (counts held against the responder's
own, CPU per PING), and the CPU time to read TLOG (`tlog:`, three times). Medians over
the rounds; the ratio is the shipped build's over opt-level 3's.
"""
import os
import statistics
import sys

import run

ARGS = sys.argv[1:]
SHIPPED, OPT3, TLOG = (os.path.abspath(a) for a in ARGS[:3])
ROUNDS = int(ARGS[ARGS.index("--rounds") + 1]) if "--rounds" in ARGS else 3


def paced(binary, responder, rate, seconds):
    s, r, _, cpu, _ = run.mavping_json(
        ["--rate", str(rate), "-w", f"{seconds}s", "-W", "1s"], responder, binary)
    return s, r, cpu


def flood(binary):
    """150k/s for 5 s at a fresh responder: (exact, lost, CPU per PING µs)."""
    resp = run.Responder()
    s, r, _, cpu, _ = run.mavping_json(["--rate", "150000", "-c", "750000", "-W", "1s"], resp, binary)
    replies = resp.stop()
    exact = r is not None and replies == r["received"] + r["late"] + r["duplicate"]
    return exact, (r["lost"] if r else None), run.per_ping_us(cpu, s)


def tlog_cpu(binary):
    """CPU time (wait4's, to the microsecond) of reading TLOG three times."""
    return sum(run.run_rusage([binary, "-q", f"tlog:{TLOG}"])[3] for _ in range(3))


def main():
    figures = {b: {"p50": [], "cpu1k": [], "cpu150k": [], "tlog": [], "exact": [], "lost": []}
               for b in (SHIPPED, OPT3)}
    resp = run.Responder()
    try:
        for k in range(ROUNDS):
            for binary in (SHIPPED, OPT3) if k % 2 == 0 else (OPT3, SHIPPED):
                f = figures[binary]
                s, r, cpu = paced(binary, resp, 1000, 5)
                f["p50"].append(r["rtt_us"]["p50"])
                f["cpu1k"].append(run.per_ping_us(cpu, s))
                exact, lost, per = flood(binary)
                f["exact"].append(exact)
                f["lost"].append(lost)
                f["cpu150k"].append(per)
                f["tlog"].append(tlog_cpu(binary))
            print(f"bench-dist: round {k + 1} of {ROUNDS} done", flush=True)
    finally:
        resp.stop()
    med = {b: {key: statistics.median(v) for key, v in f.items() if key not in ("exact", "lost")}
           for b, f in figures.items()}
    size = {b: os.path.getsize(b) for b in (SHIPPED, OPT3)}
    rows = [
        ("binary size (bytes)", f"{size[SHIPPED]:,}", f"{size[OPT3]:,}",
         f"{size[SHIPPED] / size[OPT3]:.2f}x"),
        ("RTT p50 at 1 kHz (µs)", f"{med[SHIPPED]['p50']:.1f}", f"{med[OPT3]['p50']:.1f}",
         f"{med[SHIPPED]['p50'] / med[OPT3]['p50']:.2f}x"),
        ("CPU per PING at 1 kHz (µs)", f"{med[SHIPPED]['cpu1k']:.1f}", f"{med[OPT3]['cpu1k']:.1f}",
         f"{med[SHIPPED]['cpu1k'] / med[OPT3]['cpu1k']:.2f}x"),
        ("CPU per PING at 150k/s (µs)", f"{med[SHIPPED]['cpu150k']:.2f}",
         f"{med[OPT3]['cpu150k']:.2f}", f"{med[SHIPPED]['cpu150k'] / med[OPT3]['cpu150k']:.2f}x"),
        ("150k/s for 5 s: lost, counts exact", 
         f"{figures[SHIPPED]['lost']}, {all(figures[SHIPPED]['exact'])}",
         f"{figures[OPT3]['lost']}, {all(figures[OPT3]['exact'])}", ""),
        (f"tlog: CPU to read {os.path.getsize(TLOG) / 1e6:.0f} MB three times (s)", f"{med[SHIPPED]['tlog']:.2f}",
         f"{med[OPT3]['tlog']:.2f}", f"{med[SHIPPED]['tlog'] / med[OPT3]['tlog']:.2f}x"),
    ]
    for b, name in ((SHIPPED, "shipped"), (OPT3, "opt-level 3")):
        print(f"bench-dist: {name} per round: " + "; ".join(
            f"{key} " + " ".join(f"{x:.2f}" for x in v)
            for key, v in figures[b].items() if key not in ("exact", "lost")))
    print(f"\nload average {os.getloadavg()[0]:.2f} (1-minute; {os.cpu_count()} CPUs); "
          f"medians of {ROUNDS} rounds\n")
    print("| figure | dist (opt-level s, shipped) | dist at opt-level 3 | ratio |")
    print("|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
