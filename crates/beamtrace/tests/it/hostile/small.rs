//! The smaller cases of issue 9.

use super::*;
use serde_json::Value;

#[test]
fn a_full_stdout_is_an_error_not_a_panic() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return; // no /dev/full on this system
    };
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_beamtrace"));
    let o = cmd
        .args(["trace", &one_wall(), "--json"])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("writing to stdout"), "{err}");
}

fn trace_json(args: &[&str]) -> Value {
    let mut all = vec!["trace"];
    all.extend_from_slice(args);
    all.push("--json");
    let r = beamtrace(&all);
    assert_ok(&r);
    serde_json::from_slice(&r.stdout).unwrap()
}

#[test]
fn ipc_line_of_sight_has_a_numeric_residual() {
    let v = trace_json(&[&one_wall(), "--solver", "ipc"]);
    let paths = v["paths"].as_array().unwrap();
    assert!(paths.iter().any(|p| p["order"] == 0));
    for p in paths {
        assert!(p["residual_m"].is_f64(), "{p}");
    }
}

#[test]
fn extreme_frequencies_are_refused_not_given_infinite_loss() {
    let dir = scratch("freq");
    for f in ["1e300", "1e-300"] {
        let text = std::fs::read_to_string(one_wall()).unwrap().replace(
            "\"name\": \"one-wall\",",
            &format!("\"name\": \"f\", \"frequency_hz\": {f},"),
        );
        let scene = scene_with(&dir, "f.json", &text);
        assert_refused(&beamtrace(&["trace", &scene]), &["frequency_hz", "between"]);
    }
}

#[test]
fn terminals_closer_than_a_wavelength_get_a_clamped_loss_and_a_warning() {
    let r = beamtrace(&[
        "trace",
        &one_wall(),
        "--tx",
        "0,1,1",
        "--rx",
        "0,1,1.0000001",
        "--json",
    ]);
    assert_ok(&r);
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    let floor = 20.0 * (4.0 * std::f64::consts::PI).log10();
    for p in v["paths"].as_array().unwrap() {
        let loss = p["free_space_loss_db"].as_f64().unwrap();
        assert!(loss >= floor - 1e-9, "a loss of {loss} dB is a gain: {p}");
    }
    assert!(String::from_utf8_lossy(&r.stderr).contains("near field"));
}

#[test]
fn nan_options_are_refused() {
    let dir = scratch("nan");
    let r = beamtrace(&[
        "extract",
        "whatever.ply",
        "--min-reflector-area",
        "nan",
        "-o",
        dir.join("x.json").to_str().unwrap(),
    ]);
    assert_refused(
        &r,
        &["--min-reflector-area", "'nan'", "must be a finite number"],
    );
}

#[test]
fn unresolvable_coordinates_are_refused_with_that_reason() {
    let dir = scratch("huge");
    let desc = serde_json::json!({
        "tx": [1e300, 1, 2], "rx": [1e300, 2, 1],
        "surfaces": [{ "name": "wall", "vertices":
            [[1e300, 0, 0], [1e300 + 5.0, 0, 0], [1e300 + 5.0, 0, 3], [1e300, 0, 3]] }]
    });
    let scene = scene_with(&dir, "huge.json", &desc.to_string());
    let r = beamtrace(&["scene", "check", &scene]);
    assert_refused(&r, &["cannot resolve", "nearer the origin"]);
    assert!(!text(&r).contains("same position"), "{}", text(&r));
}

#[test]
fn os_errors_are_printed_once() {
    let r = beamtrace(&["trace", "/nonexistent/scene.json"]);
    assert_refused(&r, &["No such file"]);
    assert_eq!(text(&r).matches("No such file").count(), 1, "{}", text(&r));
}

#[test]
fn a_directory_as_input_is_named_as_such() {
    let dir = scratch("dir-input");
    let r = beamtrace(&["trace", dir.to_str().unwrap()]);
    assert_refused(&r, &["is a directory"]);
    assert!(
        !text(&r).contains("unsupported scene format"),
        "{}",
        text(&r)
    );
}

