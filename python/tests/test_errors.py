"""Errors reach Python as exceptions with the CLI's messages."""

from __future__ import annotations

import numpy as np
import pytest

import beamtrace
from conftest import TESTDATA


def assert_cli_says(done, message: str) -> None:
    """The CLI failed cleanly with `error: MESSAGE` (anyhow may append the cause chain, which
    for file errors repeats the OS message: `PATH: No such file ...: No such file ...`)."""
    assert done.returncode not in (0, 101), done.stderr
    text = done.stderr.strip()
    assert text == f"error: {message}" or text.startswith(f"error: {message}: "), (text, message)


def test_missing_file_names_the_file(cli, tmp_path):
    missing = tmp_path / "no-such-room.json"
    with pytest.raises(beamtrace.BeamtraceError) as info:
        beamtrace.load(missing)
    message = str(info.value)
    assert "no-such-room.json" in message
    assert_cli_says(cli("trace", str(missing)), message)


def test_invalid_scene_lists_every_problem_like_the_cli(cli):
    bad = TESTDATA / "bad-scene.toml"
    with pytest.raises(beamtrace.BeamtraceError) as info:
        beamtrace.load(bad)
    done = cli("scene", "check", str(bad))
    assert done.returncode == 1
    assert str(info.value) == done.stdout.strip()


def test_mesh_without_terminals_says_what_is_missing():
    # A mesh loads as bare geometry; the trace that lacks a terminal names its keyword.
    scene = beamtrace.load(TESTDATA / "box-room.obj")
    assert scene.tx is None and scene.rx is None
    with pytest.raises(ValueError, match=r"no tx and rx given: pass tx=\[x, y, z\] and rx=") as info:
        scene.trace()
    assert "--tx" not in str(info.value)
    with pytest.raises(ValueError, match=r"no rx given: pass rx=\[x, y, z\]"):
        scene.trace(tx=[1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"no tx given: pass tx=\[x, y, z\]"):
        scene.trace_many(None, np.array([[3.0, 2.0, 1.5]]))


def test_unknown_builtin_lists_the_builtins():
    with pytest.raises(beamtrace.BeamtraceError, match="living-room"):
        beamtrace.load("builtin:kitchen")


def test_receiver_on_a_surface_is_an_error(cli):
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(beamtrace.BeamtraceError, match="rx") as info:
        scene.trace(scene.tx, [2.0, 2.0, 0.0])  # on the floor
    assert_cli_says(cli("trace", "builtin:living-room", "--rx", "2,2,0"), str(info.value))
    # trace_many fails the call with that receiver's error.
    with pytest.raises(beamtrace.BeamtraceError):
        scene.trace_many(None, np.array([[2.0, 2.0, 1.0], [2.0, 2.0, 0.0]]))


def test_budget_error_carries_the_cli_message(cli):
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(beamtrace.BeamtraceError, match="candidate budget exceeded") as info:
        scene.trace(max_order=3, candidates="exhaustive", max_candidates=100)
    done = cli("trace", "builtin:living-room", "--candidates", "exhaustive",
               "--max-candidates", "100")
    assert_cli_says(done, str(info.value))


@pytest.mark.parametrize(
    "options, message",
    [
        ({"solver": "magic"}, "solver must be one of"),
        ({"candidates": "all"}, "candidates must be one of"),
        ({"solver": "sbr", "sbr_step_deg": 0.0}, "sbr step must be a positive"),
        ({"solver": "sbr", "sbr_step_deg": 0.001}, "sbr ray budget exceeded"),
        ({"solver": "sbr", "sbr_step_deg": 1.0, "sbr_rays": 10}, "not both"),
        ({"diffraction_coefficient": "sionna"}, "diffraction_coefficient must be one of"),
        # checked even when the solver chosen does not use it
        ({"sbr_step_deg": float("nan")}, "sbr step must be a positive"),
    ],
)
def test_bad_options_are_value_errors(options, message):
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(ValueError, match=message):
        scene.trace(**options)


@pytest.mark.parametrize(
    "keyword", ["solver", "candidates", "ipc_order", "ipc_accel", "diffraction_coefficient"]
)
def test_a_long_bad_value_is_cut_in_the_message(keyword):
    # As the CLI's messages: the value escaped and cut after 64 characters, with its length.
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(ValueError, match=f"{keyword} must be one of") as info:
        scene.trace(**{keyword: "x" * 10_000})
    assert str(info.value).endswith("x" * 64 + '…(10000 bytes)"')
    assert len(str(info.value)) < 300


def test_bad_point_shape_is_a_value_error():
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(ValueError, match="three numbers"):
        scene.trace([1.0, 2.0], None)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"merge_angle_deg": float("nan")}, "angle_tol_deg"),
        ({"merge_distance": -1.0}, "dist_tol_m"),
        ({"min_reflector_area": float("inf")}, "min-reflector-area"),
    ],
)
def test_load_options_are_checked_for_every_source(options, message):
    # A built-in scene merges no mesh, but a NaN given is still refused, not ignored.
    with pytest.raises(beamtrace.BeamtraceError, match=message):
        beamtrace.load("builtin:living-room", **options)
