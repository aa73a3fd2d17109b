//! Outputs trust only what the program wrote (issue 27): a hand-edited manifest, inputs
//! reached through a scene or a paths document, special files, a second run into a locked
//! folder, and the leftovers of killed runs.

use super::*;
use bt_testkit::special::{is_fifo, mkfifo};
use std::path::PathBuf;

/// A process id no process has (beyond Linux's `pid_max`, 2^22).
const GONE_PID: u32 = 999_999_999;

const HLS_GEN: &str = "hls gen builtin:living-room --max-order 1 -o {}";

fn run_line(line: &str, value: &Path) -> std::process::Output {
    beamtrace(&cli(line, &[value.to_str().unwrap()]))
}

/// SHA-256 of a file as `sha256sum` prints it (the manifest's format), from the system tool.
fn sha256(path: &Path) -> String {
    let o = std::process::Command::new("sha256sum")
        .arg(path)
        .output()
        .expect("sha256sum runs");
    String::from_utf8(o.stdout).unwrap()[..64].to_string()
}

fn append(path: &Path, text: &str) {
    let mut all = std::fs::read_to_string(path).unwrap();
    all.push_str(text);
    std::fs::write(path, all).unwrap();
}

/// The warnings of a run that succeeded.
fn ok_stderr(o: &std::process::Output) -> String {
    assert_ok(o);
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn study_leaves_a_users_file_listed_in_a_hand_edited_manifest() {
    let dir = scratch("manifest-forged");
    let out = dir.join("study");
    let line = "study 2d --rooms 1 --steps 1 --max-order 1 --out {}";
    assert_ok(&run_line(line, &out));
    let mine = out.join("mine.txt");
    let other = out.join("other.txt");
    std::fs::write(&mine, "the user's").unwrap();
    std::fs::write(&other, "the user's too").unwrap();
    // One entry as an older beamtrace wrote them (no hash), one with a made-up hash.
    let forged = format!("mine.txt\n{}  other.txt\n", "0".repeat(64));
    append(&out.join(".beamtrace-manifest"), &forged);
    let warnings = ok_stderr(&run_line(line, &out));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "the user's");
    assert_eq!(std::fs::read_to_string(&other).unwrap(), "the user's too");
    for name in ["mine.txt", "other.txt"] {
        let needle = format!("{name}: listed in .beamtrace-manifest but left alone");
        assert!(warnings.contains(&needle), "{warnings}");
    }
    assert!(warnings.contains("older beamtrace"), "{warnings}");
    assert!(out.join("results.csv").exists());
}

#[test]
fn hls_gen_never_removes_through_a_link_listed_in_the_manifest() {
    let dir = scratch("manifest-link");
    let out = dir.join("accel");
    assert_ok(&run_line(HLS_GEN, &out));
    let outside = dir.join("outside");
    std::fs::create_dir_all(&outside).unwrap();
    let precious = outside.join("precious.txt");
    std::fs::write(&precious, "keep").unwrap();
    std::os::unix::fs::symlink(&outside, out.join("link")).unwrap();
    // Listed with its true hash: only the link makes it someone else's file.
    let hash = sha256(&precious);
    let manifest = out.join(".beamtrace-manifest");
    append(
        &manifest,
        &format!(
            "{hash}  link/precious.txt\n{hash}  ../outside/precious.txt\n{hash}  {}\n",
            precious.display()
        ),
    );
    let warnings = ok_stderr(&run_line(HLS_GEN, &out));
    assert_eq!(std::fs::read_to_string(&precious).unwrap(), "keep");
    assert!(
        warnings.contains("link/precious.txt: listed in .beamtrace-manifest but left alone")
            && warnings.contains("symbolic link"),
        "{warnings}"
    );
    assert!(warnings.contains("not a relative path"), "{warnings}");
    assert!(
        !std::fs::read_to_string(&manifest)
            .unwrap()
            .contains("precious")
    );
}

/// A Mitsuba XML scene in `dir` whose one shape is the PLY mesh `meshes/room.ply`.
fn xml_scene(dir: &Path) -> (PathBuf, PathBuf) {
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    let mesh = meshes.join("room.ply");
    std::fs::copy(crate::common::testdata("box-room-ascii.ply"), &mesh).unwrap();
    let xml = dir.join("scene.xml");
    std::fs::write(
        &xml,
        r#"<scene><shape type="ply" id="room"><string name="filename" value="meshes/room.ply"/></shape></scene>"#,
    )
    .unwrap();
    (xml, mesh)
}

#[test]
fn a_mesh_of_an_xml_scene_is_never_an_output() {
    let dir = scratch("xml-mesh-out");
    let (xml, mesh) = xml_scene(&dir);
    let x = xml.to_str().unwrap();
    // Another spelling of the mesh, as the output of sample (PLY) and of view (any name).
    let spelled = dir.join("meshes/../meshes/room.ply");
    let m = spelled.to_str().unwrap();
    for line in [
        "sample {} --density 10 -o {}",
        "view {} --tx 1,1,1 --rx 4,3,1.5 -o {}",
    ] {
        assert_refused_keeping(
            &cli(line, &[x, m]),
            &mesh,
            &["refusing to write", "it is the input", "room.ply"],
        );
    }
    assert_eq!(tree(&dir), ["meshes/room.ply", "scene.xml"]);
}

#[test]
fn view_refuses_to_write_over_its_paths_document() {
    let dir = scratch("view-paths-out");
    let doc = dir.join("paths.json");
    let d = doc.to_str().unwrap();
    let wall = one_wall();
    assert_ok(&beamtrace(&cli("trace {} --out {}", &[&wall, d])));
    assert_refused_keeping(
        &cli("view {} --paths {} -o {}", &[&wall, d, d]),
        &doc,
        &["refusing to write", "it is the input", "paths.json"],
    );
    assert_eq!(tree(&dir), ["paths.json"]);
}

