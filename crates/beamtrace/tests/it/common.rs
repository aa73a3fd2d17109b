//! What every test module shares: the repository, the binary, its output and scratch folders.

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

pub use bt_testkit::golden::{self, assert_golden};

/// The repository root (for `testdata/`).
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `testdata/scenes/NAME` as an argument.
pub fn testdata(name: &str) -> String {
    repo()
        .join("testdata/scenes")
        .join(name)
        .display()
        .to_string()
}

/// A command line written as one string: its words split at white space, each `{}` word
/// replaced by the next of `values` (paths, passed apart so that a space in one stays in it).
pub fn cli<'a>(line: &'a str, values: &[&'a str]) -> Vec<&'a str> {
    let mut values = values.iter();
    let args = line
        .split_whitespace()
        .map(|w| match w {
            "{}" => *values
                .next()
                .unwrap_or_else(|| panic!("{line:?}: too few values")),
            _ => w,
        })
        .collect();
    assert!(values.next().is_none(), "{line:?}: too many values");
    args
}

/// Runs the binary with `args`.
pub fn beamtrace(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// Runs the binary and asserts it succeeded (its stderr as the message).
pub fn run_ok(args: &[&str]) -> Output {
    let o = beamtrace(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    o
}

/// Runs the binary with `args` in the folder `dir` (its working directory, against which
/// relative paths in `args` resolve) and asserts it succeeded.
pub fn run_ok_in(dir: &Path, args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("binary runs");
    assert!(
        o.status.success(),
        "{args:?} in {}: {}",
        dir.display(),
        stderr(&o)
    );
    o
}

/// Runs the binary, asserts it succeeded and parses its standard output as JSON.
pub fn run_json(args: &[&str]) -> Value {
    serde_json::from_slice(&run_ok(args).stdout).expect("valid JSON")
}

/// A failing command: non-zero exit, not a panic (101), and stderr mentions every needle.
pub fn assert_clear_error(args: &[&str], needles: &[&str]) {
    let o = beamtrace(args);
    let code = o.status.code();
    assert!(
        code.is_some() && code != Some(0) && code != Some(101),
        "{args:?}: exit {code:?}"
    );
    let text = text(&o);
    assert!(!text.contains("panicked"), "{args:?} panicked: {text}");
    for n in needles {
        assert!(text.contains(n), "{args:?}: message lacks {n:?}:\n{text}");
    }
}

/// Standard output, lossy UTF-8.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts that `o`'s standard output contains `needle`, showing the output when not.
#[track_caller]
pub fn assert_stdout_has(o: &Output, needle: &str) {
    let out = stdout(o);
    assert!(out.contains(needle), "stdout lacks {needle:?}:\n{out}");
}

/// Standard error, lossy UTF-8.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Standard output followed by standard error.
pub fn text(o: &Output) -> String {
    format!("{}{}", stdout(o), stderr(o))
}

/// A JSON file the binary wrote.
pub fn read_json(path: &Path) -> Value {
    let text =
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Each path of a trace document as (its `interactions`, its `surfaces`).
pub fn kinds_and_surfaces(doc: &Value) -> Vec<(Vec<String>, Vec<String>)> {
    let strings = |v: &Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap().to_string())
            .collect()
    };
    doc["paths"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (strings(&p["interactions"]), strings(&p["surfaces"])))
        .collect()
}

/// The largest TX angle error, degrees, of the fixed-point model against f64 in the summary
/// `hls gen` writes for a design or a step.
pub fn fixed_point_tx_error_deg(summary: &Value) -> f64 {
    summary["fixed_vs_f64"]["max_angle_error_tx_deg"]
        .as_f64()
        .expect("max_angle_error_tx_deg")
}

/// A fresh, empty folder for the files of one test. All tests share one process (one pid in
/// the name), so each name may be taken once.
pub fn scratch(name: &str) -> PathBuf {
    static TAKEN: Mutex<BTreeSet<String>> = Mutex::new(BTreeSet::new());
    assert!(
        TAKEN.lock().unwrap().insert(name.to_string()),
        "scratch folder {name:?} taken by two tests"
    );
    let dir = std::env::temp_dir().join(format!("beamtrace-it-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
