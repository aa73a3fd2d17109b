"""Time ``Scene.trace_many`` over 1,000 receivers of the living room (order 3, the full report
and its NumPy columns), on one core (``parallel=False``) and on all of them, alternating runs
so that both see the same load; prints the best run of each and their ratio
(docs/performance.md). Run with the package installed:

    python python/bench/trace_many.py [RECEIVERS] [RUNS]
"""

import sys
import time

import numpy as np

import beamtrace


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    scene = beamtrace.load("builtin:living-room")
    rng = np.random.default_rng(30)
    lo, hi = np.array([0.3, 0.3, 0.3]), np.array([5.7, 4.2, 2.4])
    rx = np.round(lo + (hi - lo) * rng.random((count, 3)), 3)
    best = {False: float("inf"), True: float("inf")}
    for _ in range(runs):
        for parallel in (False, True):
            t0 = time.perf_counter()
            paths = scene.trace_many(None, rx, max_order=3, parallel=parallel, on_error="skip")
            best[parallel] = min(best[parallel], time.perf_counter() - t0)
    traced = sum(p is not None for p in paths)
    one, all_cores = best[False] / count * 1e6, best[True] / count * 1e6
    print(f"{count} receivers ({traced} traced), order 3, best of {runs}:")
    print(f"  one core:  {one:.1f} us per receiver")
    print(f"  all cores: {all_cores:.1f} us per receiver ({one / all_cores:.2f}x)")


if __name__ == "__main__":
    main()
