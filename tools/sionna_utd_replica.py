#!/usr/bin/env python3
"""Sionna RT 2.2's diffraction coefficient, re-done in numpy, next to Kouyoumjian-Pathak.

Why: docs/sionna-diffraction-notes.md says what Sionna 2.2 computes for a
diffracted path; this file is that statement in code, checked against
Sionna's own numbers. ``--check`` takes every path in
``testdata/sionna-reference/*.json`` that is a single diffraction (TX -> edge
-> RX, no reflection), rebuilds the wedge from the scene mesh the way
``sionna/rt/utils/wedges.py`` does, evaluates the Jones matrix the way
``RadioMaterial._diffraction_matrix`` does, and prints the replica's ``a``
beside Sionna's, and beside what Kouyoumjian-Pathak (PEC) and Luebbers
(lossy, same ITU slab reflection coefficients) give for the same geometry and
the same V-polarised antennas.

``--check`` then does the same for every path that reflects before or after
its diffraction: the Jones chain of Sionna's reflections
(``jones_matrix_to_world_implicit`` with the ITU slab coefficients) and the
diffraction, with the spreading 1/sqrt(s s' (s + s')) that
``FieldCalculator.transport_electric_field`` applies. It uses the diffracted leg
s that Sionna 2.2 actually computes, which is not the unfolded length for a
path that reflects after its edge and has fewer interactions than the solver's
``max_depth``: ``FieldCalculator._diffraction_compute_s_s_prime`` reads one
vertex slot past the path's end, where ``ImageMethod.
_compute_diffraction_point_images`` left the image X of the diffraction point
through the later reflections' planes, so s = s_unfolded - |RX - P| + |X - P| +
|RX - X| (P the last interaction point). Each such path is printed with the
replica's gain for both legs (``sionna_leg``). Result on the committed
reference: the 55 single diffractions within 9.2e-4 of Sionna's ``a``
(relative), the 269 paths with reflections within 6.6e-4, 84 of them with the
leg grown (the unfolded leg 2.2-8.2 dB above Sionna there), except two Florence
paths on free edges where Sionna's gain is 55 and 110 dB below the replica's
(listed apart, not explained here). Exit status 1 if any other path is off by
more than 1e-3.

``--solver-depth`` runs Sionna itself on the canyon case with max_depth 2, 3
and 4 and prints, for every [diffraction, reflection] path found at all three,
the gain each depth reports: the same path loses 2-8 dB from depth 2 to 3 (the
leg above), and nothing from 3 to 4.

``--boundaries`` puts the same formula on a PEC wedge and prints the total
(GO + diffracted) field just before and after the reflection and incident
shadow boundaries, for Sionna's formula and for Kouyoumjian-Pathak.

``--unit-cases`` prints, for a few synthetic wedges (the faces as triangles,
swapped as Sionna does), the four V/H path gains the formula gives; these are
the reference numbers of bt-channel's unit test
``sionna_coefficient_matches_the_replica`` (numpy/scipy only, no Sionna).

Run (needs the venv of tools/sionna_reference.py, for loading the meshes):

    /work/sionna-venv/bin/python tools/sionna_utd_replica.py --check
    /work/sionna-venv/bin/python tools/sionna_utd_replica.py --boundaries
    /work/sionna-venv/bin/python tools/sionna_utd_replica.py --unit-cases
    /work/sionna-venv/bin/python tools/sionna_utd_replica.py --solver-depth

Conventions (all in the notes): phi, phi' are measured from the 0-face through
the exterior, the 0-face is the face whose outward normal faces the incident
wave, e is oriented so that n0 x e runs along the 0-face away from the edge,
and Sionna's Jones vectors are (E . s, E . (k x s)) with s = theta_hat(k).
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys
from pathlib import Path

import numpy as np
from scipy.special import fresnel

C0 = 299792458.0
EPS0 = 8.8541878128e-12
REPO = Path(__file__).resolve().parents[1]
# A chain path whose Sionna gain is this far below the replica's is listed apart by --check
# (two Florence paths, 55 and 110 dB below; dB).
FAR_BELOW_DB = 40.0


def nrm(v):
    return v / np.linalg.norm(v)


def F(x):
    """UTD transition function F(x) = 2j sqrt(x) e^{jx} int_sqrt(x)^inf e^{-jt^2} dt."""
    x = float(x)
    u = np.sqrt(2 * x / np.pi)
    S, C = fresnel(u)
    tail = np.sqrt(np.pi / 2) * ((0.5 - C) - 1j * (0.5 - S))
    return 2j * np.sqrt(x) * np.exp(1j * x) * tail


def slab(cos, eta, d, lam):
    """ITU-R P.2040 single-layer slab reflection coefficients (r_te, r_tm), as Sionna."""
    a = np.sqrt(eta - (1 - cos**2) + 0j)
    rte = (cos - a) / (cos + a)
    rtm = (eta * cos - a) / (eta * cos + a)
    e2 = np.exp(-2j * (2 * np.pi * d / lam) * a)
    return rte * (1 - e2) / (1 - rte**2 * e2), rtm * (1 - e2) / (1 - rtm**2 * e2)


def theta_hat(k):
    th = np.arccos(np.clip(k[2], -1, 1))
    ph = np.arctan2(k[1], k[0])
    return np.array([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), -np.sin(th)])


def rotator(k, s_cur, s_tgt):
    """Sionna's jones_matrix_rotator: components in basis (s_cur, k x s_cur) -> (s_tgt, k x s_tgt)."""
    c = s_cur @ s_tgt
    s = k @ np.cross(s_cur, s_tgt)
    return np.array([[c, s], [-s, c]])


