"""beamtrace.study_beam_management: the CLI's study from Python, same files, same numbers."""

import json

import pytest

import beamtrace


def test_study_returns_the_summary_it_writes(tmp_path):
    out = tmp_path / "bm"
    summary = beamtrace.study_beam_management(
        out, scenarios=["living-room"], positions=4, scan_density=0, seed=3
    )
    assert list(summary) == ["scenarios"]
    methods = summary["scenarios"]["living-room"]["methods"]
    assert methods["exhaustive"]["beams_measured"] == 512.0
    on_disk = json.loads((out / "summary.json").read_text())
    for name, m in methods.items():
        for key, value in m.items():
            if key != "latency_us":
                assert on_disk["scenarios"]["living-room"]["methods"][name][key] == value
    assert (out / "decisions.csv").is_file() and (out / "snr-loss-cdf.png").is_file()


def test_bad_settings_name_the_option(tmp_path):
    with pytest.raises(ValueError, match="--positions"):
        beamtrace.study_beam_management(tmp_path / "x", positions=1)
    with pytest.raises(beamtrace.BeamtraceError, match="no-such-scene"):
        beamtrace.study_beam_management(
            tmp_path / "y", scenarios=["no-such-scene.json"], positions=3
        )
