//! Terminals per trace, not per scene: meshes, XML scenes and point clouds load as bare
//! geometry; `scene check` and `view` work on it, and every command that traces names the
//! flag of each missing terminal (exit 2, never a panic).

use crate::common::*;

#[test]
fn scene_check_accepts_bare_meshes_and_xml() {
    for scene in ["box-room.obj", "sionna/room.xml"] {
        let o = run_ok(&["scene", "check", &testdata(scene)]);
        let out = stdout(&o);
        assert!(out.contains(": ok: "), "{scene}: {out}");
        assert!(out.contains("tx none, rx none"), "{scene}: {out}");
    }
    // One terminal given, the other still none.
    let o = run_ok(&["scene", "check", &testdata("box-room.obj"), "--tx", "1,1,1"]);
    assert_stdout_has(&o, "tx [1.0, 1.0, 1.0], rx none");
}

#[test]
fn view_draws_bare_geometry_without_terminals() {
    let dir = scratch("terminals-view");
    let html = dir.join("v.html");
    let html_arg = html.display().to_string();
    let o = run_ok(&["view", &testdata("box-room.obj"), "-o", &html_arg]);
    assert_stdout_has(&o, "0 paths");
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains(r#""tx":null,"rx":null"#),
        "no terminals drawn"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn tracing_bare_geometry_names_the_missing_flags() {
    let mesh = testdata("box-room.obj");
    let xml = testdata("sionna/room.xml");
    let dir = scratch("terminals-trace");
    let out = dir.join("out").display().to_string();
    for (args, code) in [
        (cli("trace {}", &[&mesh]), Some(2)),
        (cli("trace {}", &[&xml]), Some(2)),
        (cli("trace --steps {}", &[&mesh]), Some(2)),
        (cli("wvrn {}", &[&mesh]), Some(2)),
        (cli("channel {} --out {}", &[&mesh, &out]), Some(2)),
    ] {
        let o = beamtrace(&args);
        assert_eq!(o.status.code(), code, "{args:?}: {}", stderr(&o));
        assert_clear_error(&args, &["no tx and rx given", "--tx X,Y,Z and --rx X,Y,Z"]);
    }
    assert_clear_error(
        &cli("trace {} --tx 1,1,1", &[&mesh]),
        &["no rx given: pass --rx X,Y,Z"],
    );
    assert_clear_error(
        &cli("trace {} --rx 1,1,1", &[&mesh]),
        &["no tx given: pass --tx X,Y,Z"],
    );
    // The sweep needs only the TX.
    assert_clear_error(
        &cli("sweep {} --grid 1:2:1,1:2:1,1 --out {}", &[&mesh, &out]),
        &["no tx given: pass --tx X,Y,Z"],
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_bare_mesh_with_flags_traces_like_before() {
    let o = run_ok(&cli(
        "trace {} --tx 1,1,1 --rx 3,2,1.5 --json",
        &[&testdata("box-room.obj")],
    ));
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(doc["tx"], serde_json::json!([1.0, 1.0, 1.0]));
    assert!(!doc["paths"].as_array().unwrap().is_empty());
}
