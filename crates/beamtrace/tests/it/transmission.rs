//! `--transmission` and a material's `"transmission": true` from the CLI: the golden document
//! of the two-room example, the table's `through "NAME"`, every front end showing crossings,
//! and the refusals (SBR, a half-space with the key).

use crate::common::*;
use serde_json::Value;

const TWO_ROOMS: &str = "examples/two-rooms.json";

fn example() -> String {
    repo().join(TWO_ROOMS).display().to_string()
}

/// The crossings of each path of a trace document: (interactions, surfaces) where any
/// interaction is a transmission.
fn crossing_paths(doc: &Value) -> Vec<(Vec<String>, Vec<String>)> {
    kinds_and_surfaces(doc)
        .into_iter()
        .filter(|(kinds, _)| kinds.iter().any(|k| k == "transmission"))
        .collect()
}

#[test]
fn golden_json_of_the_two_rooms_with_transmission() {
    let mut doc = run_json(&["trace", &example(), "--transmission", "--json"]);
    doc["stats"].as_object_mut().unwrap().remove("time_s");
    assert_eq!(doc["transmission"], true);
    let text = serde_json::to_string_pretty(&doc).unwrap() + "\n";
    assert_golden(golden::dir().join("two-rooms-transmission.json"), text);
}

/// The partition (plasterboard) opens only with the switch; the curtain, whose material says
/// `"transmission": true`, either way; the concrete shell never (and the warning says so).
#[test]
fn the_switch_opens_slabs_and_the_key_its_material() {
    let through = crossing_paths(&run_json(&[
        "trace",
        &example(),
        "--transmission",
        "--json",
    ]));
    let crossed = |paths: &[(Vec<String>, Vec<String>)], name: &str| {
        paths.iter().any(|(kinds, names)| {
            kinds
                .iter()
                .zip(names)
                .any(|(k, n)| k == "transmission" && n == name)
        })
    };
    assert!(crossed(&through, "partition") && crossed(&through, "curtain"));
    let shell_crossed = through.iter().any(|(kinds, names)| {
        kinds
            .iter()
            .zip(names)
            .any(|(k, n)| k == "transmission" && n.starts_with("shell"))
    });
    assert!(
        !shell_crossed,
        "the concrete shell is a half-space: {through:?}"
    );
    let plain = crossing_paths(&run_json(&["trace", &example(), "--json"]));
    assert!(crossed(&plain, "curtain") && !crossed(&plain, "partition"));
    let out = run_ok(&["trace", &example(), "--transmission"]);
    assert!(
        stdout(&out).contains("through \"partition\""),
        "{}",
        stdout(&out)
    );
    assert!(
        stderr(&out).contains("\"concrete\" stay opaque"),
        "{}",
        stderr(&out)
    );
}

/// The shell is concrete, a half-space: a receiver outside gets nothing through it, until
/// `--thickness` makes every material a slab; then every path leaves through the shell.
#[test]
fn a_thickness_makes_a_half_space_a_slab() {
    let outside = ["trace", TWO_ROOMS, "--rx", "9,1,1.2", "--transmission"];
    let none = beamtrace_in_repo(&[&outside[..], &["--json"]].concat());
    assert_eq!(none["paths"].as_array().unwrap().len(), 0, "{none}");
    let slab = [
        &outside[..],
        &["--material", "itu:concrete", "--thickness", "0.1", "--json"],
    ]
    .concat();
    let doc = beamtrace_in_repo(&slab);
    let paths = doc["paths"].as_array().unwrap();
    assert!(!paths.is_empty());
    for p in paths {
        let last = p["surfaces"].as_array().unwrap().last().unwrap();
        assert_eq!(last, "shell.east", "{p}");
        assert_eq!(
            p["interactions"].as_array().unwrap().last().unwrap(),
            "transmission"
        );
    }
}

