//! Point cloud to scene, end to end through the CLI: sample the built-in living room into a
//! noisy cloud (5 mm), extract its planes, and compare with the original surfaces and paths.

use crate::common::*;
use bt_geom::{Vec3, poly2};
use serde_json::Value;

/// (unit normal, area, centroid) of a planar polygon: Newell's area vector, the vertex mean.
fn plane_of(vertices: &[Vec3]) -> (Vec3, f64, Vec3) {
    let s = poly2::newell(vertices);
    let c = vertices.iter().copied().sum::<Vec3>() / vertices.len() as f64;
    (s.normalize(), s.length() / 2.0, c)
}

fn polygons(doc: &Value) -> Vec<(String, String, Vec<Vec3>)> {
    doc["surfaces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let v = s["vertices"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| Vec3::from_array(serde_json::from_value(p.clone()).unwrap()))
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
    let dir = scratch("pointcloud-extract");
    let (cloud, scene) = (dir.join("living-room.ply"), dir.join("extracted.json"));
    let c = cloud.to_str().unwrap();
    run_ok(&cli(
        "sample builtin:living-room -o {} --density 2000 --noise 0.005 --seed 3",
        &[c],
    ));
    run_ok(&cli(
        "extract {} -o {} --seed 1",
        &[c, scene.to_str().unwrap()],
    ));

    let original: Value =
        serde_json::from_str(bt_import::builtin_json("living-room").unwrap()).unwrap();
    let extracted = read_json(&scene);
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
                let angle = n.dot(m).abs().min(1.0).acos().to_degrees();
                let offset = m.dot(c - fc).abs();
                (
                    angle,
                    offset,
                    (farea - area).abs() / area,
                    (c - fc).length(),
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
        let v = run_json(&cli(
            "trace {} --tx 5.6,0.6,2.2 --rx 2.3,2.1,0.72 --json",
            &[s],
        ));
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
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_point_cloud_traces_directly_and_bad_clouds_are_reported() {
    let dir = scratch("pointcloud-trace");
    let cloud = dir.join("box.pcd");
    let c = cloud.to_str().unwrap();
    run_ok(&cli(
        "sample {} -o {} --density 3000 --noise 0.002",
        &[&testdata("one-wall.json"), c],
    ));
    let v = run_json(&cli("trace {} --tx -1.5,1,2 --rx 2,2,1 --json", &[c]));
    assert_eq!(
        v["paths"].as_array().unwrap().len(),
        2,
        "line of sight and the wall reflection"
    );
    let truncated = dir.join("truncated.pcd");
    let bytes = std::fs::read(&cloud).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).unwrap();
    let bad = beamtrace(&cli(
        "extract {} -o {}",
        &[
            truncated.to_str().unwrap(),
            dir.join("x.json").to_str().unwrap(),
        ],
    ));
    let msg = stderr(&bad);
    assert_eq!(bad.status.code(), Some(2), "{msg}");
    assert!(msg.contains("truncated.pcd"), "{msg}");
    std::fs::remove_dir_all(dir).ok();
}
