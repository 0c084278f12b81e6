#!/usr/bin/env python3
"""The passive rows of mavping's benchmark (run through scripts/bench.sh,
or alone with `bash scripts/bench.sh --passive`): what listening costs
per received frame at 100,000 frames/s over UDP loopback.

One sender feeds every listener the same stream (examples/stream_floor.rs
send: ATTITUDE from 1/1, one frame a datagram, its packet sequence
counting up), in the same run: `mavping --passive`, the least a listener
can do with it (examples/stream_floor.rs read: recvmmsg and count), and
pymavlink's mavutil (bench/pymavlink_listener.py, what MAVProxy and
mavloss run), which is also stepped down to the rate it keeps up with.
mavping's count is held against the sender's: every frame received, none
lost. Beside them, for scale, mavping's CPU per PING at the same rate
against `mavping respond`. CPU is the kernel's run time of each process
(wait4(2) for mavping, getrusage(2) inside the baselines).

`--pair` (issue 41): what matching one vehicle's frames across two links
costs. Taking turns, three trials each: `mavping --passive` on one link
fed at 50,000 frames/s, and on two links each fed the same frames at
50,000 frames/s (one vehicle on two links, 100,000 frames/s in all, each
frame's two copies for the pair tracker to match), and the plain reader
on one link and on two (a process a link); with `--pair-against BINARY`,
also BINARY (a build without the pair tracker) on the same two links.
Then pymavlink's mavutil once on one link and once on two (a connection
a link in one process, as MAVProxy holds its masters), for scale. Every
link's count is held against the sender's less the kernel's drops at its
socket (/proc/net/udp, read before mavping closes it), and the pair
report's against the sender's: every frame distinct once, copied once,
lost on no link.
"""
import json
import os
import socket
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FLOOR = os.path.join(ROOT, "target", "release", "examples", "stream_floor")
PY = sys.executable
RATE = 100000
PAIR_RATE = 50000
ONE = {"sysid": 1, "compid": 1}


def free_ports(n):
    """n ports free at once (one at a time, the kernel may give one twice)."""
    socks = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(n)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = [s.getsockname()[1] for s in socks]
    for s in socks:
        s.close()
    return ports


def free_port():
    return free_ports(1)[0]


def send(ports, rate, seconds):
    """Runs the sender to its end, the same frames to every port: frames
    sent (to each)."""
    to = ",".join(f"127.0.0.1:{port}" for port in ports)
    out = subprocess.run([FLOOR, "send", to, str(rate), str(seconds)],
                         capture_output=True, text=True, timeout=seconds + 60, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])["sent"]


def udp_drops(ports):
    """The kernel's count of datagrams it dropped at each of `ports`'
    sockets, their receive buffers full while the listener was not
    scheduled (the last field of /proc/net/udp): read while the listener
    holds them open."""
    want = {f"{port:04X}": port for port in ports}
    drops = dict.fromkeys(ports, 0)
    with open("/proc/net/udp") as f:
        next(f)
        for line in f:
            fields = line.split()
            local = fields[1].split(":")[1]
            if local in want:
                drops[want[local]] += int(fields[-1])
    return [drops[port] for port in ports]


def one_source(sources):
    return next((s for s in sources if s["source"] == ONE), None)


