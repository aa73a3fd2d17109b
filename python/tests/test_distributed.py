"""The Ray sweep against trace_many on a local two-CPU Ray cluster; the core without Ray."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import beamtrace
from test_many import assert_equal, receivers


@pytest.fixture(scope="module")
def ray_local():
    import ray
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


def test_sweep_equals_trace_many(ray_local):
    from beamtrace import distributed

    points = receivers()
    scene = beamtrace.load("builtin:living-room")
    local = scene.trace_many(scene.tx, points, max_order=2)
    for chunks in (1, 3, 5):
        remote = distributed.sweep("builtin:living-room", scene.tx, points,
                                   chunks=chunks, max_order=2)
        assert len(remote) == len(local)
        for a, b in zip(remote, local):
            assert_equal(a, b)


def test_sweep_raises_the_task_error(ray_local):
    from beamtrace import distributed

    with pytest.raises(beamtrace.BeamtraceError, match="no-such-room.json"):
        distributed.sweep("/nonexistent/no-such-room.json", None, np.ones((2, 3)), chunks=2)


def test_core_imports_without_ray():
    # Block `ray` as if it were not installed: the core package and the module still import.
    code = (
        "import sys; sys.modules['ray'] = None\n"
        "import beamtrace, beamtrace.distributed\n"
        "print(len(beamtrace.load('builtin:living-room').trace()))\n"
        "try:\n"
        "    beamtrace.distributed.sweep('builtin:living-room', None, [[1, 1, 1]])\n"
        "except ImportError as e:\n"
        "    print('ImportError', e)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "45"
    assert lines[1].startswith("ImportError") and "[ray]" in lines[1]


def test_a_loaded_scene_travels_without_its_file(ray_local, tmp_path):
    """A Scene goes to the workers as data: its file is gone before the sweep starts, and the
    workers run in a folder where its path does not exist either."""
    import shutil
    from beamtrace import distributed
    from conftest import TESTDATA

    copy = tmp_path / "room.obj"
    shutil.copy(TESTDATA / "box-room.obj", copy)
    scene = beamtrace.load(copy)
    copy.unlink()
    tx = [1.0, 1.0, 1.5]
    points = np.array([[4.0, 3.0, 1.2], [2.5, 2.0, 2.0], [1.5, 3.0, 0.8]])
    local = scene.trace_many(tx, points, max_order=2)
    remote = distributed.sweep(scene, tx, points, chunks=3, max_order=2)
    assert len(remote) == len(local) == 3
    for a, b in zip(remote, local):
        assert_equal(a, b)


def test_a_scene_pickles_as_its_data():
    import pickle

    scene = beamtrace.load("builtin:living-room")
    back = pickle.loads(pickle.dumps(scene))
    assert back.name == scene.name and back.surface_names == scene.surface_names
    assert_equal(back.trace(max_order=2), scene.trace(max_order=2))
    with pytest.raises(beamtrace.BeamtraceError, match="not a pickled beamtrace scene"):
        beamtrace._scene_from_bytes("bad", b"\xff\x00garbage")
