"""Scene.trace against the CLI's `beamtrace trace --json` (the same report, every field)."""

from __future__ import annotations

import numpy as np
import pytest

import beamtrace
from conftest import REPO, TESTDATA, vec


def assert_same_as_cli(paths: beamtrace.Paths, doc: dict) -> None:
    """Every field of every path equal to the CLI's JSON (floats to the last bit)."""
    expected = doc["paths"]
    assert len(paths) == len(expected) == doc["stats"]["valid_paths"]
    assert len(paths) > 0
    for i, e in enumerate(expected):
        assert paths.rank[i] == e["rank"]
        assert paths.order[i] == e["order"]
        assert paths.surfaces[i] == e["surfaces"]
        assert paths.points[i].shape == (e["order"], 3)
        assert paths.points[i].tolist() == e["points"]
        assert paths.length_m[i] == e["length_m"]
        assert paths.delay_s[i] == e["delay_s"]
        for key in ("aod_deg", "aoa_deg"):
            assert paths.to_dict()[key][i].tolist() == [
                e[key]["azimuth"],
                e[key]["elevation"],
            ]
        # A diffraction's incidence is the document's null, −inf in Python.
        incidence = [-np.inf if x is None else x for x in e["incidence_deg"]]
        assert paths.incidence_deg[i].tolist() == incidence
        assert paths.interactions[i] == e["interactions"]
        for key in ("free_space_loss_db", "reflection_loss_db", "diffraction_loss_db",
                    "transmission_loss_db", "loss_db"):
            assert paths.to_dict()[key][i] == e[key]
        assert paths.gain[i] == complex(e["gain"][0], e["gain"][1])
        for key in ("gain_db", "power_dbm"):
            want = e[key] if e[key] is not None else -np.inf
            assert paths.to_dict()[key][i] == want
        if "iterations" in e:
            assert paths.iterations[i] == e["iterations"]
            assert paths.residual_m[i] == e["residual_m"]
    # Columns carry every field of the CLI's path objects, and nothing the CLI lacks.
    assert set(paths.columns) == set(expected[0])


def test_living_room_matches_cli(cli_json):
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(scene.tx, scene.rx, max_order=3)
    assert_same_as_cli(paths, cli_json("builtin:living-room", "--max-order", "3"))
    assert paths.order.dtype == np.int64
    assert paths.aod_deg.shape == (len(paths), 2)
    assert paths.delay_s.dtype == np.float64


def test_moved_terminals_and_ipc_match_cli(cli_json):
    tx, rx = [1.0, 3.5, 2.0], [4.2, 1.1, 1.3]
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(tx, rx, max_order=2, solver="ipc", ipc_order="jacobi")
    doc = cli_json(
        "builtin:living-room",
        "--tx", vec(tx), "--rx", vec(rx),
        "--max-order", "2", "--solver", "ipc", "--ipc-order", "jacobi",
    )
    assert_same_as_cli(paths, doc)
    assert "iterations" in paths.columns


@pytest.mark.parametrize("name", ["box-room.obj", "box-room-ascii.stl", "box-room-binary.stl",
                                  "box-room.glb"])
def test_mesh_with_terminals_matches_cli(cli_json, name):
    tx, rx = [1.0, 1.0, 1.5], [3.0, 2.0, 1.2]
    mesh = TESTDATA / name
    scene = beamtrace.load(mesh, tx=tx, rx=rx)
    paths = scene.trace(max_order=2, candidates="exhaustive")
    doc = cli_json(str(mesh), "--tx", vec(tx), "--rx", vec(rx), "--max-order", "2",
                   "--candidates", "exhaustive")
    assert_same_as_cli(paths, doc)
    # The box as 12 triangles is 6 surfaces: 1 + 6 + 18 image sources up to order 2.
    assert len(paths) == 25


