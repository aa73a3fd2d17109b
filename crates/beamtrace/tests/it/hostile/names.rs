//! Names are data: checked at load, escaped wherever printed.

use super::*;
use crate::common::stdout;

/// The issue's injection: a surface name that ends the Verilog comment and opens a module.
const INJECTION: &str = "wall\nmodule pwn; initial $display(\"pwned\"); endmodule\n//";

fn scene_named(dir: &std::path::Path, surface: &str, material: &str) -> String {
    let desc = serde_json::json!({
        "name": "named",
        "tx": [-1.5, 1, 2],
        "rx": [2, 2, 1],
        "materials": { material: { "reflection_loss_db": 3.0 } },
        "surfaces": [
            { "name": surface, "material": material,
              "vertices": [[-5, 0, 0], [5, 0, 0], [5, 0, 3], [-5, 0, 3]] }
        ]
    });
    scene_with(dir, "named.json", &desc.to_string())
}

#[test]
fn the_injection_name_is_refused_at_load_with_the_name_escaped() {
    let dir = scratch("inject");
    let scene = scene_named(&dir, INJECTION, "brick");
    let r = beamtrace(&["scene", "check", &scene]);
    assert_refused(&r, &["surfaces[0]", "U+000A", "wall\\nmodule pwn"]);
    assert!(
        !text(&r).contains("\nmodule pwn"),
        "raw name reached the terminal"
    );
    // Nor does it reach RTL: hls gen refuses the scene before writing anything.
    let out = dir.join("accel");
    assert_refused_writing_nothing(
        &[
            "hls",
            "gen",
            &scene,
            "--max-order",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
        &["U+000A"],
    );
}

#[test]
fn escape_sequences_and_nul_in_names_are_refused() {
    let dir = scratch("ansi");
    for (surface, material, code) in [
        ("wall\u{1b}[2J", "brick", "U+001B"),
        ("wall", "brick\u{1b}]0;title\u{7}", "U+001B"),
        ("wall\0", "brick", "U+0000"),
        ("wall\u{202e}llaw", "brick", "U+202E"),
    ] {
        let scene = scene_named(&dir, surface, material);
        for cmd in [
            &["scene", "check"][..],
            &["wvrn", "--dot"][..],
            &["trace"][..],
        ] {
            let mut args = cmd.to_vec();
            args.push(&scene);
            let r = beamtrace(&args);
            assert_refused(&r, &[code]);
            let t = text(&r);
            assert!(!t.contains('\u{1b}') && !t.contains('\0'), "{t:?}");
        }
    }
}

#[test]
fn overlong_names_are_refused() {
    let dir = scratch("long");
    let scene = scene_named(&dir, &"w".repeat(5000), "brick");
    assert_refused(
        &beamtrace(&["scene", "check", &scene]),
        &["5000 characters (at most 200)"],
    );
}

#[test]
fn printable_unicode_names_pass_and_print_as_themselves() {
    let dir = scratch("unicode");
    let scene = scene_named(&dir, "Wand \"Süd\" 壁", "Ziegel");
    let r = beamtrace(&["trace", &scene]);
    assert_ok(&r);
    assert!(text(&r).contains("Wand \\\"Süd\\\" 壁"), "{}", text(&r));
    let r = beamtrace(&["wvrn", "--dot", &scene]);
    assert_ok(&r);
    assert!(text(&r).contains("\"Wand \\\"Süd\\\" 壁\""), "{}", text(&r));
}

/// Round 2 (issue 27): surfaces named `TX` and `RX` stay apart from the terminals in
/// `wvrn --dot`: nodes are named by index and labelled with their names.
#[test]
fn surfaces_named_like_the_terminals_stay_apart_in_dot() {
    let dir = scratch("tx-named");
    let scene = scene_with(
        &dir,
        "scene.json",
        r#"{ "tx": [0, 0, 1], "rx": [3, 0, 1], "surfaces": [
            { "name": "TX", "vertices": [[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]] },
            { "name": "RX", "vertices": [[-5, 5, 0], [5, 5, 0], [5, 5, 3], [-5, 5, 3]] } ] }"#,
    );
    let r = beamtrace(&["wvrn", "--dot", &scene]);
    assert_ok(&r);
    let dot = text(&r);
    let declared = dot.lines().filter(|l| l.contains("[label=")).count();
    assert_eq!(declared, 4, "{dot}");
    assert_eq!(dot.matches("label=\"TX\"").count(), 2, "{dot}");
    std::fs::remove_dir_all(dir).ok();
}

