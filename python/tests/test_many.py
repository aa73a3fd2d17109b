"""Scene.trace_many (many receivers, one call, parallel) against repeated Scene.trace."""

from __future__ import annotations

import numpy as np
import pytest

import beamtrace


def receivers() -> np.ndarray:
    """A 4 x 3 grid at laptop height in the living room, away from furniture."""
    xs, ys = np.meshgrid(np.linspace(1.0, 4.6, 4), np.linspace(0.9, 3.6, 3))
    return np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 1.1)])


def assert_equal(a: beamtrace.Paths, b: beamtrace.Paths) -> None:
    assert a.columns == b.columns
    for key in a.columns:
        x, y = a.to_dict()[key], b.to_dict()[key]
        if isinstance(x, list):
            assert len(x) == len(y)
            for u, v in zip(x, y):
                assert np.array_equal(np.asarray(u), np.asarray(v)), key
        else:
            assert np.array_equal(x, y), key


@pytest.mark.parametrize("solver", ["image", "ipc"])
def test_trace_many_equals_repeated_trace(solver):
    scene = beamtrace.load("builtin:living-room")
    points = receivers()
    many = scene.trace_many(scene.tx, points, max_order=2, solver=solver)
    assert len(many) == len(points)
    counts = set()
    for rx, paths in zip(points, many):
        one = scene.trace(scene.tx, rx, max_order=2, solver=solver)
        assert_equal(paths, one)
        counts.add(len(paths))
    # The grid is not degenerate: receivers see different numbers of paths.
    assert len(counts) > 1


def test_trace_many_single_thread_is_identical():
    scene = beamtrace.load("builtin:living-room")
    points = receivers()
    a = scene.trace_many(None, points, max_order=2)
    b = scene.trace_many(None, points, max_order=2, parallel=False)
    for x, y in zip(a, b):
        assert_equal(x, y)


def test_trace_many_accepts_no_receivers():
    scene = beamtrace.load("builtin:living-room")
    assert scene.trace_many(None, np.zeros((0, 3))) == []


def test_trace_many_rejects_bad_shapes():
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(ValueError, match=r"shape \(m, 3\)"):
        scene.trace_many(None, np.zeros((4, 2)))
