"""Real-time radio ray tracing from Python.

>>> import beamtrace
>>> scene = beamtrace.load("builtin:living-room")
>>> paths = scene.trace(scene.tx, scene.rx, max_order=3)
>>> paths.length_m[:3]          # metres, ranked by order then length
>>> paths.aoa_deg               # (n, 2): azimuth, elevation in degrees

Everything is computed by the Rust library the ``beamtrace`` CLI uses (same loading, the same
trace pipeline, the same report as ``beamtrace trace --json``). Units: metres, seconds,
degrees, dB; angles as in docs/conventions.md (azimuth from +x towards +y, elevation from the
horizontal plane; the arrival direction points from RX towards where the wave comes from).
"""

from __future__ import annotations

import inspect
import json
import os
import warnings
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import _native
from ._native import BeamtraceError

__all__ = [
    "BeamtraceError",
    "Path",
    "Paths",
    "Scene",
    "Tracer",
    "View",
    "builtin_names",
    "load",
    "study_beam_management",
]

Point = Union[Sequence[float], npt.NDArray[np.float64]]
"""A position in metres: three numbers x, y, z."""


class Paths:
    """The paths from one TX to one RX, specular and diffracted, ranked (order, then length,
    then angle).

    Per-path columns are NumPy arrays of length ``n = len(paths)``; per-reflection values are
    lists of ``n`` arrays. Every field of ``beamtrace trace --json``'s path objects is here
    under the same name, in the same order (``beamtrace._native.PATH_COLUMNS`` lists them all;
    the columns come from the report record itself). ``iterations``/``residual_m`` exist for
    the IPC solver only.
    """

    rank: npt.NDArray[np.int64]
    """1-based rank, shape (n,)."""
    order: npt.NDArray[np.int64]
    """Number of interactions (0 = line of sight), shape (n,)."""
    interactions: List[List[str]]
    """What happens at each point of each path: "reflection", "diffraction" or "transmission"
    (a crossing of a penetrable surface)."""
    surfaces: List[List[str]]
    """The surface of each interaction, TX side first: "A|B" (a wedge's two faces) or "A" (a
    free edge's face) at a diffraction, with ``\\`` and ``|`` inside a face name written
    ``\\\\`` and ``\\|`` (docs/output-format.md, "Edge names"): split a diffraction's entry
    only at an unescaped ``|``."""
    points: List[npt.NDArray[np.float64]]
    """Interaction points of each path, (k, 3) metres, TX side first (TX and RX excluded)."""
    length_m: npt.NDArray[np.float64]
    """Unfolded length, metres, shape (n,)."""
    delay_s: npt.NDArray[np.float64]
    """Propagation delay, seconds, shape (n,)."""
    aod_deg: npt.NDArray[np.float64]
    """Angle of departure (azimuth, elevation), degrees, shape (n, 2)."""
    aoa_deg: npt.NDArray[np.float64]
    """Angle of arrival (azimuth, elevation), degrees, shape (n, 2)."""
    incidence_deg: List[npt.NDArray[np.float64]]
    """Angle of incidence at each point from the surface normal, degrees, (k,) each; −inf at a
    diffraction (the document's null)."""
    free_space_loss_db: npt.NDArray[np.float64]
    """Friis free-space loss over the unfolded length, dB, shape (n,)."""
    reflection_loss_db: npt.NDArray[np.float64]
    """Sum of the materials' reflection losses, dB, shape (n,)."""
    diffraction_loss_db: npt.NDArray[np.float64]
    """The diffraction's excess loss over free space, dB (0 for specular paths), shape (n,)."""
    transmission_loss_db: npt.NDArray[np.float64]
    """The crossings' loss (ITU-R P.2040 slab transmission), dB (0 without), shape (n,)."""
    loss_db: npt.NDArray[np.float64]
    """Total loss, dB, shape (n,)."""
    gain: npt.NDArray[np.complex128]
    """Complex path gain (antennas, polarised bounces, λ/(4π·length); no propagation phase),
    shape (n,)."""
    gain_db: npt.NDArray[np.float64]
    """20·log10|gain|, dB (−inf for a path carrying no power), shape (n,)."""
    power_dbm: npt.NDArray[np.float64]
    """Received power of the path for the transmitted power (default 0 dBm), dBm, shape (n,)."""
    iterations: npt.NDArray[np.int64]
    """IPC rounds per path (IPC solver only), shape (n,)."""
    residual_m: npt.NDArray[np.float64]
    """IPC's last mean displacement, metres (IPC solver only), shape (n,)."""

    def __init__(self, columns: Dict[str, Any]) -> None:
        self._columns = dict(columns)
        self.__dict__.update(self._columns)

    @classmethod
    def _of_receiver(cls, batch: Dict[str, Any], i: int) -> "Paths":
        """Receiver ``i``'s paths of a flat batch, made on first use of a column (a
        many-receiver call builds one batch; most callers read a few receivers' columns)."""
        paths = cls.__new__(cls)
        paths.__dict__["_receiver"] = (batch, i)
        return paths

    def __getattr__(self, name: str) -> Any:
        # Reached only for a name not set yet: the columns of a receiver of a batch.
        receiver = self.__dict__.pop("_receiver", None)
        if receiver is None:
            raise AttributeError(f"'Paths' object has no attribute {name!r}")
        self.__init__(_receiver_columns(*receiver))  # type: ignore[misc]
        return getattr(self, name)

    def __len__(self) -> int:
        receiver = self.__dict__.get("_receiver")
        if receiver is not None:
            batch, i = receiver
            return int(batch["path_offsets"][i + 1] - batch["path_offsets"][i])
        return len(self._columns["order"])

    def __getitem__(self, i: int) -> "Path":
        """The ``i``-th path (ranked order; negative counts from the end) as a :class:`Path`."""
        n = len(self)
        if not isinstance(i, (int, np.integer)):
            raise TypeError(f"path index must be an integer, got {type(i).__name__}")
        k = int(i) + n if i < 0 else int(i)
        if not 0 <= k < n:
            raise IndexError(f"path index {i} out of range for {n} paths")
        return Path({name: column[k] for name, column in self._columns.items()})

    def __iter__(self):
        return (self[k] for k in range(len(self)))

    def to_pandas(self):
        """The paths as a pandas DataFrame, one row per path and one column per field
        (per-interaction fields hold arrays or lists); needs pandas installed."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Paths.to_pandas needs pandas: pip install pandas") from e
        return pandas.DataFrame({name: list(column) for name, column in self._columns.items()})

    def __repr__(self) -> str:
        orders = np.bincount(self._columns["order"]) if len(self) else []
        return f"Paths({len(self)} paths, per order {list(map(int, orders))})"

    @property
    def columns(self) -> List[str]:
        """Names of the columns present."""
        return list(self._columns)

    def to_dict(self) -> Dict[str, Any]:
        """The columns as a dict (name -> array or list)."""
        return dict(self._columns)

    def __getstate__(self) -> Dict[str, Any]:
        return self._columns

    def __setstate__(self, state: Dict[str, Any]) -> None:
        self.__init__(state)  # type: ignore[misc]


def _receiver_columns(batch: Dict[str, Any], i: int) -> Dict[str, Any]:
    """Receiver ``i``'s columns of a flat batch (``Scene.trace_many(..., flat=True)``): views
    of its rows, the per-interaction columns split into one array (or list) per path; IPC's
    optional columns left out when it has no path, as ``Scene.trace`` leaves them."""
    p0, p1 = int(batch["path_offsets"][i]), int(batch["path_offsets"][i + 1])
    bounds = batch["interaction_offsets"][p0 : p1 + 1].tolist()
    i0, i1 = bounds[0], bounds[-1]
    # Each path's interactions, as slice bounds within the receiver's.
    spans = [(a - i0, b - i0) for a, b in zip(bounds, bounds[1:])]
    columns: Dict[str, Any] = {}
    for name in _native.PATH_COLUMNS:
        if name not in batch or (p0 == p1 and name in _native.OPTIONAL_PATH_COLUMNS):
            continue
        column = batch[name]
        if name not in _native.PER_INTERACTION_COLUMNS:
            columns[name] = column[p0:p1]
            continue
        part = column[i0:i1]
        if name in _native.TEXT_COLUMNS:
            texts = batch["texts"]
            part = [texts[t] for t in part.tolist()]
        columns[name] = [part[a:b] for a, b in spans]
    return columns


class Path:
    """One path of a :class:`Paths`: the same fields, each this path's value (``order`` an int,
    ``points`` a (k, 3) array, ``aod_deg`` an (azimuth, elevation) array, ...)."""

    def __init__(self, fields: Dict[str, Any]) -> None:
        self._fields = dict(fields)
        self.__dict__.update(self._fields)

    def to_dict(self) -> Dict[str, Any]:
        """The fields as a dict."""
        return dict(self._fields)

    def __repr__(self) -> str:
        via = " > ".join(self._fields["surfaces"]) or "line of sight"
        return f"Path(rank {self._fields['rank']}, order {self._fields['order']}, {via})"


def _scene_from_bytes(source: str, data: bytes) -> "Scene":
    """A pickled :class:`Scene` back (``Scene.__reduce__``)."""
    return Scene(_native.scene_from_bytes(source, data))


def _point(value: Optional[Point], name: str) -> Optional[tuple]:
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.shape != (3,):
        raise ValueError(f"{name} must be three numbers x, y, z (metres), got shape {a.shape}")
    return tuple(float(x) for x in a)


def _receivers(rx: Any) -> npt.NDArray[np.float64]:
    a = np.ascontiguousarray(rx, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"rx must have shape (m, 3), metres, got shape {a.shape}")
    return a


class Scene:
    """A validated scene (surfaces, materials and, when the file or :func:`load` gives them, a
    default TX and RX), loaded by :func:`load`."""

    def __init__(self, native: Any) -> None:
        self._native = native

    @property
    def name(self) -> str:
        """Scene name."""
        return self._native.name

    @property
    def source(self) -> str:
        """What the scene was loaded from: a file path or ``builtin:NAME``."""
        return self._native.source

    @property
    def tx(self) -> Optional[npt.NDArray[np.float64]]:
        """The scene's transmitter position, metres; None when it has none (a mesh)."""
        tx = self._native.tx
        return None if tx is None else np.array(tx)

    @property
    def rx(self) -> Optional[npt.NDArray[np.float64]]:
        """The scene's receiver position, metres; None when it has none (a mesh)."""
        rx = self._native.rx
        return None if rx is None else np.array(rx)

    @property
    def frequency_hz(self) -> float:
        """Carrier frequency, Hz."""
        return self._native.frequency_hz

    @property
    def surface_names(self) -> List[str]:
        """Names of all surfaces (reflectors and blockers), in scene order."""
        return self._native.surface_names

    @property
    def warnings(self) -> List[str]:
        """Non-fatal notes of the import (merged faces, unknown materials, ...)."""
        return self._native.warnings

    def __reduce__(self):
        # Pickling (Ray, multiprocessing) ships the scene itself, not its path: the receiving
        # process rebuilds it, every polygon checked, without reading any file.
        return (_scene_from_bytes, (self._native.source, self._native.to_bytes()))

    def __repr__(self) -> str:
        return f"Scene({self.name!r}, {len(self.surface_names)} surfaces)"

    def trace(
        self,
        tx: Optional[Point] = None,
        rx: Optional[Point] = None,
        max_order: int = 3,
        solver: str = "image",
        candidates: str = "beam-tree",
        *,
        max_candidates: int = _native.DEFAULT_MAX_CANDIDATES,
        max_wvrn_tests: int = _native.DEFAULT_MAX_WVRN_TESTS,
        ipc_order: str = "gauss-seidel",
        ipc_accel: str = "none",
        ipc_threshold: Optional[float] = None,
        ipc_max_iterations: int = _native.DEFAULT_IPC_MAX_ITERATIONS,
        sbr_step_deg: Optional[float] = None,
        sbr_rays: Optional[int] = None,
        sbr_planar: bool = False,
        max_rays: int = _native.DEFAULT_MAX_RAYS,
        parallel: bool = True,
        diffraction: bool = False,
        max_diffractions: Optional[int] = None,
        min_edge_length: float = 0.0,
        diffraction_coefficient: str = "utd",
        transmission: bool = False,
        tx_pattern: str = "iso",
        rx_pattern: str = "iso",
        tx_polarization: str = "V",
        rx_polarization: str = "V",
        tx_orientation: Point = (0.0, 0.0, 0.0),
        rx_orientation: Point = (0.0, 0.0, 0.0),
        tx_power_dbm: float = 0.0,
    ) -> Paths:
        """Trace every path from ``tx`` to ``rx`` (metres; the scene's own if None): specular,
        and with ``diffraction=True`` (or ``max_diffractions=1``) those that diffract once on
        an edge at least ``min_edge_length`` metres long, their gains with
        ``diffraction_coefficient`` "utd" (default) or "sionna-rt-2.2" (Sionna RT 2.2's gains,
        for comparing with Sionna: its combination, and its diffracted leg for a PathSolver
        whose ``max_depth`` is ``max_order``; docs/channel.md §8). ``transmission=True`` is
        ``--transmission``: waves also cross every reflector whose material is a slab (ITU-R
        P.2040 thin-slab transmission, no deflection; each crossing counts in ``max_order``).

        Options are ``beamtrace trace``'s flags: ``solver`` "image" | "ipc" | "sbr",
        ``candidates`` "beam-tree" | "wvrn" | "exhaustive", ``ipc_order`` "gauss-seidel" |
        "jacobi", ``ipc_accel`` "none" | "newton", ``ipc_threshold`` (m) and
        ``ipc_max_iterations``, ``sbr_step_deg`` or ``sbr_rays`` and the ``max_rays`` budget; the
        antennas ``tx_pattern``/``rx_pattern`` "iso" | "tr38901", ``tx_polarization``/
        ``rx_polarization`` "V" | "H" | "+45" | "-45", ``tx_orientation``/``rx_orientation``
        (yaw, pitch, roll in degrees) and ``tx_power_dbm``, as ``beamtrace trace``'s flags of
        those names (docs/channel.md §4). Raises
        :class:`BeamtraceError` when a position is invalid (on a surface, equal to the other
        terminal) or a budget is exceeded (``max_candidates``; ``max_wvrn_tests``, the WVRN's
        node pairs × surfaces, with ``candidates="wvrn"``), ``ValueError`` on a bad option or when
        a terminal is neither given nor in the scene (meshes, XML and point clouds have none).
        """
        batch = self._native.trace(
            _point(tx, "tx"),
            _point(rx, "rx"),
            _options(locals()),
        )
        return Paths(_receiver_columns(batch, 0))

    def trace_many(
        self,
        tx: Optional[Point],
        rx: Any,
        max_order: int = 3,
        solver: str = "image",
        candidates: str = "beam-tree",
        *,
        max_candidates: int = _native.DEFAULT_MAX_CANDIDATES,
        max_wvrn_tests: int = _native.DEFAULT_MAX_WVRN_TESTS,
        ipc_order: str = "gauss-seidel",
        ipc_accel: str = "none",
        ipc_threshold: Optional[float] = None,
        ipc_max_iterations: int = _native.DEFAULT_IPC_MAX_ITERATIONS,
        sbr_step_deg: Optional[float] = None,
        sbr_rays: Optional[int] = None,
        sbr_planar: bool = False,
        max_rays: int = _native.DEFAULT_MAX_RAYS,
        parallel: bool = True,
        diffraction: bool = False,
        max_diffractions: Optional[int] = None,
        min_edge_length: float = 0.0,
        diffraction_coefficient: str = "utd",
        transmission: bool = False,
        tx_pattern: str = "iso",
        rx_pattern: str = "iso",
        tx_polarization: str = "V",
        rx_polarization: str = "V",
        tx_orientation: Point = (0.0, 0.0, 0.0),
        rx_orientation: Point = (0.0, 0.0, 0.0),
        tx_power_dbm: float = 0.0,
        on_error: str = "raise",
        flat: bool = False,
    ) -> Any:
        """Trace one ``tx`` to every row of ``rx`` (an (m, 3) array, metres): one
        :class:`Paths` per receiver, in order, equal to calling :meth:`trace` for each.

        Receivers run in parallel on all cores with the GIL released. A receiver that cannot be
        traced (on a surface, at the TX): with ``on_error="raise"`` (default) the call raises
        :class:`BeamtraceError` naming the first such receiver's index and position; with
        ``on_error="skip"`` its entry is ``None`` and the others are traced, as the CLI's
        ``sweep`` marks such grid points.

        All receivers' columns are built in one set of arrays; a receiver's :class:`Paths`
        makes its own columns (views of its rows) when one is first read. With ``flat=True``
        the call returns that set instead, one dict for all receivers (as Sionna RT's path
        tensors are indexed by receiver): every column of :class:`Paths` over the ``n`` paths
        of all receivers in receiver order, the per-interaction ones (``interactions``,
        ``surfaces``, ``points``, ``incidence_deg``) flat over all interactions, the texts
        (``interactions``, ``surfaces``) as ``uint32`` indices into ``texts`` (a list of the
        distinct texts: ``np.array(flat["texts"])[flat["surfaces"]]`` names them); beside them
        ``receiver`` (n,) each path's receiver index, ``path_offsets`` (m + 1,) (receiver
        ``i``'s paths are rows ``path_offsets[i]:path_offsets[i + 1]``),
        ``interaction_offsets`` (n + 1,) (path ``j``'s interactions are rows
        ``interaction_offsets[j]:interaction_offsets[j + 1]``) and ``traced`` (m,) (False
        where ``on_error="skip"`` skipped a receiver: it has no paths).
        """
        if on_error not in ("raise", "skip"):
            raise ValueError(f'on_error must be "raise" or "skip", got {on_error!r}')
        arguments = dict(locals())
        del arguments["on_error"], arguments["flat"]
        batch = self._native.trace_many(
            _point(tx, "tx"),
            _receivers(rx),
            _options(arguments),
            on_error == "skip",
        )
        if flat:
            return batch
        traced = batch["traced"].tolist()
        return [Paths._of_receiver(batch, i) if t else None for i, t in enumerate(traced)]

    def view(
        self, tx: Optional[Point] = None, rx: Optional[Point] = None, **options: Any
    ) -> "View":
        """The 3-D view of ``beamtrace view``: the scene with the paths from ``tx`` to ``rx``
        (metres; the scene's own if None) traced with :meth:`trace`'s keywords, or the
        geometry alone when a terminal is neither given nor in the scene. A Jupyter cell
        shows it inline; :meth:`View.save` writes the page.

        >>> scene.view(max_order=2, diffraction=True)      # last line of a notebook cell
        """
        keywords = _trace_keywords(options)
        return View(self._native.view(_point(tx, "tx"), _point(rx, "rx"), keywords))


