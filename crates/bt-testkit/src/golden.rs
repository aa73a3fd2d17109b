//! Golden files: the one check every golden test uses. A test renders its output
//! deterministically and hands it to [`assert_golden`] with the file that pins it (under
//! [`dir`], the repository's `testdata/golden/`). The test fails on any difference and names
//! the first differing line; with the update switch [`UPDATE_VAR`] set
//! (`UPDATE_GOLDEN=1 cargo test ...`) it rewrites the file instead, after a deliberate change
//! whose diff is then reviewed in git.

use std::path::{Path, PathBuf};

/// The update switch: when this environment variable is set (to anything but empty or `0`),
/// [`assert_golden`] writes the golden file instead of comparing with it.
pub const UPDATE_VAR: &str = "UPDATE_GOLDEN";

/// Lines of a golden file longer than this are cut in a failure message, characters.
const SHOWN_CHARS: usize = 200;

/// `testdata/golden/` at the repository root: where the golden files live.
pub fn dir() -> PathBuf {
    let mut up = Path::new(env!("CARGO_MANIFEST_DIR")).ancestors();
    let root = up
        .nth(2)
        .expect("crates/bt-testkit sits two folders below the root");
    root.join("testdata/golden")
}

/// Whether the update switch [`UPDATE_VAR`] is on.
pub fn updating() -> bool {
    std::env::var_os(UPDATE_VAR).is_some_and(|v| !v.is_empty() && v != "0")
}

/// Asserts that the golden file `path` holds exactly `actual` (bytes, so text and images
/// alike); with the update switch on ([`updating`]) writes `actual` there instead (creating
/// its folder, leaving an identical file untouched). Panics with the first differing line when
/// they differ, and when the file is missing.
#[track_caller]
pub fn assert_golden(path: impl AsRef<Path>, actual: impl AsRef<[u8]>) {
    check(path.as_ref(), actual.as_ref(), updating());
}

/// [`assert_golden`] with the update switch given.
#[track_caller]
fn check(path: &Path, actual: &[u8], update: bool) {
    if update {
        if std::fs::read(path).is_ok_and(|old| old == actual) {
            return;
        }
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).unwrap_or_else(|e| panic!("{}: {e}", parent.display()));
        }
        std::fs::write(path, actual).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        return;
    }
    // A `match`, not `unwrap_or_else`: a panic in a closure would not carry `track_caller`.
    let expected = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) => panic!("{}: {e} ({UPDATE_VAR}=1 writes it)", path.display()),
    };
    if let Some(difference) = first_difference(&expected, actual) {
        panic!(
            "{} differs from the generated output ({UPDATE_VAR}=1 to accept, then review the \
             diff):\n{difference}",
            path.display()
        );
    }
}

/// Where `actual` first departs from `expected`, line by line (`\n`-separated): the line
/// number (from 1) and both lines, or `None` when the two are equal.
fn first_difference(expected: &[u8], actual: &[u8]) -> Option<String> {
    if expected == actual {
        return None;
    }
    let mut want = expected.split(|&b| b == b'\n');
    let mut got = actual.split(|&b| b == b'\n');
    let mut number = 1;
    loop {
        match (want.next(), got.next()) {
            (Some(w), Some(g)) if w == g => number += 1,
            (w, g) => {
                return Some(format!(
                    "first difference at line {number}:\n  golden:    {}\n  generated: {}",
                    shown(w),
                    shown(g)
                ));
            }
        }
    }
}

/// A line for a failure message: lossy UTF-8 in debug quotes, cut at [`SHOWN_CHARS`]; the end
/// of the file where there is no line.
fn shown(line: Option<&[u8]>) -> String {
    let Some(line) = line else {
        return "(end of file)".to_string();
    };
    let text = String::from_utf8_lossy(line);
    let cut: String = text.chars().take(SHOWN_CHARS).collect();
    let more = if cut.len() < text.len() { " ..." } else { "" };
    format!("{cut:?}{more}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_files_have_no_difference() {
        assert_eq!(first_difference(b"a\nb\n", b"a\nb\n"), None);
    }

    #[test]
    fn the_first_differing_line_is_named() {
        let d = first_difference(b"a\nb\nc\n", b"a\nB\nc\n").unwrap();
        assert!(d.contains("line 2"), "{d}");
        assert!(d.contains("golden:    \"b\""), "{d}");
        assert!(d.contains("generated: \"B\""), "{d}");
    }

    #[test]
    fn a_missing_final_newline_is_a_difference() {
        let d = first_difference(b"a\nb\n", b"a\nb").unwrap();
        assert!(d.contains("line 3"), "{d}");
        assert!(d.contains("(end of file)"), "{d}");
    }

    #[test]
    fn long_lines_are_cut() {
        let long = "x".repeat(5 * SHOWN_CHARS);
        let d = first_difference(long.as_bytes(), b"y").unwrap();
        assert!(d.len() < 3 * SHOWN_CHARS, "{d}");
        assert!(d.contains(" ..."), "{d}");
    }

    #[test]
    fn a_wrong_file_fails_and_the_update_switch_rewrites_it() {
        let dir = std::env::temp_dir().join(format!("bt-testkit-golden-{}", std::process::id()));
        let path = dir.join("new/file.txt");
        let missing = std::panic::catch_unwind(|| check(&path, b"one\ntwo\n", false));
        check(&path, b"one\ntwo\n", true);
        check(&path, b"one\ntwo\n", false);
        let wrong = std::panic::catch_unwind(|| check(&path, b"one\nthree\n", false));
        check(&path, b"one\nthree\n", true);
        let rewritten = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let message = |r: std::thread::Result<()>| *r.unwrap_err().downcast::<String>().unwrap();
        assert!(message(missing).contains("UPDATE_GOLDEN=1 writes it"));
        let wrong = message(wrong);
        assert!(wrong.contains("line 2"), "{wrong}");
        assert_eq!(rewritten, b"one\nthree\n");
    }
}
