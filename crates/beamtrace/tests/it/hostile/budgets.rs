//! Every unbounded quantity has a budget, checked before the work, named in the error with the
//! option that raises it. Runs are held under an address-space limit (`MEMORY_LIMIT_BYTES`):
//! on main these cases allocated 8 GB to 10 TB.

use super::*;

#[test]
fn wvrn_at_order_50_stops_at_the_candidate_budget() {
    let r = beamtrace(&["wvrn", "builtin:living-room", "--max-order", "50"]);
    assert_refused(
        &r,
        &["candidate budget exceeded", "order 50", "--max-candidates"],
    );
}

#[test]
fn wvrn_at_order_10_is_held_by_the_budget_under_a_memory_limit() {
    let r = beamtrace(&["wvrn", "builtin:living-room", "--max-order", "10"]);
    assert_refused(&r, &["candidate budget exceeded", "--max-candidates"]);
}

#[test]
fn dynamic_steps_respect_the_candidate_budget() {
    let r = beamtrace(&cli(
        "trace builtin:living-room-dynamic --steps --max-order 40",
        &[],
    ));
    assert_refused(&r, &["candidate budget exceeded", "--max-candidates"]);
}

#[test]
fn hls_and_study_respect_the_candidate_budget() {
    let out = scratch("budget-hls").join("a");
    assert_line_refused_writing_nothing(
        "hls gen builtin:living-room --max-order 30 -o {}",
        &out,
        &["candidate budget exceeded", "--max-candidates"],
    );
    assert_line_refused_writing_nothing(
        "study living-room --max-order 3 --max-candidates 100 --out {}",
        &out,
        &["candidate budget exceeded", "budget 100"],
    );
    // The 2-D study accepted --max-candidates and ignored it.
    assert_line_refused_writing_nothing(
        "study 2d --rooms 1 --steps 1 --max-candidates 3 --out {}",
        &out,
        &["room-0-step-0", "--max-candidates"],
    );
}

#[test]
fn sbr_grids_beyond_the_ray_budget_are_refused_not_answered_with_zero_paths() {
    let wall = one_wall();
    for step in ["1e-20", "1e-5"] {
        let r = beamtrace(&cli(
            "trace {} --solver sbr --sbr-step-deg {}",
            &[&wall, step],
        ));
        assert_refused(&r, &["sbr ray budget exceeded", "--max-rays"]);
    }
    let r = beamtrace(&cli(
        "trace {} --solver sbr --sbr-rays 1000000000",
        &[&wall],
    ));
    assert_refused(&r, &["1.000e9 rays", "--max-rays"]);
    // Within the budget SBR still finds the wall's reflection.
    let r = beamtrace(&cli("trace {} --solver sbr --json", &[&wall]));
    assert_ok(&r);
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert!(v["stats"]["valid_paths"].as_u64().unwrap() >= 2, "{v}");
}

#[test]
fn sampling_beyond_the_point_budget_is_refused_before_allocating() {
    let out = scratch("budget-sample").join("c.ply");
    assert_line_refused_writing_nothing(
        "sample builtin:living-room --density 1e12 -o {}",
        &out,
        &["point budget exceeded", "--max-points"],
    );
}

#[test]
fn a_polygon_with_too_many_vertices_is_refused_not_checked_for_minutes() {
    let dir = scratch("budget-vertices");
    let n = 20_001;
    let vertices: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            [5.0 * a.cos(), 5.0 * a.sin(), 0.0]
        })
        .collect();
    let desc = serde_json::json!({
        "tx": [0, 0, 1], "rx": [1, 0, 2],
        "surfaces": [{ "name": "disc", "vertices": vertices }]
    });
    let scene = scene_with(&dir, "disc.json", &desc.to_string());
    let r = beamtrace(&["scene", "check", &scene]);
    assert_refused(&r, &["20001 vertices", "10000"]);
}