def utd_terms(phi, phip, n, k, L, beta0):
    """D1..D4 of Kouyoumjian-Pathak, each with the factor -e^{-j pi/4} / (2 n sqrt(2 pi k) sin beta0)."""
    ext = n * np.pi

    def a_pm(beta):
        n_p = np.round((beta + np.pi) / (2 * ext))
        n_m = np.round((beta - np.pi) / (2 * ext))
        return 2 * np.cos(ext * n_p - beta / 2) ** 2, 2 * np.cos(ext * n_m - beta / 2) ** 2

    fac = -np.exp(-1j * np.pi / 4) / (2 * n * np.sqrt(2 * np.pi * k) * np.sin(beta0))
    a1, a2 = a_pm(phi - phip)
    a3, a4 = a_pm(phi + phip)
    cot = lambda x: np.cos(x) / np.sin(x)  # noqa: E731
    kl = k * L
    d1 = fac * cot((np.pi + (phi - phip)) / (2 * n)) * F(kl * a1)
    d2 = fac * cot((np.pi - (phi - phip)) / (2 * n)) * F(kl * a2)
    d3 = fac * cot((np.pi + (phi + phip)) / (2 * n)) * F(kl * a3)
    d4 = fac * cot((np.pi - (phi + phip)) / (2 * n)) * F(kl * a4)
    return d1, d2, d3, d4


def wedge(v0, v1, f0, fn, ki):
    """Sionna's wedge_geometry + swap_faces: outward n0, nn, edge direction e.

    v0, v1: edge endpoints; f0, fn: the two triangles (3x3 vertex arrays);
    fn is None for a free edge (a screen: nn = -n0).
    """
    def normal(f):
        return nrm(np.cross(f[1] - f[0], f[2] - f[0]))

    c0 = f0.mean(0)
    n0 = normal(f0)
    if fn is None:
        cn, nn = c0, -n0
    else:
        cn, nn = fn.mean(0), normal(fn)
        if n0 @ (cn - v0) > 1e-6:
            n0 = -n0
        if nn @ (c0 - v0) > 1e-6:
            nn = -nn
    if ki @ n0 > 0:  # the 0-face is the one the incident wave sees
        n0, nn, c0, cn = nn, n0, cn, c0
    e = nrm(v1 - v0)
    if np.cross(n0, e) @ (c0 - v0) < 0:
        e = -e
    return n0, nn, e


