"""Write a seeded random walk of receivers in the living room as `beamtrace serve` requests,
one JSON line each (0.2 m steps on a millimetre grid, 0.3 m from the walls), for timing a
whole `serve` stream (docs/performance.md). Needs only Python's standard library:

    python3 python/bench/serve_walk.py 10000 > /tmp/serve-walk.jsonl
"""

import random
import sys


def walk(count: int):
    """The walk's receivers, [x, y, z] in metres, in order."""
    rng = random.Random(30)
    p = [2.3, 2.1, 0.72]
    bounds = [(0.3, 5.7), (0.3, 4.2), (0.3, 2.4)]
    for _ in range(count):
        for k, (lo, hi) in enumerate(bounds):
            p[k] = round(min(max(p[k] + rng.uniform(-0.2, 0.2), lo), hi) * 1000) / 1000
        yield list(p)


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
    out = sys.stdout
    for i, p in enumerate(walk(count)):
        out.write('{"id": %d, "rx": [%s, %s, %s]}\n' % (i, p[0], p[1], p[2]))

if __name__ == "__main__":
    main()
