"""beamtrace.Tracer: the loop of `beamtrace serve` in Python, answering what serve answers."""

from __future__ import annotations

import json
import pickle
import subprocess

import numpy as np
import pytest

import beamtrace
from conftest import REPO, _cli_path


def serve(requests, *args):
    """The answers of `beamtrace serve builtin:living-room-dynamic ARGS` to `requests`."""
    lines = "".join(json.dumps(r) + "\n" for r in requests)
    done = subprocess.run(
        [str(_cli_path()), "serve", "builtin:living-room-dynamic", *args],
        input=lines, capture_output=True, text=True, check=True,
    )
    return [json.loads(line) for line in done.stdout.splitlines()]


def without_times(answer):
    """An answer without what varies between runs (latency_us, stats.time_s)."""
    answer = dict(answer)
    answer.pop("latency_us")
    answer["stats"] = {k: v for k, v in answer["stats"].items() if k != "time_s"}
    return answer


def test_updates_answer_what_serve_answers():
    requests = [
        {"rx": [1.0, 1.0, 1.0]},
        {"objects": {"person": {"offset": [0.5, 1.5, 0.0]}, "door": {"angle_deg": 30}}},
        {"tx": [3.0, 3.5, 2.0], "rx": [2.0, 1.0, 1.2]},
        {"step": 9},
    ]
    expected = serve(requests, "--max-order", "2")
    tracer = beamtrace.Tracer("builtin:living-room-dynamic", max_order=2)
    got = [tracer.update(**r) for r in requests]
    assert len(got) == len(expected) == 4
    for g, e in zip(got, expected):
        assert without_times(g) == without_times(e)
    assert len(got[0]["paths"]) > 5
    assert "update" in got[1]["stats"], "moving objects is an incremental update"
    assert got[3]["tx"] == [3.0, 3.5, 2.0], "the transmitter stays where the last update put it"


def test_a_partner_thread_changes_no_answer():
    """``partner_spin_us`` (serve's ``--partner-spin-us``) splits a lone receiver's report
    over two threads; 0 answers on one: the same answers, and the same as serve's with
    ``--partner-spin-us 0``."""
    walk = [{"rx": [0.6 + 0.2 * k, 1.0 + 0.1 * (k % 7), 1.1]} for k in range(20)]
    one = beamtrace.Tracer("builtin:living-room-dynamic", partner_spin_us=0)
    two = beamtrace.Tracer("builtin:living-room-dynamic", partner_spin_us=5000)
    expected = serve(walk, "--partner-spin-us", "0")
    for r, e in zip(walk, expected):
        alone, split = one.update(**r), two.update(**r)
        assert without_times(split) == without_times(alone) == without_times(e)
    assert sum(len(e["paths"]) for e in expected) > 20 * 16, "answers with paths to split"
    with pytest.raises(ValueError, match="partner_spin_us"):
        beamtrace.Tracer("builtin:living-room", partner_spin_us=-1)


def test_one_receiver_is_the_trace_of_the_scene():
    scene = beamtrace.load("builtin:living-room")
    tracer = beamtrace.Tracer(scene)
    answer = tracer.update(rx=np.array([1.0, 2.0, 1.2]))
    paths = scene.trace(rx=[1.0, 2.0, 1.2])
    assert answer["tx"] == list(scene.tx)
    assert [p["length_m"] for p in answer["paths"]] == list(paths.length_m)
    assert [p["surfaces"] for p in answer["paths"]] == paths.surfaces


@pytest.mark.parametrize(
    "source, load_options, rx, trace_options",
    [
        ("builtin:living-room", {"frequency": 3.5e9, "material": "itu:glass", "thickness": 0.01},
         [1.0, 2.0, 1.2], {"max_order": 2}),
        ("examples/two-rooms.json", {"thickness": 0.1}, [9.0, 1.0, 1.2],
         {"max_order": 2, "transmission": True}),
        ("testdata/scenes/box-room.obj", {"min_reflector_area": 4.0, "frequency": 3.5e9},
         [4.0, 3.0, 1.2], {"max_order": 2}),
    ],
)
def test_a_tracer_of_a_loaded_scene_loads_it_as_load_did(source, load_options, rx,
                                                          trace_options):
    """Tracer(scene) reloads the scene with the options load was given (the carrier, radio
    material, thickness and mesh options): its answers are the scene's own traces, gain for
    gain (it lost them all once, silently)."""
    tx = [1.0, 1.0, 1.5] if source.endswith(".obj") else None
    path = source if source.startswith("builtin:") else str(REPO / source)
    scene = beamtrace.load(path, tx=tx, rx=rx, **load_options)
    paths = scene.trace(**trace_options)
    assert len(paths) > 0
    answer = beamtrace.Tracer(scene, **trace_options).update(rx=rx)
    assert [p["gain_db"] for p in answer["paths"]] == list(paths.gain_db)
    assert [p["surfaces"] for p in answer["paths"]] == paths.surfaces


