use super::*;
use bt_testkit::special::{is_fifo, mkfifo};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bt-output-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A fresh scratch folder `name` and the output folder `out` to be built in it (not created).
fn scratch_out(name: &str) -> (PathBuf, PathBuf) {
    let root = scratch(name);
    let dir = root.join("out");
    (root, dir)
}

fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The file `name` holding `old` in a fresh scratch folder `dir`.
fn old_file(dir: &str, name: &str) -> PathBuf {
    let f = scratch(dir).join(name);
    write_atomic(&f, b"old").unwrap();
    f
}

/// What a writer returns when it fails half-way (after writing part of its output).
fn simulated_failure() -> Result<(), OutputError> {
    Err(OutputError::BadRelative("simulated".into()))
}

/// One build of the output folder `dir` that writes `files` (path, contents) and commits.
fn commit_files(dir: &Path, files: &[(&str, &[u8])]) {
    let mut out = OutputDir::begin(dir, &[]).unwrap();
    for (path, contents) in files {
        out.write(path, contents).unwrap();
    }
    out.commit().unwrap();
}

/// `file` holds `content` and is the only entry of its directory (no temporary file left).
fn assert_alone(file: &Path, content: &[u8]) {
    assert_eq!(std::fs::read(file).unwrap(), content);
    let name = file.file_name().unwrap().to_string_lossy();
    assert_eq!(listing(file.parent().unwrap()), [name]);
}

#[test]
fn atomic_write_replaces_and_leaves_no_temporary() {
    let dir = scratch("atomic");
    let f = dir.join("a.json");
    write_atomic(&f, b"one").unwrap();
    write_atomic(&f, b"two").unwrap();
    assert_alone(&f, b"two");
}

#[test]
fn failed_fill_keeps_the_old_file() {
    let f = old_file("fail", "a.csv");
    let r = write_atomic_with(&f, |w| {
        w.write_all(b"half").unwrap();
        simulated_failure()
    });
    assert!(r.is_err());
    assert_alone(&f, b"old");
}

#[test]
fn path_writer_sees_the_extension_and_a_failure_keeps_the_old_file() {
    let f = old_file("via", "fig.png");
    let r = write_atomic_via(&f, |tmp| {
        assert_eq!(tmp.extension().unwrap(), "png");
        assert_eq!(tmp.parent(), f.parent());
        std::fs::write(tmp, b"half").unwrap();
        simulated_failure()
    });
    assert!(r.is_err());
    assert_alone(&f, b"old");
    write_atomic_via(&f, |tmp| {
        std::fs::write(tmp, b"new").map_err(|e| OutputError::Io {
            path: tmp.display().to_string(),
            source: e,
        })
    })
    .unwrap();
    assert_alone(&f, b"new");
}

#[test]
fn output_equal_to_input_is_refused_in_any_spelling() {
    let dir = scratch("same");
    let f = dir.join("cloud.ply");
    std::fs::write(&f, b"ply").unwrap();
    let other = dir.join(".").join("cloud.ply");
    assert!(matches!(
        refuse_input(&other, std::slice::from_ref(&f)),
        Err(OutputError::SameAsInput { .. })
    ));
    assert!(refuse_input(&dir.join("scene.json"), &[f]).is_ok());
}

#[test]
fn extension_chooses_or_refuses() {
    assert_eq!(
        extension_in(Path::new("x.TOML"), &["json", "toml"]).unwrap(),
        "toml"
    );
    let e = extension_in(Path::new("x.yaml"), &["json", "toml"]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.yaml: cannot write this format (extension .yaml); use .json or .toml"
    );
    assert!(extension_in(Path::new("x"), &["json"]).is_err());
}

#[test]
fn new_directory_shows_no_output_before_the_commit() {
    let (root, dir) = scratch_out("new");
    let mut out = OutputDir::begin(&dir, &[]).unwrap();
    out.write("rtl/a.v", b"module a; endmodule").unwrap();
    out.write("summary.json", b"{}").unwrap();
    let before = listing(&dir);
    assert_eq!(before.len(), 2, "only the lock and the staging: {before:?}");
    assert_eq!(before[0], LOCK);
    assert!(before[1].starts_with(".beamtrace-staging-"));
    out.commit().unwrap();
    assert_eq!(listing(&root), ["out"]);
    assert_eq!(listing(&dir), [MANIFEST, "rtl", "summary.json"]);
}

#[test]
fn user_files_survive_and_only_our_stale_files_go() {
    let (_, dir) = scratch_out("keep");
    commit_files(&dir, &[("rtl/a.v", b"1"), ("rtl/b.v", b"1")]);
    std::fs::write(dir.join("rtl/mine.v"), b"user").unwrap();
    commit_files(&dir, &[("rtl/a.v", b"2")]);
    assert_eq!(listing(&dir.join("rtl")), ["a.v", "mine.v"]);
    assert_eq!(std::fs::read(dir.join("rtl/a.v")).unwrap(), b"2");
    assert_eq!(std::fs::read(dir.join("rtl/mine.v")).unwrap(), b"user");
}