/// `value` with every coordinate triple under a position key moved by `offset`.
fn shifted(value: &Value, offset: [f64; 3]) -> Value {
    let shift = |p: &Value| -> Value {
        let p: Vec<f64> = p
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap())
            .collect();
        serde_json::json!([p[0] + offset[0], p[1] + offset[1], p[2] + offset[2]])
    };
    let mut out = value.clone();
    for key in ["tx", "rx"] {
        out[key] = shift(&value[key]);
    }
    for b in out["boxes"].as_array_mut().into_iter().flatten() {
        for key in ["min", "max"] {
            b[key] = shift(&b[key]);
        }
    }
    for s in out["surfaces"].as_array_mut().into_iter().flatten() {
        let moved: Vec<Value> = s["vertices"]
            .as_array()
            .unwrap()
            .iter()
            .map(shift)
            .collect();
        s["vertices"] = Value::Array(moved);
    }
    out
}

#[test]
fn a_scene_far_from_the_origin_traces_like_the_same_scene_at_it() {
    let dir = scratch("far");
    let room: Value =
        serde_json::from_str(bt_import::builtin_json("living-room").unwrap()).unwrap();
    let near = scene_with(&dir, "near.json", &room.to_string());
    for offset in [[1e7, 1e7, 100.0], [-3.2e5, 2.7e6, -50.0]] {
        let far = scene_with(&dir, "far.json", &shifted(&room, offset).to_string());
        for solver in ["image", "ipc"] {
            let args = ["--solver", solver, "--max-order", "3"];
            let a = trace_json(&[&[near.as_str()][..], &args].concat());
            let b = trace_json(&[&[far.as_str()][..], &args].concat());
            let (pa, pb) = (
                a["paths"].as_array().unwrap(),
                b["paths"].as_array().unwrap(),
            );
            assert!(pa.len() > 20, "{solver}: {} paths", pa.len());
            assert_eq!(pa.len(), pb.len(), "{solver} at {offset:?}: path counts");
            for k in 0..3 {
                let tx = b["tx"][k].as_f64().unwrap() - offset[k];
                assert!(
                    (tx - a["tx"][k].as_f64().unwrap()).abs() < 1e-8,
                    "tx in world"
                );
            }
            for (p, q) in pa.iter().zip(pb) {
                assert_eq!(p["surfaces"], q["surfaces"], "{solver} at {offset:?}");
                let (lp, lq) = (
                    p["length_m"].as_f64().unwrap(),
                    q["length_m"].as_f64().unwrap(),
                );
                assert!(
                    (lp - lq).abs() <= 1e-9 * lp,
                    "{solver}: length {lp} vs {lq}"
                );
                let points = p["points"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .zip(q["points"].as_array().unwrap());
                for (u, v) in points {
                    for k in 0..3 {
                        let d = v[k].as_f64().unwrap() - offset[k] - u[k].as_f64().unwrap();
                        assert!(d.abs() <= 1e-6, "{solver}: point {u} vs {v}");
                    }
                }
            }
        }
    }
}

#[test]
fn a_terminal_shut_inside_a_closed_solid_is_warned_about() {
    let dir = scratch("shut-in");
    let desc = serde_json::json!({
        "tx": [4.5, 1.5, 1.0], "rx": [1, 1, 1],
        "boxes": [
            { "name": "room", "min": [0, 0, 0], "max": [6, 4, 3] },
            { "name": "safe", "material": "metal", "min": [4, 1, 0.5], "max": [5, 2, 1.5] }
        ]
    });
    let scene = scene_with(&dir, "safe.json", &desc.to_string());
    let needle = "tx lies inside the closed solid of 6 surfaces (\"safe.top\", \"safe.bottom\"";
    for command in [&["scene", "check"][..], &["trace"][..]] {
        let r = beamtrace(&[command, &[scene.as_str()][..]].concat());
        assert_ok(&r);
        assert!(text(&r).contains(needle), "{}", text(&r));
        assert!(
            text(&r).contains("no path can connect them"),
            "{}",
            text(&r)
        );
    }
    // RX in the safe too: paths exist inside it, no warning; an open safe: no warning.
    let mut both = desc.clone();
    both["rx"] = serde_json::json!([4.25, 1.25, 0.75]);
    let r = beamtrace(&[
        "scene",
        "check",
        &scene_with(&dir, "both.json", &both.to_string()),
    ]);
    assert!(!text(&r).contains("closed solid"), "{}", text(&r));
    let mut open = desc.clone();
    open["boxes"][1]["omit"] = serde_json::json!(["top"]);
    let r = beamtrace(&[
        "scene",
        "check",
        &scene_with(&dir, "open.json", &open.to_string()),
    ]);
    assert!(!text(&r).contains("closed solid"), "{}", text(&r));
    // A closed mesh (a triangulated cube) with RX inside, TX outside.
    let mut obj = String::from("o cube\n");
    for v in 0..8 {
        let c = |bit: usize| if v & bit != 0 { 2 } else { 0 };
        obj.push_str(&format!("v {} {} {}\n", c(1), c(2), c(4)));
    }
    for f in [
        "1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6",
    ] {
        let i: Vec<&str> = f.split(' ').collect();
        obj.push_str(&format!(
            "f {} {} {}\nf {} {} {}\n",
            i[0], i[1], i[2], i[0], i[2], i[3]
        ));
    }
    let cube = scene_with(&dir, "cube.obj", &obj);
    let r = beamtrace(&["scene", "check", &cube, "--tx", "5,1,1", "--rx", "1,1,1"]);
    assert_ok(&r);
    assert!(
        text(&r).contains("rx lies inside the closed solid of 6 surfaces"),
        "{}",
        text(&r)
    );
}

/// Round 2 (issue 27): a NaN or negative minimum reflector area is refused, naming the
/// option, instead of turning every surface into a blocker.
#[test]
fn a_nan_minimum_reflector_area_is_refused() {
    for value in ["nan", "-1", "inf"] {
        crate::common::assert_clear_error(
            &[
                "trace",
                "builtin:living-room",
                &format!("--min-reflector-area={value}"),
            ],
            &["--min-reflector-area", "finite number"],
        );
    }
}

/// Round 2 (issue 27): a surface named like a spreadsheet formula is not a formula in the CSV.
#[test]
fn a_formula_name_is_escaped_in_the_csv() {
    let dir = scratch("formula-csv");
    let scene = scene_with(
        &dir,
        "scene.json",
        r#"{ "tx": [0, 0, 1], "rx": [3, 0, 1], "surfaces": [ { "name": "=HYPERLINK(1)",
            "vertices": [[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]] } ] }"#,
    );
    let cir = dir.join("cir.csv");
    let o = beamtrace(&["channel", &scene, "--out", cir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(&cir).unwrap();
    assert!(csv.contains("\"'=HYPERLINK(1)\""), "{csv}");
    assert!(!csv.contains(",=HYPERLINK"), "{csv}");
    std::fs::remove_dir_all(dir).ok();
}

/// Round 2 (issue 27): a FIFO named as a mesh, or reached as an XML scene's mesh, is refused
/// at once, naming it, instead of hanging the run.
#[cfg(unix)]
#[test]
fn a_fifo_as_a_mesh_is_refused_not_waited_on() {
    let dir = scratch("fifo-mesh");
    let fifo = dir.join("room.obj");
    bt_testkit::special::mkfifo(&fifo);
    crate::common::assert_clear_error(
        &[
            "trace",
            fifo.to_str().unwrap(),
            "--tx",
            "0,0,1",
            "--rx",
            "1,0,1",
        ],
        &["room.obj", "not a regular file"],
    );
    let xml = scene_with(
        &dir,
        "scene.xml",
        r#"<scene version="2.1.0"><shape type="obj" id="room"><string name="filename" value="room.obj"/></shape></scene>"#,
    );
    crate::common::assert_clear_error(
        &["trace", &xml, "--tx", "0,0,1", "--rx", "1,0,1"],
        &["room.obj", "not a regular file"],
    );
    std::fs::remove_dir_all(dir).ok();
}

/// Round 2 (issue 27): a receiver 1e9 m away is reported as the receiver's problem, not as the
/// transmitter lying on surfaces (the far terminal had scaled the tolerance to a metre).
#[test]
fn a_far_receiver_is_named_as_the_problem() {
    crate::common::assert_clear_error(
        &["trace", "builtin:living-room", "--rx", "1e9,0,1"],
        &[
            "rx: lies 1.000e9 m from the scene's surfaces",
            "move it nearer",
        ],
    );
    let o = beamtrace(&["trace", "builtin:living-room", "--rx", "1e9,0,1"]);
    assert!(!text(&o).contains("tx:"), "{}", text(&o));
}

/// Round 2 (issue 27): `view --paths` refuses a document traced from another scene, naming a
/// surface the scene lacks, and writes nothing.
#[test]
fn view_refuses_paths_of_another_scene() {
    let dir = scratch("foreign-paths");
    let doc = dir.join("room.json");
    let o = beamtrace(&[
        "trace",
        "builtin:living-room",
        "--json",
        "--out",
        doc.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let page = dir.join("view.html");
    crate::common::assert_clear_error(
        &[
            "view",
            &crate::common::testdata("sionna-rt/simple_wedge/simple_wedge.xml"),
            "--paths",
            doc.to_str().unwrap(),
            "-o",
            page.to_str().unwrap(),
        ],
        &["room.json", "which scene simple_wedge does not have"],
    );
    assert!(!page.exists());
    std::fs::remove_dir_all(dir).ok();
}

/// Round 2 (issue 27): two identical coplanar walls counted every path reflecting there twice
/// while `scene check` said ok. Now `scene check` and `trace` refuse the file, naming both.
#[test]
fn identical_coplanar_walls_are_refused_naming_both() {
    let dir = scratch("coincident");
    let wall = r#"[[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3]]"#;
    let scene = scene_with(
        &dir,
        "twice.json",
        &format!(
            r#"{{ "tx": [1, 2, 1], "rx": [3, 2, 1], "surfaces": [
                {{ "name": "wall", "vertices": {wall} }},
                {{ "name": "wall-again", "vertices": {wall} }} ] }}"#
        ),
    );
    let needles = [
        "twice.json",
        "surface \"wall-again\": the same polygon as surface \"wall\"",
    ];
    assert_refused(&beamtrace(&["scene", "check", &scene]), &needles);
    assert_refused(&beamtrace(&["trace", &scene]), &needles);
    // Another material makes no difference: a scene file must say which one is meant.
    let glass = scene_with(
        &dir,
        "glass.json",
        &std::fs::read_to_string(&scene).unwrap().replace(
            r#""name": "wall-again","#,
            r#""name": "wall-again", "material": "glass","#,
        ),
    );
    assert_refused(&beamtrace(&["scene", "check", &glass]), &needles[1..]);
    std::fs::remove_dir_all(dir).ok();
}