#[test]
fn an_output_that_is_a_fifo_is_refused_and_stays_a_fifo() {
    let dir = scratch("out-fifo");
    let fifo = dir.join("paths.json");
    mkfifo(&fifo);
    let o = beamtrace(&cli(
        "trace {} --out {}",
        &[&one_wall(), fifo.to_str().unwrap()],
    ));
    assert_refused(&o, &["paths.json", "not a regular file"]);
    assert!(is_fifo(&fifo));
    // In an output folder too, where a file of the design goes.
    let out = dir.join("accel");
    std::fs::create_dir_all(&out).unwrap();
    mkfifo(&out.join("summary.json"));
    assert_refused(
        &run_line(HLS_GEN, &out),
        &["summary.json", "not a regular file"],
    );
    assert!(is_fifo(&out.join("summary.json")));
    assert_eq!(tree(&dir), ["accel/summary.json", "paths.json"]);
}

/// Holds `dir`'s lock as a concurrent `hls gen` would, until dropped.
fn hold_lock(dir: &Path) -> std::fs::File {
    use std::os::fd::AsRawFd;
    let file = std::fs::File::create(dir.join(".beamtrace-lock")).unwrap();
    // SAFETY: flock only reads the descriptor, which `file` keeps open.
    let r = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    assert_eq!(r, 0, "{}", std::io::Error::last_os_error());
    file
}

#[test]
fn a_second_hls_gen_into_the_same_folder_is_refused() {
    let dir = scratch("hls-busy");
    let out = dir.join("accel");
    std::fs::create_dir_all(&out).unwrap();
    let first = hold_lock(&out);
    let o = run_line(HLS_GEN, &out);
    assert_refused(
        &o,
        &[
            out.to_str().unwrap(),
            "another beamtrace run is writing into this directory",
        ],
    );
    assert_eq!(tree(&out), [".beamtrace-lock"], "nothing written");
    drop(first);
    assert_ok(&run_line(HLS_GEN, &out));
    assert!(out.join("rtl/bt_top.v").exists());
    assert!(!out.join(".beamtrace-lock").exists(), "removed at the end");
}

#[test]
fn leftovers_of_killed_runs_are_cleaned_by_the_next_run() {
    let dir = scratch("stale");
    // A killed `trace --out paths.json` and a killed `hls gen -o accel` (and one of an older
    // beamtrace, which staged beside the folder).
    let tmp = dir.join(format!(".paths.json.tmp-{GONE_PID}-0.json"));
    std::fs::write(&tmp, "half").unwrap();
    let out = dir.join("accel");
    let staging = out.join(format!(".beamtrace-staging-{GONE_PID}-0"));
    let beside = dir.join(format!("accel.tmp-{GONE_PID}-3"));
    for d in [&staging, &beside] {
        std::fs::create_dir_all(d.join("rtl")).unwrap();
        std::fs::write(d.join("rtl/bt_top.v"), "half").unwrap();
    }
    // A link with our pattern's name is not ours: neither it nor its target goes.
    let target = dir.join("target.txt");
    std::fs::write(&target, "keep").unwrap();
    let link = dir.join(format!(".paths.json.tmp-{GONE_PID}-1.json"));
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let paths = dir.join("paths.json");
    assert_ok(&beamtrace(&cli(
        "trace {} --out {}",
        &[&one_wall(), paths.to_str().unwrap()],
    )));
    assert_ok(&run_line(HLS_GEN, &out));
    assert!(!tmp.exists() && !staging.exists() && !beside.exists());
    assert!(std::fs::symlink_metadata(&link).is_ok());
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    let mut top: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    top.sort();
    let link_name = link.file_name().unwrap().to_string_lossy().into_owned();
    assert_eq!(
        top,
        [link_name.as_str(), "accel", "paths.json", "target.txt"]
    );
}

#[test]
fn channel_checks_every_option_and_output_before_writing_its_cir() {
    let dir = scratch("channel-late-refusal");
    let cir = dir.join("cir.csv");
    let cfr = dir.join("cfr.csv");
    let (cir_s, cfr_s) = (cir.to_str().unwrap(), cfr.to_str().unwrap());
    // The frequency response's budget is the last option checked.
    assert_refused_writing_nothing(
        &cli(
            "channel builtin:living-room --max-order 1 --out {} --cfr {} --subcarriers 2000",
            &[cir_s, cfr_s],
        )
        .into_iter()
        .chain(["--max-subcarriers", "1000"])
        .collect::<Vec<_>>(),
        &cir,
        &["--max-subcarriers"],
    );
    // A PDP figure that would replace a directory.
    std::fs::create_dir(dir.join("pdp.svg")).unwrap();
    let stem = dir.join("pdp");
    assert_refused_writing_nothing(
        &cli(
            "channel builtin:living-room --max-order 1 --out {} --pdp {}",
            &[cir_s, stem.to_str().unwrap()],
        ),
        &cir,
        &["pdp.svg"],
    );
    assert!(!cfr.exists());
}

#[test]
fn sweep_checks_its_heat_map_before_writing_its_csv() {
    let dir = scratch("sweep-late-refusal");
    std::fs::create_dir(dir.join("coverage.png")).unwrap();
    assert_refused_writing_nothing(
        &cli(
            "sweep builtin:living-room --max-order 1 --grid 1:2:1,1:2:1,1.2 --out {}",
            &[dir.to_str().unwrap()],
        ),
        &dir.join("coverage.csv"),
        &["coverage.png"],
    );
}