#[test]
fn abandoned_build_leaves_nothing() {
    let (root, dir) = scratch_out("abandon");
    {
        let mut out = OutputDir::begin(&dir, &[]).unwrap();
        out.write("a.txt", b"x").unwrap();
    }
    assert!(listing(&root).is_empty());
}

#[test]
fn commit_refuses_to_replace_an_input() {
    let (root, dir) = scratch_out("protect");
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("summary.json");
    std::fs::write(&input, b"precious").unwrap();
    let mut out = OutputDir::begin(&dir, std::slice::from_ref(&input)).unwrap();
    out.write("summary.json", b"{}").unwrap();
    assert!(matches!(out.commit(), Err(OutputError::SameAsInput { .. })));
    assert_eq!(std::fs::read(&input).unwrap(), b"precious");
    assert_eq!(listing(&root), ["out"]);
}

#[test]
fn paths_outside_the_directory_are_refused() {
    let root = scratch("escape");
    let mut out = OutputDir::begin(&root.join("out"), &[]).unwrap();
    for bad in [
        "../x",
        "/etc/x",
        "",
        MANIFEST,
        LOCK,
        ".beamtrace-staging-1-2/x",
        "a/../../b",
    ] {
        assert!(out.write(bad, b"x").is_err(), "{bad}");
    }
}

/// A path no process can have (beyond Linux's `pid_max`, 2^22).
const GONE_PID: u32 = 999_999_999;

/// A committed output folder holding `a.txt` (ours) and a user's `notes.txt`, whose manifest
/// is then replaced by `manifest` (a hand edit); the next commit writes only `b.txt`.
fn commit_over_edited_manifest(name: &str, manifest: &str) -> (PathBuf, Committed) {
    let (_, dir) = scratch_out(name);
    commit_files(&dir, &[("a.txt", b"ours")]);
    std::fs::write(dir.join("notes.txt"), b"user").unwrap();
    std::fs::write(dir.join(MANIFEST), manifest).unwrap();
    let mut out = OutputDir::begin(&dir, &[]).unwrap();
    out.write("b.txt", b"new").unwrap();
    (dir.clone(), out.commit().unwrap())
}

#[test]
fn manifest_records_the_hash_of_each_file() {
    let (_, dir) = scratch_out("hash");
    commit_files(&dir, &[("a.txt", b"abc")]);
    let text = std::fs::read_to_string(dir.join(MANIFEST)).unwrap();
    assert!(
        text.contains("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad  a.txt\n")
    );
    assert_eq!(
        manifest_files(&dir)
            .unwrap()
            .into_iter()
            .collect::<Vec<_>>(),
        ["a.txt"]
    );
}

#[test]
fn hand_listed_user_file_is_left_alone_with_a_warning() {
    // The user's file listed with a made-up hash, and without any (an older manifest).
    let forged = format!("{}  notes.txt\n", "0".repeat(64));
    for manifest in [forged.as_str(), "notes.txt\n"] {
        let (dir, done) = commit_over_edited_manifest("forged", manifest);
        assert_eq!(std::fs::read(dir.join("notes.txt")).unwrap(), b"user");
        assert_eq!(done.left_alone.len(), 1, "{manifest}");
        let warning = done.left_alone[0].to_string();
        assert!(warning.contains("notes.txt: listed in .beamtrace-manifest but left alone"));
    }
}

#[test]
fn old_manifest_entries_are_not_trusted() {
    let (dir, done) = commit_over_edited_manifest("old", "a.txt\n");
    assert_eq!(std::fs::read(dir.join("a.txt")).unwrap(), b"ours");
    assert!(done.left_alone[0].reason.contains("older beamtrace"));
    // The new manifest no longer lists it: the file is the user's from now on.
    assert!(!manifest_files(&dir).unwrap().contains("a.txt"));
}

#[test]
fn manifest_entries_outside_or_through_links_are_left_alone() {
    let (root, dir) = scratch_out("links");
    let outside = root.join("precious.txt");
    std::fs::write(&outside, b"keep").unwrap();
    commit_files(&dir, &[("a.txt", b"keep")]);
    std::os::unix::fs::symlink(&root, dir.join("up")).unwrap();
    std::os::unix::fs::symlink(&outside, dir.join("link.txt")).unwrap();
    let wrong = "0".repeat(64);
    let keep = crate::manifest::sha256_file(&outside).unwrap();
    let manifest = format!(
        "{keep}  up/precious.txt\n{keep}  link.txt\n{keep}  ../precious.txt\n{keep}  {}\n{wrong}  a.txt\n",
        outside.display()
    );
    std::fs::write(dir.join(MANIFEST), manifest).unwrap();
    let done = OutputDir::begin(&dir, &[]).unwrap().commit().unwrap();
    assert_eq!(std::fs::read(&outside).unwrap(), b"keep");
    assert!(std::fs::symlink_metadata(dir.join("link.txt")).is_ok());
    assert_eq!(std::fs::read(dir.join("a.txt")).unwrap(), b"keep");
    let reasons: Vec<String> = done.left_alone.iter().map(|l| l.to_string()).collect();
    assert_eq!(reasons.len(), 5, "{reasons:#?}");
    assert!(
        reasons[0].contains("through the symbolic link"),
        "{reasons:#?}"
    );
}