def sionna_jones(ki, ko, s_prime, s, e, n0, nn, eta, thick, lam, scattering=0.0):
    """Jones matrix of RadioMaterial._diffraction_matrix (sionna-rt 2.2), world implicit bases."""
    k = 2 * np.pi / lam
    ext = 2 * np.pi - np.arccos(np.clip(-(n0 @ nn), -1.0, 1.0))
    n = ext / np.pi
    beta0 = np.arccos(abs(ki @ e))
    t0 = nrm(np.cross(n0, e))
    kip = nrm(ki - (ki @ e) * e)
    kop = nrm(ko - (ko @ e) * e)
    phip = (np.pi - np.arccos(np.clip(-kip @ t0, -1, 1))) * -np.sign(-kip @ n0) + np.pi
    phi = (np.pi - np.arccos(np.clip(kop @ t0, -1, 1))) * -np.sign(kop @ n0) + np.pi
    L = s * s_prime / (s + s_prime) * np.sin(beta0) ** 2
    d1, d2, d3, d4 = utd_terms(phi, phip, n, k, L, beta0)

    k_sb0 = ki - 2 * (ki @ n0) * n0
    k_sbn = ki - 2 * (ki @ nn) * nn
    phi_hat_p = nrm(np.cross(ki, e))
    phi_sb0 = -nrm(np.cross(k_sb0, e))
    phi_sbn = -nrm(np.cross(k_sbn, e))
    phi_hat = -nrm(np.cross(ko, e))
    es0 = nrm(np.cross(ki, n0))
    esn = nrm(np.cross(ki, nn))
    red = np.sqrt(1 - scattering**2)
    r0 = np.array(slab(abs(ki @ n0), eta, thick, lam)) * red
    rn = np.array(slab(abs(ki @ nn), eta, thick, lam)) * red
    R0 = rotator(k_sb0, es0, phi_sb0) @ np.diag(r0) @ rotator(ki, phi_hat_p, es0)
    Rn = rotator(k_sbn, esn, phi_sbn) @ np.diag(rn) @ rotator(ki, phi_hat_p, esn)
    if ext > np.pi + phip:  # n-face not lit by the incident wave
        Rn = -np.eye(2)
    J_edge = R0 * (d1 - d4) + Rn * (d2 - d3)
    J = rotator(ko, phi_hat, theta_hat(ko)) @ J_edge @ rotator(ki, theta_hat(ki), phi_hat_p)
    return J, dict(phi=phi, phip=phip, n=n, beta0=beta0, L=L, d=(d1, d2, d3, d4), R0=R0, Rn=Rn,
                   phi_hat_p=phi_hat_p, phi_hat=phi_hat)


def kp_luebbers_a(ki, ko, s_prime, s, e, n0, nn, eta, thick, lam, geo):
    """a for V-pol iso antennas with KP (PEC) and Luebbers (ITU slab) coefficients.

    Dyadic D = -beta'beta D_s - phi'phi D_h in KP's edge-fixed bases; E_d = D . E_i.
    Luebbers: D_{s,h} = D1 + D2 + R_n^{s,h} D3 + R_0^{s,h} D4 with R^s = r_te, R^h = r_tm of
    each face at its own grazing angle (0-face: phi', n-face: n pi - phi).
    """
    d1, d2, d3, d4 = geo["d"]
    pref = lam / (4 * np.pi) / np.sqrt(s * s_prime * (s + s_prime))
    # KP edge-fixed unit vectors: phi' = -(e x s')/|..| with s' = ki; beta0' = phi' x s'
    phi_p = -nrm(np.cross(e, ki))
    beta_p = np.cross(phi_p, ki)
    phi_d = nrm(np.cross(e, ko))
    beta_d = np.cross(phi_d, ko)
    t_in, t_out = theta_hat(ki), theta_hat(ko)
    n = geo["n"]
    sb = np.sin(geo["beta0"])
    r0 = slab(abs(np.sin(geo["phip"])) * sb, eta, thick, lam)
    rn = slab(abs(np.sin(n * np.pi - geo["phi"])) * sb, eta, thick, lam)
    out = {}
    for name, Ds, Dh in [
        ("kp_pec", d1 + d2 - (d3 + d4), d1 + d2 + (d3 + d4)),
        ("luebbers", d1 + d2 + rn[0] * d3 + r0[0] * d4, d1 + d2 + rn[1] * d3 + r0[1] * d4),
    ]:
        # project: E_i = theta_hat(ki); E_d = -(beta' . E_i) beta D_s - (phi' . E_i) phi D_h; a = theta_hat(ko) . E_d
        amp = -(beta_p @ t_in) * (beta_d @ t_out) * Ds - (phi_p @ t_in) * (phi_d @ t_out) * Dh
        out[name] = pref * amp
    return out