def test_bare_mesh_traces_with_terminals_per_call(cli_json):
    # Terminals per trace: load the mesh bare, give tx/rx to each trace; the result is the
    # CLI's for the mesh loaded with those terminals, to the last bit.
    tx, rx = [1.0, 1.0, 1.5], [3.0, 2.0, 1.2]
    mesh = TESTDATA / "box-room.obj"
    scene = beamtrace.load(mesh)
    assert scene.tx is None and scene.rx is None
    paths = scene.trace(tx=tx, rx=rx, max_order=2)
    doc = cli_json(str(mesh), "--tx", vec(tx), "--rx", vec(rx), "--max-order", "2")
    assert_same_as_cli(paths, doc)
    many = scene.trace_many(tx, np.array([rx, [2.0, 3.0, 1.0]]), max_order=2)
    assert many[0].length_m.tolist() == paths.length_m.tolist()


def test_diffraction_coefficient_matches_cli(cli_json):
    # Sionna RT 2.2's coefficient changes a diffracted gain, as `--diffraction-coefficient`.
    wedge = TESTDATA / "sionna-rt" / "simple_wedge" / "simple_wedge.xml"
    tx, rx = [10.0, 5.0, 1.0], [-5.0, -10.0, 1.0]
    scene = beamtrace.load(wedge)
    options = dict(max_order=1, diffraction=True)
    args = ["--tx", vec(tx), "--rx", vec(rx), "--max-order", "1", "--diffraction"]
    utd = scene.trace(tx, rx, **options)
    sionna = scene.trace(tx, rx, diffraction_coefficient="sionna-rt-2.2", **options)
    assert abs(utd.gain_db[0] - sionna.gain_db[0]) > 0.5
    for paths, name in [(utd, "utd"), (sionna, "sionna-rt-2.2")]:
        doc = cli_json(str(wedge), *args, "--diffraction-coefficient", name)
        assert doc["radio"]["diffraction_coefficient"] == name
        [e] = doc["paths"]
        assert paths.interactions[0] == e["interactions"] == ["diffraction"]
        assert paths.points[0].tolist() == e["points"]
        assert paths.gain[0] == complex(e["gain"][0], e["gain"][1])
        assert paths.gain_db[0] == e["gain_db"]
        assert paths.diffraction_loss_db[0] == e["diffraction_loss_db"]
    many = scene.trace_many(tx, np.array([rx]), diffraction_coefficient="sionna-rt-2.2",
                            **options)
    assert many[0].gain.tolist() == sionna.gain.tolist()


def test_thickness_alone_matches_cli(cli_json):
    """load(thickness=) alone is --thickness alone: the scene's half-space materials (the two
    rooms' concrete shell) become slabs, so a receiver outside is reached through the shell,
    with the CLI's every field."""
    two_rooms = str(REPO / "examples" / "two-rooms.json")
    outside = [9.0, 1.0, 1.2]
    scene = beamtrace.load(two_rooms, thickness=0.1)
    paths = scene.trace(rx=outside, max_order=2, transmission=True)
    assert len(paths) > 0
    assert all(names[-1] == "shell.east" for names in paths.surfaces)
    assert_same_as_cli(paths, cli_json(two_rooms, "--max-order", "2", "--rx", vec(outside),
                                       "--transmission", "--thickness", "0.1"))
    assert len(beamtrace.load(two_rooms).trace(rx=outside, max_order=2, transmission=True)) == 0


def test_transmission_matches_cli(cli_json):
    # Through the partition (plasterboard) with transmission=True, as `--transmission`; the
    # curtain's material opens it either way.
    two_rooms = str(REPO / "examples" / "two-rooms.json")
    scene = beamtrace.load(two_rooms)
    through = scene.trace(max_order=3, transmission=True)
    assert_same_as_cli(through, cli_json(two_rooms, "--max-order", "3", "--transmission"))
    crossed = {s for kinds, names in zip(through.interactions, through.surfaces)
               for k, s in zip(kinds, names) if k == "transmission"}
    assert {"partition", "curtain"} <= crossed
    assert through.transmission_loss_db.max() > 0
    plain = scene.trace(max_order=3)
    assert_same_as_cli(plain, cli_json(two_rooms, "--max-order", "3"))
    assert len(plain) < len(through)
    many = scene.trace_many(scene.tx, np.array([scene.rx]), max_order=3, transmission=True)
    assert many[0].gain.tolist() == through.gain.tolist()
    tracer = beamtrace.Tracer(two_rooms, max_order=3, transmission=True)
    answer = tracer.update(rx=list(scene.rx))
    assert [p["gain"] for p in answer["paths"]] == [[g.real, g.imag] for g in through.gain]


