"""Scene.view (the CLI's `beamtrace view` page, inline in Jupyter) and the type stub."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import beamtrace
from beamtrace import _native
from conftest import REPO


def test_view_is_the_clis_page(cli, tmp_path):
    # The same page, byte for byte, as `beamtrace view SCENE -o FILE` (which traces the
    # scene's own terminals with trace's defaults).
    scene = beamtrace.load("builtin:living-room")
    view = scene.view(max_order=3)
    out = tmp_path / "v.html"
    done = cli("view", "builtin:living-room", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert view.html == out.read_text()
    assert view._repr_html_().startswith("<iframe srcdoc=")
    assert "beamtrace view: living-room" in view.html


def test_view_takes_trace_keywords_and_bare_geometry(cli, tmp_path):
    two_rooms = str(REPO / "examples" / "two-rooms.json")
    scene = beamtrace.load(two_rooms)
    out = tmp_path / "t.html"
    done = cli("view", two_rooms, "--transmission", "--max-order", "2", "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert scene.view(max_order=2, transmission=True).html == out.read_text()
    bare = beamtrace.load(REPO / "examples" / "room.obj")
    assert bare.tx is None
    assert "beamtrace view" in bare.view().html   # geometry alone: no terminals
    with pytest.raises(TypeError, match="unknown trace keyword"):
        scene.view(max_orders=2)


def test_save_writes_a_page_and_never_replaces_another_file(tmp_path):
    view = beamtrace.load("builtin:living-room").view(max_order=1)
    target = tmp_path / "page.html"
    view.save(target)
    assert target.read_text() == view.html
    view.save(target)                              # its own page: replaced
    other = tmp_path / "notes.txt"
    other.write_text("mine")
    with pytest.raises(FileExistsError, match="not a beamtrace view"):
        view.save(other)
    assert other.read_text() == "mine"


def _stub_names() -> dict:
    """Top-level names and each class's members of _native.pyi."""
    tree = ast.parse((Path(beamtrace.__file__).parent / "_native.pyi").read_text())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))
                and not getattr(n, "name", "").startswith("__")
            } | {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.AnnAssign):
            names[node.target.id] = None
    return names


def test_the_stub_names_every_native_item():
    stub = _stub_names()
    public = {n for n in dir(_native) if not n.startswith("_")}
    assert public == set(stub), f"stub lacks {public - set(stub)}, has extra {set(stub) - public}"
    for cls in ("Scene", "Tracer"):
        members = {n for n in dir(getattr(_native, cls)) if not n.startswith("_")}
        assert members == stub[cls], f"{cls}: stub lacks {members - stub[cls]}, extra {stub[cls] - members}"