def load_meshes(doc, scenes):
    """Faces, vertices and material name of every object of the case's scene, as Sionna loads it."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
    import drjit as dr
    import mitsuba as mi
    import sionna.rt as rt

    sname = doc["scene"]["name"]
    if sname not in scenes:
        sc = rt.load_scene(str(REPO / doc["scene"]["xml"]), merge_shapes=False)
        meshes = {}
        for name, o in sc.objects.items():
            m = o.mi_mesh
            meshes[name] = (dr.unravel(mi.Point3u, m.faces_buffer()).numpy().T,
                            dr.unravel(mi.Point3f, m.vertex_positions_buffer()).numpy().T.astype(float),
                            o.radio_material.name)
        scenes[sname] = meshes
    return scenes[sname]


def material(doc, name):
    """(complex relative permittivity, thickness m, scattering coefficient) of a material."""
    m = doc["scene"]["materials"][name]
    eta = m["relative_permittivity"] - 1j * m["conductivity_S_per_m"] / (2 * np.pi * doc["frequency_hz"] * EPS0)
    return eta, m["thickness_m"], m["scattering_coefficient"]


def reflection_jones(ki, ko, normal, eta, thick, lam, scattering=0.0):
    """Sionna's specular reflection: jones_matrix_to_world_implicit with the ITU slab coefficients."""
    n = normal * np.sign(normal @ -ki)
    r = np.array(slab(-(ki @ n), eta, thick, lam)) * np.sqrt(1 - scattering**2)
    es = nrm(np.cross(ki, n))
    return rotator(ko, es, theta_hat(ko)) @ np.diag(r) @ rotator(ki, theta_hat(ki), es)


def sionna_leg(pts, kinds, normals, max_depth):
    """The diffracted leg s Sionna 2.2 uses (FieldCalculator._diffraction_compute_s_s_prime).

    pts: TX, the interaction points, RX. With fewer interactions than max_depth the walk
    reads the slot after the last one, which holds the diffraction point's image X through
    the later reflections' planes (ImageMethod._compute_diffraction_point_images), and s
    becomes s - |RX - P| + |X - P| + |RX - X|, P the last point (X = P without them).
    """
    d = kinds.index("diffraction") + 1
    s = sum(np.linalg.norm(pts[i + 1] - pts[i]) for i in range(d, len(pts) - 1))
    if len(kinds) >= max_depth:
        return s
    x = pts[d].copy()
    for i in range(d + 1, len(pts) - 1):
        x = x - 2 * ((x - pts[i]) @ normals[i - 1]) * normals[i - 1]
    p, rx = pts[-2], pts[-1]
    return s - np.linalg.norm(rx - p) + np.linalg.norm(x - p) + np.linalg.norm(rx - x)