def test_a_tracer_of_an_unpickled_scene_traces_that_scene():
    """A Scene sent through pickle (to a Ray worker, say) keeps its materials and carrier but
    not the options load was given: its Tracer traces the scene itself, not a reload of its
    source with default options."""
    scene = beamtrace.load("builtin:living-room", frequency=3.5e9, material="itu:glass",
                           thickness=0.01)
    copy = pickle.loads(pickle.dumps(scene))
    rx = [1.0, 2.0, 1.2]
    paths = copy.trace(rx=rx, max_order=2)
    assert list(paths.gain_db) == list(scene.trace(rx=rx, max_order=2).gain_db)
    answer = beamtrace.Tracer(copy, max_order=2).update(rx=rx)
    assert [p["gain_db"] for p in answer["paths"]] == list(paths.gain_db)
    moved = beamtrace.Tracer(copy, tx=[5.0, 1.0, 2.0], max_order=2).update(rx=rx)
    assert moved["tx"] == [5.0, 1.0, 2.0]
    assert [p["gain_db"] for p in moved["paths"]] == list(
        copy.trace(tx=[5.0, 1.0, 2.0], rx=rx, max_order=2).gain_db)


def test_a_tracer_takes_loads_keywords_with_a_source():
    """Tracer(source, material=, thickness=, frequency=, min_reflector_area=, ...) loads the
    source with them, as serve's flags of those names: the answers of
    Tracer(load(source, ...)); with a Scene they are a TypeError."""
    load_options = {"frequency": 3.5e9, "material": "itu:glass", "thickness": 0.01}
    rx = [1.0, 2.0, 1.2]
    given = beamtrace.Tracer("builtin:living-room", max_order=2, **load_options).update(rx=rx)
    loaded = beamtrace.load("builtin:living-room", **load_options)
    assert [p["gain_db"] for p in given["paths"]] == list(loaded.trace(rx=rx, max_order=2).gain_db)
    assert given["paths"] != beamtrace.Tracer("builtin:living-room", max_order=2).update(rx=rx)["paths"]
    with pytest.raises(TypeError, match="material: load options of a source"):
        beamtrace.Tracer(loaded, material="itu:glass")


def test_several_receivers_give_one_entry_each_and_a_bad_one_fails_alone():
    tracer = beamtrace.Tracer("builtin:living-room", max_order=1)
    answer = tracer.update(rx=np.array([[1.0, 1.0, 1.0], [3.0, 0.0, 1.0], [2.0, 3.0, 1.5]]))
    results = answer["results"]
    assert len(results) == 3
    assert results[0]["paths"] and results[2]["paths"]
    assert results[1]["error"].startswith('rx[1]: lies on surface "wall-south"')


@pytest.mark.parametrize(
    "update, message",
    [
        ({"rx": [3.0, 0.0, 1.0]}, 'rx: lies on surface "wall-south"'),
        ({"objects": {"kitchen": {}}}, "objects.kitchen: no such object"),
        ({"objects": {"person": {"angle_deg": 10}}}, "objects.person.angle_deg: the object has no pivot"),
        ({"objects": {"door": {"spin": 1}}}, "objects.door: unknown field `spin`"),
        ({"step": 99}, "step: is 99; the scene has 10 step(s)"),
    ],
)
def test_errors_name_the_field_and_change_nothing(update, message):
    tracer = beamtrace.Tracer("builtin:living-room-dynamic", max_order=1)
    before = tracer.update(rx=[2.3, 2.1, 0.72])
    with pytest.raises(beamtrace.BeamtraceError) as info:
        tracer.update(**update)
    assert str(info.value).startswith(message), str(info.value)
    after = tracer.update()
    assert without_times(after) == without_times(before)


def test_bad_arguments_are_value_errors():
    with pytest.raises(ValueError, match="solver"):
        beamtrace.Tracer("builtin:living-room", solver="nope")
    with pytest.raises(TypeError, match="unknown trace keyword.*max_ordr"):
        beamtrace.Tracer("builtin:living-room", max_ordr=2)
    tracer = beamtrace.Tracer("builtin:living-room", max_order=1)
    with pytest.raises(ValueError, match="rx must be"):
        tracer.update(rx=[1.0, 2.0])
    with pytest.raises(ValueError, match="finite"):
        tracer.update(rx=[1.0, float("nan"), 1.0])


def test_arrays_give_each_answer_serves_beams(cli):
    # Tracer(tx_array=, rx_array=) answers with serve --tx-array/--rx-array's "beams": the
    # sweep of `beamtrace beams` for that receiver, its best pair and the first `top`.
    tracer = beamtrace.Tracer("builtin:living-room", tx_array=(2, 4), rx_array=(1, 4),
                              ranking="paper", top=3)
    answer = tracer.update(rx=[2.3, 2.1, 0.72])
    done = cli("beams", "builtin:living-room", "--rx", "2.3,2.1,0.72", "--tx-array", "2x4",
               "--rx-array", "1x4", "--ranking", "paper", "--json")
    assert done.returncode == 0, done.stderr
    pairs = json.loads(done.stdout)["pairs"]
    assert answer["beams"]["top"] == pairs[:3]
    assert answer["beams"]["best"] == pairs[0]
    assert "beams" not in beamtrace.Tracer("builtin:living-room").update(rx=[1, 1, 1.2])
    with pytest.raises(ValueError, match="ranking must be one of"):
        beamtrace.Tracer("builtin:living-room", tx_array=(1, 4), ranking="best")
    with pytest.raises(ValueError, match="max_beam_pairs"):
        beamtrace.Tracer("builtin:living-room", tx_array=(8, 8), rx_array=(8, 8), max_beam_pairs=10)
