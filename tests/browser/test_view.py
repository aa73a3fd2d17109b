"""Browser test of `beamtrace view`: the page loads in headless Chromium (Debian's, driven by
Playwright) without console errors, draws one line per path of the trace's JSON, its time-step
slider switches the drawn step, hostile names stay text, and a diffracting wedge shows its edges
and its diffraction point.

Run: target/ci-venv/bin/python -m pytest tests/browser (`.ci/run` sets the venv up).
BEAMTRACE_BIN names the binary (default: target/debug/beamtrace, built when missing);
SCREENSHOT_DIR keeps the wedge's screenshot (default: the test's temporary folder)."""

import json
import os
import subprocess
from pathlib import Path

import pytest
from playwright.sync_api import sync_playwright

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")


@pytest.fixture(scope="session")
def beamtrace():
    binary = Path(os.environ.get("BEAMTRACE_BIN", REPO / "target/debug/beamtrace"))
    if not binary.exists():
        subprocess.run(["cargo", "build", "-q", "-p", "beamtrace"], cwd=REPO, check=True)

    def run(*args):
        done = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout

    return run


@pytest.fixture(scope="session")
def browser():
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


def open_view(browser, html):
    """Open the page, wait until the viewer has drawn, return (page, console errors)."""
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("request", lambda r: errors.append("network request: " + r.url)
            if not r.url.startswith(("file:", "data:", "blob:")) else None)
    page.goto(html.as_uri())
    page.wait_for_function("window.beamtraceView && window.beamtraceView.ready", timeout=30000)
    return page, errors


def drawn(page):
    return page.evaluate("window.beamtraceView")


def test_living_room_draws_one_line_per_path(beamtrace, browser, tmp_path):
    paths_json = tmp_path / "paths.json"
    beamtrace("trace", "builtin:living-room", "--json", "--out", paths_json)
    expected = len(json.loads(paths_json.read_text())["paths"])
    assert expected > 10
    html = tmp_path / "view.html"
    beamtrace("view", "builtin:living-room", "--paths", paths_json, "-o", html)
    page, errors = open_view(browser, html)
    state = drawn(page)
    assert state["pathLines"] == expected
    assert state["steps"] == 1
    assert page.locator("#stepper").is_hidden()
    # WebGL really drew: the canvas has a WebGL 2 context.
    assert page.evaluate("!!document.querySelector('canvas').getContext('webgl2')")
    page.screenshot(path=str(tmp_path / "view.png"))
    assert errors == []
    # Hovering a path shows its numbers: the middle of the line of sight.
    doc = json.loads(paths_json.read_text())
    mid = [(a + b) / 2 for a, b in zip(doc["tx"], doc["rx"])]
    x, y = page.evaluate("p => window.beamtraceView.project(p)", mid)
    page.mouse.move(x, y)
    tip = page.locator("#tip")
    assert tip.is_visible()
    lines = tip.text_content().split("\n")
    lengths = {f"{p['length_m']:.3f}" for p in doc["paths"]}
    assert lines[1].split()[1] in lengths, lines
    assert lines[2].startswith("AoD az") and lines[3].startswith("AoA az"), lines
    # Colour by loss is a switch away.
    page.select_option("#colour-by", "loss")
    assert "dB" in page.locator("#legend-paths").text_content()
    assert errors == []
    # Without --paths the viewer traces the scene itself: the same count.
    traced = tmp_path / "traced.html"
    beamtrace("view", "builtin:living-room", "-o", traced)
    page, errors = open_view(browser, traced)
    assert drawn(page)["pathLines"] == expected
    assert errors == []


def test_dynamic_slider_switches_steps(beamtrace, browser, tmp_path):
    steps_json = tmp_path / "steps.json"
    beamtrace("trace", "builtin:living-room-dynamic", "--steps", "--out", steps_json)
    counts = [len(s["paths"]) for s in json.loads(steps_json.read_text())["steps"]]
    assert len(counts) == 10 and len(set(counts)) > 1
    html = tmp_path / "dynamic.html"
    beamtrace("view", "builtin:living-room-dynamic", "-o", html)
    page, errors = open_view(browser, html)
    assert drawn(page)["steps"] == len(counts)
    assert drawn(page)["step"] == 0 and drawn(page)["pathLines"] == counts[0]
    slider = page.locator("#step")
    assert slider.is_visible()
    slider.focus()
    page.keyboard.press("ArrowRight")
    assert drawn(page)["step"] == 1 and drawn(page)["pathLines"] == counts[1]
    page.keyboard.press("End")
    last = len(counts) - 1
    assert drawn(page)["step"] == last and drawn(page)["pathLines"] == counts[last]
    assert page.locator("#step-label").text_content() == str(last)
    assert errors == []


def test_hostile_names_stay_text(beamtrace, browser, tmp_path):
    name = "</script><img src=x onerror=\"window.pwned=1\"><!-- {{THREE}}"
    scene = {
        "name": name,
        "tx": [-1.5, 1, 2], "rx": [2, 2, 1],
        "materials": {name: {"reflection_loss_db": 3}},
        "surfaces": [{"name": name, "material": name,
                      "vertices": [[-5, 0, 0], [5, 0, 0], [5, 0, 3], [-5, 0, 3]]}],
    }
    path = tmp_path / "hostile.json"
    path.write_text(json.dumps(scene))
    html = tmp_path / "hostile.html"
    beamtrace("view", path, "-o", html)
    page, errors = open_view(browser, html)
    assert drawn(page)["pathLines"] == 2  # line of sight and the wall's reflection
    assert page.evaluate("window.pwned") is None
    assert page.locator("img").count() == 0
    assert page.locator("#title").text_content() == name
    assert errors == []


def test_wedge_diffraction_draws_edges_and_the_diffraction_point(beamtrace, browser, tmp_path):
    # Sionna RT's wedge hides RX from TX: the one path diffracts on the wedge's edge.
    wedge = REPO / "testdata/scenes/sionna-rt/simple_wedge/simple_wedge.xml"
    html = tmp_path / "wedge.html"
    beamtrace("view", wedge, "--tx=-10,-20,2", "--rx=20,5,1", "--diffraction", "-o", html)
    page, errors = open_view(browser, html)
    state = drawn(page)
    assert state["edges"] > 0
    assert state["diffractionPoints"] == 1
    assert state["pathLines"] == 1
    legend = page.locator("#legend-edges").text_content()
    assert "diffracting edge" in legend and "diffraction point" in legend
    assert "1 path, 1 diffraction point" in page.locator("#counts").text_content()
    page.screenshot(path=str(Path(os.environ.get("SCREENSHOT_DIR", tmp_path)) / "wedge.png"))
    # Hovering the path names the edge it diffracts on.
    doc = json.loads(page.evaluate("document.getElementById('beamtrace-data').textContent"))
    step = doc["steps"][0]
    point = step["paths"][0]["points"][0]
    mid = [(a + b) / 2 for a, b in zip(step["tx"], point)]
    x, y = page.evaluate("p => window.beamtraceView.project(p)", mid)
    page.mouse.move(x, y)
    assert page.locator("#tip").text_content().startswith("order 1: edge ")
    assert errors == []
    # Without --diffraction the same page draws the edges but no diffraction point.
    plain = tmp_path / "plain.html"
    beamtrace("view", wedge, "--tx=-10,-20,2", "--rx=20,5,1", "-o", plain)
    page, errors = open_view(browser, plain)
    assert drawn(page)["edges"] == state["edges"]
    assert drawn(page)["diffractionPoints"] == 0
    assert "diffraction point" not in page.locator("#legend-edges").text_content()
    assert errors == []