def chain_a(doc, meshes, tx, rx, p, leg):
    """Replica a (V-pol iso antennas) of a path with one diffraction and reflections.

    leg: "sionna" (Sionna 2.2's s, see sionna_leg) or "unfolded".
    """
    lam = doc["wavelength_m"]
    pts = [tx] + [np.array(v, float) for v in p["vertices"]] + [rx]
    normals = []
    for i, kind in enumerate(p["kinds"]):
        faces, verts, _ = meshes[p["shapes"][i]]
        tri = verts[faces[p["primitives"][i]]]
        normals.append(nrm(np.cross(tri[1] - tri[0], tri[2] - tri[0])))
    d = p["kinds"].index("diffraction")
    sp = sum(np.linalg.norm(pts[i + 1] - pts[i]) for i in range(d + 1))
    s_unfolded = sum(np.linalg.norm(pts[i + 1] - pts[i]) for i in range(d + 1, len(pts) - 1))
    s = sionna_leg(pts, p["kinds"], normals, doc["max_depth"]) if leg == "sionna" else s_unfolded
    J = np.eye(2, dtype=complex)
    for i, kind in enumerate(p["kinds"]):
        ki, ko = nrm(pts[i + 1] - pts[i]), nrm(pts[i + 2] - pts[i + 1])
        faces, verts, mat = meshes[p["shapes"][i]]
        eta, thick, scat = material(doc, mat)
        if kind == "diffraction":
            ed = p["edges"][i]
            f0 = verts[faces[ed["faces"][0]]]
            fn_ = None if ed["free"] else verts[faces[ed["faces"][1]]]
            n0, nn, e = wedge(np.array(ed["a"]), np.array(ed["b"]), f0, fn_, ki)
            Ji, _ = sionna_jones(ki, ko, sp, s, e, n0, nn, eta, thick, lam, scat)
        else:
            Ji = reflection_jones(ki, ko, normals[i], eta, thick, lam, scat)
        J = Ji @ J
    return lam / (4 * np.pi) / np.sqrt(s * sp * (s + sp)) * J[0, 0], s - s_unfolded


def check_single(doc, meshes, fn, rows):
    """Append one row per single-diffraction path of ``doc`` (TX -> edge -> RX)."""
    lam = doc["wavelength_m"]
    tx = np.array(doc["tx"]["position"], float)
    for r in doc["receivers"]:
        rx = np.array(r["position"], float)
        for p in r["paths"]:
            if p["kinds"] != ["diffraction"]:
                continue
            faces, verts, mat = meshes[p["shapes"][0]]
            ed = p["edges"][0]
            q = np.array(p["vertices"][0], float)
            ki = nrm(q - tx)
            ko = nrm(rx - q)
            f0 = verts[faces[ed["faces"][0]]]
            fn_ = None if ed["free"] else verts[faces[ed["faces"][1]]]
            n0, nn, e = wedge(np.array(ed["a"]), np.array(ed["b"]), f0, fn_, ki)
            eta, thick, scat = material(doc, mat)
            sp, s = np.linalg.norm(q - tx), np.linalg.norm(rx - q)
            J, geo = sionna_jones(ki, ko, sp, s, e, n0, nn, eta, thick, lam, scat)
            pref = lam / (4 * np.pi) / np.sqrt(s * sp * (s + sp))
            a_rep = pref * J[0, 0]
            a_s = complex(*p["a"])
            other = kp_luebbers_a(ki, ko, sp, s, e, n0, nn, eta, thick, lam, geo)
            rows.append((Path(fn).stem, r["name"], p["shapes"][0], ed["free"], geo["n"],
                         np.degrees(geo["phip"]), np.degrees(geo["phi"]), a_s, a_rep, other))


def check_chains(doc, meshes, fn):
    """Rows (case, rx, kinds, a_sionna, a_replica, a_unfolded_leg, extra leg m) of every
    diffracted path of ``doc`` with at least one reflection."""
    tx = np.array(doc["tx"]["position"], float)
    rows = []
    for r in doc["receivers"]:
        rx = np.array(r["position"], float)
        for p in r["paths"]:
            if "diffraction" not in p["kinds"] or len(p["kinds"]) < 2:
                continue
            a_rep, extra = chain_a(doc, meshes, tx, rx, p, "sionna")
            a_unf, _ = chain_a(doc, meshes, tx, rx, p, "unfolded")
            kinds = ",".join("D" if k == "diffraction" else "R" for k in p["kinds"])
            rows.append((Path(fn).stem, r["name"], kinds, complex(*p["a"]), a_rep, a_unf, extra))
    return rows


def db(a):
    return 20 * np.log10(abs(a)) if a != 0 else float("-inf")


