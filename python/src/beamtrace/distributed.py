"""Receiver sweeps on a Ray cluster: the same numbers as ``Scene.trace_many``, more machines.

``sweep`` cuts the receiver points into ``chunks`` contiguous blocks, runs one Ray task per
block (each calls ``trace_many`` on its block) and concatenates the results in the order of
``points``. Given a loaded :class:`beamtrace.Scene`, the scene itself goes into Ray's object
store once and every task reads it from there, so workers need no file; given a path, each
task loads the scene from it. Ray is an optional extra:
``pip install './python[ray]'``; ``import beamtrace`` works without it.

On one machine, ``sweep`` starts a local Ray instance when none is running. On a cluster,
connect first and make the package importable on every worker, e.g.::

    import ray
    ray.init(address="ray://head-node:10001",          # or "auto" on a cluster node
             runtime_env={"pip": ["/shared/beamtrace-0.1.0-cp39-abi3-linux_x86_64.whl"]})
    paths = beamtrace.distributed.sweep("/shared/room.json", tx, points, chunks=64)

A scene *path* is read by the workers, so it must exist on them (a shared filesystem, or a
``builtin:NAME`` scene); pass the loaded scene instead when it does not. The wheel comes from ``pip wheel ./python`` or
``maturin build --release -m python/pyproject.toml`` (under ``target/wheels/``); it is abi3,
so one wheel serves every CPython >= 3.9 on the same platform.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Union

import numpy as np

from . import Paths, Point, Scene, _receivers, load


def _trace_chunk(
    scene: Union[str, Scene],
    load_options: Dict[str, Any],
    tx: Optional[Point],
    points: np.ndarray,
    trace_options: Dict[str, Any],
) -> List[Paths]:
    """One Ray task: the scene (loaded once from its path, or shipped), every receiver of the
    block traced."""
    if not isinstance(scene, Scene):
        scene = load(scene, **load_options)
    return scene.trace_many(tx, points, **trace_options)


def sweep(
    scene: Union[str, "os.PathLike[str]", Scene],
    tx: Optional[Point],
    points: Any,
    *,
    chunks: Optional[int] = None,
    max_order: int = 3,
    load_options: Optional[Dict[str, Any]] = None,
    **trace_options: Any,
) -> List[Paths]:
    """Trace ``tx`` to every row of ``points`` ((m, 3) metres) on Ray: one :class:`Paths`
    per point, in order, equal to ``scene.trace_many(tx, points, ...)`` for a loaded
    :class:`Scene` (shipped to the workers through Ray's object store, once), or to
    ``load(scene).trace_many(tx, points, ...)`` for a path or ``builtin:NAME``.

    ``chunks`` is the number of Ray tasks (default: the cluster's CPU count, at most one
    point per task). ``load_options`` go to :func:`beamtrace.load` for a path (e.g.
    ``tx``/``rx`` for meshes, merge tolerances); ``trace_options`` to :meth:`Scene.trace_many` (``solver``,
    ``candidates``, ...). Each task traces its block with all the cores Ray gives it.
    Errors of a task (a bad scene, a receiver on a wall) are raised here as
    :class:`beamtrace.BeamtraceError` (Ray wraps them; the original is re-raised).
    """
    try:
        import ray
    except ImportError as e:  # pragma: no cover - exercised by the no-ray import test
        raise ImportError(
            "beamtrace.distributed needs Ray: pip install 'beamtrace[ray]' "
            "(from a checkout: pip install './python[ray]')"
        ) from e

    receivers = _receivers(points)
    if not ray.is_initialized():
        ray.init()
    if chunks is None:
        chunks = int(ray.cluster_resources().get("CPU", 1))
    if chunks < 1:
        raise ValueError(f"chunks must be at least 1, got {chunks}")
    if len(receivers) == 0:
        return []
    blocks = np.array_split(receivers, min(chunks, len(receivers)))
    task = ray.remote(_trace_chunk)
    options = dict(trace_options, max_order=max_order)
    if isinstance(scene, Scene):
        if load_options:
            raise ValueError("load_options apply to a scene path, not to a loaded Scene")
        source: Any = ray.put(scene)
    else:
        source = os.fspath(scene)
    refs = [
        task.remote(source, dict(load_options or {}), tx, block, options) for block in blocks
    ]
    try:
        results = ray.get(refs)
    except ray.exceptions.RayTaskError as e:
        # Hand back the task's own exception (BeamtraceError with the CLI's message).
        if isinstance(getattr(e, "cause", None), Exception):
            raise e.cause from None
        raise
    return [paths for block in results for paths in block]
