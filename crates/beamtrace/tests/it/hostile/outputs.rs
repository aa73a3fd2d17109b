//! Outputs never destroy data.

use super::*;

/// Writes the user's `files` (path in `out`, contents) into the output folder `out` in `dir`,
/// then runs the command `line` (its `{}` is `out`) `runs` times, each run succeeding: the
/// files are still there unchanged, and nothing but `out` is left in `dir` (no staging
/// folders beside it).
fn assert_runs_keep_users_files(
    dir: &Path,
    out: &Path,
    files: &[(&str, &str)],
    line: &str,
    runs: usize,
) {
    for (name, contents) in files {
        let path = out.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, contents).unwrap();
    }
    for _ in 0..runs {
        assert_ok(&beamtrace(&cli(line, &[out.to_str().unwrap()])));
    }
    for (name, contents) in files {
        let kept = std::fs::read_to_string(out.join(name));
        assert_eq!(kept.unwrap(), *contents, "{name}");
    }
    let siblings = std::fs::read_dir(dir).unwrap().count();
    assert_eq!(siblings, 1, "no staging left");
}

#[test]
fn hls_gen_keeps_the_users_files_and_replaces_its_own() {
    let dir = scratch("hls-keep");
    let out = dir.join("accel");
    let mine = [
        ("rtl/my_wrapper.v", "module my_wrapper; endmodule\n"),
        ("notes.txt", "mine"),
    ];
    // The second run replaces what the first wrote.
    let line = "hls gen builtin:living-room --max-order 1 -o {}";
    assert_runs_keep_users_files(&dir, &out, &mine, line, 2);
    assert!(out.join("rtl/bt_top.v").exists());
    assert!(out.join("summary.json").exists());
    let manifest = std::fs::read_to_string(out.join(".beamtrace-manifest")).unwrap();
    assert!(manifest.contains("rtl/bt_top.v") && manifest.contains("summary.json"));
    assert!(!manifest.contains("my_wrapper") && !manifest.contains("notes.txt"));
}

#[test]
fn hls_gen_that_cannot_fit_fails_fast_and_creates_nothing() {
    let dir = scratch("hls-fail");
    let out = dir.join("accel");
    assert_line_refused_writing_nothing(
        "hls gen builtin:living-room --max-order 1 --m9k-budget 4 -o {}",
        &out,
        &["M9K blocks", "budget of 4", "--max-order"],
    );
    assert!(tree(&dir).is_empty(), "{:?}", tree(&dir));
}

fn sampled_cloud(dir: &std::path::Path) -> std::path::PathBuf {
    let cloud = dir.join("room.ply");
    let r = beamtrace(&cli(
        "sample {} -o {} --density 2000",
        &[&one_wall(), cloud.to_str().unwrap()],
    ));
    assert_ok(&r);
    cloud
}

#[test]
fn extract_refuses_to_overwrite_its_input() {
    let dir = scratch("extract-same");
    let cloud = sampled_cloud(&dir);
    let c = cloud.to_str().unwrap();
    assert_refused_keeping(
        &["extract", c, "-o", c],
        &cloud,
        &["refusing to write", "it is the input"],
    );
    // Another spelling of the same file.
    let other = dir.join(".").join("room.ply");
    let report = other.to_str().unwrap();
    assert_refused_keeping(
        &cli(
            "extract {} --report {} -o {}",
            &[c, report, dir.join("s.json").to_str().unwrap()],
        ),
        &cloud,
        &["it is the input"],
    );
}

#[test]
fn extract_writes_the_format_its_extension_names_or_refuses() {
    let dir = scratch("extract-ext");
    let cloud = sampled_cloud(&dir);
    let c = cloud.to_str().unwrap();
    let toml = dir.join("room.toml");
    let r = beamtrace(&["extract", c, "-o", toml.to_str().unwrap()]);
    assert_ok(&r);
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(text.contains("[[surfaces]]"), "not TOML:\n{text}");
    // trace reads it back (as TOML, by extension).
    let r = beamtrace(&cli(
        "trace {} --tx -1.5,1,2 --rx 2,2,1",
        &[toml.to_str().unwrap()],
    ));
    assert_ok(&r);
    let json = dir.join("room.json");
    assert_ok(&beamtrace(&["extract", c, "-o", json.to_str().unwrap()]));
    let text = std::fs::read_to_string(&json).unwrap();
    assert!(
        !text.contains("null"),
        "no null where a value is promised:\n{text}"
    );
    let yaml = dir.join("room.yaml");
    assert_refused_writing_nothing(
        &["extract", c, "-o", yaml.to_str().unwrap()],
        &yaml,
        &["room.yaml", ".json or .toml"],
    );
}

#[test]
fn trace_out_refuses_the_scene_file_and_other_formats() {
    let dir = scratch("trace-out");
    let scene = dir.join("scene.json");
    std::fs::copy(one_wall(), &scene).unwrap();
    let s = scene.to_str().unwrap();
    assert_refused_keeping(&["trace", s, "--out", s], &scene, &["it is the input"]);
    let csv = dir.join("paths.csv");
    assert_refused_writing_nothing(
        &["trace", s, "--out", csv.to_str().unwrap()],
        &csv,
        &["paths.csv", ".json"],
    );
    let out = dir.join("paths.json");
    assert_ok(&beamtrace(&["trace", s, "--out", out.to_str().unwrap()]));
    assert_eq!(tree(&dir), ["paths.json", "scene.json"]);
}

#[test]
fn sample_refuses_to_overwrite_its_input_and_leaves_no_temporary() {
    let dir = scratch("sample-same");
    let cloud = sampled_cloud(&dir);
    let c = cloud.to_str().unwrap();
    assert_refused_keeping(&["sample", c, "-o", c], &cloud, &["it is the input"]);
    assert_eq!(tree(&dir), ["room.ply"]);
}

#[test]
fn study_keeps_files_it_did_not_write() {
    let dir = scratch("study");
    let out = dir.join("study");
    let mine = [("README.txt", "mine")];
    let line = "study 2d --rooms 1 --steps 1 --max-order 1 --out {}";
    assert_runs_keep_users_files(&dir, &out, &mine, line, 1);
    assert!(out.join("results.csv").exists());
}