def check(paths_glob):
    rows, chains, scenes = [], [], {}
    for fn in sorted(glob.glob(paths_glob)):
        doc = json.load(open(fn))
        meshes = load_meshes(doc, scenes)
        check_single(doc, meshes, fn, rows)
        chains += check_chains(doc, meshes, fn)
    print(f"{'case':18s} {'rx':4s} {'shape':28s} {'free':5s} {'n':>6s} {'phi_p':>7s} {'phi':>7s} "
          f"{'sionna dB':>10s} {'replica':>9s} {'|rel err|':>9s} {'KP-PEC':>8s} {'Luebbers':>8s}")
    worst = 0.0
    for case, rx, shape, free, n, php, ph, a_s, a_rep, other in rows:
        rel = abs(a_rep - a_s) / abs(a_s)
        worst = max(worst, rel) if np.isfinite(rel) else float("inf")
        print(f"{case:18s} {rx:4s} {shape[:28]:28s} {str(free):5s} {n:6.3f} {php:7.2f} {ph:7.2f} "
              f"{db(a_s):10.3f} {db(a_rep):9.3f} {rel:9.2e} {db(other['kp_pec']):8.2f} {db(other['luebbers']):8.2f}")
    print(f"{len(rows)} single-diffraction paths; worst |a_replica - a_sionna| / |a_sionna| = {worst:.2e}")
    print()
    print("Paths that reflect before or after the edge: replica with Sionna's diffracted leg, and with")
    print("the unfolded leg (UTD's s); 'extra' = Sionna's leg - unfolded, m (max_depth of the case)")
    print(f"{'case':18s} {'rx':4s} {'kinds':6s} {'sionna dB':>10s} {'replica':>9s} {'|rel err|':>9s} "
          f"{'unfolded':>9s} {'diff dB':>8s} {'extra m':>8s}")
    worst_chain, far = 0.0, []
    for case, rx, kinds, a_s, a_rep, a_unf, extra in chains:
        rel = abs(a_rep - a_s) / abs(a_s)
        if db(a_rep) - db(a_s) > FAR_BELOW_DB:
            far.append(f"{case} {rx} {kinds}: Sionna {db(a_s):.1f} dB, replica {db(a_rep):.1f} dB")
        else:
            worst_chain = max(worst_chain, rel)
        print(f"{case:18s} {rx:4s} {kinds:6s} {db(a_s):10.3f} {db(a_rep):9.3f} {rel:9.2e} "
              f"{db(a_unf):9.3f} {db(a_unf) - db(a_s):8.3f} {extra:8.2f}")
    grown = [c for c in chains if c[6] > 1e-6 and db(c[4]) - db(c[3]) <= FAR_BELOW_DB]
    print(f"{len(chains)} paths with reflections, {len(grown)} of them with Sionna's leg grown "
          f"(unfolded leg {min(db(c[5]) - db(c[3]) for c in grown):.2f} to "
          f"{max(db(c[5]) - db(c[3]) for c in grown):.2f} dB above Sionna there); "
          f"worst |a_replica - a_sionna| / |a_sionna| = {worst_chain:.2e}, leaving out {len(far)} "
          f"where Sionna's gain is more than {FAR_BELOW_DB:.0f} dB below the replica (not explained "
          "here; both diffract on a free edge):")
    for line in far:
        print("  " + line)
    return max(worst, worst_chain)


