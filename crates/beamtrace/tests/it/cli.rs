//! Integration tests of the `beamtrace` binary: the README's commands, every input format, bad
//! input (clear errors, never a panic) and the golden JSON of the built-in scene.

use crate::common::*;
use serde_json::Value;
use std::path::Path;

/// Runs and parses `--json` output, asserting success.
fn trace_json(args: &[&str]) -> Value {
    let mut all = vec!["trace"];
    all.extend_from_slice(args);
    all.push("--json");
    run_json(&all)
}

/// Write `text` to `dir/name`; the path as an argument.
fn write_in(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn without_timings(mut v: Value) -> Value {
    v["stats"].as_object_mut().unwrap().remove("time_s");
    v
}

#[test]
fn demo_prints_a_table_of_paths() {
    let out = stdout(&run_ok(&["demo"]));
    assert!(out.contains("(line of sight)"));
    assert!(out.contains("valid paths from"));
}

#[test]
fn golden_json_of_the_builtin_scene() {
    let doc = without_timings(trace_json(&["builtin:living-room"]));
    let text = serde_json::to_string_pretty(&doc).unwrap() + "\n";
    assert_golden(golden::dir().join("living-room-image.json"), text);
}

#[test]
fn json_document_has_the_documented_fields() {
    let doc = trace_json(&["builtin:living-room", "--max-order", "2"]);
    let paths = doc["paths"].as_array().unwrap();
    assert!(!paths.is_empty());
    for p in paths {
        for field in [
            "order", "surfaces", "points", "length_m", "delay_s", "aod_deg", "aoa_deg", "loss_db",
        ] {
            assert!(p.get(field).is_some(), "path lacks {field}");
        }
        assert_eq!(
            p["points"].as_array().unwrap().len(),
            p["order"].as_u64().unwrap() as usize
        );
        assert!(p["aod_deg"]["azimuth"].is_f64() && p["aoa_deg"]["elevation"].is_f64());
    }
    let stats = &doc["stats"];
    assert_eq!(stats["valid_paths"].as_u64().unwrap() as usize, paths.len());
    assert!(
        stats["candidates"]["generated"].as_u64().unwrap()
            >= stats["candidates"]["candidates"].as_u64().unwrap()
    );
    assert!(stats["time_s"]["solve"].is_f64());
}

#[test]
fn ipc_orders_agree_with_the_image_method_through_the_cli() {
    let image = trace_json(&["builtin:living-room"]);
    for order in ["gauss-seidel", "jacobi"] {
        let ipc = trace_json(&cli(
            "builtin:living-room --solver ipc --ipc-order {}",
            &[order],
        ));
        let (a, b) = (
            image["paths"].as_array().unwrap(),
            ipc["paths"].as_array().unwrap(),
        );
        assert_eq!(a.len(), b.len(), "{order}");
        for (p, q) in a.iter().zip(b) {
            assert_eq!(p["surfaces"], q["surfaces"]);
            for (x, y) in p["points"]
                .as_array()
                .unwrap()
                .iter()
                .zip(q["points"].as_array().unwrap())
            {
                for i in 0..3 {
                    let d = (x[i].as_f64().unwrap() - y[i].as_f64().unwrap()).abs();
                    assert!(d < 1e-9, "{order}: {d}");
                }
            }
            assert!(q["iterations"].as_u64().unwrap() >= 1);
        }
    }
}

#[test]
fn negative_coordinates_work_in_both_spellings() {
    let scene = testdata("one-wall.json");
    let a = trace_json(&[&scene, "--tx", "-1.5,0.5,2", "--rx=-0.5,3,1"]);
    let b = trace_json(&[&scene, "--tx=-1.5,0.5,2", "--rx", "-0.5,3,1"]);
    assert_eq!(a["tx"], serde_json::json!([-1.5, 0.5, 2.0]));
    assert_eq!(without_timings(a), without_timings(b));
}

#[test]
fn single_wall_reflection_point_is_analytic() {
    // TX (-1.5, 1, 2), RX (2, 2, 1): image of TX is (-1.5, -1, 2); the line to RX meets y = 0
    // at a third of the way: (-1.5 + 3.5/3, 0, 2 - 1/3).
    let doc = trace_json(&[&testdata("one-wall.json")]);
    let p = &doc["paths"][1]["points"][0];
    let expected = [-1.5 + 3.5 / 3.0, 0.0, 2.0 - 1.0 / 3.0];
    for i in 0..3 {
        assert!((p[i].as_f64().unwrap() - expected[i]).abs() < 1e-12);
    }
}

#[test]
fn meshes_import_and_trace_like_the_equivalent_scene() {
    let rx = "3.6,2.9,0.8";
    let tx = "1.1,0.7,2.1";
    let obj = trace_json(&[&testdata("box-room.obj"), "--tx", tx, "--rx", rx]);
    let ascii = trace_json(&[&testdata("box-room-ascii.ply"), "--tx", tx, "--rx", rx]);
    let binary = trace_json(&[&testdata("box-room-binary.ply"), "--tx", tx, "--rx", rx]);
    // The box as 12 triangles is 6 surfaces: 1 + 6 + 18 + 38 image sources up to order 3.
    assert_eq!(obj["paths"].as_array().unwrap().len(), 63);
    let (a, b) = (without_timings(ascii), without_timings(binary));
    assert_eq!(a["paths"], b["paths"]);
    let lengths = |v: &Value| {
        v["paths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["length_m"].as_f64().unwrap())
            .collect::<Vec<_>>()
    };
    for (x, y) in lengths(&obj).iter().zip(lengths(&a)) {
        assert!((x - y).abs() < 1e-9);
    }
    // The same triangles as STL (float32 corners, exact for these integers): the ASCII file's
    // `solid room` names the surfaces as the OBJ's `o room` does, so its paths are the OBJ's
    // to the last bit; the binary file has no names, as the PLY files.
    let stl = trace_json(&[&testdata("box-room-ascii.stl"), "--tx", tx, "--rx", rx]);
    let stl_binary = trace_json(&[&testdata("box-room-binary.stl"), "--tx", tx, "--rx", rx]);
    assert_eq!(
        without_timings(stl)["paths"],
        without_timings(obj.clone())["paths"]
    );
    assert_eq!(without_timings(stl_binary)["paths"], b["paths"]);
    // As glTF (+Y up, turned to +Z up; the mesh 1 m off, put back by its node "room"'s
    // translation): the OBJ's paths, names included.
    let glb = trace_json(&[&testdata("box-room.glb"), "--tx", tx, "--rx", rx]);
    assert_eq!(without_timings(glb)["paths"], without_timings(obj)["paths"]);
}

#[test]
fn scene_check_reports_every_problem() {
    let o = beamtrace(&["scene", "check", &testdata("bad-scene.toml")]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let out = stdout(&o);
    for needle in [
        "bent-quad",
        "not planar",
        "zero area",
        "duplicate surface name",
        "unknown material",
        // No "tx: missing": a scene without a TX is bare geometry, which `scene check` accepts.
        "rx: coordinates must be finite",
    ] {
        assert!(out.contains(needle), "report lacks {needle:?}:\n{out}");
    }
}

#[test]
fn scene_check_accepts_the_builtin_scene() {
    let o = run_ok(&["scene", "check", "builtin:living-room"]);
    assert_stdout_has(&o, "25 reflectors");
}

#[test]
fn bad_inputs_give_clear_errors() {
    let dir = scratch("cli-bad-inputs");
    let write = |name: &str, text: &str| write_in(&dir, name, text);
    let malformed = write(
        "malformed.json",
        "{ \"tx\": [0, 0, 1],\n  \"surfaces\": [ }",
    );
    assert_clear_error(&["trace", &malformed], &["malformed.json", "line 2"]);
    let unknown = write(
        "unknown.json",
        r#"{ "tx": [0,0,1], "rx": [1,0,1], "surfacez": [] }"#,
    );
    assert_clear_error(&["trace", &unknown], &["unknown field `surfacez`"]);
    let no_tx = write("no-tx.json", r#"{ "rx": [1,0,1] }"#);
    assert_clear_error(
        &["trace", &no_tx],
        &["no-tx.json", "no tx given", "--tx X,Y,Z"],
    );
    let same = write("same.json", r#"{ "tx": [1,0,1], "rx": [1,0,1] }"#);
    assert_clear_error(&["trace", &same], &["same position"]);
    let on_wall = write(
        "on-wall.json",
        r#"{ "tx": [0,0,1], "rx": [0,1,1], "surfaces": [ { "name": "w", "vertices": [[-1,0,0],[1,0,0],[1,0,2],[-1,0,2]] } ] }"#,
    );
    assert_clear_error(&["trace", &on_wall], &["tx: lies on surface \"w\""]);
    let bad_obj = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n");
    assert_clear_error(
        &["trace", &bad_obj, "--tx", "0,0,1", "--rx", "1,1,1"],
        &["bad.obj", "line 4"],
    );
    let garbage = write("garbage.obj", "v 0 0 zero\n");
    assert_clear_error(
        &["trace", &garbage, "--tx", "0,0,1", "--rx", "1,1,1"],
        &["garbage.obj", "line 1"],
    );
    assert_clear_error(
        &cli(
            "trace {} --tx 0,0,1 --rx 1,1,1",
            &[&testdata("huge-claim.ply")],
        ),
        &["huge-claim.ply", "3000000000"],
    );
    assert_clear_error(&["trace", &testdata("box-room.obj")], &["--tx"]);
    assert_clear_error(&["trace", "builtin:living-room", "--tx", "1,2"], &["X,Y,Z"]);
    assert_clear_error(
        &["trace", "builtin:living-room", "--tx", "1,nan,2"],
        &["not finite"],
    );
    assert_clear_error(&["trace", "no/such/file.json"], &["no/such/file.json"]);
    assert_clear_error(&["trace", "scene.xyz"], &["unsupported scene format"]);
    let dir_arg = dir.display().to_string();
    for command in [
        &["trace"][..],
        &["trace", "--steps"],
        &["wvrn"],
        &["scene", "check"],
    ] {
        let mut args = command.to_vec();
        args.push(&dir_arg);
        assert_clear_error(&args, &[&dir_arg, "is a directory"]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Every command loads through `bt_import::load`: an unknown built-in gives the same message
/// from the static, dynamic and WVRN paths.
#[test]
fn unknown_builtin_is_one_error_everywhere() {
    let expected = "unknown built-in scene \"nowhere\" (built-in scenes: living-room, living-room-dynamic, city)";
    for command in [
        &["trace", "builtin:nowhere"][..],
        &["trace", "builtin:nowhere", "--steps"],
        &["wvrn", "builtin:nowhere"],
        &["scene", "check", "builtin:nowhere"],
        &["sample", "builtin:nowhere", "-o", "never-written.ply"],
    ] {
        assert_clear_error(command, &[expected]);
    }
    assert!(!Path::new("never-written.ply").exists());
}

/// A Sionna-style XML scene (three shapes with transforms, three kinds of bsdf) traces exactly
/// like the same geometry and materials written by hand as a JSON scene, and its floor
/// reflection has the image-method length.
#[test]
fn xml_scene_traces_like_its_json_twin() {
    let (tx, rx) = ("1.5,1,2", "4.5,3,1.2");
    let xml = trace_json(&[&testdata("sionna/room.xml"), "--tx", tx, "--rx", rx]);
    let json = trace_json(&[&testdata("sionna-room.json")]);
    let (xml, json) = (without_timings(xml), without_timings(json));
    let paths = |v: &Value| v["paths"].as_array().unwrap().clone();
    let (a, b) = (paths(&xml), paths(&json));
    assert!(a.len() >= 8, "{} paths", a.len());
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(&b) {
        assert_eq!(p["surfaces"], q["surfaces"]);
        for field in ["length_m", "loss_db", "delay_s", "reflection_loss_db"] {
            let (x, y) = (p[field].as_f64().unwrap(), q[field].as_f64().unwrap());
            // Relative: delays are ~1e-8 s, where an absolute bound would always hold.
            assert!(
                (x - y).abs() <= 1e-10 * x.abs().max(y.abs()),
                "{field}: {x} vs {y} on {:?}",
                p["surfaces"]
            );
        }
    }
    // Floor z = 0: mirror RX to (4.5, 3, -1.2); |TX - RX'| = sqrt(3² + 2² + 3.2²).
    let floor = a
        .iter()
        .find(|p| p["surfaces"] == serde_json::json!(["mesh-floor.face_0"]))
        .expect("floor reflection");
    let expected = (9.0f64 + 4.0 + 3.2 * 3.2).sqrt();
    assert!((floor["length_m"].as_f64().unwrap() - expected).abs() < 1e-9);
    // The glass pane (Sionna 0.x style id) and the custom wall keep their own materials.
    let check = run_ok(&cli(
        "scene check {} --tx {} --rx {}",
        &[&testdata("sionna/room.xml"), tx, rx],
    ));
    assert_stdout_has(&check, "3 surfaces (3 reflectors");
}

#[test]
fn bad_xml_scenes_name_the_element_and_line() {
    let dir = scratch("cli-bad-xml");
    let write = |name: &str, text: &str| write_in(&dir, name, text);
    let terminals = ["--tx", "0,0,1", "--rx", "1,1,1"];
    let run = |file: &str, needles: &[&str]| {
        let mut args = vec!["trace", file];
        args.extend_from_slice(&terminals);
        assert_clear_error(&args, needles);
    };
    let sphere = write(
        "sphere.xml",
        "<scene>\n  <shape type=\"sphere\">\n  </shape>\n</scene>\n",
    );
    run(
        &sphere,
        &[
            "sphere.xml",
            "line 2",
            "<shape type=\"sphere\"> is not supported",
        ],
    );
    let missing = write(
        "missing.xml",
        "<scene>\n<shape type=\"ply\" id=\"floor\">\n<string name=\"filename\" value=\"meshes/floor.ply\"/>\n</shape>\n</scene>\n",
    );
    run(
        &missing,
        &["missing.xml", "line 2", "floor", "meshes/floor.ply"],
    );
    let bad_ref = write(
        "bad-ref.xml",
        "<scene>\n<shape type=\"ply\" id=\"floor\">\n<string name=\"filename\" value=\"f.ply\"/>\n<ref id=\"mat-nothing\" name=\"bsdf\"/>\n</shape>\n</scene>\n",
    );
    run(&bad_ref, &["bad-ref.xml", "line 4", "\"mat-nothing\""]);
    let text = write("text.xml", "not xml at all");
    run(&text, &["text.xml", "not well-formed XML"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// `--out` keeps the terminal quiet: the document goes to the file only (with `--json` too),
/// and one line on stderr says where; without `--out`, `--json` prints the same document.
#[test]
fn out_writes_the_document_instead_of_printing_it() {
    let dir = scratch("out-quiet");
    for (extra, what) in [(&[][..], "paths"), (&["--steps"][..], "steps")] {
        let scene = if extra.is_empty() {
            "builtin:living-room"
        } else {
            "builtin:living-room-dynamic"
        };
        let file = dir.join(format!("{what}.json"));
        let mut args = vec!["trace", scene, "--json", "--out", file.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = run_ok(&args);
        assert!(stdout(&o).is_empty(), "{}", stdout(&o));
        assert!(stderr(&o).contains(&format!("wrote {}", file.display())));
        let mut printed = vec!["trace", scene, "--json"];
        printed.extend_from_slice(extra);
        let mut a = read_json(&file);
        let mut b = run_json(&printed);
        // The run times differ; everything else is the same document.
        for doc in [&mut a, &mut b] {
            strip_times(doc);
        }
        assert_eq!(a, b);
    }
    std::fs::remove_dir_all(dir).ok();
}

/// Remove every `time_s` field (run times) from `v`, recursively.
fn strip_times(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(map) => {
            map.remove("time_s");
            map.values_mut().for_each(strip_times);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(strip_times),
        _ => {}
    }
}