def test_two_diffractions_match_cli(cli_json):
    # max_diffractions=2 is `--max-diffractions 2`: the paths over both garden walls, which
    # one diffraction cannot give, field by field as the CLI's.
    two_walls = str(REPO / "examples" / "two-walls.json")
    scene = beamtrace.load(two_walls)
    twice = scene.trace(max_order=3, max_diffractions=2)
    assert_same_as_cli(twice, cli_json(two_walls, "--max-order", "3", "--max-diffractions", "2"))
    over = [names for kinds, names in zip(twice.interactions, twice.surfaces)
            if list(kinds) == ["diffraction", "diffraction"]]
    assert ["wall-a", "wall-b"] in [list(n) for n in over]
    once = scene.trace(max_order=3, diffraction=True)
    assert not any("wall-a" in names and "wall-b" in names for names in once.surfaces)
    with pytest.raises(ValueError, match="max-diffractions"):
        scene.trace(max_order=3, max_diffractions=3)


def test_scene_properties():
    scene = beamtrace.load("builtin:living-room")
    assert scene.name == "living-room"
    assert scene.frequency_hz == pytest.approx(28e9)
    assert len(scene.surface_names) == 31
    assert "living-room" in beamtrace.builtin_names()


@pytest.mark.parametrize(
    "material, thickness, frequency",
    [("itu:concrete", 0.2, 3.5e9), ("custom:4.5,0.02", None, 28e9), ("itu:glass", 0.006, None)],
)
def test_radio_load_options_match_cli(cli_json, material, thickness, frequency):
    """load(material=, thickness=, frequency=) is trace's --material/--thickness/--frequency:
    every field of every path equal to the CLI's, on a mesh and a scene file."""
    flags = ["--material", material]
    flags += [] if thickness is None else ["--thickness", str(thickness)]
    flags += [] if frequency is None else ["--frequency", str(frequency)]
    for source in ("builtin:living-room", str(TESTDATA / "box-room.obj")):
        terminals = [] if source.startswith("builtin") else ["--tx", "1,1,1.5", "--rx", "4,3,1.2"]
        scene = beamtrace.load(source, material=material, thickness=thickness, frequency=frequency)
        tx, rx = (None, None) if not terminals else ([1, 1, 1.5], [4, 3, 1.2])
        paths = scene.trace(tx, rx, max_order=2)
        assert_same_as_cli(paths, cli_json(source, "--max-order", "2", *terminals, *flags))


def test_radio_load_options_are_checked():
    with pytest.raises(ValueError, match="expected itu:NAME"):
        beamtrace.load("builtin:living-room", material="concrete")
    with pytest.raises(ValueError, match="thickness= must be a finite number"):
        beamtrace.load("builtin:living-room", thickness=-0.2)
    with pytest.raises(beamtrace.BeamtraceError, match="frequency"):
        beamtrace.load("builtin:living-room", frequency=-1.0)


def test_antenna_keywords_match_cli(cli_json):
    """tx_/rx_pattern, _polarization, _orientation and tx_power_dbm are trace's flags of those
    names: every field of every path equal to the CLI's."""
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(
        max_order=2,
        tx_pattern="tr38901",
        rx_polarization="+45",
        tx_orientation=[180, -10, 0],
        rx_orientation=(30, 0, 5),
        tx_power_dbm=20,
    )
    doc = cli_json(
        "builtin:living-room", "--max-order", "2", "--tx-pattern", "tr38901",
        "--rx-polarization", "+45", "--tx-orientation", "180,-10,0",
        "--rx-orientation", "30,0,5", "--tx-power-dbm", "20",
    )
    assert_same_as_cli(paths, doc)
    # Not the defaults' numbers: the options took effect.
    plain = scene.trace(max_order=2)
    assert not np.array_equal(plain.gain_db, paths.gain_db)
    with pytest.raises(ValueError, match="tx_pattern"):
        scene.trace(tx_pattern="dipole")
    with pytest.raises(ValueError, match="tx_power_dbm"):
        scene.trace(tx_power_dbm=float("nan"))
    with pytest.raises(ValueError, match="rx_orientation"):
        scene.trace(rx_orientation=[0, float("inf"), 0])