#[test]
fn special_files_are_never_replaced() {
    let dir = scratch("fifo");
    let fifo = dir.join("out.json");
    mkfifo(&fifo);
    let e = write_atomic(&fifo, b"x").unwrap_err();
    assert!(matches!(e, OutputError::NotRegular(_)), "{e}");
    assert!(e.to_string().contains("out.json"));
    assert!(is_fifo(&fifo));
    assert_eq!(listing(&dir), ["out.json"]);
    let e = write_atomic(&dir, b"x").unwrap_err();
    assert!(matches!(e, OutputError::IsDirectory(_)), "{e}");

    let (_, out_dir) = scratch_out("fifo-dir");
    std::fs::create_dir_all(&out_dir).unwrap();
    mkfifo(&out_dir.join("summary.json"));
    let mut out = OutputDir::begin(&out_dir, &[]).unwrap();
    out.write("summary.json", b"{}").unwrap();
    assert!(matches!(out.commit(), Err(OutputError::NotRegular(_))));
    assert!(is_fifo(&out_dir.join("summary.json")));
}

#[test]
fn outputs_are_not_written_through_a_link_inside_the_directory() {
    let (root, dir) = scratch_out("through");
    let elsewhere = root.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::fs::create_dir_all(&dir).unwrap();
    std::os::unix::fs::symlink(&elsewhere, dir.join("rtl")).unwrap();
    let mut out = OutputDir::begin(&dir, &[]).unwrap();
    out.write("rtl/a.v", b"x").unwrap();
    let e = out.commit().unwrap_err();
    assert!(matches!(e, OutputError::ThroughSymlink { .. }), "{e}");
    assert!(listing(&elsewhere).is_empty());
}

#[test]
fn a_second_run_into_a_locked_directory_is_refused() {
    let (root, dir) = scratch_out("busy");
    let first = OutputDir::begin(&dir, &[]).unwrap();
    let e = OutputDir::begin(&dir, &[]).unwrap_err();
    assert!(matches!(e, OutputError::Busy { .. }), "{e}");
    assert!(e.to_string().contains(&dir.display().to_string()));
    drop(first);
    assert!(
        listing(&root).is_empty(),
        "the first run created and removed out"
    );
    commit_files(&dir, &[("a.txt", b"1")]);
    assert_eq!(listing(&dir), [MANIFEST, "a.txt"]);
}

#[test]
fn leftovers_of_killed_runs_are_removed_and_nothing_else() {
    let dir = scratch("stale");
    let ours = std::process::id();
    let stale = format!(".a.json.tmp-{GONE_PID}-3.json");
    let keep = [
        format!(".a.json.tmp-{ours}-999999.json"), // a live process (this one)
        format!(".a.json.tmp-{GONE_PID}-x.json"),  // not our pattern
        format!(".b.json.tmp-{GONE_PID}-1.json"),  // another output's
        format!(".a.json.tmp-{GONE_PID}-4.json.bak"),
    ];
    std::fs::write(dir.join(&stale), b"half").unwrap();
    for k in &keep {
        std::fs::write(dir.join(k), b"keep").unwrap();
    }
    let link = format!(".a.json.tmp-{GONE_PID}-5.json");
    std::os::unix::fs::symlink(dir.join(&keep[1]), dir.join(&link)).unwrap();
    write_atomic(&dir.join("a.json"), b"{}").unwrap();
    let mut expected: Vec<String> = keep.to_vec();
    expected.extend([link, "a.json".to_string()]);
    expected.sort();
    assert_eq!(listing(&dir), expected);
}

#[test]
fn staging_of_killed_runs_is_removed() {
    let (root, dir) = scratch_out("staging");
    commit_files(&dir, &[("a.txt", b"1")]);
    let inside = dir.join(format!(".beamtrace-staging-{GONE_PID}-0"));
    let beside = root.join(format!("out.tmp-{GONE_PID}-0"));
    for d in [&inside, &beside] {
        std::fs::create_dir_all(d.join("rtl")).unwrap();
        std::fs::write(d.join("rtl/a.v"), b"half").unwrap();
    }
    std::fs::write(
        dir.join(format!(".beamtrace-staging-{GONE_PID}-1")),
        b"a file",
    )
    .unwrap();
    commit_files(&dir, &[("a.txt", b"2")]);
    assert_eq!(listing(&root), ["out"]);
    assert_eq!(
        listing(&dir),
        [
            MANIFEST.to_string(),
            format!(".beamtrace-staging-{GONE_PID}-1"),
            "a.txt".to_string()
        ]
    );
}
