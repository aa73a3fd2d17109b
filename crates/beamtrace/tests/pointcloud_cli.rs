//! Point cloud to scene, end to end through the CLI: sample the built-in living room into a
//! noisy cloud (5 mm), extract its planes, and compare with the original surfaces and paths.

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn beamtrace(args: &[&str]) -> std::process::Output {
    let o = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args(args)
        .output()
        .expect("binary runs");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("beamtrace-pc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

type V = [f64; 3];
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: V) -> f64 {
    dot(a, a).sqrt()
}

/// (unit normal, area, centroid) of a planar polygon by Newell's method.
fn plane_of(vertices: &[V]) -> (V, f64, V) {
    let n = vertices.len();
    let mut s = [0.0; 3];
    let mut c = [0.0; 3];
    for i in 0..n {
        let x = cross(vertices[i], vertices[(i + 1) % n]);
        for k in 0..3 {
            s[k] += x[k];
            c[k] += vertices[i][k] / n as f64;
        }
    }
    let area = norm(s) / 2.0;
    (
        [
            s[0] / (2.0 * area),
            s[1] / (2.0 * area),
            s[2] / (2.0 * area),
        ],
        area,
        c,
    )
}

fn polygons(doc: &Value) -> Vec<(String, String, Vec<V>)> {
    doc["surfaces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let v = s["vertices"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| serde_json::from_value::<V>(p.clone()).unwrap())
                .collect();
            (
                s["name"].as_str().unwrap().to_string(),
                s["kind"].as_str().unwrap_or("reflector").to_string(),
                v,
            )
        })
        .collect()
}

#[test]
fn extraction_recovers_the_living_room_and_its_paths() {
    let cloud = tmp("living-room.ply");
    let scene = tmp("extracted.json");
    beamtrace(&[
        "sample",
        "builtin:living-room",
        "-o",
        cloud.to_str().unwrap(),
        "--density",
        "2000",
        "--noise",
        "0.005",
        "--seed",
        "3",
    ]);
    beamtrace(&[
        "extract",
        cloud.to_str().unwrap(),
        "-o",
        scene.to_str().unwrap(),
        "--seed",
        "1",
    ]);

    let original: Value =
        serde_json::from_str(bt_scene::builtin_json("living-room").unwrap()).unwrap();
    let extracted: Value = serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    let found = polygons(&extracted);
    let mut failures = Vec::new();
    // Every reflector of the original scene comes back: normal within 1°, offset within 2 cm,
    // area within 5 %, as a reflector.
    for (name, kind, verts) in polygons(&original) {
        if kind == "blocker" {
            continue;
        }
        let (n, area, c) = plane_of(&verts);
        let best = found
            .iter()
            .map(|(fname, fkind, fv)| {
                let (m, farea, fc) = plane_of(fv);
                let angle = dot(n, m).abs().min(1.0).acos().to_degrees();
                let offset = dot(m, sub(c, fc)).abs();
                (
                    angle,
                    offset,
                    (farea - area).abs() / area,
                    norm(sub(c, fc)),
                    fname.clone(),
                    fkind.clone(),
                )
            })
            .filter(|t| t.0 < 5.0 && t.1 < 0.1)
            .min_by(|a, b| a.3.total_cmp(&b.3))
            .unwrap_or_else(|| panic!("{name}: no extracted plane"));
        if !(best.0 < 1.0 && best.1 < 0.02 && best.2 < 0.05 && best.5 == "reflector") {
            failures.push(format!(
                "{name}: normal {:.3}°, offset {:.4} m, area {:.1} % ({} {})",
                best.0,
                best.1,
                best.2 * 100.0,
                best.4,
                best.5
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of 25 planes not recovered:\n{}",
        failures.len(),
        failures.join("\n")
    );

    // Tracing the extracted scene gives the same paths: same count per order, lengths within
    // 1 cm, departure directions within 1°.
    let trace = |s: &str| -> Vec<Value> {
        let o = beamtrace(&[
            "trace",
            s,
            "--tx",
            "5.6,0.6,2.2",
            "--rx",
            "2.3,2.1,0.72",
            "--json",
        ]);
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        v["paths"].as_array().unwrap().clone()
    };
    let a = trace("builtin:living-room");
    let b = trace(scene.to_str().unwrap());
    assert_eq!(a.len(), b.len());
    let mut used = vec![false; b.len()];
    for p in &a {
        let (k, q) = b
            .iter()
            .enumerate()
            .filter(|(k, q)| !used[*k] && q["order"] == p["order"])
            .min_by(|x, y| {
                let d = |q: &Value| {
                    (q["length_m"].as_f64().unwrap() - p["length_m"].as_f64().unwrap()).abs()
                };
                d(x.1).total_cmp(&d(y.1))
            })
            .expect("a path of the same order");
        used[k] = true;
        let dl = (q["length_m"].as_f64().unwrap() - p["length_m"].as_f64().unwrap()).abs();
        assert!(dl < 0.01, "{:?}: length differs by {dl} m", p["surfaces"]);
        let daz = (q["aod_deg"]["azimuth"].as_f64().unwrap()
            - p["aod_deg"]["azimuth"].as_f64().unwrap())
        .abs();
        let del = (q["aod_deg"]["elevation"].as_f64().unwrap()
            - p["aod_deg"]["elevation"].as_f64().unwrap())
        .abs();
        assert!(
            daz.min(360.0 - daz) < 1.0 && del < 1.0,
            "{:?}: AoD differs by {daz}°, {del}°",
            p["surfaces"]
        );
    }
    std::fs::remove_dir_all(cloud.parent().unwrap()).ok();
}

#[test]
fn a_point_cloud_traces_directly_and_bad_clouds_are_reported() {
    let cloud = tmp("box.pcd");
    beamtrace(&[
        "sample",
        &format!(
            "{}/../../testdata/scenes/one-wall.json",
            env!("CARGO_MANIFEST_DIR")
        ),
        "-o",
        cloud.to_str().unwrap(),
        "--density",
        "3000",
        "--noise",
        "0.002",
    ]);
    let o = beamtrace(&[
        "trace",
        cloud.to_str().unwrap(),
        "--tx",
        "-1.5,1,2",
        "--rx",
        "2,2,1",
        "--json",
    ]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        v["paths"].as_array().unwrap().len(),
        2,
        "line of sight and the wall reflection"
    );
    let truncated = tmp("truncated.pcd");
    let bytes = std::fs::read(&cloud).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).unwrap();
    let bad = Command::new(env!("CARGO_BIN_EXE_beamtrace"))
        .args([
            "extract",
            truncated.to_str().unwrap(),
            "-o",
            tmp("x.json").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let msg = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "{msg}");
    assert!(msg.contains("truncated.pcd"), "{msg}");
}
