//! CLI integration tests of `beamtrace wvrn` and `beamtrace trace --steps`.

use crate::common::{cli, run_json, run_ok};
use std::collections::BTreeSet;

/// Standard output of a successful run.
fn beamtrace(args: &[&str]) -> String {
    String::from_utf8(run_ok(args).stdout).expect("utf-8 output")
}

/// Minimal DOT check: balanced braces, quoted node declarations, every edge between declared
/// nodes. Node names in our output are always quoted.
fn check_dot(dot: &str) -> (usize, usize) {
    let opens = dot.matches('{').count();
    assert_eq!(opens, dot.matches('}').count(), "unbalanced braces");
    assert!(dot.trim_start().starts_with("graph wvrn {") && dot.trim_end().ends_with('}'));
    let mut nodes = BTreeSet::new();
    let mut edges = 0;
    for line in dot.lines().map(str::trim) {
        if let Some((a, rest)) = line.split_once(" -- ") {
            let b = rest.split(" [").next().unwrap().trim_end_matches(';');
            assert!(nodes.contains(a), "edge from undeclared node {a}");
            assert!(nodes.contains(b), "edge to undeclared node {b}");
            edges += 1;
        } else if line.starts_with('"') {
            let name = line.split(" [").next().unwrap().trim_end_matches(';');
            assert!(name.ends_with('"'), "unquoted node {line}");
            nodes.insert(name.to_string());
        }
    }
    (nodes.len(), edges)
}

#[test]
fn wvrn_dot_and_json_describe_the_same_graph() {
    let dot = beamtrace(&cli("wvrn builtin:living-room-dynamic --step 3 --dot", &[]));
    let (nodes, edges) = check_dot(&dot);
    let json = run_json(&cli(
        "wvrn builtin:living-room-dynamic --step 3 --json",
        &[],
    ));
    assert_eq!(json["nodes"].as_array().unwrap().len(), nodes);
    assert_eq!(json["edges"].as_array().unwrap().len(), edges);
    assert!(dot.contains("color=red") && dot.contains("color=green"));
    // The person stands in the line of sight at step 3.
    let pruned = json["pruned"].as_array().unwrap();
    assert!(
        pruned
            .iter()
            .any(|p| p["a"] == 0 && p["b"] == 1 && p["reason"] == "occluded")
    );
    // Graphviz, when installed, must accept it.
    if let Ok(mut child) = std::process::Command::new("dot")
        .arg("-Tsvg")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
    {
        use std::io::Write;
        child
            .stdin
            .take()
            .unwrap()
            .write_all(dot.as_bytes())
            .unwrap();
        assert!(child.wait().unwrap().success(), "dot rejected the output");
    }
}

#[test]
fn trace_steps_json_and_jsonl() {
    // `trace --steps` of the dynamic living room at order 2, then `extra`.
    let trace = |extra: &[&str]| {
        let steps = [
            "trace",
            "builtin:living-room-dynamic",
            "--steps",
            "--max-order",
            "2",
        ];
        beamtrace(&[&steps[..], extra].concat())
    };
    let doc: serde_json::Value = serde_json::from_str(&trace(&["--json"])).unwrap();
    let steps = doc["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 10);
    for (k, s) in steps.iter().enumerate() {
        assert_eq!(s["step"], k);
        assert_eq!(
            s["stats"]["valid_paths"],
            s["paths"].as_array().unwrap().len()
        );
    }
    let los = |s: &serde_json::Value| {
        s["paths"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["order"] == 0)
    };
    assert!(los(&steps[0]) && !los(&steps[2]) && !los(&steps[3]) && los(&steps[4]));
    let lines = trace(&["--jsonl"]);
    let lines: Vec<serde_json::Value> = lines
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 10);
    // From scratch gives the same paths as the incremental default.
    let scratch: serde_json::Value =
        serde_json::from_str(&trace(&["--json", "--from-scratch"])).unwrap();
    for k in 0..10 {
        assert_eq!(scratch["steps"][k]["paths"], steps[k]["paths"], "step {k}");
    }
}

#[test]
fn wvrn_flag_changes_candidates_not_paths() {
    let on = run_json(&cli("trace builtin:living-room-dynamic --json", &[]));
    let off = run_json(&cli(
        "trace builtin:living-room-dynamic --json --no-wvrn",
        &[],
    ));
    assert_eq!(on["paths"], off["paths"]);
    assert_eq!(off["stats"]["candidates"]["pruned_visibility"], 0);
}