class View:
    """One offline HTML page (three.js inside) showing a scene and its paths: inline in
    Jupyter (``_repr_html_``), or written with :meth:`save` and opened in a browser."""

    def __init__(self, html: str) -> None:
        self.html = html
        """The whole page, as ``beamtrace view`` writes it."""

    def _repr_html_(self) -> str:
        escaped = self.html.replace("&", "&amp;").replace('"', "&quot;")
        return f'<iframe srcdoc="{escaped}" style="width:100%;height:520px;border:0"></iframe>'

    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Write the page to ``path`` (a new file, or one this view wrote before: an existing
        file is refused with ``FileExistsError`` unless it holds a beamtrace page)."""
        path = os.fspath(path)
        if os.path.exists(path):
            with open(path, encoding="utf-8", errors="replace") as f:
                if "<title>beamtrace view:" not in f.read(4096):
                    raise FileExistsError(f"{path} exists and is not a beamtrace view: not replaced")
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(self.html)
        os.replace(tmp, path)

    def __repr__(self) -> str:
        return f"View({len(self.html) // 1024} KiB)"


class Tracer:
    """The real-time loop of ``beamtrace serve`` in Python: a scene kept loaded with one
    tracer (its beam tree of the TX and its caches carry over from update to update), moved by
    :meth:`update` (docs/serve.md).

    >>> tracer = beamtrace.Tracer("builtin:living-room-dynamic", max_order=3)
    >>> tracer.update(rx=[1.0, 2.0, 1.2])["paths"][0]["length_m"]
    >>> tracer.update(objects={"person": {"offset": [0.5, 1.5, 0.0]}})

    ``scene`` is a source (``builtin:NAME`` or a scene file, loaded with its time steps and
    moving objects) or a :class:`Scene` (reloaded from its :attr:`Scene.source` with the
    options :func:`load` was given: mesh options, ``material``, ``thickness``, ``frequency``;
    with its TX and RX; an unpickled :class:`Scene`, whose pickle keeps no load options, is
    traced as it is, as one step without moving objects). With a source, ``options`` may also
    hold :func:`load`'s keywords (``material``, ``thickness``, ``frequency``, the mesh options
    and budgets, ``cache``: ``serve``'s flags of the same names); the source is then loaded
    with them. ``tx`` overrides the scene's transmitter. ``options`` are :meth:`Scene.trace`'s
    keywords with its defaults (``max_order=3``, ``solver``, ``diffraction``, ...); an unknown
    one raises ``TypeError``, a bad value ``ValueError``, here.

    With ``tx_array`` or ``rx_array`` (``(rows, columns)``; the other one 1 × 8) every answer
    also holds ``"beams"``, as ``serve --tx-array/--rx-array``: the beam sweep of ``beamtrace
    beams`` over the answer's paths, its ``best`` pair and the first ``top`` pairs, with
    ``tx_spacing``/``rx_spacing`` (wavelengths), ``ranking`` ("power" or "paper") and the
    ``max_beam_pairs`` budget.

    ``partner_spin_us`` is ``serve --partner-spin-us``: how long (µs) a second thread spins
    after each update for the next one, to take half of a lone receiver's tree walk and report; 0 answers
    every update on one thread (the same answers either way).
    """

    def __init__(
        self,
        scene: Union[str, "os.PathLike[str]", Scene],
        tx: Optional[Point] = None,
        *,
        tx_array: Optional[Sequence[int]] = None,
        rx_array: Optional[Sequence[int]] = None,
        tx_spacing: float = 0.5,
        rx_spacing: float = 0.5,
        ranking: str = "power",
        top: int = 5,
        max_beam_pairs: int = _native.DEFAULT_MAX_BEAM_PAIRS,
        partner_spin_us: int = _native.PARTNER_SPIN_US,
        **options: Any,
    ) -> None:
        rx, native_scene = None, None
        loading = _load_keywords(options)
        if loading and isinstance(scene, Scene):
            raise TypeError(
                f"{', '.join(sorted(loading))}: load options of a source; this Scene is "
                "loaded already (give them to beamtrace.load)"
            )
        if loading:
            scene = load(scene, tx=tx, **loading)
        if isinstance(scene, Scene):
            source, native_scene = scene.source, scene._native
            tx = scene.tx if tx is None else tx
            rx = scene.rx
        else:
            source = os.fspath(scene)
        keywords = _trace_keywords(options)
        beams = None
        if tx_array is not None or rx_array is not None:
            shape = lambda a: None if a is None else (int(a[0]), int(a[1]))  # noqa: E731
            beams = {
                "tx_array": shape(tx_array),
                "rx_array": shape(rx_array),
                "tx_spacing": float(tx_spacing),
                "rx_spacing": float(rx_spacing),
                "ranking": ranking,
                "top": int(top),
                "max_beam_pairs": int(max_beam_pairs),
            }
        spin = int(partner_spin_us)
        if not 0 <= spin <= 1_000_000:
            raise ValueError(f"partner_spin_us: {spin} is outside 0..=1000000")
        self._native = _native.Tracer(
            source, keywords, _point(tx, "tx"), _point(rx, "rx"), beams, spin, native_scene
        )

    def update(
        self,
        rx: Any = None,
        tx: Optional[Point] = None,
        objects: Optional[Dict[str, Dict[str, Any]]] = None,
        step: Optional[int] = None,
    ) -> Dict[str, Any]:
        """Move what is given and trace: ``rx`` one receiver ``[x, y, z]`` or an (m, 3)
        array of them (metres), ``tx`` the transmitter, ``objects`` poses by object name
        (``{"door": {"angle_deg": 30}, "person": {"offset": [dx, dy, dz]}}``, as a dynamic
        scene's keyframes spell them), ``step`` every object to its pose at that step of the
        scene file. What is not given stays as the previous update left it.

        Returns the answer of ``beamtrace serve`` as Python objects: for one receiver
        ``{"id", "tx", "rx", "paths", "stats", "latency_us"}`` (``paths``: the records of
        ``beamtrace trace --json``), for several ``{"id", "results": [...], "latency_us"}``,
        one entry per receiver (an entry ``{"rx", "error"}`` for a receiver that cannot be
        traced). Raises :class:`BeamtraceError` with serve's message, naming the field, when
        the update cannot be traced; the tracer then stays as it was.
        """
        request: Dict[str, Any] = {}
        if rx is not None:
            request["rx"] = _request_receivers(rx)
        if tx is not None:
            request["tx"] = list(_point(tx, "tx") or ())
            if not np.isfinite(request["tx"]).all():
                raise ValueError("tx must be finite numbers (metres)")
        if objects is not None:
            request["objects"] = objects
        if step is not None:
            request["step"] = step
        line = json.dumps(request, default=_plain, allow_nan=False)
        answer = json.loads(self._native.answer(line))
        if "error" in answer:
            raise BeamtraceError(answer["error"])
        return answer


def _load_keywords(options: Dict[str, Any]) -> Dict[str, Any]:
    """The keywords of :func:`load` (but the source and terminals) among ``options``, taken
    out of them."""
    names = set(inspect.signature(load).parameters) - {"source", "tx", "rx"}
    return {name: options.pop(name) for name in sorted(names & set(options))}


def _trace_keywords(options: Dict[str, Any]) -> Dict[str, Any]:
    """``options`` as the native module takes them, each keyword absent taking
    :meth:`Scene.trace`'s default (its signature is the one list of them)."""
    parameters = inspect.signature(Scene.trace).parameters
    names = [name for name in parameters if name not in ("self", "tx", "rx")]
    unknown = sorted(set(options) - set(names))
    if unknown:
        raise TypeError(
            f"unknown trace keyword(s) {', '.join(unknown)}; they are {', '.join(names)}"
        )
    return _options({name: options.get(name, parameters[name].default) for name in names})


def _request_receivers(rx: Any) -> Any:
    """One receiver as [x, y, z], several as [[x, y, z], ...] (the serve request's spelling)."""
    a = np.asarray(rx, dtype=np.float64)
    if a.shape != (3,) and (a.ndim != 2 or a.shape[1] != 3):
        raise ValueError(f"rx must be [x, y, z] or have shape (m, 3), metres, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError("rx must be finite numbers (metres)")
    return a.tolist()


def _plain(value: Any) -> Any:
    """NumPy values in a pose as plain Python numbers and lists (for JSON)."""
    if isinstance(value, (np.ndarray, np.generic)):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not a number or a list of numbers")


def _options(arguments: Dict[str, Any]) -> Dict[str, Any]:
    """The trace keywords as the native module takes them: IPC's and SBR's in their own dicts."""
    options = {
        name: arguments[name]
        for name in (
            "max_order",
            "solver",
            "candidates",
            "max_candidates",
            "max_wvrn_tests",
            "parallel",
            "transmission",
        )
    }
    threshold = arguments["ipc_threshold"]
    options["ipc"] = {
        "order": arguments["ipc_order"],
        "accel": arguments["ipc_accel"],
        "threshold": None if threshold is None else float(threshold),
        "max_iterations": arguments["ipc_max_iterations"],
    }
    options["sbr"] = {
        "step_deg": arguments["sbr_step_deg"],
        "rays": arguments["sbr_rays"],
        "planar": arguments["sbr_planar"],
        "max_rays": arguments["max_rays"],
    }
    maximum = arguments["max_diffractions"]
    options["diffraction"] = {
        "max_diffractions": int(arguments["diffraction"]) if maximum is None else maximum,
        "min_edge_length": float(arguments["min_edge_length"]),
        "coefficient": arguments["diffraction_coefficient"],
    }
    options["antennas"] = {
        name: arguments[name]
        for name in ("tx_pattern", "rx_pattern", "tx_polarization", "rx_polarization")
    }
    for name in ("tx_orientation", "rx_orientation"):
        options["antennas"][name] = _point(arguments[name], name)
    options["antennas"]["tx_power_dbm"] = float(arguments["tx_power_dbm"])
    return options


def load(
    source: Union[str, "os.PathLike[str]"],
    *,
    tx: Optional[Point] = None,
    rx: Optional[Point] = None,
    min_reflector_area: float = 0.25,
    merge_angle_deg: float = 1.0,
    merge_distance: float = 1e-3,
    max_file_bytes: int = _native.DEFAULT_MAX_FILE_BYTES,
    max_xml_substitution: int = _native.DEFAULT_MAX_XML_SUBSTITUTION,
    max_mesh_elements: int = _native.DEFAULT_MAX_MESH_ELEMENTS,
    max_cloud_points: int = _native.DEFAULT_MAX_CLOUD_POINTS,
    cache: bool = False,
    frequency: Optional[float] = None,
    material: Optional[str] = None,
    thickness: Optional[float] = None,
) -> Scene:
    """Load a scene: a file the CLI reads (.json, .toml, .obj, .ply mesh, Mitsuba .xml, .ply/.pcd
    point cloud, whose planes are extracted as the CLI does) or ``"builtin:NAME"``.

    ``tx``/``rx`` override the file's terminals. Meshes, XML scenes and point clouds carry
    none: load them bare and give ``tx``/``rx`` to each :meth:`Scene.trace`. The mesh
    options are ``beamtrace trace``'s ``--min-reflector-area`` (m²), ``--merge-angle-deg`` and
    ``--merge-distance`` (m); the budgets are its ``--max-file-bytes`` (any input file),
    ``--max-xml-substitution`` (bytes an XML scene's ``$parameters`` expand to),
    ``--max-mesh-elements`` (vertices and faces of a mesh, or of all meshes of an XML scene) and
    ``--max-cloud-points`` (points a point-cloud file declares), each checked before the work. ``cache=True`` is ``--cache``: the loaded scene is kept in
    the user's cache directory (``$BEAMTRACE_CACHE_DIR``, else ``$XDG_CACHE_HOME/beamtrace``,
    else ``~/.cache/beamtrace``) and read from there while the files and options are unchanged;
    a damaged entry is rebuilt with a :class:`RuntimeWarning`. ``frequency`` (Hz),
    ``material`` and ``thickness`` (m) are ``--frequency``, ``--material`` and ``--thickness``:
    the carrier (replacing a scene file's), and every surface's radio material spelled
    ``"itu:NAME"`` (e.g. ``"itu:concrete"``) or ``"custom:EPS_R,SIGMA"``, a slab of
    ``thickness`` metres or a half-space; ``thickness`` alone makes every material the scene
    leaves a half-space a slab of that thickness (so that ``transmission=True`` crosses it;
    slabs keep their own); a bad value is a ``ValueError``. Raises :class:`BeamtraceError`
    with the CLI's message (naming the file, line or field) when the scene cannot be read or is
    invalid.
    """
    native = _native.load(
        os.fspath(source),
        tx=_point(tx, "tx"),
        rx=_point(rx, "rx"),
        min_reflector_area=min_reflector_area,
        merge_angle_deg=merge_angle_deg,
        merge_distance=merge_distance,
        budgets={
            "max_file_bytes": max_file_bytes,
            "max_xml_substitution": max_xml_substitution,
            "max_mesh_elements": max_mesh_elements,
            "max_cloud_points": max_cloud_points,
        },
        cache=bool(cache),
        frequency=None if frequency is None else float(frequency),
        material=material,
        thickness=None if thickness is None else float(thickness),
    )
    for note in native.cache_warnings:
        warnings.warn(note, RuntimeWarning, stacklevel=2)
    return Scene(native)


def builtin_names() -> List[str]:
    """Names of the built-in scenes, loadable as ``load("builtin:NAME")``."""
    return list(_native.builtin_names())


def study_beam_management(
    out: Union[str, "os.PathLike[str]"],
    *,
    scenarios: Optional[Sequence[str]] = None,
    seed: int = 1,
    positions: int = 1000,
    scan_density: float = 2000.0,
) -> Dict[str, Any]:
    """Run ``beamtrace study beam-management`` (docs/study-beam-management.md) and write its
    files into ``out``; returns the parsed ``summary.json``:
    ``{"scenarios": {NAME: {"methods": {METHOD: {"top1", ...}}}}}``.

    ``scenarios``: ``"living-room"``, ``"city"`` or scene files (default the two built-ins);
    ``positions`` UE positions per scenario; ``scan_density`` points/m² of the scan behind
    the extracted twin (0: none). Every other setting is the CLI's default.
    """
    text = _native.study_beam_management(
        os.fspath(out),
        scenarios=None if scenarios is None else [str(s) for s in scenarios],
        seed=int(seed),
        positions=int(positions),
        scan_density=float(scan_density),
    )
    result: Dict[str, Any] = json.loads(text)
    return result


def __dir__() -> List[str]:
    """The public names only (not the modules this one imports)."""
    return sorted(__all__ + ["distributed"])
