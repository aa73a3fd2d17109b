"""Shared fixtures: the CLI binary the Python results are compared with."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TESTDATA = REPO / "testdata" / "scenes"


def _cli_path() -> Path:
    """The CLI: BEAMTRACE_BIN (.ci/run passes the one `cargo test` built), else the release
    build, built when missing."""
    override = os.environ.get("BEAMTRACE_BIN")
    if override:
        return Path(override)
    path = REPO / "target" / "release" / "beamtrace"
    if not path.exists():
        subprocess.run(
            ["cargo", "build", "--release", "-p", "beamtrace"], cwd=REPO, check=True
        )
    return path


@pytest.fixture(scope="session")
def cli():
    """Run `beamtrace ARGS...`; returns the CompletedProcess (text mode, never raises)."""
    path = _cli_path()

    def run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([str(path), *args], capture_output=True, text=True)

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """`beamtrace trace ARGS... --json`, parsed."""

    def run(*args: str) -> dict:
        done = cli("trace", *args, "--json")
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)

    return run


def vec(v) -> str:
    """A point as the CLI's X,Y,Z argument (repr keeps every bit of a float)."""
    return ",".join(repr(float(x)) for x in v)
