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
    flat = scene.trace_many(None, np.zeros((0, 3)), flat=True)
    assert list(flat["path_offsets"]) == [0] and len(flat["traced"]) == 0
    assert len(flat["rank"]) == 0 and flat["points"].shape == (0, 3)


@pytest.mark.parametrize("solver", ["image", "ipc"])
def test_flat_columns_are_the_receivers_paths_end_to_end(solver):
    scene = beamtrace.load("builtin:living-room")
    # The second receiver lies on the floor: skipped, it has no paths.
    points = np.vstack([receivers()[:3], [[2.0, 2.0, 0.0]], receivers()[3:6]])
    flat = scene.trace_many(None, points, max_order=2, solver=solver, on_error="skip", flat=True)
    one = [
        None if k == 3 else scene.trace(None, rx, max_order=2, solver=solver)
        for k, rx in enumerate(points)
    ]
    traced = [p for p in one if p is not None]
    assert flat["traced"].tolist() == [p is not None for p in one]
    counts = [0 if p is None else len(p) for p in one]
    assert flat["path_offsets"].tolist() == np.concatenate([[0], np.cumsum(counts)]).tolist()
    assert flat["receiver"].tolist() == np.repeat(np.arange(len(points)), counts).tolist()
    orders = np.concatenate([p.order for p in traced])
    assert flat["interaction_offsets"].tolist() == np.concatenate([[0], np.cumsum(orders)]).tolist()
    for key in traced[0].columns:
        values = [p.to_dict()[key] for p in traced]
        if key in beamtrace._native.PER_INTERACTION_COLUMNS:
            items = [item for v in values for per_path in v for item in per_path]
            if key in beamtrace._native.TEXT_COLUMNS:
                assert flat[key].dtype == np.uint32
                assert [flat["texts"][t] for t in flat[key]] == items, key
            else:
                assert np.array_equal(flat[key], np.array(items).reshape(flat[key].shape)), key
        else:
            assert np.array_equal(flat[key], np.concatenate(values)), key
    assert len(set(flat["texts"])) == len(flat["texts"])
    for name in ("texts", "receiver", "path_offsets", "interaction_offsets", "traced"):
        assert name not in beamtrace._native.PATH_COLUMNS


def test_a_receivers_paths_are_made_on_first_use_and_pickle():
    import pickle

    scene = beamtrace.load("builtin:living-room")
    many = scene.trace_many(None, receivers()[:2], max_order=2)
    one = scene.trace(None, receivers()[1], max_order=2)
    assert len(many[1]) == len(one) and "_receiver" in many[1].__dict__
    assert_equal(pickle.loads(pickle.dumps(many[1])), one)
    assert "_receiver" not in many[1].__dict__
    assert many[0].gain.shape == (len(many[0]),)
    with pytest.raises(AttributeError, match="no attribute 'gains'"):
        many[0].gains


def test_trace_many_rejects_bad_shapes():
    scene = beamtrace.load("builtin:living-room")
    with pytest.raises(ValueError, match=r"shape \(m, 3\)"):
        scene.trace_many(None, np.zeros((4, 2)))


def test_on_error_skip_keeps_one_entry_per_receiver():
    scene = beamtrace.load("builtin:living-room")
    # The second receiver lies on the floor, the fourth at the TX: neither can be traced.
    points = np.array([[2.0, 2.0, 1.0], [2.0, 2.0, 0.0], [3.0, 1.5, 1.2], list(scene.tx)])
    many = scene.trace_many(None, points, max_order=2, on_error="skip")
    assert [p is None for p in many] == [False, True, False, True]
    for k in (0, 2):
        assert_equal(many[k], scene.trace(None, points[k], max_order=2))
    # The first receiver may be the bad one: the others are still traced.
    first_bad = scene.trace_many(None, points[[1, 0]], max_order=2, on_error="skip")
    assert first_bad[0] is None
    assert_equal(first_bad[1], many[0])


def test_on_error_raise_names_the_receiver():
    scene = beamtrace.load("builtin:living-room")
    points = np.array([[2.0, 2.0, 1.0], [2.0, 2.0, 0.0], [3.0, 1.5, 1.2]])
    with pytest.raises(beamtrace.BeamtraceError, match=r"receiver 1 \[2\.0, 2\.0, 0\.0\]: "):
        scene.trace_many(None, points, max_order=2)
    with pytest.raises(ValueError, match="on_error"):
        scene.trace_many(None, points, on_error="ignore")


def test_paths_index_and_iterate_as_path_records():
    scene = beamtrace.load("builtin:living-room")
    paths = scene.trace(max_order=2)
    assert len(list(paths)) == len(paths)
    last = paths[-1]
    assert isinstance(last, beamtrace.Path)
    assert last.rank == paths.rank[-1] and last.order == paths.order[-1]
    assert np.array_equal(last.points, paths.points[-1])
    assert last.surfaces == paths.surfaces[-1]
    assert paths[0].order == 0 and "line of sight" in repr(paths[0])
    with pytest.raises(IndexError):
        paths[len(paths)]
    with pytest.raises(TypeError):
        paths["rank"]


def test_the_namespace_lists_only_public_names():
    names = dir(beamtrace)
    for public in ("load", "Scene", "Paths", "Path", "Tracer", "BeamtraceError"):
        assert public in names
    for private in ("np", "os", "Any", "json", "warnings"):
        assert private not in names
