#!/usr/bin/env python3
"""Reference paths from Sionna RT 2.2 with first-order diffraction.

What it is
----------
beamtrace is getting exact first-order edge diffraction. This script runs
Sionna RT's ``PathSolver`` on the Sionna scenes committed under
``testdata/scenes/sionna-rt/`` for a fixed list of cases (scene, TX, RX
positions, max_depth, frequency) and writes what Sionna found, one JSON file
per case, to ``testdata/sionna-reference/<case>.json``. Those files are the
data beamtrace's diffraction is compared with; ``docs/sionna-diffraction-notes.md``
describes Sionna's diffraction model (what to expect from these numbers).

Install (outside the repository; Debian 12, CPU only, no GPU needed)
--------------------------------------------------------------------
    apt-get install -y libllvm19           # Dr.Jit's CPU (LLVM) backend; 19 is the tested version
    python3 -m venv /work/sionna-venv
    /work/sionna-venv/bin/pip install sionna-rt==2.2.0
    export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1

(The script sets ``DRJIT_LIBLLVM_PATH`` itself when it is unset and that file
exists.) sionna-rt 2.2.0 pulls mitsuba 3.9.1 and drjit 1.5.0; Mitsuba's
``llvm_ad_mono_polarized`` variant is used, i.e. float32 everywhere.

Run
---
    /work/sionna-venv/bin/python tools/sionna_reference.py            # every case
    /work/sionna-venv/bin/python tools/sionna_reference.py --list     # case names and why each was chosen
    /work/sionna-venv/bin/python tools/sionna_reference.py --case wedge-shadow-d1 --case box-edges-d2
    /work/sionna-venv/bin/python tools/sionna_reference.py --no-timing   # skip the timing runs

Every case runs once, then (unless ``--no-timing``) three more times for a
warm best-of-3 wall time; the four results must be identical (the script
checks it), since the solver is built with ``PathSolver(deterministic=True)``
and a fixed seed. Everything but ``metadata`` (timings, host load) is
byte-identical from run to run and from process to process; with
``--no-timing`` there is no ``metadata``, so the whole file is. The whole set
takes about four minutes on an idle 2-core machine.

What it writes
--------------
``testdata/sionna-reference/<case>.json``::

    {
      "case": name, "why": why these positions,
      "sionna_rt": "2.2.0", "mitsuba": ..., "drjit": ..., "variant": ...,
      "scene": {"name", "xml" (repo-relative), "merge_shapes": false,
                "materials": {name: {itu_type, relative_permittivity,
                                     conductivity_S_per_m, thickness_m}}},
      "frequency_hz", "wavelength_m",
      "tx": {"position": [x,y,z], ...}, "max_depth",
      "solver": {every PathSolver argument used, deterministic, seed, antenna},
      "receivers": [
        {"index", "position", ..., "counts": {"los", "reflection_only",
         "with_diffraction", "total"},
         "total_power_db": 10 log10 sum |a|^2,
         "paths": [
           {"kinds": ["reflection"|"diffraction", ...]   (empty = line of sight),
            "vertices": [[x,y,z], ...]                     (world frame, metres),
            "shapes": [shape name, ...],
            "primitives": [triangle index within the shape, ...],
            "edges": [null | {"a":[x,y,z], "b":[x,y,z], "free": bool,
                              "faces": [prim, prim|null]}, ...],
            "a": [re, im], "gain_db": 20 log10 |a|,
            "tau_s": delay,
            "a_with_delay_phase": [re, im]  (a * exp(-j 2 pi f tau), float64),
            "length_m": c * tau}
         ]}
      ],
      "metadata": {"timing": {...}, "host": {...}}   (timing only without --no-timing)
    }

Conventions, read before comparing:

* ``a`` is Sionna's ``Paths.a`` for the single isotropic, V-polarised TX and
  RX antenna (``PlanarArray(1, 1, pattern="iso", polarization="V")``):
  the complex, unitless channel coefficient WITHOUT the propagation phase;
  Sionna applies ``exp(-j 2 pi f tau)`` only in ``Paths.cir()``/``cfr()``.
  ``a_with_delay_phase`` is that product, computed here in float64 from the
  float32 ``a`` and ``tau`` (so its phase carries the float32 rounding of
  tau: about 2 pi f tau 6e-8 rad, 0.08 degrees per microsecond at 3.5 GHz).
  Free-space LoS: ``|a| = lambda / (4 pi d)``.
* Sionna's diffraction paths are *sampled*, not enumerated: a diffraction
  path is found only when some shot ray lands near the edge's silhouette (see
  the notes). So each ``paths`` list is what Sionna found with these
  samples, a subset of the geometrically valid paths; reflection-only
  (specular chain) paths are found the same sampled way.
* Numbers from Sionna (vertices, a, tau) are float32, written as the
  shortest decimal that reads back to the same float32.
* For a diffraction interaction the ``edges`` entry names the triangle edge of
  ``primitives[i]`` on which the vertex lies (found here, geometrically,
  since ``Paths`` does not expose it), whether it is a free edge (no
  neighbouring triangle in that mesh: Sionna treats it as a screen, n = 2)
  and the two faces.
* Sionna's object ids (``Paths.objects``) are Dr.Jit registry indices that
  depend on what the process loaded before, so they are not written.
  ``shapes`` names the objects instead: the ``<shape id>`` of the XML without
  Sionna's ``mesh-`` prefix, as ``scene.objects`` names them
  (``merge_shapes=False``, so every PLY stays its own object, as beamtrace
  loads it).
* Paths are sorted per receiver by (number of interactions, kinds, vertices).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

# The repository and Sionna RT's committed scenes, named once for every tool.
from cities import REPO, SCENES  # noqa: E402

OUT = REPO / "testdata" / "sionna-reference"

_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(_LLVM):
    os.environ["DRJIT_LIBLLVM_PATH"] = _LLVM

import numpy as np  # noqa: E402

SPEED_OF_LIGHT = 299792458.0
INVALID = 0xFFFFFFFF
SEED = 42
SAMPLES = 10**7  # the diffraction paths found stop growing by 1e7 on simple_street_canyon
FREQ = 3.5e9

# --------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------
# Positions: "tx"/"rx" are world (x, y, z). Florence's are (x, y, h): h metres
# above the ground found by casting a ray straight down at (x, y).
#
# simple_wedge: two 30 m x 30 m concrete plates (the planes x = 0, y in
# [-30, 0] and y = 0, x in [0, 30]; z in [-15, 15]) meeting along the z axis:
# a 90 degree interior angle, so the exterior is 270 degrees and n = 1.5.
# Angles below are azimuths around the edge (the z axis): the exterior is
# 0 < phi < 270 deg, measured from the plate along +x. TX at phi' = 30 deg,
# 20 m from the edge, gives: reflection region phi < 150 (the +x plate
# reflects), lit region 150 < phi < 210, shadow region 210 < phi < 270.
WEDGE_TX = [17.3205, 10.0, 1.0]  # 20 m from the edge at phi' = 30 deg


def _polar(r, phi_deg, z):
    p = math.radians(phi_deg)
    return [round(r * math.cos(p), 4), round(r * math.sin(p), 4), z]


CASES = [
    dict(
        name="wedge-shadow-d1",
        scene="simple_wedge",
        tx=WEDGE_TX,
        rx=[_polar(15, 240, -0.5), _polar(15, 260, -0.5)],
        max_depth=1,
        why=(
            "TX at phi'=30 deg, 20 m from the wedge edge; RX 15 m from the edge at "
            "phi=240 and 260 deg, inside the shadow region (210..270 deg): no LoS, no "
            "reflection, only the edge-diffracted field (deep shadow at 260, 30 deg past "
            "the shadow boundary at 240). TX 1 m above, RX 0.5 m below the plates' "
            "mid-height, so the incidence is oblique (beta0 != 90 deg) and the "
            "diffraction point is off both heights (Keller cone)."
        ),
    ),
    dict(
        name="wedge-shadow-d2",
        scene="simple_wedge",
        tx=WEDGE_TX,
        rx=[_polar(15, 240, -0.5), _polar(15, 260, -0.5)],
        max_depth=2,
        why=(
            "Same TX/RX as wedge-shadow-d1 with max_depth 2: whether Sionna adds "
            "reflection+diffraction combinations or paths over the plates' free edges "
            "(it should not find any valid one here: such paths are blocked by the other "
            "plate or degenerate onto the edge)."
        ),
    ),
    dict(
        name="wedge-lit-d2",
        scene="simple_wedge",
        tx=WEDGE_TX,
        rx=[_polar(15, 180, 0.5), _polar(15, 100, 0.5)],
        max_depth=2,
        why=(
            "Same TX; RX at phi=180 deg is in the lit region (150..210: LoS, no reflection), "
            "RX at phi=100 deg in the reflection region (LoS + reflection off the +x "
            "plate): diffraction in the lit region, which Sionna adds by default "
            "(diffraction_lit_region=True), next to the GO field it should smooth, plus "
            "diffraction at the plates' free outer edges."
        ),
    ),
    dict(
        name="box-edges-d2",
        scene="box",
        tx=[-15.0, 1.0, 2.0],
        rx=[[8.0, -1.0, 7.0], [12.0, 9.0, 1.5], [15.0, -2.0, 1.5]],
        max_depth=2,
        why=(
            "Metal box x, y in -5..5, z in 0..5 (no ground); its ITU 'metal' (sigma = 1e7 S/m) "
            "is nearly PEC, so the coefficients can be checked against Kouyoumjian-Pathak. "
            "TX 10 m west of it at 2 m. RX0 east of the box at 7 m, above the roof: "
            "in the shadow of the west roof edge (90 deg wedge, n = 1.5), reached by one "
            "diffraction over it. RX1 north-east of the box at 1.5 m: the box hides it, one "
            "diffraction round the north-west vertical edge reaches it. RX2 straight "
            "behind the box at 1.5 m: every path needs two diffractions (over or round a "
            "10 m thick box), so Sionna (first order only) finds none: an empty reference."
        ),
    ),
    dict(
        name="one-screen-d2",
        scene="box_one_screen",
        tx=[-3.0, 1.0, 2.5],
        rx=[[3.0, -1.0, 2.0], [3.5, 2.5, 4.0], [2.0, -4.0, 1.0]],
        max_depth=2,
        why=(
            "A metal 10 x 10 x 5 m box cut by a glass screen at x = 0 from floor to ceiling, "
            "y in -3..3 (Sionna's own scene, not used before this case): TX west of the "
            "screen, every receiver east of it. No LoS; reached round the screen's vertical "
            "free edges at y = +-3 (alone, or with a reflection off the box before or after "
            "them) and by reflections through the 2 m gaps beside the screen."
        ),
    ),
    dict(
        name="two-screens-d2",
        scene="box_two_screens",
        tx=[-4.0, 0.5, 2.5],
        rx=[[0.0, 4.0, 3.0], [0.0, -1.0, 2.0], [4.0, -0.5, 2.0]],
        max_depth=2,
        why=(
            "The same box with two glass screens at x = -2 and x = 2 (y in -3..3). TX "
            "behind the first screen; RX0 and RX1 between the screens (round one screen's "
            "edge, with a reflection or not), RX2 behind the second screen: there every "
            "path needs two diffractions or reflections round both screens."
        ),
    ),
    dict(
        name="canyon-cars-d2",
        scene="simple_street_canyon_with_cars",
        tx=[-50.0, -3.0, 8.0],
        rx=[[20.0, 3.0, 1.5], [40.0, 7.6, 1.0], [-12.0, 8.0, 0.8]],
        max_depth=2,
        why=(
            "The street canyon with five cars parked along y in 4.7..6.5 (Sionna's own "
            "scene, not used before this case). TX 8 m up at the west end; RX0 in the "
            "street near a car, RX1 and RX2 behind cars (between the cars and the north "
            "buildings), below the cars' roofs: reached over and round the cars' edges and "
            "off the buildings."
        ),
    ),
    dict(
        name="canyon-d3",
        scene="simple_street_canyon",
        tx=[-45.0, 0.0, 10.0],
        rx=[[30.0, 0.0, 1.5], [23.5, 25.0, 1.5], [-23.0, -25.0, 1.5]],
        max_depth=3,
        why=(
            "TX 10 m up in the east-west street (y in -8.6..9.6). RX0 down the same street "
            "(LoS, ground and wall reflections; lit-region diffraction at building "
            "corners). RX1 round the corner in the north-south street x in 16..31.5: no "
            "LoS, reached by diffraction at the vertical corner edges (building_4's "
            "south-east corner at (16, 9.6) and building_2's south-west corner) and by "
            "reflection chains. RX2 round the other corner, in the street x in -31..-15 "
            "south of the main street: no LoS (building_1 blocks it), diffraction at "
            "building_1's north-east corner (-31, -8.6) or building_6's north-west corner."
        ),
    ),
    dict(
        name="canyon-refraction-d2",
        scene="simple_street_canyon",
        tx=[-45.0, 0.0, 10.0],
        rx=[[23.5, 25.0, 1.5], [-23.0, -25.0, 1.5], [30.0, 0.0, 1.5]],
        max_depth=2,
        refraction=True,
        diffraction=False,
        why=(
            "canyon-d3's positions with refraction (Sionna's thin-slab transmission: every "
            "material of the scene is an ITU slab 0.1 m thick) and no diffraction: the "
            "receivers round the corners are reached through buildings' walls (two "
            "crossings, or one crossing and a reflection), the one down the street also by "
            "LoS and reflections. beamtrace's `--transmission` is compared with it."
        ),
    ),
    dict(
        name="florence-mast-d3",
        scene="florence",
        tx_above_ground=[5.0, -55.0, 60.0],
        rx_above_ground=[[0.0, -150.0, 1.5], [46.0, -128.0, 1.5], [185.0, -40.0, 1.5]],
        max_depth=3,
        why=(
            "TX on a 60 m mast in Piazza del Duomo, between the Baptistery and the "
            "cathedral's facade, above most roofs (15-25 m). RX0 1.5 m above the street "
            "running south from the piazza (Via dei Calzaiuoli), down which the mast is "
            "seen (4.1 m from the nearest wall); RX1 in a 3 m wide east-west alley south of "
            "the cathedral (1.6 m from the walls), under the roofs' horizon: reached over "
            "roof edges (diffraction) and by reflections; RX2 in the piazza behind the "
            "cathedral's dome (114 m), in its shadow, 12 m from the nearest wall: "
            "diffraction round the dome/nave and reflections off the houses around the "
            "piazza. Ground heights found by casting a ray down (all 0 m: Florence's "
            "ground is the flat plane z = 0)."
        ),
    ),
    dict(
        name="munich-roof-d3",
        scene="munich",
        tx=[8.5, 21.0, 27.0],
        rx_above_ground=[[45.0, 90.0, 1.5], [60.0, 20.0, 1.5], [-50.0, 0.0, 1.5]],
        max_depth=3,
        why=(
            "The 40k-triangle city (38,936 triangles) of issue 28's speed target, with the TX "
            "of the city benchmarks (issue 29): 1 m above a 26 m roof at (8.5, 21), i.e. at "
            "z = 27 m. Three street receivers 1.5 m above the ground (z = 0): RX0 in an open "
            "square 39 m from the nearest wall, RX1 in a street 9 m from the walls, RX2 in a "
            "lane 4.5 m from them. Mostly reached over roof edges and by reflections."
        ),
    ),
    dict(
        name="primitives-d2",
        scene="mitsuba-primitives",
        xml="testdata/scenes/mitsuba-primitives.xml",
        tx=[-5.0, -3.0, 2.0],
        rx=[[5.0, -3.0, 1.5], [6.0, 2.0, 3.0], [-2.0, 1.0, 1.0]],
        max_depth=2,
        diffraction=False,
        why=(
            "Mitsuba's primitives, not meshes: a ground rectangle ([-1, 1]^2 scaled by 10) "
            "and a block (the cube [-1, 1]^3 scaled by 3, 1, 2, at (0, 5, 2)), a scene of "
            "ours that Sionna loads through Mitsuba. Specular only: RX0 in front of the "
            "block's south face, RX1 beside its east face (x = 3), RX2 close to the south "
            "face; reflections on the ground, the faces and both."
        ),
    ),
]

# --------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------


def f32(x) -> float:
    """The shortest decimal that reads back to the same float32, as a float."""
    return float(str(np.float32(x)))


def f32v(v) -> list:
    return [f32(c) for c in v]


def import_sionna():
    import drjit as dr
    import mitsuba as mi
    import sionna.rt as rt

    return dr, mi, rt


def load(case):
    """The case's scene: Sionna's own under ``SCENES``, or the repository file ``case["xml"]``."""
    dr, mi, rt = import_sionna()
    name = case["scene"]
    xml = REPO / case["xml"] if "xml" in case else SCENES / name / f"{name}.xml"
    scene = rt.load_scene(str(xml), merge_shapes=False)
    return scene, xml


def ground_height(scene, x, y):
    """Height of the first surface under (x, y), and the shape hit there."""
    dr, mi, rt = import_sionna()
    names = {o.object_id: n for n, o in scene.objects.items()}
    top = 10000.0
    ray = mi.Ray3f(mi.Point3f(x, y, top), mi.Vector3f(0, 0, -1))
    si = scene.mi_scene.ray_intersect(ray)
    if not bool(si.is_valid()[0]):
        raise SystemExit(f"no ground under ({x}, {y})")
    shape = names[int(dr.reinterpret_array(mi.UInt32, si.shape)[0])]
    return top - float(si.t[0]), shape


def clearance(scene, p, n_dirs=16):
    """Shortest horizontal distance from p to the scene (16 directions)."""
    dr, mi, rt = import_sionna()
    ang = np.arange(n_dirs) * 2 * np.pi / n_dirs
    o = mi.Point3f(np.full(n_dirs, p[0], np.float32), np.full(n_dirs, p[1], np.float32),
                   np.full(n_dirs, p[2], np.float32))
    d = mi.Vector3f(np.cos(ang).astype(np.float32), np.sin(ang).astype(np.float32),
                    np.zeros(n_dirs, np.float32))
    si = scene.mi_scene.ray_intersect(mi.Ray3f(o, d))
    t = np.where(si.is_valid().numpy(), si.t.numpy(), np.inf)
    return float(t.min())


def resolve_positions(case, scene):
    """World TX and RX positions, and notes on how they were found."""
    info = {}
    if "tx" in case:
        tx = [float(c) for c in case["tx"]]
    else:
        x, y, h = case["tx_above_ground"]
        g, shape = ground_height(scene, x, y)
        if shape != "ground":
            raise SystemExit(f"{case['name']}: TX mast foot ({x}, {y}) is on {shape}, not the ground")
        tx = [x, y, g + h]
        info["tx"] = {"ground_z": f32(g), "ground_shape": shape, "height_above_ground": h}
    rxs, rx_info = [], []
    if "rx" in case:
        rxs = [[float(c) for c in r] for r in case["rx"]]
        rx_info = [{} for _ in rxs]
    else:
        for x, y, h in case["rx_above_ground"]:
            g, shape = ground_height(scene, x, y)
            if shape != "ground":
                raise SystemExit(f"{case['name']}: RX ({x}, {y}) is on {shape}, not in a street")
            p = [x, y, g + h]
            rxs.append(p)
            rx_info.append({"ground_z": f32(g), "ground_shape": shape, "height_above_ground": h,
                            "horizontal_clearance_m": round(clearance(scene, p), 2)})
    return tx, rxs, info, rx_info


def material_table(scene):
    mats = {}
    for name, m in sorted(scene.radio_materials.items()):
        mats[name] = {
            "itu_type": getattr(m, "itu_type", None),
            "relative_permittivity": f32(m.relative_permittivity[0]),
            "conductivity_S_per_m": f32(m.conductivity[0]),
            "thickness_m": f32(m.thickness[0]),
            "scattering_coefficient": f32(m.scattering_coefficient[0]),
        }
    return mats


def solve(scene, case, solver):
    """One PathSolver call, with every output read back to numpy."""
    paths = solver(
        scene,
        max_depth=case["max_depth"],
        max_num_paths_per_src=10**6,
        samples_per_src=case.get("samples", SAMPLES),
        synthetic_array=True,
        los=True,
        specular_reflection=True,
        diffuse_reflection=False,
        refraction=case.get("refraction", False),
        diffraction=case.get("diffraction", True),
        edge_diffraction=case.get("diffraction", True),
        diffraction_lit_region=True,
        seed=SEED,
    )
    a_re, a_im = paths.a
    out = {
        "a_re": a_re.numpy(),
        "a_im": a_im.numpy(),
        "tau": paths.tau.numpy(),
        "valid": paths.valid.numpy(),
        "interactions": paths.interactions.numpy(),
        "vertices": paths.vertices.numpy(),
        "objects": paths.objects.numpy(),
        "primitives": paths.primitives.numpy(),
    }
    return out


def same(r1, r2):
    return all(np.array_equal(r1[k], r2[k]) for k in r1)


def triangle_edge(scene, obj_name, prim, p):
    """The edge of triangle `prim` of `obj_name` closest to p (the diffraction point)."""
    dr, mi, rt = import_sionna()
    mesh = scene.objects[obj_name].mi_mesh
    f = dr.unravel(mi.Point3u, mesh.faces_buffer()).numpy()[:, prim]
    v = dr.unravel(mi.Point3f, mesh.vertex_positions_buffer()).numpy()
    best = None
    for e in range(3):
        # Mitsuba's local edge e of a face runs from vertex e to vertex (e+1) % 3
        a = v[:, f[e]].astype(np.float64)
        b = v[:, f[(e + 1) % 3]].astype(np.float64)
        ab = b - a
        t = np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0)
        d = float(np.linalg.norm(a + t * ab - p))
        if best is None or d < best[0]:
            best = (d, e, a, b)
    d, e, a, b = best
    opp = int(mesh.opposite_dedge(mi.UInt(3 * prim + e))[0])
    other = None if opp == INVALID else opp // 3
    # Report the endpoints in a canonical order (lexicographic) so the bytes do
    # not depend on which of the two faces Sionna stored.
    ends = sorted([f32v(a), f32v(b)])
    faces = [prim] if other is None else sorted([prim, other])
    return {
        "a": ends[0],
        "b": ends[1],
        "free": other is None,
        "faces": faces if other is not None else [prim, None],
        "vertex_to_edge_m": round(d, 6),
    }


KIND = {1: "reflection", 2: "diffuse", 4: "refraction", 8: "diffraction"}


def paths_json(scene, res, rx_index, freq):
    names = {o.object_id: n for n, o in scene.objects.items()}
    n_paths = res["tau"].shape[-1]
    out = []
    for i in range(n_paths):
        if not res["valid"][rx_index, 0, i]:
            continue
        inter = res["interactions"][:, rx_index, 0, i]
        kinds, verts, objs, shapes, prims, edges = [], [], [], [], [], []
        for d in range(inter.shape[0]):
            k = int(inter[d])
            if k == 0:
                break
            kinds.append(KIND[k])
            v = res["vertices"][d, rx_index, 0, i].astype(np.float64)
            verts.append(f32v(v))
            obj = int(res["objects"][d, rx_index, 0, i])
            prim = int(res["primitives"][d, rx_index, 0, i])
            objs.append(obj)
            prims.append(prim)
            name = names.get(obj)
            shapes.append(name)
            edges.append(triangle_edge(scene, name, prim, v) if k == 8 else None)
        a = complex(float(res["a_re"][rx_index, 0, 0, 0, i]), float(res["a_im"][rx_index, 0, 0, 0, i]))
        tau = float(res["tau"][rx_index, 0, i])
        aph = a * complex(math.cos(-2 * math.pi * freq * tau), math.sin(-2 * math.pi * freq * tau))
        out.append({
            "kinds": kinds,
            "vertices": verts,
            "shapes": shapes,
            "primitives": prims,
            "edges": edges,
            "a": [f32(a.real), f32(a.imag)],
            "gain_db": round(20 * math.log10(abs(a)), 6) if a != 0 else None,
            "tau_s": f32(tau),
            "a_with_delay_phase": [aph.real, aph.imag],
            "length_m": round(tau * SPEED_OF_LIGHT, 6),
        })
    out.sort(key=lambda p: (len(p["kinds"]), p["kinds"], p["vertices"]))
    # Flag exact duplicates (same kinds and vertices within 1 mm): Sionna
    # deduplicates candidates by hashing, so none are expected.
    for j, p in enumerate(out):
        for q in range(j):
            o = out[q]
            if o["kinds"] == p["kinds"] and np.allclose(o["vertices"], p["vertices"], atol=1e-3):
                p["duplicate_of"] = q
                break
    return out


def counts(paths):
    los = sum(1 for p in paths if not p["kinds"])
    diff = sum(1 for p in paths if "diffraction" in p["kinds"])
    refl = sum(1 for p in paths if p["kinds"] and "diffraction" not in p["kinds"])
    return {"los": los, "reflection_only": refl, "with_diffraction": diff, "total": len(paths)}


def host_info():
    cpu = platform.processor()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": cpu, "logical_cpus": os.cpu_count(), "python": platform.python_version(),
            "load_avg_1min_at_start": round(os.getloadavg()[0], 2)}


def run_case(case, timing=True):
    dr, mi, rt = import_sionna()
    from sionna.rt import PathSolver, PlanarArray, Receiver, Transmitter

    scene, xml = load(case)
    freq = case.get("frequency", FREQ)
    scene.frequency = freq
    scene.tx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.rx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    tx, rxs, tx_info, rx_info = resolve_positions(case, scene)
    scene.add(Transmitter(name="tx", position=mi.Point3f(*tx)))
    for i, r in enumerate(rxs):
        scene.add(Receiver(name=f"rx{i}", position=mi.Point3f(*r)))

    solver = PathSolver(deterministic=True)
    load_avg = host_info()
    t0 = time.perf_counter()
    res = solve(scene, case, solver)
    cold = time.perf_counter() - t0
    times, cpu = [], []
    if timing:
        for _ in range(3):
            t0, c0 = time.perf_counter(), time.process_time()
            again = solve(scene, case, solver)
            times.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            if not same(res, again):
                raise SystemExit(f"{case['name']}: two runs of the deterministic solver differ")

    receivers = []
    for i, r in enumerate(rxs):
        paths = paths_json(scene, res, i, freq)
        power = sum(p["a"][0] ** 2 + p["a"][1] ** 2 for p in paths)
        entry = {"index": i, "name": f"rx{i}", "position": f32v(r)}
        entry.update(rx_info[i])
        entry["counts"] = counts(paths)
        entry["total_power_db"] = round(10 * math.log10(power), 6) if power > 0 else None
        entry["paths"] = paths
        receivers.append(entry)

    doc = {
        "case": case["name"],
        "why": case["why"],
        "sionna_rt": rt.__version__,
        "mitsuba": mi.__version__,
        "drjit": dr.__version__,
        "variant": mi.variant(),
        "scene": {
            "name": case["scene"],
            "xml": str(xml.relative_to(REPO)),
            "xml_sha256": hashlib.sha256(xml.read_bytes()).hexdigest(),
            "merge_shapes": False,
            "materials": material_table(scene),
        },
        "frequency_hz": freq,
        "wavelength_m": SPEED_OF_LIGHT / freq,
        "tx": dict({"position": f32v(tx)}, **tx_info.get("tx", {})),
        "max_depth": case["max_depth"],
        "solver": {
            "class": "PathSolver(deterministic=True)",
            "max_depth": case["max_depth"],
            "max_num_paths_per_src": 10**6,
            "samples_per_src": case.get("samples", SAMPLES),
            "synthetic_array": True,
            "los": True,
            "specular_reflection": True,
            "diffuse_reflection": False,
            "refraction": case.get("refraction", False),
            "diffraction": case.get("diffraction", True),
            "edge_diffraction": case.get("diffraction", True),
            "diffraction_lit_region": True,
            "seed": SEED,
            "antenna": 'PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V") at TX and RX',
            "load_scene": "load_scene(xml, merge_shapes=False)",
        },
        "receivers": receivers,
    }
    if timing:
        doc["metadata"] = {
            "timing": {
                "what": "wall time of one PathSolver call plus reading a, tau, valid, interactions, "
                        "vertices, objects, primitives back to numpy (CPU, LLVM backend)",
                "cold_first_call_s": round(cold, 3),
                "warm_runs_s": [round(t, 3) for t in times],
                "warm_best_of_3_s": round(min(times), 3),
                "warm_runs_cpu_s": [round(t, 3) for t in cpu],
                "cpu_note": "process CPU time of the same runs, all of Dr.Jit's threads: less "
                            "sensitive than wall time to other jobs sharing the cores",
            },
            "host": dict(load_avg, load_avg_1min_at_end=round(os.getloadavg()[0], 2)),
        }
    return doc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", action="append", help="run only this case (repeatable)")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--no-timing", action="store_true", help="one run per case, no metadata.timing")
    ap.add_argument("--out", type=Path, default=OUT, help=f"output folder (default {OUT.relative_to(REPO)})")
    args = ap.parse_args(argv)

    if args.list:
        for c in CASES:
            print(f"{c['name']}: {c['scene']}, max_depth {c['max_depth']}\n    {c['why']}\n")
        return 0
    wanted = set(args.case or [c["name"] for c in CASES])
    unknown = wanted - {c["name"] for c in CASES}
    if unknown:
        raise SystemExit(f"unknown case(s): {', '.join(sorted(unknown))}")
    args.out.mkdir(parents=True, exist_ok=True)
    for c in CASES:
        if c["name"] not in wanted:
            continue
        t0 = time.perf_counter()
        doc = run_case(c, timing=not args.no_timing)
        path = args.out / f"{c['name']}.json"
        path.write_text(json.dumps(doc, indent=1) + "\n")
        summary = "; ".join(
            f"rx{r['index']}: {r['counts']['los']} LoS, {r['counts']['reflection_only']} refl, "
            f"{r['counts']['with_diffraction']} diffr" for r in doc["receivers"])
        tm = doc.get("metadata", {}).get("timing", {}).get("warm_best_of_3_s")
        print(f"{c['name']}: {summary}; warm best {tm} s; total {time.perf_counter() - t0:.1f} s -> "
              f"{path.relative_to(REPO) if path.is_relative_to(REPO) else path}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
