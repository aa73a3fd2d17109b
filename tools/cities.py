"""The city cases of issue 29, shared by ``city_speed.py`` and ``ab_cities.py``: which scenes,
where their terminals are, and the ``beamtrace trace`` command that traces them. Imports
nothing beyond the standard library (``ab_cities.py`` runs without Sionna RT's venv)."""

import importlib.util
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# Sionna RT's scenes committed to the repository.
SCENES = REPO / "testdata" / "scenes" / "sionna-rt"
# (scene, TX, RX) in the scene's frame, metres: a roof or mast TX and a street receiver.
CASES = [
    ("munich", (8.5, 21.0, 27.0), (45.0, 90.0, 1.5)),
    ("florence", (5.0, -55.0, 60.0), (0.0, -150.0, 1.5)),
    ("etoile", (0.0, 0.0, 30.0), (20.0, 5.0, 1.5)),
    # Not committed to testdata/: taken from the installed sionna-rt wheel (an unseen city).
    ("san_francisco", (185.4021453857422, -86.6235580444336, 45.3857421875),
     (-12.491729736328125, 41.86780548095703, 14.31640625)),
]
FREQUENCY_HZ = 3.5e9
MAX_DEPTH = 3


def find_xml(name):
    """The scene's XML: the committed copy, else the one shipped in an installed sionna-rt
    wheel; None when neither is there."""
    xml = SCENES / name / f"{name}.xml"
    if xml.is_file():
        return xml
    try:
        spec = importlib.util.find_spec("sionna.rt.scenes")
    except ModuleNotFoundError:
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    xml = Path(list(spec.submodule_search_locations)[0]) / name / f"{name}.xml"
    return xml if xml.is_file() else None


def trace_command(binary, xml, tx, rx):
    """The whole ``beamtrace trace`` process of a case: order ``MAX_DEPTH``, JSON out."""
    return [
        str(binary), "trace", str(xml),
        "--tx=" + ",".join(map(repr, tx)), "--rx=" + ",".join(map(repr, rx)),
        "--max-order", str(MAX_DEPTH), "--frequency", repr(FREQUENCY_HZ), "--json",
    ]