def solver_depth():
    """Sionna's gain of the canyon's [diffraction, reflection] paths at max_depth 2, 3, 4."""
    sys.path.insert(0, str(REPO / "tools"))
    import sionna_reference as ref
    _, mi, _ = ref.import_sionna()
    from sionna.rt import PathSolver, PlanarArray, Receiver, Transmitter

    case = dict(next(c for c in ref.CASES if c["name"] == "canyon-d3"))
    scene, _ = ref.load(case["scene"])
    scene.frequency = ref.FREQ
    scene.tx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    scene.rx_array = PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="V")
    tx, rxs, _, _ = ref.resolve_positions(case, scene)
    scene.add(Transmitter(name="tx", position=mi.Point3f(*tx)))
    for i, r in enumerate(rxs):
        scene.add(Receiver(name=f"rx{i}", position=mi.Point3f(*r)))
    gains = {}
    for depth in (2, 3, 4):
        case["max_depth"] = depth
        res = ref.solve(scene, case, PathSolver(deterministic=True))
        for i in range(len(rxs)):
            for p in ref.paths_json(scene, res, i, ref.FREQ):
                if p["kinds"] == ["diffraction", "reflection"]:
                    key = (i, tuple(np.round(np.array(p["vertices"]).ravel(), 2)))
                    gains.setdefault(key, {})[depth] = p["gain_db"]
    rows = [(k, v) for k, v in sorted(gains.items()) if len(v) == 3]
    print("canyon-d3 [diffraction, reflection] paths, Sionna's gain (dB) at max_depth 2 / 3 / 4")
    for (rx, _), v in rows:
        print(f"rx{rx} {v[2]:9.3f} {v[3]:9.3f} {v[4]:9.3f}")
    d3 = [v[3] - v[2] for _, v in rows]
    d4 = [v[4] - v[3] for _, v in rows]
    print(f"{len(rows)} paths found at all three depths; depth 3 - depth 2: {min(d3):.3f} to "
          f"{max(d3):.3f} dB; depth 4 - depth 3: {min(d4):.3f} to {max(d4):.3f} dB")


def boundaries():
    """Continuity of GO + diffracted field across the shadow boundaries of a PEC wedge.

    The simple_wedge geometry (90 degree wedge, n = 1.5) with ITU metal, TX at
    phi' = 30 deg, 20 m from the edge, RX 15 m from the edge, all in one plane
    (beta0 = 90 deg). The reflection boundary of the 0-face is at phi = 150 deg,
    the incident shadow boundary at 210 deg. GO = LoS (phi < 210) + reflection
    off the 0-face (phi < 150); the total GO + diffracted field must not jump
    there. Soft = E along the edge (V-pol here), hard = E across it (H-pol).
    """
    f = 3.5e9
    lam = C0 / f
    k = 2 * np.pi / lam
    eta = 1 - 1j * 1e7 / (2 * np.pi * f * EPS0)
    tx = np.array([20 * np.cos(np.radians(30)), 20 * np.sin(np.radians(30)), 0.0])
    n0, nn, e = np.array([0, 1.0, 0]), np.array([-1.0, 0, 0]), np.array([0, 0, 1.0])
    print("|GO + diffracted| just before / after each boundary (a jump = a discontinuity)")
    for label, slot, rsign in [("soft", 0, -1), ("hard", 1, 1)]:
        for name, phib in [("RSB 0-face", 150.0), ("ISB", 210.0)]:
            vals = {}
            for side, phi_deg in [("before", phib - 5e-4), ("after", phib + 5e-4)]:
                rx = np.array([15 * np.cos(np.radians(phi_deg)), 15 * np.sin(np.radians(phi_deg)), 0.0])
                ki, ko = nrm(-tx), nrm(rx)
                J, geo = sionna_jones(ki, ko, 20.0, 15.0, e, n0, nn, eta, 1.0, lam)
                pref = lam / (4 * np.pi) / np.sqrt(15.0 * 20.0 * 35.0) * np.exp(-1j * k * 35.0)
                d1, d2, d3, d4 = geo["d"]
                kp = d1 + d2 - (d3 + d4) if slot == 0 else d1 + d2 + (d3 + d4)
                dl = np.linalg.norm(rx - tx)
                go = lam / (4 * np.pi * dl) * np.exp(-1j * k * dl) if phi_deg < 210 else 0
                img = tx * np.array([1, -1, 1])
                dr_ = np.linalg.norm(rx - img)
                go += rsign * lam / (4 * np.pi * dr_) * np.exp(-1j * k * dr_) if phi_deg < 150 else 0
                vals[side] = (abs(go + pref * J[slot, slot]), abs(go + pref * kp))
            print(f"  {label} {name} (phi = {phib:.0f}): Sionna 2.2 {vals['before'][0]:.4e} / {vals['after'][0]:.4e}"
                  f"   Kouyoumjian-Pathak {vals['before'][1]:.4e} / {vals['after'][1]:.4e}")


