#!/usr/bin/env python3
"""Two beamtrace builds, whole `trace` processes on the city scenes, in alternating runs.

The host's load moves a run's wall time by tens of percent from one minute to the next, so two
builds are only compared in the same minutes: each round runs every city once with each build,
in turn. Prints the best and the median of each build per city and the ratio of the bests.

    python3 tools/ab_cities.py OLD_BINARY NEW_BINARY [--rounds 7] [--scene munich ...]

The cities are `cities.CASES` (those of `city_speed.py`): Munich, Florence and Etoile from
testdata/scenes/sionna-rt, and San Francisco when an installed sionna-rt wheel has it (run with
that venv's Python), traced as `city_speed.py` traces them (output discarded).
"""

import argparse
import os
import statistics
import subprocess
import sys
import time

from cities import CASES, find_xml, trace_command


def run(cmd):
    """Wall seconds of one whole process; exits with its stderr if it fails."""
    start = time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({done.returncode}): "
                 f"{done.stderr.decode(errors='replace').strip()[-400:]}")
    return seconds


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old", help="the first build's beamtrace binary")
    ap.add_argument("new", help="the second build's beamtrace binary")
    ap.add_argument("--rounds", type=int, default=7, help="alternating rounds (default 7)")
    ap.add_argument("--scene", action="append", choices=[c[0] for c in CASES],
                    help="a city to run (repeatable; default: every one whose scene is found)")
    args = ap.parse_args(argv)
    for binary in (args.old, args.new):
        if not os.access(binary, os.X_OK):
            sys.exit(f"{binary}: not an executable (build one with "
                     "`cargo build --release -p beamtrace`)")
    if args.rounds < 1:
        sys.exit("--rounds: at least 1")
    wanted = args.scene or [c[0] for c in CASES]
    cases = [(name, find_xml(name), tx, rx) for name, tx, rx in CASES if name in wanted]
    for name, xml, _, _ in cases:
        if xml is None and args.scene:
            sys.exit(f"{name}: scene not found (San Francisco needs an installed sionna-rt: "
                     "run this script with that venv's Python)")
    cases = [c for c in cases if c[1] is not None]
    names = [c[0] for c in cases]
    times = {(b, c): [] for b in (args.old, args.new) for c in names}
    for r in range(args.rounds):
        for city, xml, tx, rx in cases:
            for binary in (args.old, args.new):
                times[(binary, city)].append(run(trace_command(binary, xml, tx, rx)))
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr, flush=True)
    print("| city | old, best (median) | new, best (median) | new / old, best |")
    print("|---|---:|---:|---:|")
    for city in names:
        old, new = times[(args.old, city)], times[(args.new, city)]
        print(f"| {city} | {min(old) * 1e3:.1f} ms ({statistics.median(old) * 1e3:.1f}) "
              f"| {min(new) * 1e3:.1f} ms ({statistics.median(new) * 1e3:.1f}) "
              f"| {min(new) / min(old):.3f} |")


if __name__ == "__main__":
    main()
