"""load(cache=True): the scene of a fresh load, kept in the cache directory only, a damaged
entry rebuilt with a warning."""

from __future__ import annotations

import numpy as np
import pytest

import beamtrace
from conftest import TESTDATA

CANYON = TESTDATA / "sionna-rt" / "simple_street_canyon"
XML = CANYON / "simple_street_canyon.xml"
TX, RX = [-20.0, 0.0, 10.0], [20.0, 5.0, 1.5]


def listing(folder):
    """Every file under folder with its size and modification time."""
    return sorted((str(p), p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*"))


def assert_same_scene(a, b):
    assert a.name == b.name
    assert a.surface_names == b.surface_names
    assert a.warnings == b.warnings
    assert a.frequency_hz == b.frequency_hz
    pa = a.trace(TX, RX, max_order=2)
    pb = b.trace(TX, RX, max_order=2)
    assert len(pa) == len(pb) > 2
    assert pa.surfaces == pb.surfaces
    np.testing.assert_array_equal(pa.length_m, pb.length_m)


def test_cached_load_equals_a_fresh_load(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("BEAMTRACE_CACHE_DIR", str(cache))
    before = listing(CANYON)
    fresh = beamtrace.load(XML)
    assert not cache.exists()
    first = beamtrace.load(XML, cache=True)
    entries = sorted(cache.iterdir())
    assert len(entries) == 1
    written = entries[0].stat().st_ino
    second = beamtrace.load(XML, cache=True)
    assert sorted(cache.iterdir()) == entries
    assert entries[0].stat().st_ino == written  # read, not rewritten
    assert_same_scene(fresh, first)
    assert_same_scene(fresh, second)
    assert listing(CANYON) == before


def test_damaged_entry_is_rebuilt_with_a_warning(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("BEAMTRACE_CACHE_DIR", str(cache))
    fresh = beamtrace.load(XML)
    beamtrace.load(XML, cache=True)
    (entry,) = cache.iterdir()
    data = bytearray(entry.read_bytes())
    data[len(data) // 2] ^= 0xFF
    entry.write_bytes(bytes(data))
    with pytest.warns(RuntimeWarning, match="ignored and rebuilt"):
        rebuilt = beamtrace.load(XML, cache=True)
    assert_same_scene(fresh, rebuilt)
    assert len(entry.read_bytes()) == len(data)
    assert entry.read_bytes() != bytes(data)
