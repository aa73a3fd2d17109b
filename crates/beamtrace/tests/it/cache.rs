//! `--cache`: the same output as without it, the entry in the cache directory only, a damaged
//! entry rebuilt with a warning on stderr, no cache directory a clear error.

use crate::common::{scratch, stderr, stdout, testdata};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the binary with `args`, `BEAMTRACE_CACHE_DIR` set to `cache`.
fn with_cache(cache: &Path, args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .env("BEAMTRACE_CACHE_DIR", cache)
        .output()
        .expect("binary runs");
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    o
}

/// The files in `dir` (not recursive), sorted.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = (std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().path())
        .collect();
    out.sort();
    out
}

/// The JSON document of a trace without its timings.
fn document(o: &Output) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(&stdout(o)).unwrap();
    v["stats"].as_object_mut().unwrap().remove("time_s");
    v
}

#[test]
fn cache_flag_gives_the_same_output_and_writes_only_the_cache() {
    let dir = scratch("cache-flag");
    let cache = dir.join("cache");
    let xml = testdata("sionna-rt/simple_street_canyon/simple_street_canyon.xml");
    let scene_dir = Path::new(&xml).parent().unwrap().to_path_buf();
    let before = (files(&scene_dir), files(&scene_dir.join("meshes")));
    let trace = [
        "trace",
        &xml,
        "--tx",
        "-20,0,10",
        "--rx",
        "20,5,1.5",
        "--max-order",
        "2",
        "--json",
    ];
    let plain = with_cache(&cache, &trace);
    assert!(!cache.exists(), "no --cache, no cache directory");
    let cached: Vec<&str> = trace.iter().copied().chain(["--cache"]).collect();
    let first = with_cache(&cache, &cached);
    let entries = files(&cache);
    assert_eq!(entries.len(), 1, "{entries:?}");
    let second = with_cache(&cache, &cached);
    assert_eq!(files(&cache), entries);
    assert_eq!(document(&plain), document(&first));
    assert_eq!(document(&plain), document(&second));
    assert!(document(&plain)["paths"].as_array().unwrap().len() > 2);
    assert_eq!(stderr(&plain), stderr(&second));
    // scene check prints the same with and without; without terminals, its options are
    // another key, so another entry.
    let check = ["scene", "check", &xml];
    let check_cached = with_cache(&cache, &["scene", "check", &xml, "--cache"]);
    assert_eq!(stdout(&with_cache(&cache, &check)), stdout(&check_cached));
    let entries = files(&cache);
    assert_eq!(entries.len(), 2, "{entries:?}");
    // A damaged entry: a warning on stderr, the same output, the entry rebuilt.
    for entry in &entries {
        std::fs::write(entry, b"not an entry").unwrap();
    }
    let damaged = with_cache(&cache, &cached);
    let warning = stderr(&damaged);
    assert!(
        warning.contains("warning: load cache: ") && warning.contains("ignored and rebuilt"),
        "{warning}"
    );
    assert_eq!(document(&plain), document(&damaged));
    let rebuilt = entries
        .iter()
        .filter(|e| std::fs::read(e).unwrap().len() > 100);
    assert_eq!(
        rebuilt.count(),
        1,
        "the trace's entry rebuilt, the other left"
    );
    assert_eq!(files(&cache), entries, "no temporary file left");
    let after = (files(&scene_dir), files(&scene_dir.join("meshes")));
    assert_eq!(before, after, "nothing written beside the inputs");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn cache_without_a_cache_directory_is_a_clear_error() {
    let xml = testdata("sionna-rt/simple_street_canyon/simple_street_canyon.xml");
    let o = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(["scene", "check", &xml, "--cache"])
        .env_remove("BEAMTRACE_CACHE_DIR")
        .env_remove("XDG_CACHE_HOME")
        .env_remove("HOME")
        .output()
        .expect("binary runs");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--cache: no cache directory"),
        "{}",
        stderr(&o)
    );
}
