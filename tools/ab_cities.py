#!/usr/bin/env python3
"""Two beamtrace builds, whole `trace` processes on the city scenes, in alternating runs.

The host's load moves a run's wall time by tens of percent from one minute to the next, so two
builds are only compared in the same minutes: each round runs every city once with each build,
in turn. Prints the best and the median of each build per city and the ratio of the bests.

    python3 tools/ab_cities.py OLD_BINARY NEW_BINARY [--rounds 7] [--scene munich ...]

The cities are Sionna RT's Munich, Etoile and Florence from testdata/scenes/sionna-rt, and its
San Francisco from an installed `sionna-rt` wheel when one is found (`--sionna-scenes DIR`),
with the terminals of issue 29 (`--max-order 3 --frequency 3.5e9 --json`, output discarded).
"""

import argparse
import glob
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TESTDATA = os.path.join(ROOT, "testdata", "scenes", "sionna-rt")
CITIES = {
    "etoile": ("{t}/etoile/etoile.xml", "0,0,30", "20,5,1.5"),
    "munich": ("{t}/munich/munich.xml", "8.5,21,27", "45,90,1.5"),
    "florence": ("{t}/florence/florence.xml", "5,-55,60", "0,-150,1.5"),
    "san_francisco": (
        "{s}/san_francisco/san_francisco.xml",
        "185.4021453857422,-86.6235580444336,45.3857421875",
        "-12.491729736328125,41.86780548095703,14.31640625",
    ),
}


def sionna_scenes():
    """The scenes folder of an installed sionna-rt wheel, or None."""
    found = glob.glob("/work/sionna-venv/lib/python3*/site-packages/sionna/rt/scenes")
    return found[0] if found else None


def command(binary, city, sionna):
    path, tx, rx = CITIES[city]
    scene = path.format(t=TESTDATA, s=sionna or "")
    return [binary, "trace", scene, "--tx", tx, "--rx", rx, "--max-order", "3",
            "--frequency", "3.5e9", "--json"]


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
    ap.add_argument("--scene", action="append", choices=sorted(CITIES),
                    help="a city to run (repeatable; default: all found)")
    ap.add_argument("--sionna-scenes", default=sionna_scenes(),
                    help="sionna-rt's scenes folder, for San Francisco")
    args = ap.parse_args(argv)
    for binary in (args.old, args.new):
        if not os.access(binary, os.X_OK):
            sys.exit(f"{binary}: not an executable (build one with "
                     "`cargo build --release -p beamtrace`)")
    if args.rounds < 1:
        sys.exit("--rounds: at least 1")
    cities = args.scene or [c for c in CITIES if c != "san_francisco" or args.sionna_scenes]
    if "san_francisco" in cities and not args.sionna_scenes:
        sys.exit("san_francisco needs --sionna-scenes (pip install sionna-rt in a venv)")
    times = {(b, c): [] for b in (args.old, args.new) for c in cities}
    for r in range(args.rounds):
        for city in cities:
            for binary in (args.old, args.new):
                times[(binary, city)].append(run(command(binary, city, args.sionna_scenes)))
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr, flush=True)
    print("| city | old, best (median) | new, best (median) | new / old, best |")
    print("|---|---:|---:|---:|")
    for city in cities:
        old, new = times[(args.old, city)], times[(args.new, city)]
        print(f"| {city} | {min(old) * 1e3:.1f} ms ({statistics.median(old) * 1e3:.1f}) "
              f"| {min(new) * 1e3:.1f} ms ({statistics.median(new) * 1e3:.1f}) "
              f"| {min(new) / min(old):.3f} |")


if __name__ == "__main__":
    main()
