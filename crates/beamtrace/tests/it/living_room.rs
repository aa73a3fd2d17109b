//! `beamtrace study living-room` and `beamtrace hls gen --steps` on a short version of the
//! built-in dynamic living room (the same room, person and door, fewer steps): the CSV is
//! consistent and the accuracy ordering of the paper holds (image exact, IPC ~1e-11°, the
//! fixed-point accelerator < 0.1°, SBR visibly worse), the figures exist, and every step gets
//! its own schedule (run on one platform) with a positive cycle count.

use crate::common::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The built-in dynamic living room cut to `steps` steps: the person walks as before, the door
/// opens by 10° per step.
fn short_living_room(dir: &Path, steps: usize) -> String {
    let source =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../bt-import/scenes/living-room-dynamic.json");
    let mut scene: Value =
        serde_json::from_str(&std::fs::read_to_string(source).expect("built-in scene")).unwrap();
    scene["steps"] = steps.into();
    scene["objects"]["door"]["keyframes"] = serde_json::json!([
        { "step": 0, "angle_deg": 0 },
        { "step": steps - 1, "angle_deg": 10 * (steps - 1) }
    ]);
    let path = dir.join(format!("living-room-{steps}-steps.json"));
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path.display().to_string()
}

#[test]
fn study_living_room_writes_consistent_csv_and_figures() {
    let dir = scratch("living-room-study");
    let scene = short_living_room(&dir, 2);
    let out = dir.join("out");
    // The short study into `out` (a fast SBR and order 2).
    let study = |out: &Path| {
        run_ok(&cli(
            "study living-room --out {} --steps-from {} --sbr-step-deg 5 --max-order 2",
            &[out.to_str().unwrap(), &scene],
        ))
    };
    let stdout = stdout(&study(&out));
    assert!(stdout.contains("FPGA IPC error"), "{stdout}");

    let csv = std::fs::read_to_string(out.join("results.csv")).expect("results.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 5, "{csv}");
    let mut by_solver: BTreeMap<&str, Vec<&Vec<&str>>> = BTreeMap::new();
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
        by_solver.entry(r[col("solver")]).or_default().push(r);
    }
    assert_eq!(
        by_solver.keys().copied().collect::<Vec<_>>(),
        [
            "image",
            "ipc-fixed-point",
            "ipc-gauss-seidel",
            "ipc-jacobi",
            "sbr"
        ]
    );
    let num = |r: &Vec<&str>, name: &str| -> f64 {
        let v: f64 = r[col(name)]
            .parse()
            .unwrap_or_else(|_| panic!("{name}: {r:?}"));
        assert!(v.is_finite() && v >= 0.0, "{name}: {r:?}");
        v
    };
    let int = |r: &Vec<&str>, name: &str| -> usize { r[col(name)].parse().expect(name) };
    for r in &rows {
        // Every number finite; counts add up.
        for name in [
            "mean_err_tx_deg",
            "max_err_tx_deg",
            "mean_err_rx_deg",
            "max_err_rx_deg",
            "time_s",
        ] {
            num(r, name);
        }
        assert!(
            num(r, "mean_err_tx_deg") <= num(r, "max_err_tx_deg"),
            "{r:?}"
        );
        assert_eq!(
            int(r, "matched") + int(r, "spurious"),
            int(r, "paths"),
            "{r:?}"
        );
        let step = r[col("step")];
        let image = by_solver["image"]
            .iter()
            .find(|i| i[col("step")] == step)
            .expect("image row");
        assert_eq!(
            int(r, "matched") + int(r, "missed"),
            int(image, "paths"),
            "{r:?}"
        );
        let has_fpga = !r[col("fpga_cycles")].is_empty();
        assert_eq!(has_fpga, r[col("solver")] == "ipc-fixed-point", "{r:?}");
        if has_fpga {
            assert!(int(r, "fpga_cycles") > 0, "{r:?}");
            let latency = num(r, "fpga_latency_s");
            assert!(
                (latency - int(r, "fpga_cycles") as f64 / 50e6).abs() <= 1e-12,
                "{r:?}"
            );
        }
    }
    let max_err = |solver: &str| {
        by_solver[solver]
            .iter()
            .map(|r| num(r, "max_err_tx_deg").max(num(r, "max_err_rx_deg")))
            .fold(0.0, f64::max)
    };
    let mean_err = |solver: &str| {
        by_solver[solver]
            .iter()
            .map(|r| num(r, "mean_err_tx_deg"))
            .sum::<f64>()
    };
    assert_eq!(max_err("image"), 0.0);
    assert!(max_err("ipc-gauss-seidel") < 1e-6, "{csv}");
    assert!(max_err("ipc-jacobi") < 1e-6, "{csv}");
    assert!(max_err("ipc-fixed-point") < 0.1, "{csv}");
    assert!(mean_err("sbr") > 0.0, "{csv}");
    assert!(mean_err("sbr") > mean_err("ipc-fixed-point"), "{csv}");
    for r in &by_solver["image"] {
        assert!(int(r, "paths") > 10, "{r:?}");
    }

    let fpga = std::fs::read_to_string(out.join("fpga.csv")).expect("fpga.csv");
    assert_eq!(fpga.lines().count(), 1 + 2, "{fpga}");
    // Per-step latency on the one platform, every exact path found (against the exhaustive
    // image method), and the second step warm-started from the first.
    let fpga_header: Vec<&str> = fpga.lines().next().unwrap().split(',').collect();
    let fcol = |name: &str| fpga_header.iter().position(|h| *h == name).expect(name);
    for (k, line) in fpga.lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let cycles: f64 = f[fcol("cycles")].parse().unwrap();
        let latency: f64 = f[fcol("latency_s")].parse().unwrap();
        assert!((latency - cycles / 50e6).abs() <= 1e-12, "{line}");
        assert_eq!(f[fcol("missed")], "0", "{line}");
        assert_eq!(f[fcol("spurious")], "0", "{line}");
        assert!(
            f[fcol("host_time_s")].parse::<f64>().unwrap() > 0.0,
            "{line}"
        );
        let warm: usize = f[fcol("warm_started")].parse().unwrap();
        assert_eq!(warm > 0, k > 0, "{line}");
    }
    let summary = std::fs::read_to_string(out.join("summary.md")).expect("summary.md");
    assert!(
        summary.contains("The paper's conclusions, measured"),
        "{summary}"
    );
    for stem in [
        "fig17-angular-error",
        "fig18-ray-directions",
        "fig19-run-time",
    ] {
        for ext in ["svg", "png"] {
            let f = out.join(format!("{stem}.{ext}"));
            let len = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
            assert!(len > 1000, "{} missing or empty", f.display());
        }
    }
    // Deterministic except the times: a second run gives the same errors and cycles.
    let out2 = dir.join("out2");
    study(&out2);
    let strip_times = |text: &str| -> Vec<String> {
        text.lines()
            .map(|l| {
                let mut f: Vec<&str> = l.split(',').collect();
                if f.len() == header.len() {
                    f[col("time_s")] = "";
                }
                f.join(",")
            })
            .collect()
    };
    let again = std::fs::read_to_string(out2.join("results.csv")).unwrap();
    assert_eq!(strip_times(&csv), strip_times(&again));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn hls_gen_steps_plans_every_step() {
    let dir = scratch("living-room-hls");
    let scene = short_living_room(&dir, 3);
    let out = dir.join("out");
    let stdout = stdout(&run_ok(&cli(
        "hls gen {} --steps --plan-only --max-order 2 -o {}",
        &[&scene, out.to_str().unwrap()],
    )));
    let doc = read_json(&out.join("steps.json"));
    let steps = doc["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), 3, "{doc}");
    assert_eq!(doc["cycles"].as_array().map(Vec::len), Some(3), "{doc}");
    assert_eq!(doc["rtl_written"], false);
    for (k, s) in steps.iter().enumerate() {
        assert_eq!(s["step"], k, "{s}");
        let cycles = s["predicted_cycles"].as_u64().expect("cycles");
        assert!(cycles > 0, "{s}");
        assert_eq!(doc["cycles"][k], cycles);
        assert!(fixed_point_tx_error_deg(s) < 0.1, "{s}");
        let step_dir = out.join(format!("step-{k}"));
        assert!(!out.join("rtl").exists());
        let own = read_json(&step_dir.join("summary.json"));
        assert_eq!(own["predicted_cycles"], cycles);
        assert!(own["host_time_s"].as_f64().unwrap() > 0.0, "{own}");
        assert!(own["latency_s_at_50mhz"].as_f64().unwrap() > 0.0, "{own}");
        assert!(own["fixed_vs_f64"]["missed"].is_u64(), "{own}");
        assert!(own["fixed_vs_f64"]["spurious"].is_u64(), "{own}");
        // The door moves: its candidates go to the host, and it is no platform plane.
        assert!(own["host_paths"].as_u64().unwrap() > 0, "{own}");
        assert_eq!(own["platform_instances"], doc["platform_instances"]);
        assert!(stdout.contains(&format!(" {cycles} ")), "{stdout}");
    }
    // The person and the door move: the candidate sets differ between steps.
    let all = |s: &Value| s["paths"].as_u64().unwrap() + s["host_paths"].as_u64().unwrap();
    assert_ne!(all(&steps[0]), all(&steps[2]), "{doc}");
    std::fs::remove_dir_all(&dir).ok();
}
