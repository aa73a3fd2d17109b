#!/usr/bin/env python3
"""Time Sionna RT on the 10,000-receiver Munich map of docs/performance.md (issue 29).

The same receivers as ``beamtrace sweep testdata/scenes/sionna-rt/munich/munich.xml --tx
8.5,21,27 --grid=-250:245:5,-250:245:5,1.5 --max-order 2``: a 100 x 100 grid at 1.5 m,
specular reflections up to depth 2, 3.5 GHz, isotropic V antennas, on Sionna's LLVM CPU
backend. Two ways a Sionna user gets such a map:

- ``RadioMapSolver`` on the grid's cells (5 m, centred on the receivers), 1e6 samples;
- ``PathSolver`` with the 10,000 receivers, 1e6 samples.

Each is run once cold and three times warm; the best warm wall and CPU times are printed
as JSON, the radio map's first. The PathSolver part takes many minutes on 2 cores (its cold
call had not finished after 4.5 minutes when it was first tried); ``--skip-paths`` leaves it
out. Needs a venv with ``sionna-rt`` (see testdata/sionna-reference/README.md):

    /work/sionna-venv/bin/python tools/sionna_radio_map.py [--skip-paths]
"""

import argparse
import json
import os
import time
from pathlib import Path

SCENE = Path(__file__).resolve().parent.parent / "testdata/scenes/sionna-rt/munich/munich.xml"
TX = (8.5, 21.0, 27.0)
XS = [-250.0 + 5.0 * i for i in range(100)]
HEIGHT = 1.5
SAMPLES = 10**6


def timed(run):
    """Cold run, then the best of three warm runs: (cold wall, best wall, best CPU), s."""
    t0 = time.perf_counter()
    run()
    cold = time.perf_counter() - t0
    walls, cpus = [], []
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        run()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return cold, min(walls), min(cpus)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-paths", action="store_true", help="only the RadioMapSolver")
    args = parser.parse_args()
    import mitsuba as mi
    import sionna.rt as rt

    scene = rt.load_scene(str(SCENE), merge_shapes=False)
    scene.frequency = 3.5e9
    scene.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.rx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.add(rt.Transmitter(name="tx", position=mi.Point3f(*TX)))
    out = {"sionna_rt": rt.__version__, "load_average": os.getloadavg()[0], "samples": SAMPLES}

    solver = rt.RadioMapSolver()

    def radio_map():
        rm = solver(
            scene,
            center=mi.Point3f(-2.5, -2.5, HEIGHT),
            orientation=mi.Point3f(0.0, 0.0, 0.0),
            size=mi.Point2f(500.0, 500.0),
            cell_size=mi.Point2f(5.0, 5.0),
            samples_per_tx=SAMPLES,
            max_depth=2,
            los=True,
            specular_reflection=True,
            diffuse_reflection=False,
            refraction=False,
        )
        return rm.path_gain.numpy()

    out["radio_map_s"] = dict(zip(["cold", "warm_wall", "warm_cpu"], timed(radio_map)))
    print(json.dumps(out), flush=True)
    if args.skip_paths:
        return
    for i, x in enumerate(XS):
        for j, y in enumerate(XS):
            scene.add(rt.Receiver(name=f"rx{i}_{j}", position=mi.Point3f(x, y, HEIGHT)))
    paths = rt.PathSolver()

    def path_map():
        p = paths(
            scene,
            max_depth=2,
            samples_per_src=SAMPLES,
            synthetic_array=True,
            los=True,
            specular_reflection=True,
            diffuse_reflection=False,
            refraction=False,
        )
        return p.a[0].numpy()

    out["path_solver_s"] = dict(zip(["cold", "warm_wall", "warm_cpu"], timed(path_map)))
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
