"""Type stub of the native module (crates/bt-python); use the wrappers in ``beamtrace``."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

PATH_COLUMNS: List[str]
PER_INTERACTION_COLUMNS: List[str]
OPTIONAL_PATH_COLUMNS: List[str]
TEXT_COLUMNS: List[str]
"""Every column a trace can give, in the order of ``beamtrace trace --json``'s path objects
(derived from the report record; ``iterations``/``residual_m`` only for IPC)."""
DEFAULT_MAX_CANDIDATES: int
DEFAULT_MAX_WVRN_TESTS: int
DEFAULT_IPC_MAX_ITERATIONS: int
DEFAULT_MAX_RAYS: int
DEFAULT_MAX_FILE_BYTES: int
DEFAULT_MAX_XML_SUBSTITUTION: int
DEFAULT_MAX_MESH_ELEMENTS: int
DEFAULT_MAX_CLOUD_POINTS: int
DEFAULT_MAX_BEAM_PAIRS: int
PARTNER_SPIN_US: int

class BeamtraceError(Exception): ...

_Point = Optional[Tuple[float, float, float]]

class Scene:
    @property
    def name(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def tx(self) -> List[float]: ...
    @property
    def rx(self) -> List[float]: ...
    @property
    def frequency_hz(self) -> float: ...
    @property
    def surface_names(self) -> List[str]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def cache_warnings(self) -> List[str]: ...
    def trace(self, tx: _Point, rx: _Point, keywords: Dict[str, Any]) -> Dict[str, Any]: ...
    def trace_many(
        self,
        tx: _Point,
        receivers: npt.NDArray[np.float64],
        keywords: Dict[str, Any],
        skip_errors: bool,
    ) -> Dict[str, Any]: ...
    def view(self, tx: _Point, rx: _Point, keywords: Dict[str, Any]) -> str: ...
    def to_bytes(self) -> bytes: ...

class Tracer:
    def __init__(
        self,
        source: str,
        keywords: Dict[str, Any],
        tx: _Point,
        rx: _Point,
        beams: Optional[Dict[str, Any]] = None,
        partner_spin_us: int = ...,
        scene: Optional[Scene] = None,
    ) -> None: ...
    def answer(self, line: str) -> str: ...

def load(
    source: str,
    *,
    tx: _Point = None,
    rx: _Point = None,
    min_reflector_area: float = 0.25,
    merge_angle_deg: float = 1.0,
    merge_distance: float = 1e-3,
    budgets: Optional[Dict[str, int]] = None,
    cache: bool = False,
    frequency: Optional[float] = None,
    material: Optional[str] = None,
    thickness: Optional[float] = None,
) -> Scene: ...
def builtin_names() -> List[str]: ...
def scene_from_bytes(source: str, data: bytes) -> Scene: ...
def study_beam_management(
    out: str,
    *,
    scenarios: Optional[List[str]] = None,
    seed: int = 1,
    positions: int = 1000,
    scan_density: float = 2000.0,
) -> str: ...