#[test]
fn meshes_beyond_the_element_budget_stop_early_naming_count_budget_and_option() {
    let dir = scratch("mesh-budget");
    // A triangulated cube: 8 vertices, 12 faces, as OBJ and as ASCII PLY.
    let corners: Vec<[u8; 3]> = (0..8u8)
        .map(|v| [v & 1, (v >> 1) & 1, (v >> 2) & 1])
        .collect();
    let triangles: Vec<[usize; 3]> = CUBE_QUADS
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let mut obj = String::new();
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        triangles.len()
    );
    for c in &corners {
        obj.push_str(&format!("v {} {} {}\n", c[0], c[1], c[2]));
        ply.push_str(&format!("{} {} {}\n", c[0], c[1], c[2]));
    }
    for t in &triangles {
        obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        ply.push_str(&format!("3 {} {} {}\n", t[0], t[1], t[2]));
    }
    let obj = scene_with(&dir, "cube.obj", &obj);
    let ply = scene_with(&dir, "cube.ply", &ply);
    let check_line = "scene check {} --max-mesh-elements {} --tx 2,2,2 --rx 3,2,2";
    for (file, budget, needle) in [
        (
            &obj,
            "5",
            "at least 6 (line 6) vertices, more than the budget of 5 vertices",
        ),
        (
            &obj,
            "10",
            "at least 11 (line 19) faces, more than the budget of 10 faces",
        ),
        (&ply, "10", "12 faces, more than the budget of 10 faces"),
        (&ply, "7", "8 vertices, more than the budget of 7 vertices"),
    ] {
        let check = cli(check_line, &[file.as_str(), budget]);
        assert_refused(&beamtrace(&check), &[needle, "--max-mesh-elements"]);
    }
    for file in [&obj, &ply] {
        assert_ok(&beamtrace(&cli(check_line, &[file.as_str(), "12"])));
    }
}

#[test]
fn saturated_estimates_print_as_a_bound_not_as_u64_max() {
    let dir = scratch("saturated");
    // Candidates: 25 reflectors at order 50 overflow u64.
    let wvrn = beamtrace(&["wvrn", "builtin:living-room", "--max-order", "50"]);
    // Grid: 1e600 points per axis.
    let out = dir.join("sweep");
    let grid = "0:1e300:1e-300,0:1e300:1e-300,1";
    let sweep = beamtrace(&cli(
        "sweep builtin:living-room --grid {} --out {}",
        &[grid, out.to_str().unwrap()],
    ));
    // PLY: a vertex count whose byte size overflows u64.
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n\
                  property float x\nproperty float y\nproperty float z\nelement face 1\n\
                  property list uchar int vertex_indices\nend_header\n";
    let ply = scene_with(&dir, "huge.ply", &format!("{header}{}", "\0".repeat(64)));
    let mesh = beamtrace(&["scene", "check", &ply, "--tx", "1,1,1", "--rx", "2,2,2"]);
    for (r, needle) in [
        (wvrn, "more than 1.8e19 candidates at order 50"),
        (sweep, "grid has more than 1.8e19 points"),
        (mesh, "which need more than 1.8e19 bytes"),
    ] {
        assert_refused(&r, &[needle]);
        // the PLY's own count is what the file says; no estimate may print as u64::MAX
        let estimates = text(&r).replace("vertex\" claims 18446744073709551615", "");
        assert!(!estimates.contains("18446744073709551615"), "{}", text(&r));
    }
}

#[test]
fn point_clouds_beyond_the_point_budget_stop_before_reading() {
    let dir = scratch("cloud-budget");
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float y\n\
         property float z\nend_header\n",
    );
    for i in 0..100 {
        ply.push_str(&format!("{} {} 0\n", i % 10, i / 10));
    }
    let pcd_header = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
                      WIDTH 100\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100\nDATA ascii\n";
    let body: String = ply.lines().skip(7).map(|l| format!("{l}\n")).collect();
    let ply = scene_with(&dir, "cloud.ply", &ply);
    let pcd = scene_with(&dir, "cloud.pcd", &format!("{pcd_header}{body}"));
    let out = dir.join("x.json");
    for file in [&ply, &pcd] {
        let needle = "declares 100 points, more than the budget of 50 points";
        let trace = ["trace", file.as_str(), "--tx", "1,1,1", "--rx", "2,2,2"];
        let r = beamtrace(&[&trace[..], &["--max-cloud-points", "50"]].concat());
        assert_refused(&r, &[needle, "--max-cloud-points"]);
        let extract = ["extract", file.as_str(), "-o", out.to_str().unwrap()];
        let r = beamtrace(&[&extract[..], &["--max-cloud-points", "50"]].concat());
        assert_refused(&r, &[needle, "--max-cloud-points"]);
        // at the budget: read (the extraction may then find what it finds)
        let r = beamtrace(&[&extract[..], &["--max-cloud-points", "100"]].concat());
        assert_ok(&r);
        assert!(!text(&r).contains("more than the budget"), "{}", text(&r));
    }
}
