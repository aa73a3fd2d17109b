#!/usr/bin/env python3
"""Issue 29's speed protocol: the whole ``beamtrace trace`` process against Sionna RT on its cities.

What it measures
----------------
For each of Sionna RT's city scenes committed under ``testdata/scenes/sionna-rt/`` (etoile,
florence, munich), and San Francisco from the installed sionna-rt wheel (not committed here: a
city no test was tuned on), with one fixed transmitter/receiver pair each, in the same minutes:

* **Sionna RT 2.2** (``PathSolver``, CPU LLVM backend, 1e6 samples, ``max_depth`` 3, specular
  reflection and line of sight only, ``synthetic_array``, isotropic V-polarised antennas,
  3.5 GHz): one warm-up call, then the best of ``--rounds`` warm calls. The scene load is not
  timed (warm, as the protocol says).
* **beamtrace**: the best of ``--rounds`` whole processes, ``beamtrace trace XML --tx .. --rx ..
  --max-order 3 --frequency 3.5e9 --json``, load included (wall time of the process).

Per scene, beamtrace's runs come first and Sionna's right after, so that both see the same
machine in the same minute (a pause of two seconds lets Sionna's worker threads go idle before
the next scene's beamtrace runs). It prints a Markdown
table: the times, their ratio, and the paths each tool found (Sionna's valid paths; beamtrace's
records), with a line saying whether beamtrace found at least as many. That every one of Sionna's
paths is among beamtrace's is tested separately (``crates/bt-solve/tests/it/sionna.rs``).

Install (outside the repository; see ``tools/sionna_reference.py`` for the details)
-----------------------------------------------------------------------------------
    apt-get install -y libllvm19
    python3 -m venv /work/sionna-venv && /work/sionna-venv/bin/pip install sionna-rt==2.2.0
    cargo build --release -p beamtrace

Run
---
    /work/sionna-venv/bin/python tools/city_speed.py                    # the four cities
    /work/sionna-venv/bin/python tools/city_speed.py --scene munich --rounds 5
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

# The reference script's paths, its DRJIT_LIBLLVM_PATH setting, seed and Sionna importer.
import sionna_reference as ref  # noqa: E402

from cities import (  # noqa: E402
    CASES, FREQUENCY_HZ, MAX_DEPTH, REPO, SCENES, find_xml, trace_command,
)

SAMPLES = 10**6
# Seconds of rest before a scene's beamtrace runs, for Sionna's threads to go idle.
SETTLE_S = 2.0


def scene_xml(name):
    """The scene's XML (``cities.find_xml``), or exit naming where it was looked for."""
    xml = find_xml(name)
    if xml is None:
        sys.exit(f"scene {name}: not in {SCENES} and sionna-rt is not installed")
    return xml


def sionna_setup(name, tx, rx):
    """The scene loaded by Sionna RT with one TX and one RX, and Sionna's default solver."""
    _, mi, rt = ref.import_sionna()
    from sionna.rt import PathSolver, PlanarArray, Receiver, Transmitter

    scene = rt.load_scene(str(scene_xml(name)), merge_shapes=False)
    scene.frequency = FREQUENCY_HZ
    scene.tx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.rx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.add(Transmitter(name="tx", position=mi.Point3f(*tx)))
    scene.add(Receiver(name="rx", position=mi.Point3f(*rx)))
    return scene, PathSolver()


def sionna_call(scene, solver):
    """One PathSolver call with the protocol's settings; its valid paths' count. (Not
    ``sionna_reference.solve``: that reads every output back to numpy, work the timing must
    not charge to Sionna.)"""
    paths = solver(
        scene,
        max_depth=MAX_DEPTH,
        max_num_paths_per_src=10**6,
        samples_per_src=SAMPLES,
        synthetic_array=True,
        los=True,
        specular_reflection=True,
        diffuse_reflection=False,
        refraction=False,
        diffraction=False,
        edge_diffraction=False,
        seed=ref.SEED,
    )
    return int(paths.valid.numpy().sum())


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return time.perf_counter() - t0, out


def beamtrace_call(binary, name, tx, rx):
    """One whole ``beamtrace trace`` process; its path records' count."""
    args = trace_command(binary, scene_xml(name), tx, rx)
    done = subprocess.run(args, capture_output=True, check=False)
    if done.returncode != 0:
        sys.exit(f"{' '.join(args)} failed: {done.stderr.decode(errors='replace')}")
    return len(json.loads(done.stdout)["paths"])


def measure(binary, name, tx, rx, rounds):
    """Best-of-`rounds` seconds of both tools and their path counts: beamtrace's processes
    first, then Sionna's calls (its LLVM backend's worker threads stay busy for a while after
    a call, and would take a core from a beamtrace process started right after it)."""
    best = {"sionna": float("inf"), "beamtrace": float("inf")}
    time.sleep(SETTLE_S)
    for r in range(rounds):
        t, ours = timed(lambda: beamtrace_call(binary, name, tx, rx))
        best["beamtrace"] = min(best["beamtrace"], t)
        print(f"  {name} beamtrace {r + 1}/{rounds}: {t:.3f} s", file=sys.stderr, flush=True)
    scene, solver = sionna_setup(name, tx, rx)
    sionna_call(scene, solver)  # warm-up: the kernels compile here
    for r in range(rounds):
        t, theirs = timed(lambda: sionna_call(scene, solver))
        best["sionna"] = min(best["sionna"], t)
        print(f"  {name} Sionna RT {r + 1}/{rounds}: {t:.3f} s", file=sys.stderr, flush=True)
    return best, ours, theirs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", action="append", choices=[c[0] for c in CASES],
                    help="a city to measure (repeatable; default: all four)")
    ap.add_argument("--rounds", type=int, default=3, help="turns of each tool (best of them)")
    ap.add_argument("--beamtrace", type=Path, default=REPO / "target" / "release" / "beamtrace",
                    help="the beamtrace binary (default: target/release/beamtrace)")
    args = ap.parse_args(argv)
    if args.rounds < 1:
        ap.error("--rounds must be at least 1")
    if not args.beamtrace.is_file():
        ap.error(f"--beamtrace {args.beamtrace}: no such file (cargo build --release -p beamtrace)")
    wanted = args.scene or [c[0] for c in CASES]
    print("| scene | TX → RX | beamtrace, whole process | Sionna RT, warm | ratio | paths (ours / Sionna's) |")
    print("|---|---|---:|---:|---:|---|")
    for name, tx, rx in (c for c in CASES if c[0] in wanted):
        best, ours, theirs = measure(args.beamtrace, name, tx, rx, args.rounds)
        ratio = best["sionna"] / best["beamtrace"]
        found = "" if ours >= theirs else " **fewer**"
        print(f"| {name} | {tx} → {rx} | {best['beamtrace']:.3f} s | {best['sionna']:.3f} s "
              f"| {ratio:.1f}× | {ours} / {theirs}{found} |", flush=True)


if __name__ == "__main__":
    main()
