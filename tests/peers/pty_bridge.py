#!/usr/bin/env python3
"""A null-modem cable made of two pseudo-terminals, like
`socat pty,raw,echo=0 pty,raw,echo=0`, with nothing to install.

Prints "ready", then one line "A_PATH B_PATH" (the two device paths), and
copies bytes between them. Killing it is unplugging the cable: both ends
see the device hang up. --chunk splits what B sends into small pieces with
a pause between them, so frames arrive split across reads. --link-a makes
a symlink to A's device, so a restarted bridge reappears under one name.
Prints one JSON line of ground truth on SIGTERM.
"""
import argparse
import json
import os
import sys
import time

import ptys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--chunk", type=int, default=0, help="forward B->A in pieces of this many bytes")
    ap.add_argument("--chunk-delay-ms", type=float, default=3.0)
    ap.add_argument("--link-a", default="", help="symlink to A's device path")
    args = ap.parse_args()

    (ma, pa), (mb, pb) = ptys.open_raw_pair()
    if args.link_a:
        tmp = args.link_a + ".tmp"
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(pa, tmp)
        os.replace(tmp, args.link_a)

    until = ptys.UntilSignalled()
    print("ready", flush=True)
    print(pa, pb, flush=True)
    truth = {"a_to_b": 0, "b_to_a": 0}
    while until.running:
        for fd, data in ptys.read_ready([ma, mb], 0.05):
            if fd == ma:
                os.write(mb, data)
                truth["a_to_b"] += len(data)
            elif args.chunk > 0:
                for i in range(0, len(data), args.chunk):
                    os.write(ma, data[i:i + args.chunk])
                    time.sleep(args.chunk_delay_ms / 1000.0)
                truth["b_to_a"] += len(data)
            else:
                os.write(ma, data)
                truth["b_to_a"] += len(data)
    print(json.dumps(truth), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
