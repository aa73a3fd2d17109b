"""Time ``Scene.trace_many`` over 1,000 receivers of the living room (order 3, the full report
and its NumPy columns), on one core (``parallel=False``) and on all of them, alternating runs
so that all see the same load; prints the best run of each and their ratio
(docs/performance.md). Three ways to use the result are timed:

- ``list``: the call as most callers make it, a list of ``Paths`` (each receiver's columns
  are made when first read, and none is read here);
- ``flat``: ``flat=True``, one dict of columns for all receivers;
- ``list+read``: the list, then every column of every receiver read (each receiver's
  per-path arrays made).

The receivers are uniform random points of the room, or with ``walk`` the receivers of
``serve_walk.py``'s walk (0.2 m steps: nearby receivers, as a moving device gives). Run with
the package installed:

    python python/bench/trace_many.py [RECEIVERS] [RUNS] [random|walk]
"""

import sys
import time

import numpy as np

import beamtrace
from serve_walk import walk

MODES = ("list", "flat", "list+read")


def run(scene, rx, parallel: bool, mode: str):
    many = scene.trace_many(
        None, rx, max_order=3, parallel=parallel, on_error="skip", flat=mode == "flat"
    )
    if mode == "list+read":
        for paths in many:
            if paths is not None:
                paths.to_dict()
    return many


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    scene = beamtrace.load("builtin:living-room")
    if (sys.argv[3] if len(sys.argv) > 3 else "random") == "walk":
        rx = np.array(list(walk(count)))
    else:
        rng = np.random.default_rng(30)
        lo, hi = np.array([0.3, 0.3, 0.3]), np.array([5.7, 4.2, 2.4])
        rx = np.round(lo + (hi - lo) * rng.random((count, 3)), 3)
    best = {(m, p): float("inf") for m in MODES for p in (False, True)}
    for _ in range(runs):
        for mode in MODES:
            for parallel in (False, True):
                t0 = time.perf_counter()
                many = run(scene, rx, parallel, mode)
                best[mode, parallel] = min(best[mode, parallel], time.perf_counter() - t0)
                del many
    flat = scene.trace_many(None, rx, max_order=3, on_error="skip", flat=True)
    traced, paths = int(flat["traced"].sum()), len(flat["rank"])
    print(f"{count} receivers ({traced} traced, {paths} paths), order 3, best of {runs}:")
    for mode in MODES:
        one, all_cores = (best[mode, p] / count * 1e6 for p in (False, True))
        print(
            f"  {mode:10} one core: {one:6.1f} us per receiver, "
            f"all cores: {all_cores:6.1f} us ({one / all_cores:.2f}x)"
        )


if __name__ == "__main__":
    main()