/// Round 2 (issue 27): an OBJ `usemtl` name is held to the name rule: an escape sequence in it
/// is refused, escaped in the message, and never reaches the terminal raw.
#[test]
fn obj_material_names_follow_the_name_rule() {
    let dir = scratch("usemtl");
    let obj = scene_with(
        &dir,
        "room.obj",
        "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nusemtl evil\u{1b}[31mred\nf 1 2 3 4\n",
    );
    let r = beamtrace(&["trace", &obj, "--tx", "1,1,1", "--rx", "2,2,1"]);
    assert_refused(&r, &["room.obj", "material", "U+001B"]);
    assert!(!text(&r).contains('\u{1b}'), "{:?}", text(&r));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn long_duplicate_names_make_short_error_text() {
    let dir = scratch("long-duplicates");
    let name = "n".repeat(1024);
    let surfaces: Vec<serde_json::Value> = (0..10_000)
        .map(|i| {
            let x = f64::from(i) * 2.0;
            serde_json::json!({ "name": name, "vertices":
                [[x, 0, 0], [x + 1.0, 0, 0], [x + 1.0, 0, 1], [x, 0, 1]] })
        })
        .collect();
    let desc =
        serde_json::json!({ "tx": [0.5, 1, 0.5], "rx": [3.5, 1, 0.5], "surfaces": surfaces });
    let scene = scene_with(&dir, "long.json", &desc.to_string());
    let r = beamtrace(&["scene", "check", &scene]);
    assert_refused(&r, &["10000 problem(s)", "…(1024 bytes)", "and 9000 more"]);
    let t = text(&r);
    assert!(t.len() < 1 << 20, "{} bytes of error text", t.len());
    assert!(!t.contains(&"n".repeat(100)), "a name printed in full");
    // Names within the rule, all duplicates: cut too.
    let desc = desc.to_string().replace(&name, &"m".repeat(150));
    let scene = scene_with(&dir, "dup.json", &desc);
    let r = beamtrace(&["scene", "check", &scene]);
    assert_refused(&r, &["duplicate surface name", "…(150 bytes)"]);
    assert!(text(&r).len() < 1 << 20);
    std::fs::remove_dir_all(dir).ok();
}

/// A 10 kB value of an option clap refuses itself (a value enum, a value parser's error) is
/// cut in the message as names are: the option named, the value not echoed whole.
#[test]
fn long_option_values_make_short_error_text() {
    let long = "x".repeat(10_000);
    for flag in [
        "--diffraction-coefficient",
        "--solver",
        "--tx-pattern",
        "--tx",
    ] {
        let r = beamtrace(&["trace", "builtin:living-room", flag, &long]);
        assert_refused(&r, &[flag, "…(10000 bytes)"]);
        assert!(
            text(&r).len() < 2000,
            "{flag}: {} bytes of error text",
            text(&r).len()
        );
    }
}

/// Files whose names and header words carry an escape sequence (ESC, or the C1 CSI in XML,
/// where ESC is not a character), each with a word of the
/// message that must name the place: no run may print the escape character itself.
#[test]
fn escape_sequences_in_any_input_never_reach_the_terminal() {
    let dir = scratch("escapes-everywhere");
    let quad = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\n";
    let cases: [(&str, String, &str); 7] = [
        (
            "object.obj",
            format!("o evil\u{1b}[31m\n{quad}f 1 2 3 4\n"),
            "U+001B",
        ),
        (
            "group.obj",
            format!("{quad}g evil\u{1b}[31m\nf 1 2 3 4\n"),
            "U+001B",
        ),
        ("token.obj", "v 0 0 \u{1b}[31m\n".to_string(), "\\u{1b}"),
        (
            "type.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty flo\u{1b}[31mat x\nend_header\n"
                .to_string(),
            "\\u{1b}",
        ),
        (
            "field.pcd",
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F \u{1b}[31m\n".to_string(),
            "\\u{1b}",
        ),
        (
            "id.xml",
            "<scene version=\"2.1.0\"><shape type=\"ply\" id=\"evil\u{9b}31m\">\
             <string name=\"filename\" value=\"missing.ply\"/></shape></scene>"
                .to_string(),
            "\\u{9b}",
        ),
        (
            "usemtl.obj",
            format!("{quad}usemtl evil\u{1b}[31m\nf 1 2 3 4\n"),
            "U+001B",
        ),
    ];
    for (file, content, needle) in cases {
        let path = dir.join(file);
        std::fs::write(&path, content).unwrap();
        let r = beamtrace(&["scene", "check", path.to_str().unwrap()]);
        let t = text(&r);
        assert!(!t.contains(['\u{1b}', '\u{9b}']), "{file}: {t:?}");
        assert_refused(&r, &[needle]);
    }
}

#[test]
fn a_name_holding_the_path_separator_stays_one_name_in_csv_and_tables() {
    let dir = scratch("separator-name");
    let scene = scene_named(&dir, "a > b", "brick");
    let cir = dir.join("cir.csv");
    let r = beamtrace(&["channel", &scene, "--out", cir.to_str().unwrap()]);
    assert_ok(&r);
    let csv = std::fs::read_to_string(&cir).unwrap();
    assert!(csv.contains(",a \\> b\n"), "{csv}");
    let r = beamtrace(&["trace", &scene]);
    assert_ok(&r);
    assert!(stdout(&r).contains("a \\> b"), "{}", stdout(&r));
}
