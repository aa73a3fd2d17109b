//! The radio channel from the command line: gains in `trace --json`, `channel` (CIR, CFR,
//! power-delay profile), `beams` (codebook sweep), material and frequency overrides, and clear
//! errors on bad input.

use crate::common::*;
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().expect("a number")
}

#[test]
fn trace_json_reports_gains_and_received_power() {
    let doc = run_json(&cli(
        "trace builtin:living-room --json --tx-power-dbm 23",
        &[],
    ));
    let paths = doc["paths"].as_array().unwrap();
    let mut sum = 0.0;
    for p in paths {
        let (re, im) = (f(&p["gain"][0]), f(&p["gain"][1]));
        let db = 10.0 * (re * re + im * im).log10();
        assert!((f(&p["gain_db"]) - db).abs() < 1e-9);
        assert!((f(&p["power_dbm"]) - db - 23.0).abs() < 1e-9);
        sum += re * re + im * im;
        // Vertical isotropic antennas and line of sight: exactly Friis, real and positive.
        if p["order"] == 0 {
            assert!(
                (f(&p["gain_db"]) + f(&p["free_space_loss_db"])).abs() < 1e-9
                    && im == 0.0
                    && re > 0.0
            );
        }
    }
    let total = f(&doc["stats"]["received_power_dbm"]);
    assert!((total - (23.0 + 10.0 * sum.log10())).abs() < 1e-9);
    assert_eq!(doc["radio"]["tx_power_dbm"], 23.0);
}

#[test]
fn a_perfect_conductor_mesh_keeps_every_reflection_at_full_strength() {
    let mesh = repo()
        .join("testdata/scenes/box-room.obj")
        .display()
        .to_string();
    let doc = run_json(&cli(
        "trace {} --tx 1,1,1.5 --rx 4,3,1.2 --max-order 2 --json \
         --material custom:1,1e12 --frequency 5e9",
        &[&mesh],
    ));
    assert_eq!(doc["frequency_hz"], 5e9);
    let paths = doc["paths"].as_array().unwrap();
    assert!(paths.len() > 10);
    for p in paths {
        // |R_TE| = |R_TM| = 1 − O(1/√|η|) ≈ 1 − 5e-7: only the spreading loss remains,
        // whatever the polarisation mix.
        assert!(
            (f(&p["gain_db"]) + f(&p["free_space_loss_db"])).abs() < 1e-4,
            "{}",
            p["surfaces"]
        );
    }
    let fails = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["trace", mesh.as_str(), "--tx", "1,1,1.5", "--rx", "4,3,1.2"];
        args.extend_from_slice(extra);
        assert_clear_error(&args, needles);
    };
    // ITU brick is not defined at 60 GHz: a clear error naming it.
    fails(
        &["--material", "itu:brick", "--frequency", "60e9"],
        &["brick", "1–40 GHz", "60"],
    );
    fails(
        &["--material", "itu:marmalade"],
        &["unknown ITU material \"marmalade\""],
    );
    fails(
        &["--material", "itu:wood", "--thickness", "-1"],
        &["thickness"],
    );
}

/// The data rows of a CSV text (header skipped), split at commas.
fn csv_rows(text: &str) -> Vec<Vec<&str>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect()
}