/// Round 2 (issue 27): polygons just under the per-surface vertex limit are quadratic each, so
/// four of them ran for seconds together; their sum of squared vertex counts is a scene budget
/// checked before any is built.
#[test]
fn many_huge_polygons_stop_at_the_scene_budget() {
    let dir = scratch("huge-polygons");
    let circle = |k: usize| {
        let n = 10_000;
        let points: Vec<String> = (0..n)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / n as f64;
                format!("[{:.9}, {:.9}, {k}]", a.cos(), a.sin())
            })
            .collect();
        format!(
            r#"{{ "name": "disc{k}", "vertices": [{}] }}"#,
            points.join(",")
        )
    };
    let surfaces: Vec<String> = (0..4).map(circle).collect();
    let scene = scene_with(
        &dir,
        "discs.json",
        &format!(
            r#"{{ "tx": [0, 0, 0.5], "rx": [0, 0.1, 0.5], "surfaces": [{}] }}"#,
            surfaces.join(",")
        ),
    );
    let start = std::time::Instant::now();
    let o = beamtrace_within(&["scene", "check", &scene], 2 << 30);
    assert_refused(
        &o,
        &["discs.json", "400000000 vertex pairs", "split the largest"],
    );
    assert!(start.elapsed() < std::time::Duration::from_secs(20));
    std::fs::remove_dir_all(dir).ok();
}