/// `--thickness` alone makes the half-space materials slabs and keeps the slabs' own
/// thicknesses: the document equals that of the same scene whose file gives its half-space
/// (the concrete shell) that thickness, and the shell now lets a receiver outside be reached.
#[test]
fn a_thickness_alone_makes_the_half_spaces_slabs() {
    let outside = ["--rx", "9,1,1.2", "--transmission", "--json"];
    let mut alone =
        beamtrace_in_repo(&[&["trace", TWO_ROOMS, "--thickness", "0.1"], &outside[..]].concat());
    let mut scene: Value =
        serde_json::from_str(&std::fs::read_to_string(example()).unwrap()).unwrap();
    // The built-in concrete (a 6 dB ITU concrete half-space), as a 0.1 m slab.
    scene["materials"]["concrete"] =
        serde_json::json!({ "itu": "concrete", "thickness": 0.1, "reflection_loss_db": 6.0 });
    let twin = scratch("thickness-twin").join("two-rooms.json");
    std::fs::write(&twin, serde_json::to_string(&scene).unwrap()).unwrap();
    let mut given = run_json(&[&["trace", twin.to_str().unwrap()], &outside[..]].concat());
    assert!(!alone["paths"].as_array().unwrap().is_empty(), "{alone}");
    for doc in [&mut alone, &mut given] {
        doc["stats"].as_object_mut().unwrap().remove("time_s");
        doc.as_object_mut().unwrap().remove("scene");
    }
    assert_eq!(alone, given);
    // The partition (12.5 mm plasterboard) kept its own thickness: with 0.1 m its loss differs.
    let thick = [
        &["trace", TWO_ROOMS, "--transmission", "--thickness", "0.1"],
        &["--json"][..],
    ]
    .concat();
    let plain = beamtrace_in_repo(&["trace", TWO_ROOMS, "--transmission", "--json"]);
    let with_thickness = beamtrace_in_repo(&thick);
    let losses = |doc: &Value| -> Vec<String> {
        (doc["paths"].as_array().unwrap().iter())
            .filter(|p| {
                p["surfaces"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|s| s == "partition")
            })
            .map(|p| p["transmission_loss_db"].to_string())
            .collect()
    };
    assert!(!losses(&plain).is_empty());
    assert_eq!(losses(&with_thickness), losses(&plain));
}

fn beamtrace_in_repo(args: &[&str]) -> Value {
    serde_json::from_slice(&run_ok_in(&repo(), args).stdout).expect("valid JSON")
}

#[test]
fn sweeps_channels_and_beams_see_the_crossings() {
    let dir = scratch("transmission-fronts");
    let out = dir.join("sweep");
    let grid = "4.5:7.5:1.5,0.5:1.5:1,1.2";
    run_ok(&[
        "sweep",
        &example(),
        "--grid",
        grid,
        "--transmission",
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.join("coverage.csv")).unwrap();
    assert!(csv.contains("through \"\"partition\"\""), "{csv}");
    let beams = run_json(&["beams", &example(), "--transmission", "--json"]);
    let opaque = run_json(&["beams", &example(), "--json"]);
    assert!(beams["paths"].as_u64().unwrap() > opaque["paths"].as_u64().unwrap());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn sbr_and_half_space_keys_are_refused_clearly() {
    assert_clear_error(
        &["trace", &example(), "--transmission", "--solver", "sbr"],
        &["--transmission", "sbr does not transmit"],
    );
    // The curtain's material opens it without the switch: SBR refuses the scene.
    assert_clear_error(
        &["trace", &example(), "--solver", "sbr"],
        &["SBR solver does not transmit", "curtain"],
    );
    let dir = scratch("transmission-key");
    let file = dir.join("bad.json");
    std::fs::write(
        &file,
        r#"{ "tx": [0, 0, 1], "rx": [3, 0, 1], "materials": { "m": { "itu": "wood", "transmission": true } },
             "surfaces": [ { "name": "s", "material": "m", "vertices": [[1, -1, 0], [1, 1, 0], [1, 1, 2]] } ] }"#,
    )
    .unwrap();
    assert_clear_error(
        &["trace", file.to_str().unwrap()],
        &["materials.m.transmission", "thickness"],
    );
    std::fs::remove_dir_all(dir).ok();
}
