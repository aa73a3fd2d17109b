use super::*;

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
        refuse_input(&other, &[&f]),
        Err(OutputError::SameAsInput { .. })
    ));
    assert!(refuse_input(&dir.join("scene.json"), &[&f]).is_ok());
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
fn new_directory_is_swapped_in_whole() {
    let (root, dir) = scratch_out("new");
    let mut out = OutputDir::begin(&dir, &[]).unwrap();
    out.write("rtl/a.v", b"module a; endmodule").unwrap();
    out.write("summary.json", b"{}").unwrap();
    assert!(!dir.exists(), "nothing appears before the commit");
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
    let mut out = OutputDir::begin(&dir, &[&input]).unwrap();
    out.write("summary.json", b"{}").unwrap();
    assert!(matches!(out.commit(), Err(OutputError::SameAsInput { .. })));
    assert_eq!(std::fs::read(&input).unwrap(), b"precious");
    assert_eq!(listing(&root), ["out"]);
}

#[test]
fn paths_outside_the_directory_are_refused() {
    let root = scratch("escape");
    let mut out = OutputDir::begin(&root.join("out"), &[]).unwrap();
    for bad in ["../x", "/etc/x", "", MANIFEST, "a/../../b"] {
        assert!(out.write(bad, b"x").is_err(), "{bad}");
    }
}
