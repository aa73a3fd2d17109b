#!/usr/bin/env python3
"""A client that sends `beamtrace serve` one receiver move every period and waits for each answer.

A device updates its tracer at a steady rate (a time step), not back to back: between requests
the server's threads wait, and the answer after a wait runs on cold caches. This measures
that: it starts ``beamtrace serve`` on the living room, sends a seeded random walk of receivers
(the same bounds and step as ``crates/bt-serve/examples/stream.rs``, another generator), one
request at the start of each period, reads each answer, and prints the percentiles of the
answers' own ``latency_us`` (in-process, from the parsed request to the serialised answer).
Receivers the walk puts on a surface get error answers, which are not counted.

Run (after ``cargo build --release -p beamtrace``):

    python3 tools/serve_clock.py --period-us 1000
    python3 tools/serve_clock.py --period-us 3000 -- --partner-spin-us 5000
    python3 tools/serve_clock.py --period-us 0        # back to back

Everything after ``--`` is passed to ``beamtrace serve``.
"""

import argparse
import json
import random
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def walk(seed, n):
    """Receivers (m, scene frame) a step of at most 0.2 m apart per axis, rounded to 1 mm."""
    rng = random.Random(seed)
    p = [2.3, 2.1, 0.72]
    bounds = [(0.3, 5.7), (0.3, 4.2), (0.3, 2.4)]
    out = []
    for _ in range(n):
        for k, (lo, hi) in enumerate(bounds):
            p[k] = round(min(max(p[k] + rng.uniform(-0.2, 0.2), lo), hi), 3)
        out.append(list(p))
    return out


def latency_us(line):
    """An answer's `latency_us`, read from its tail without parsing the whole line (a parse of
    its ~37 KB takes longer than the answer and would leave the server's core cold); None for
    an error answer."""
    key = b'"latency_us":'
    at = line.rfind(key)
    if at < 0:
        if b'"error":' not in line:
            sys.exit(f"an answer with neither latency_us nor error: {line[:200]!r}")
        return None
    end = at + len(key)
    while line[end:end + 1] not in (b",", b"}"):
        end += 1
    return float(line[at + len(key):end])


def percentiles(values):
    values = sorted(values)
    at = lambda q: values[int((len(values) - 1) * q)]
    return {"p50": at(0.5), "p90": at(0.9), "p99": at(0.99), "max": values[-1]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--period-us", type=float, default=1000.0,
                        help="time between the starts of two requests (0: back to back)")
    parser.add_argument("--moves", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=30)
    parser.add_argument("--max-order", type=int, default=3)
    parser.add_argument("--binary", default=str(REPO / "target/release/beamtrace"))
    parser.add_argument("serve_args", nargs="*", help="after --: more `serve` options")
    args = parser.parse_args()
    if args.moves < 1 or args.period_us < 0:
        parser.error("--moves must be at least 1 and --period-us at least 0")
    command = [args.binary, "serve", "builtin:living-room", "--max-order", str(args.max_order),
               *args.serve_args]
    try:
        server = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                  bufsize=1 << 20)
    except OSError as e:
        sys.exit(f"--binary {args.binary}: cannot start it ({e.strerror}); "
                 "build it with `cargo build --release -p beamtrace`")
    period = args.period_us * 1e-6
    latencies, errors = [], 0
    next_start = time.perf_counter()
    for i, rx in enumerate(walk(args.seed, args.moves)):
        while time.perf_counter() < next_start:
            pass
        next_start += period
        server.stdin.write(json.dumps({"id": i, "rx": rx}).encode() + b"\n")
        server.stdin.flush()
        line = server.stdout.readline()
        if not line:
            sys.exit(f"beamtrace serve ended early (request {i}): {command}")
        latency = latency_us(line)
        if latency is None:
            errors += 1
        else:
            latencies.append(latency)
        if (i + 1) % 1000 == 0:
            print(f"  {i + 1}/{args.moves} requests", file=sys.stderr, flush=True)
    server.stdin.close()
    server.wait()
    if not latencies:
        sys.exit("no answer without an error")
    p = percentiles(latencies)
    print(f"period {args.period_us:g} us, {len(latencies)} answers ({errors} errors): latency_us "
          f"p50 {p['p50']:.1f} p90 {p['p90']:.1f} p99 {p['p99']:.1f} max {p['max']:.1f}")


if __name__ == "__main__":
    main()