#[test]
fn channel_writes_cir_cfr_and_the_pdp_plot() {
    let dir = scratch("channel-outputs");
    let cir = dir.join("cir.csv");
    let cfr = dir.join("cfr.csv");
    let pdp = dir.join("pdp");
    // `channel` writing both CSV files; the number of subcarriers and more follow.
    let (cir_arg, cfr_arg) = (cir.to_str().unwrap(), cfr.to_str().unwrap());
    let both = [
        "channel",
        "builtin:living-room",
        "--out",
        cir_arg,
        "--cfr",
        cfr_arg,
        "--subcarriers",
    ];
    let pdp_arg = pdp.to_str().unwrap();
    let o = run_ok(
        &[
            &both[..],
            &["16", "--subcarrier-spacing", "1e6", "--pdp", pdp_arg],
            &["--max-order", "2"],
        ]
        .concat(),
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("received power"));
    let trace = run_json(&["trace", "builtin:living-room", "--max-order", "2", "--json"]);
    let n_paths = trace["paths"].as_array().unwrap().len();
    let text = std::fs::read_to_string(&cir).unwrap();
    let rows = csv_rows(&text);
    assert_eq!(rows.len(), n_paths);
    let delays: Vec<f64> = rows.iter().map(|r| r[2].parse().unwrap()).collect();
    assert!(
        delays.windows(2).all(|w| w[0] <= w[1]),
        "taps sorted by delay"
    );
    // The response at the carrier is the sum of the baseband taps (columns 7 and 8).
    let (mut re, mut im) = (0.0, 0.0);
    for r in &rows {
        re += r[7].parse::<f64>().unwrap();
        im += r[8].parse::<f64>().unwrap();
    }
    let cfr_text = std::fs::read_to_string(&cfr).unwrap();
    let cfr_rows = csv_rows(&cfr_text);
    assert_eq!(cfr_rows.len(), 16);
    let centre = &cfr_rows[8];
    assert_eq!(centre[1], "0");
    let (h_re, h_im): (f64, f64) = (centre[3].parse().unwrap(), centre[4].parse().unwrap());
    assert!((h_re - re).abs() < 1e-12 && (h_im - im).abs() < 1e-12);
    for ext in ["svg", "png"] {
        let meta = std::fs::metadata(pdp.with_extension(ext)).unwrap();
        assert!(meta.len() > 1000);
    }
    let svg = std::fs::read_to_string(pdp.with_extension("svg")).unwrap();
    assert!(svg.contains("delay (ns)") && svg.contains("line of sight"));
    // No temporary files are left behind.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 4);
    assert_clear_error(&[&both[..], &["0"]].concat(), &["--subcarriers"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn beams_finds_the_best_pair_and_keeps_the_paper_ranking() {
    let sweep = |extra: &[&str]| {
        let mut args = cli(
            "beams builtin:living-room --tx-array 1x8 --rx-array 1x8 \
             --tx-orientation 180,0,0 --json --max-order 2",
            &[],
        );
        args.extend_from_slice(extra);
        run_json(&args)
    };
    let power = sweep(&[]);
    let pairs = power["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 64);
    let p = |v: &Value| v["power_dbm"].as_f64().unwrap_or(f64::NEG_INFINITY);
    assert!(pairs.windows(2).all(|w| p(&w[0]) >= p(&w[1])));
    let paper = sweep(&["--ranking", "paper"]);
    let first = &paper["pairs"][0];
    assert_eq!(first["path_rank"], 1);
    // Every pair the paper ranking picks is in the power list with the same power.
    for q in paper["pairs"].as_array().unwrap() {
        let same = pairs
            .iter()
            .find(|x| x["tx_beam"] == q["tx_beam"] && x["rx_beam"] == q["rx_beam"])
            .unwrap();
        assert_eq!(same["power_dbm"], q["power_dbm"]);
    }
    let table =
        String::from_utf8_lossy(&run_ok(&["beams", "builtin:living-room", "--top", "3"]).stdout)
            .into_owned();
    assert!(table.contains("best pair (strongest received power): tx beam"));
    // The paper ranking says what it ranks by, and a beam without a main lobe is explained.
    let paper_table = stdout(&run_ok(&[
        "beams",
        "builtin:living-room",
        "--ranking",
        "paper",
    ]));
    assert!(paper_table.contains("first pair (paper ranking: the pair for the best-ranked path"));
    let upa = stdout(&run_ok(&[
        "beams",
        "builtin:living-room",
        "--rx-array",
        "2x4",
        "--top",
        "64",
    ]));
    assert!(
        upa.contains("no direction") && upa.contains("outside the visible region"),
        "{upa}"
    );
    assert_clear_error(
        &["beams", "builtin:living-room", "--tx-array", "8"],
        &["ROWSxCOLUMNS"],
    );
    assert_clear_error(
        &["beams", "builtin:living-room", "--rx-spacing", "0"],
        &["spacing"],
    );
}

#[test]
fn near_field_is_clamped_and_warned() {
    let o = run_ok(&cli(
        "trace builtin:living-room --tx 3,2,1 --rx 3.0005,2,1 --max-order 0 --json",
        &[],
    ));
    let doc: Value = serde_json::from_slice(&o.stdout).unwrap();
    let los = &doc["paths"][0];
    assert!(f(&los["free_space_loss_db"]) >= 0.0 && f(&los["gain_db"]) <= 0.0);
    assert!(String::from_utf8_lossy(&o.stderr).contains("near field"));
}

/// `--frequency` and `--material` reach every step of a dynamic scene (they load through the
/// same `bt_import::load_dynamic` as every source); a material the table does not define at the
/// carrier is still refused, naming it.
#[test]
fn overrides_apply_to_every_step_of_a_dynamic_scene() {
    let o = beamtrace(&cli(
        "trace builtin:living-room-dynamic --steps --max-order 1 --frequency 60e9 --json",
        &[],
    ));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(doc["frequency_hz"].as_f64(), Some(60e9));
    assert_eq!(doc["steps"].as_array().unwrap().len(), 10);
    assert_clear_error(
        &cli(
            "trace builtin:living-room-dynamic --steps --frequency 60e9 --material itu:brick",
            &[],
        ),
        &["brick"],
    );
}

/// In the shadow of Sionna's wedge only diffraction reaches RX: `trace`, `beams` and `channel`
/// take `--diffraction`, and the diffracted path is in the record, the sweep and the CIR.
#[test]
fn diffraction_reaches_the_shadow_in_trace_beams_and_channel() {
    let wedge = testdata("sionna-rt/simple_wedge/simple_wedge.xml");
    let at = ["--tx=-10,-20,2", "--rx", "20,5,1"];
    let with = |command: &str, extra: &[&str]| {
        let mut args = vec![command, wedge.as_str()];
        args.extend_from_slice(&at);
        args.extend_from_slice(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let json = with("trace", &["--json"]);
    let doc = run_json(&json.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(doc["paths"].as_array().unwrap().len(), 0, "RX is in shadow");
    let json = with("trace", &["--json", "--diffraction"]);
    let doc = run_json(&json.iter().map(String::as_str).collect::<Vec<_>>());
    let paths = doc["paths"].as_array().unwrap();
    assert_eq!(paths.len(), 1);
    assert_eq!(paths[0]["interactions"][0], "diffraction");
    assert_eq!(
        paths[0]["surfaces"][0],
        "mesh-wedge.face_0|mesh-wedge.face_1"
    );
    assert!(paths[0]["incidence_deg"][0].is_null());
    let beams = with("beams", &["--diffraction"]);
    let o = run_ok(&beams.iter().map(String::as_str).collect::<Vec<_>>());
    assert_stdout_has(&o, "best pair");
    let dir = scratch("diffraction-channel");
    let cir = dir.join("cir.csv");
    let channel = with(
        "channel",
        &["--diffraction", "--out", cir.to_str().unwrap()],
    );
    run_ok(&channel.iter().map(String::as_str).collect::<Vec<_>>());
    let text = std::fs::read_to_string(&cir).unwrap();
    assert!(
        text.contains("mesh-wedge.face_0|mesh-wedge.face_1"),
        "{text}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// `--diffraction-coefficient sionna-rt-2.2` changes a diffracted gain (Sionna 2.2's
/// combination of the UTD terms, docs/channel.md §8), keeps the geometry, and the trace
/// document records which coefficient it used; a bad value is an error naming the option.
#[test]
fn the_diffraction_coefficient_is_chosen_on_the_command_line() {
    let wedge = repo()
        .join("testdata/scenes/sionna-rt/simple_wedge/simple_wedge.xml")
        .display()
        .to_string();
    let line = "trace {} --tx 10,5,1 --rx -5,-10,1 --diffraction --max-order 1 \
                --frequency 3.5e9 --json --diffraction-coefficient {}";
    let utd = run_json(&cli(line, &[&wedge, "utd"]));
    let sionna = run_json(&cli(line, &[&wedge, "sionna-rt-2.2"]));
    assert_eq!(utd["radio"]["diffraction_coefficient"], "utd");
    assert_eq!(sionna["radio"]["diffraction_coefficient"], "sionna-rt-2.2");
    let (a, b) = (&utd["paths"][0], &sionna["paths"][0]);
    assert_eq!(a["interactions"][0], "diffraction");
    assert_eq!(a["points"], b["points"]);
    assert!((f(&a["gain_db"]) - f(&b["gain_db"])).abs() > 0.5, "{a} {b}");
    assert_clear_error(
        &cli(line, &[&wedge, "sionna"]),
        &["--diffraction-coefficient", "sionna-rt-2.2"],
    );
}

/// `sionna-rt-2.2` reproduces Sionna RT 2.2's `PathSolver` with the trace's order as its
/// `max_depth`, and that solver lengthens the diffracted leg of a path that reflects after the
/// edge and has fewer interactions than `max_depth` (docs/channel.md, "Reflections after the
/// edge in Sionna RT 2.2"): in Sionna's street canyon the same [diffraction, reflection] path
/// is 2-9 dB weaker traced at order 3 than at order 2, as Sionna reports it, while `utd`'s gain
/// does not depend on the order.
#[test]
fn sionnas_coefficient_follows_the_trace_order_as_sionnas_depth() {
    let canyon = repo()
        .join("testdata/scenes/sionna-rt/simple_street_canyon/simple_street_canyon.xml")
        .display()
        .to_string();
    let line = "trace {} --tx=-45,0,10 --rx 30,0,1.5 --diffraction --max-order {} \
                --frequency 3.5e9 --min-reflector-area 0 --json --diffraction-coefficient {}";
    let gains = |order: &str, coefficient: &str| -> Vec<(String, f64)> {
        let doc = run_json(&cli(line, &[&canyon, order, coefficient]));
        (doc["paths"].as_array().unwrap().iter())
            .filter(|p| p["interactions"] == serde_json::json!(["diffraction", "reflection"]))
            .map(|p| (p["points"].to_string(), f(&p["gain_db"])))
            .collect()
    };
    let (utd2, utd3) = (gains("2", "utd"), gains("3", "utd"));
    let (sionna2, sionna3) = (gains("2", "sionna-rt-2.2"), gains("3", "sionna-rt-2.2"));
    assert!(!utd2.is_empty());
    assert_eq!(utd2, utd3);
    assert_eq!(sionna2.len(), sionna3.len());
    for ((points2, at2), (points3, at3)) in sionna2.iter().zip(&sionna3) {
        assert_eq!(points2, points3);
        assert!(
            at2 - at3 > 2.0 && at2 - at3 < 9.0,
            "{points2}: {at2} at order 2, {at3} at 3"
        );
    }
}