def mavping_links(mavping, rate, seconds, links):
    """`mavping --passive` on `links` UDP ports, each fed the same stream
    at `rate`: (sent to each, 1/1's figures on each link, 1/1's figures in
    the pair report or None, CPU s, wall s, peak RSS KiB, the kernel's
    drops at each link's socket)."""
    ports = free_ports(links)
    p = subprocess.Popen(["/usr/bin/time", "-f", "TIME %M", mavping, "--passive", "--json",
                          "-w", f"{seconds + 3}s"] + [f"udpin:127.0.0.1:{port}" for port in ports],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    starts = 0
    while starts < links:  # a start line a link: every link is open
        line = p.stdout.readline()
        if not line:
            raise RuntimeError(f"{mavping} ended before its links opened: {p.stderr.read()}")
        starts += '"type":"start"' in line
    t0 = time.monotonic()
    sent = send(ports, rate, seconds)
    drops = udp_drops(ports)  # every frame sent is queued or dropped by now
    out = p.stdout.read()
    err = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    rss = int(err.strip().splitlines()[-1].split()[1])
    lines = [json.loads(line) for line in out.splitlines()
             if '"passive_summary"' in line or '"pair_summary"' in line]
    by_link = {d["link"]: d for d in lines if d["type"] == "passive_summary"}
    srcs = [one_source(by_link[f"udpin:127.0.0.1:{port}"]["sources"]) for port in ports]
    pair = next((one_source(d["sources"]) for d in lines if d["type"] == "pair_summary"), None)
    return sent, srcs, pair, usage.ru_utime + usage.ru_stime, wall, rss, drops


def mavping_passive(mavping, rate, seconds):
    """`mavping --passive` on a UDP port fed at `rate`: (sent, 1/1's
    figures, CPU s, wall s, peak RSS KiB)."""
    sent, srcs, _, cpu, wall, rss, _ = mavping_links(mavping, rate, seconds, 1)
    return sent, srcs[0], cpu, wall, rss


def floor(rate, seconds, links=1):
    """The plain reader on the same stream, one a link: (sent to each,
    received on all, CPU s of all)."""
    ports = free_ports(links)
    ps = [subprocess.Popen([FLOOR, "read", str(port), str(seconds + 5)],
                           stdout=subprocess.PIPE, text=True) for port in ports]
    time.sleep(0.3)
    sent = send(ports, rate, seconds)
    got = [json.loads(p.communicate(timeout=seconds + 30)[0].strip().splitlines()[-1])
           for p in ps]
    return sent, sum(g["received"] for g in got), sum(g["cpu_s"] for g in got)


def pymavlink(rate, seconds, links=1):
    """pymavlink's listener on the same stream, on `links` ports in one
    process: (sent to each, parsed on all, its loss figure, CPU s)."""
    ports = free_ports(links)
    p = subprocess.Popen([PY, os.path.join(ROOT, "bench", "pymavlink_listener.py"),
                          ",".join(map(str, ports)), str(seconds + 5)],
                         stdout=subprocess.PIPE, text=True)
    p.stdout.readline()
    sent = send(ports, rate, seconds)
    got = json.loads(p.communicate(timeout=seconds + 120)[0].strip().splitlines()[-1])
    return sent, got["received"], got["loss"], got["cpu_s"]


def ping_cpu(mavping, rate, seconds):
    """CPU per PING (µs) at `rate` against `mavping respond`, for scale."""
    port = free_port()
    resp = subprocess.Popen([mavping, "respond", f"udpin:127.0.0.1:{port}"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    resp.stdout.readline()
    p = subprocess.Popen([mavping, "--json", "-q", "--rate", str(rate), "-w", f"{seconds}s",
                          "-W", "1s", f"udpout:127.0.0.1:{port}"],
                         stdout=subprocess.PIPE, text=True)
    out = p.stdout.read()
    _, _, usage = os.wait4(p.pid, 0)
    resp.terminate()
    resp.wait()
    s = json.loads(out.strip().splitlines()[-1])
    return (usage.ru_utime + usage.ru_stime) / max(1, s["requests"]) * 1e6, s


def us(cpu, n):
    return cpu / max(1, n) * 1e6


def median(xs):
    return sorted(xs)[len(xs) // 2]


def rows(mavping, quick):
    """The table rows: (figure, mavping, baseline, ratio). mavping and the
    plain reader take turns, three trials each, so a busy moment of the
    machine falls on both; the CPU figures are the medians."""
    seconds = 4 if quick else 10
    out = []
    trials, floors = [], []
    for _ in range(3):
        sent, src, cpu, wall, rss = mavping_passive(mavping, RATE, seconds)
        got = src["counts"] if src else {"received": 0, "lost": 0, "duplicate": 0,
                                         "reordered": 0, "resyncs": 0}
        # Frames the kernel drops while mavping is not scheduled come in
        # runs too long for the sequence to span: silences, estimated.
        unspanned = src["silence_frames_estimated"] if src else 0
        exact = (got["received"] == sent and got["lost"] == 0 and got["duplicate"] == 0
                 and got["reordered"] == 0)
        print(f"bench: passive {RATE}/s: sent {sent:,}, received {got['received']:,}, lost "
              f"{got['lost']}, silences {src and src['silence_count']} (~{unspanned:,} frames), "
              f"resyncs {got['resyncs']}, CPU {cpu:.3f} s", flush=True)
        trials.append((exact, sent, got, us(cpu, got["received"]), 100 * cpu / wall, rss))
        f_sent, f_got, f_cpu = floor(RATE, seconds)
        print(f"bench: plain reader {RATE}/s: sent {f_sent:,}, received {f_got:,}, "
              f"CPU {f_cpu:.3f} s", flush=True)
        floors.append((f_sent, f_got, us(f_cpu, f_got)))
    exact_n = sum(t[0] for t in trials)
    sent = sum(t[1] for t in trials)
    received = sum(t[2]["received"] for t in trials)
    lost = sum(t[2]["lost"] for t in trials)
    f_sent, f_got = sum(f[0] for f in floors), sum(f[1] for f in floors)
    mp_us, floor_us = median([t[3] for t in trials]), median([f[2] for f in floors])
    out.append((f"`--passive` at 100k frames/s, 3 x {seconds} s: sent / received / lost",
                f"{sent:,} / {received:,} / {lost:,}",
                f"plain reader received {f_got:,} of {f_sent:,}",
                "exact" if exact_n == 3 else f"exact in {exact_n} of 3"))
    out.append(("`--passive` at 100k frames/s: CPU per received frame, median (µs)",
                f"{mp_us:.2f}", f"{floor_us:.2f} (plain reader)", f"{mp_us / floor_us:.1f}x"))
    out.append(("`--passive` at 100k frames/s: CPU (% of a core), peak RSS",
                f"{median([t[4] for t in trials]):.1f} %", "",
                f"{max(t[5] for t in trials):,} KiB"))
    # pymavlink at the same rate, then stepped down to what it keeps up
    # with: every frame sent parsed (its own loss figure cannot say: the
    # kernel drops runs longer than its wrapping counter spans).
    p_sent, p_got, p_loss, p_cpu = pymavlink(RATE, seconds)
    print(f"bench: pymavlink {RATE}/s: parsed {p_got:,} of {p_sent:,}, its loss {p_loss:,}",
          flush=True)
    out.append(("pymavlink's mavutil at 100k frames/s: parsed, CPU per parsed frame (µs)",
                f"{mp_us:.2f}", f"{p_got:,} of {p_sent:,}, {us(p_cpu, p_got):.1f} µs",
                f"{us(p_cpu, p_got) / mp_us:.0f}x"))
    keeps_up = 0
    for rate in [50000, 20000, 10000, 5000, 2000]:
        r_sent, r_got, r_loss, r_cpu = pymavlink(rate, min(seconds, 5))
        print(f"bench: pymavlink {rate}/s: parsed {r_got:,} of {r_sent:,}, its loss {r_loss:,}, "
              f"{us(r_cpu, r_got):.1f} µs a frame", flush=True)
        if r_got >= 0.999 * r_sent:
            keeps_up = rate
            out.append((f"pymavlink's mavutil at {rate:,} frames/s: CPU per frame (µs)", "",
                        f"{us(r_cpu, r_got):.1f}", ""))
            break
    out.append(("frames/s kept up with, < 0.1 % lost", f"{RATE:,}",
                f"{keeps_up:,} (pymavlink)", f"{RATE / keeps_up:.0f}x" if keeps_up else "-"))
    ping_us, s = ping_cpu(mavping, RATE, seconds)
    out.append(("for scale: CPU per PING at 100k/s, send + reply (µs)", f"{ping_us:.2f}",
                "", f"{s['schedule']['achieved_rate_hz']:,.0f}/s achieved"))
    print("bench: passive done", flush=True)
    return out


def age_rows(mavping, before, quick):
    """`--age-against BINARY`: CPU per received frame of `--passive` at
    100k frames/s, this build (which reads every frame's clock stamp for
    its age) beside BINARY (a build before it, which does not), taking
    turns, three trials each, in the same run."""
    seconds = 4 if quick else 10
    per = {mavping: [], before: []}
    for _ in range(3):
        for binary in (mavping, before):
            sent, src, cpu, wall, rss = mavping_passive(binary, RATE, seconds)
            got = src["counts"]["received"] if src else 0
            ages = bool(src) and binary == mavping
            print(f"bench: age {os.path.basename(os.path.dirname(binary))}: sent {sent:,}, "
                  f"received {got:,}, CPU {cpu:.3f} s, RSS {rss:,} KiB", flush=True)
            per[binary].append((us(cpu, got), rss, ages))
    with_age, without = median([t[0] for t in per[mavping]]), median([t[0] for t in per[before]])
    return [("`--passive` at 100k frames/s: CPU per received frame, median (µs), with age "
             "tracking vs the build before", f"{with_age:.2f}", f"{without:.2f}",
             f"{with_age / without:.2f}x"),
            ("peak RSS (KiB)", f"{max(t[1] for t in per[mavping]):,}",
             f"{max(t[1] for t in per[before]):,}", "")]


def pair_trial(name, binary, links, seconds):
    """One trial of `--pair`: the figures of one column's run."""
    sent, srcs, pair, cpu, wall, rss, drops = mavping_links(binary, PAIR_RATE, seconds, links)
    counts = [s["counts"] if s else {"received": 0, "lost": 0, "duplicate": 0, "reordered": 0}
              for s in srcs]
    received = sum(c["received"] for c in counts)
    exact = all(c["received"] == sent and c["lost"] == 0 and c["duplicate"] == 0
                and c["reordered"] == 0 for c in counts)
    # What the kernel dropped is the only way a frame may go missing: any
    # other gap is a frame mavping read and did not count.
    unaccounted = sum(sent - c["received"] - d for c, d in zip(counts, drops))
    # Every frame on every link matched: one distinct frame and a later
    # copy on each other link for each frame sent, none lost on all.
    matched = (pair is not None and pair["distinct_frames"] == sent
               and pair["copies"] == sent * (links - 1) and pair["lost_on_every_link"] == 0
               and pair["conflicts"] == 0 and pair["late_beyond_window"] == 0)
    told = (f"; pair 1/1: distinct {pair['distinct_frames']:,}, copies {pair['copies']:,}, "
            f"lost on every link {pair['lost_on_every_link']:,}, conflicts "
            f"{pair['conflicts']:,}, late {pair['late_beyond_window']:,}"
            if pair else "; no pair report")
    got = " + ".join(f"{c['received']:,}" for c in counts)
    lost = " + ".join(f"{c['lost']:,}" for c in counts)
    dropped = " + ".join(f"{d:,}" for d in drops)
    print(f"bench: pair, {name}: sent {sent:,} a link, received {got}, lost {lost}, kernel "
          f"drops {dropped}, unaccounted {unaccounted:,}{told}; CPU {cpu:.3f} s, "
          f"RSS {rss:,} KiB", flush=True)
    return {"sent": sent, "received": received, "lost": sum(c["lost"] for c in counts),
            "drops": sum(drops), "unaccounted": unaccounted,
            "exact": exact, "pair": pair, "matched": matched, "us": us(cpu, received),
            "core": 100 * cpu / wall, "rss": rss}


def pair_cell(trials):
    """The pair report's figures, summed over a column's trials."""
    pairs = [t["pair"] for t in trials if t["pair"]]
    if not pairs:
        return "no pair report"
    distinct, copies, lost = (sum(p[key] for p in pairs)
                              for key in ("distinct_frames", "copies", "lost_on_every_link"))
    return (f"{distinct:,} / {copies:,} / {lost:,}; every frame matched in "
            f"{sum(t['matched'] for t in trials)} of {len(trials)}")


def pair_lag_cell(trials):
    """How far the copies came behind their first, the largest over a
    column's trials: a copy read 128 of the source's frames or more after
    its first cannot be matched (src/engine/pair/mod.rs)."""
    pairs = [t["pair"] for t in trials if t["pair"]]
    if not pairs:
        return ""
    return (f"{max(p['dedup_window_p999_ms'] or 0 for p in pairs):.2f} / "
            f"{max(p['copy_lag_max_ms'] or 0 for p in pairs):.2f} ms; "
            f"{sum(p['conflicts'] for p in pairs):,} conflicts")


def pair_rows(mavping, against, quick):
    """`--pair`: (the table's header, its rows), a column a kind of run,
    the kinds and the plain readers taking turns, three trials each, in
    the same run; then pymavlink's mavutil once on each."""
    seconds = 4 if quick else 10
    kinds = [("one link", mavping, 1), ("two links", mavping, 2)]
    header = ["figure", f"one link, {PAIR_RATE // 1000}k frames/s",
              f"two links, 2 x {PAIR_RATE // 1000}k frames/s, the same frames"]
    if against:
        kinds.append((f"two links, {against}", against, 2))
        header.append(f"two links, {os.path.basename(os.path.dirname(against))}'s build "
                      "(no pair tracker)")
    trials = [[] for _ in kinds]
    floors = [[] for _ in range(2)]
    for _ in range(3):
        for column, (name, binary, links) in zip(trials, kinds):
            column.append(pair_trial(name, binary, links, seconds))
        for links, column in zip((1, 2), floors):
            f_sent, f_got, f_cpu = floor(PAIR_RATE, seconds, links)
            print(f"bench: pair, plain reader on {links} link(s): sent {f_sent:,} a link, "
                  f"received {f_got:,}, CPU {f_cpu:.3f} s", flush=True)
            column.append((f_sent * links, f_got, us(f_cpu, f_got)))
    per_frame = [median([t["us"] for t in column]) for column in trials]
    floor_us = [median([f[2] for f in column]) for column in floors]
    # pymavlink's mavutil, a connection a link in one process as MAVProxy
    # holds its masters: it keeps up with about 20,000 frames/s on one.
    pym = []
    for links in (1, 2):
        p_sent, p_got, p_loss, p_cpu = pymavlink(PAIR_RATE, min(seconds, 5), links)
        print(f"bench: pair, pymavlink on {links} link(s): parsed {p_got:,} of "
              f"{p_sent * links:,}, its loss {p_loss:,}, CPU {p_cpu:.3f} s", flush=True)
        pym.append(f"parsed {p_got:,} of {p_sent * links:,}, {us(p_cpu, p_got):.1f} µs a frame")
    if against:
        floor_us.append(floor_us[1])
        pym.append("")

    def total(column, key):
        return sum(t[key] for t in column)

    rows = [
        (f"3 x {seconds} s: sent a link / received on all links / lost",
         *(f"{total(c, 'sent'):,} / {total(c, 'received'):,} / {total(c, 'lost'):,}"
           for c in trials)),
        ("the kernel's drops at the sockets / frames sent neither received nor dropped",
         *(f"{total(c, 'drops'):,} / {total(c, 'unaccounted'):,}" for c in trials)),
        ("every frame counted on every link, no loss, duplicate or reordering",
         *(f"in {total(c, 'exact')} of 3" for c in trials)),
        ("pair report, 1/1: distinct frames / later copies / lost on every link",
         *(pair_cell(c) for c in trials)),
        ("pair report, 1/1: copies' lag p99.9 / max, the largest of the trials; conflicts",
         *(pair_lag_cell(c) for c in trials)),
        ("CPU per received frame, median (µs)", *(f"{u:.2f}" for u in per_frame)),
        ("CPU per received frame against one link's", *(f"{u / per_frame[0]:.2f}x"
                                                        for u in per_frame)),
        ("plain reader, one a link: CPU per received frame, median (µs)",
         *(f"{u:.2f}" for u in floor_us)),
        ("mavping's CPU per received frame against the plain reader's",
         *(f"{u / f:.1f}x" for u, f in zip(per_frame, floor_us))),
        ("CPU (% of a core), median", *(f"{median([t['core'] for t in c]):.1f} %"
                                        for c in trials)),
        ("peak RSS (KiB)", *(f"{max(t['rss'] for t in c):,}" for c in trials)),
        (f"pymavlink's mavutil, a connection a link, {min(seconds, 5)} s", *pym),
    ]
    if against:
        rows.append(("the pair tracker's own cost: CPU per received frame against the build "
                     "without it", "", f"{per_frame[1] - per_frame[2]:+.2f} µs "
                     f"({per_frame[1] / per_frame[2]:.2f}x)", ""))
    print("bench: pair done", flush=True)
    return header, rows


def main():
    args = sys.argv[1:]
    mavping = (os.path.abspath(args[args.index("--binary") + 1]) if "--binary" in args
               else os.path.join(ROOT, "target", "release", "mavping"))
    load = os.getloadavg()[0]
    header = ["figure", "mavping", "baseline", "ratio"]
    if "--pair" in args or "--pair-against" in args:
        against = (os.path.abspath(args[args.index("--pair-against") + 1])
                   if "--pair-against" in args else None)
        header, table = pair_rows(mavping, against, "--quick" in args)
    elif "--age-against" in args:
        before = os.path.abspath(args[args.index("--age-against") + 1])
        table = age_rows(mavping, before, "--quick" in args)
    else:
        table = rows(mavping, "--quick" in args)
    print(f"\nload average at start {load:.2f}, at end {os.getloadavg()[0]:.2f} "
          f"(1-minute; {os.cpu_count()} CPUs)\n")
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for row in table:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
