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
