//! The hostile user's cases of issue 9, each through the CLI: exit code (never 101), message,
//! files before and after, and memory held under a budget small enough for CI.

mod budgets;
mod growth;
mod names;
mod numbers;
mod outputs;
mod outputs2;
mod small;

pub use crate::common::{cli, scratch, text};
use std::path::Path;
use std::process::{Command, Output};

pub fn one_wall() -> String {
    crate::common::testdata("one-wall.json")
}

/// The faces of the unit cube whose vertex `v` is `(v & 1, v >> 1 & 1, v >> 2 & 1)`, as quads
/// of vertex indices, outward.
pub const CUBE_QUADS: [[usize; 4]; 6] = [
    [0, 2, 3, 1],
    [4, 5, 7, 6],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 4, 6, 2],
    [1, 3, 7, 5],
];

/// Address-space limit of every run: the runaway cases of the issue asked for 8 GB to 10 TB.
const MEMORY_LIMIT_BYTES: u64 = 3 << 30;

/// Runs the binary under the memory limit.
pub fn beamtrace(args: &[&str]) -> Output {
    beamtrace_within(args, MEMORY_LIMIT_BYTES)
}

/// Runs the binary under an address-space limit of `bytes`.
pub fn beamtrace_within(args: &[&str], bytes: u64) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_beamtrace"));
    cmd.args(args);
    limit_memory(&mut cmd, bytes);
    cmd.output().expect("binary runs")
}

/// Runs the binary in the folder `dir` (relative paths resolve there) under the memory limit.
pub fn beamtrace_in(dir: &Path, args: &[&str]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_beamtrace"));
    cmd.args(args).current_dir(dir);
    limit_memory(&mut cmd, MEMORY_LIMIT_BYTES);
    cmd.output().expect("binary runs")
}

#[cfg(unix)]
fn limit_memory(cmd: &mut Command, bytes: u64) {
    use std::os::unix::process::CommandExt;
    // SAFETY: setrlimit is async-signal-safe; the closure allocates nothing.
    unsafe {
        cmd.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: bytes as libc::rlim_t,
                rlim_max: bytes as libc::rlim_t,
            };
            libc::setrlimit(libc::RLIMIT_AS, &lim);
            Ok(())
        });
    }
}

#[cfg(not(unix))]
fn limit_memory(_: &mut Command, _: u64) {}

/// A clear failure: exit code 1 or 2 (not success, not a panic, not a signal) and every needle
/// in the output.
pub fn assert_refused(o: &Output, needles: &[&str]) {
    let t = text(o);
    assert!(
        matches!(o.status.code(), Some(1) | Some(2)),
        "exit {:?}:\n{t}",
        o.status
    );
    assert!(!t.contains("panicked"), "{t}");
    for n in needles {
        assert!(t.contains(n), "message lacks {n:?}:\n{t}");
    }
}

/// A clear refusal ([`assert_refused`]) of a run that was to write `out`, which it left
/// unwritten.
pub fn assert_refused_writing_nothing(args: &[&str], out: &Path, needles: &[&str]) {
    assert_refused(&beamtrace(args), needles);
    assert!(!out.exists(), "{args:?} wrote {}", out.display());
}

/// [`assert_refused_writing_nothing`] of the command `line` (a [`cli`] line) whose one `{}`
/// word is `out`.
pub fn assert_line_refused_writing_nothing(line: &str, out: &Path, needles: &[&str]) {
    assert_refused_writing_nothing(&cli(line, &[out.to_str().unwrap()]), out, needles);
}

/// A clear refusal ([`assert_refused`]) of a run that left `file` byte for byte as it was
/// (an input it was asked to overwrite).
pub fn assert_refused_keeping(args: &[&str], file: &Path, needles: &[&str]) {
    let before = std::fs::read(file).unwrap();
    assert_refused(&beamtrace(args), needles);
    assert_eq!(
        std::fs::read(file).unwrap(),
        before,
        "{args:?} changed {}",
        file.display()
    );
}

pub fn assert_ok(o: &Output) {
    assert!(o.status.success(), "exit {:?}:\n{}", o.status, text(o));
}

/// The files under `dir` (relative, sorted), recursively.
pub fn tree(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.push(p.strip_prefix(root).unwrap().display().to_string());
            }
        }
    }
    let mut out = Vec::new();
    if dir.exists() {
        walk(dir, dir, &mut out);
    }
    out.sort();
    out
}

/// A scene file with one wall and `surface` as extra surface JSON (or none).
pub fn scene_with(dir: &Path, file: &str, json: &str) -> String {
    let path = dir.join(file);
    std::fs::write(&path, json).unwrap();
    path.display().to_string()
}
