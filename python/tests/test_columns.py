"""The path columns are derived from the report record: every key of `trace --json`'s path
objects is a column of the same name, in the same order, holding the same values to the bit;
the column shapes do not depend on the paths at hand."""

from __future__ import annotations

import numpy as np
import pytest

import beamtrace
from beamtrace import _native
from conftest import TESTDATA, vec


def as_json(value, like):
    """One path's value of a column in the form of its JSON counterpart `like`."""
    if like is None:
        assert value == -np.inf
        return None
    if isinstance(like, dict):  # a struct of reals: one row, in field order
        return dict(zip(like, value.tolist()))
    if isinstance(value, np.complexfloating):
        return [float(value.real), float(value.imag)]
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    return value


def assert_columns_are_the_json(paths: beamtrace.Paths, doc: dict) -> None:
    expected = doc["paths"]
    assert len(paths) == len(expected) > 0
    keys = list(expected[0])
    assert paths.columns == keys
    assert keys == [c for c in _native.PATH_COLUMNS if c in keys]
    columns = paths.to_dict()
    for key, column in columns.items():
        if isinstance(column, np.ndarray):
            assert column.dtype in (np.int64, np.float64, np.complex128), key
            assert column.shape[0] == len(paths), key
    for i, e in enumerate(expected):
        assert list(e) == keys
        for key in keys:
            # repr: floats to the last bit (and -0.0 apart from 0.0), ints apart from floats.
            assert repr(as_json(columns[key][i], e[key])) == repr(e[key]), (i, key)


def test_ipc_columns_are_every_json_key(cli_json):
    tx, rx = [1.0, 3.5, 2.0], [4.2, 1.1, 1.3]
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(tx, rx, max_order=2, solver="ipc")
    doc = cli_json("builtin:living-room", "--tx", vec(tx), "--rx", vec(rx),
                   "--max-order", "2", "--solver", "ipc")
    assert_columns_are_the_json(paths, doc)
    # IPC writes every field the record has.
    assert paths.columns == _native.PATH_COLUMNS


def test_image_columns_are_every_json_key(cli_json):
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(max_order=3)
    assert_columns_are_the_json(paths, cli_json("builtin:living-room", "--max-order", "3"))
    assert len(paths.columns) < len(_native.PATH_COLUMNS)


def test_line_of_sight_has_empty_per_reflection_columns():
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(max_order=0)
    assert len(paths) == 1
    assert paths.points[0].shape == (0, 3)
    assert paths.incidence_deg[0].shape == (0,)
    assert paths.surfaces[0] == []


@pytest.mark.parametrize("solver", ["image", "ipc"])
def test_no_path_gives_every_column_but_the_optional_ones_empty(solver):
    # The receiver is behind the wall: no line of sight, no reflection.
    scene = beamtrace.load(TESTDATA / "one-wall.json", rx=[2.0, -2.0, 1.0])
    paths = scene.trace(max_order=2, solver=solver)
    assert len(paths) == 0
    with_paths = beamtrace.load("builtin:living-room").trace(max_order=1)
    assert paths.columns == with_paths.columns
    assert "iterations" not in paths.columns
    for key in paths.columns:
        empty, full = paths.to_dict()[key], with_paths.to_dict()[key]
        if isinstance(full, np.ndarray):
            assert empty.dtype == full.dtype and empty.shape == (0, *full.shape[1:]), key
        else:
            assert empty == [], key


def test_paths_documents_columns_that_exist():
    """The annotations of `Paths` are its user documentation: each names a column, in the
    columns' order (a renamed or removed field fails here)."""
    documented = list(beamtrace.Paths.__annotations__)
    assert documented == [c for c in _native.PATH_COLUMNS if c in documented]