UNIT_CASES = [
    # (name, interior face n direction or None for a screen, phi' deg, phi deg)
    ("corner, face n unlit", (0.0, -1.0), 30.0, 200.0),
    ("corner, face n unlit, lit region", (0.0, -1.0), 30.0, 100.0),
    ("corner, both faces lit", (0.0, -1.0), 135.0, 60.0),
    ("corner, face 0 unlit (swapped)", (0.0, -1.0), 240.0, 100.0),
    ("screen, source behind face 0 (swapped)", None, 300.0, 100.0),
    ("acute wedge n = 1.75", (np.sqrt(0.5), -np.sqrt(0.5)), 20.0, 250.0),
]


def unit_cases():
    """V/H path gains of Sionna 2.2's formula for synthetic wedges about the z axis.

    Face 0 lies along +x in the plane y = 0, face n along the given direction (a screen:
    face 0 alone); phi is measured from +x towards +y. TX 20 m from the edge at phi', z = 1;
    RX 15 m from it at phi, z = -2; the diffraction point on the edge by Keller's law. Faces:
    eps_r = 5.24, sigma = 0.1234 S/m, a slab 0.2 m thick; 3.5 GHz. Printed: a = lambda/(4 pi)
    / sqrt(s s' (s + s')) * J in the (theta_hat, phi_hat) bases, i.e. the path gain between
    isotropic antennas of the polarisations RX/TX (V = theta_hat, H = phi_hat).
    """
    f = 3.5e9
    lam = C0 / f
    eta = 5.24 - 1j * 0.1234 / (2 * np.pi * f * EPS0)
    v0, v1 = np.array([0, 0, -50.0]), np.array([0, 0, 50.0])
    f0 = np.array([v0, v1, [5.0, 0, 0]])
    print("name | a_VV (re, im) | a_VH | a_HV | a_HH   (a_RT: RX polarisation R, TX T)")
    for name, face_n, php, ph in UNIT_CASES:
        fn_ = None if face_n is None else np.array([v0, v1, [5 * face_n[0], 5 * face_n[1], 0]])
        tx = np.array([20 * np.cos(np.radians(php)), 20 * np.sin(np.radians(php)), 1.0])
        rx = np.array([15 * np.cos(np.radians(ph)), 15 * np.sin(np.radians(ph)), -2.0])
        q = np.array([0, 0, tx[2] + (rx[2] - tx[2]) * 20 / 35])
        ki, ko = nrm(q - tx), nrm(rx - q)
        n0, nn, e = wedge(v0, v1, f0, fn_, ki)
        sp, s = np.linalg.norm(q - tx), np.linalg.norm(rx - q)
        J, _ = sionna_jones(ki, ko, sp, s, e, n0, nn, eta, 0.2, lam)
        a = lam / (4 * np.pi) / np.sqrt(s * sp * (s + sp)) * J
        cells = ", ".join(f"({a[i, j].real:.9e}, {a[i, j].imag:.9e})" for i, j in
                          [(0, 0), (0, 1), (1, 0), (1, 1)])
        print(f"{name} | {cells}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare with testdata/sionna-reference/*.json")
    ap.add_argument("--boundaries", action="store_true",
                    help="GO + diffracted field across a PEC wedge's shadow boundaries, Sionna vs KP")
    ap.add_argument("--solver-depth", action="store_true",
                    help="Sionna's own gain of the canyon's [D, R] paths at max_depth 2, 3, 4")
    ap.add_argument("--unit-cases", action="store_true",
                    help="reference gains of synthetic wedges for bt-channel's unit test")
    ap.add_argument("--glob", default=str(REPO / "testdata" / "sionna-reference" / "*.json"))
    args = ap.parse_args(argv)
    if args.unit_cases:
        unit_cases()
        return 0
    if args.solver_depth:
        solver_depth()
        return 0
    if args.boundaries:
        boundaries()
    if args.check:
        worst = check(args.glob)
        return 0 if worst < 1e-3 else 1
    if not args.boundaries:
        ap.print_help()
    return 0


if __name__ == "__main__":
    sys.exit(main())