def test_ipc_and_sbr_settings_match_cli(cli, cli_json):
    """ipc_threshold, ipc_max_iterations and max_rays are trace's flags of those names."""
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(max_order=2, solver="ipc", ipc_threshold=1e-7, ipc_max_iterations=40)
    doc = cli_json("builtin:living-room", "--max-order", "2", "--solver", "ipc",
                   "--ipc-threshold", "1e-7", "--ipc-max-iterations", "40")
    assert_same_as_cli(paths, doc)
    # The cap took effect: fewer rounds allowed than the default needs somewhere.
    assert max(paths.iterations) <= 40
    with pytest.raises(ValueError, match="ray budget exceeded") as info:
        scene.trace(max_order=1, solver="sbr", max_rays=1000)
    done = cli("trace", "builtin:living-room", "--max-order", "1", "--solver", "sbr",
               "--max-rays", "1000")
    assert done.returncode != 0 and str(info.value) in done.stderr
    with pytest.raises(ValueError, match="ipc-threshold|ipc_threshold"):
        scene.trace(solver="ipc", ipc_threshold=-1.0)


def test_point_cloud_matches_cli(cli, cli_json, tmp_path):
    # A PCD scan of the living room (the CLI's `sample`), its planes extracted on load as the
    # CLI's trace extracts them: the same paths. The cloud budget is checked before reading.
    cloud = tmp_path / "room.pcd"
    done = cli("sample", "builtin:living-room", "-o", str(cloud), "--noise", "0.005",
               "--density", "300")
    assert done.returncode == 0, done.stderr
    tx, rx = [5.6, 0.6, 2.2], [2.3, 2.1, 0.72]
    scene = beamtrace.load(cloud, tx=tx, rx=rx)
    assert_same_as_cli(scene.trace(max_order=2),
                       cli_json(str(cloud), "--tx", vec(tx), "--rx", vec(rx), "--max-order", "2"))
    with pytest.raises(beamtrace.BeamtraceError, match="max-cloud-points"):
        beamtrace.load(cloud, max_cloud_points=100)


def test_mitsuba_rectangles_and_cubes_reflect_where_the_image_method_says(cli_json):
    # Mitsuba's primitives: the ground is the rectangle [-1, 1]^2 scaled by 10, the block's
    # south face the cube [-1, 1]^3 scaled by (3, 1, 2) and moved to (0, 5, 2): y = 4.
    scene_file = TESTDATA / "mitsuba-primitives.xml"
    tx, rx = [-5.0, -3.0, 2.0], [5.0, -3.0, 1.5]
    paths = beamtrace.load(scene_file).trace(tx, rx, max_order=1)
    assert_same_as_cli(paths, cli_json(str(scene_file), "--tx", vec(tx), "--rx", vec(rx),
                                       "--max-order", "1"))
    by_surfaces = {tuple(s): i for i, s in enumerate(paths.surfaces)}
    # Images of RX in z = 0 and in y = 4; the reflection points where TX's rays to them cross.
    for surface, image, point in [
        ("ground.face_0", [5.0, -3.0, -1.5], [-5.0 + 10.0 * 2.0 / 3.5, -3.0, 0.0]),
        ("block.face_2", [5.0, 11.0, 1.5], [0.0, 4.0, 1.75]),
    ]:
        i = by_surfaces[(surface,)]
        assert paths.length_m[i] == pytest.approx(np.linalg.norm(np.subtract(image, tx)),
                                                  rel=1e-12)
        np.testing.assert_allclose(paths.points[i][0], point, rtol=0, atol=1e-12)
    assert len(paths) == 3
