//! Bad requests get an error line naming the problem, and the stream goes on.

use crate::common::{ask, error, server};
use bt_serve::Limits;
use bt_solve::settings::SolveSettings;
use serde_json::json;

/// Each bad line, then a good request: the bad one's error names `needle`, the good one is
/// answered (the stream went on), every answer on its own line in order.
#[test]
fn each_bad_request_gets_an_error_line_and_the_stream_goes_on() {
    let cases = [
        ("{\"id\": 1, \"rx\": [1, 2", "request: not valid JSON"),
        ("\u{1}\u{2}garbage", "request: not valid JSON"),
        ("[1, 2, 3]", "request: expected a JSON object"),
        (
            r#"{"id": 1, "receiver": [1, 1, 1]}"#,
            "receiver: unknown field",
        ),
        (r#"{"id": 1, "rx": "kitchen"}"#, "rx: expected [x, y, z] or"),
        (
            r#"{"id": 1, "rx": [1, 1]}"#,
            "rx: expected [x, y, z] (three numbers)",
        ),
        (
            r#"{"id": 1, "rx": [[1, 1, 1], [1, true, 1]]}"#,
            "rx[1]: expected [x, y, z]",
        ),
        (r#"{"id": 1, "tx": {"x": 1}}"#, "tx: expected [x, y, z]"),
        (
            r#"{"id": 1, "step": "next"}"#,
            "step: expected a step number",
        ),
        (
            r#"{"id": 1, "step": 1}"#,
            "step: is 1; the scene has 1 step(s)",
        ),
        (
            r#"{"id": 1, "objects": {"door": {}}}"#,
            "objects.door: no such object",
        ),
        // In the south wall (y = 0) and on the floor: on a surface.
        (
            r#"{"id": 1, "rx": [3, 0, 1]}"#,
            "rx: lies on surface \"wall-south\"",
        ),
        (
            r#"{"id": 1, "rx": [3, 2, 0]}"#,
            "rx: lies on surface \"floor\"",
        ),
        (
            r#"{"id": 1, "tx": [5.6, 0.6, 2.2], "rx": [5.6, 0.6, 2.2]}"#,
            "tx: tx and rx are at the same position",
        ),
        // Far outside the room: beyond what the scene's tolerance can resolve.
        (r#"{"id": 1, "rx": [1e9, 2, 1]}"#, "rx: "),
    ];
    let mut server = server(
        "builtin:living-room",
        SolveSettings::default(),
        Limits::default(),
    );
    let good = json!({"id": "good", "rx": [2.3, 2.1, 0.72]}).to_string();
    let mut lines = Vec::new();
    for (line, _) in &cases {
        lines.push(line.to_string());
        lines.push(good.clone());
    }
    let answers = ask(&mut server, &lines);
    assert_eq!(answers.len(), 2 * cases.len());
    for (i, (line, needle)) in cases.iter().enumerate() {
        let (bad, next) = (&answers[2 * i], &answers[2 * i + 1]);
        assert!(error(bad).contains(needle), "{line}: {bad}");
        let id = match needle.starts_with("request:") {
            true => json!(null),
            false => json!(1),
        };
        assert_eq!(bad["id"], id, "{line}: {bad}");
        assert_eq!(next["id"], "good", "after {line}");
        assert!(
            next["paths"].as_array().is_some_and(|p| !p.is_empty()),
            "after {line}: {next}"
        );
    }
}

#[test]
fn a_bad_receiver_in_a_list_fails_alone() {
    let mut server = server(
        "builtin:living-room",
        SolveSettings::default(),
        Limits::default(),
    );
    let line = json!({"id": 9, "rx": [[2.3, 2.1, 0.72], [3, 0, 1], [1, 1, 1]]}).to_string();
    let answers = ask(&mut server, &[line]);
    let results = answers[0]["results"].as_array().unwrap();
    assert_eq!(results.len(), 3);
    assert!(results[0]["paths"].is_array() && results[2]["paths"].is_array());
    assert_eq!(results[1]["rx"], json!([3.0, 0.0, 1.0]));
    let e = results[1]["error"].as_str().unwrap();
    assert!(
        e.starts_with("rx[1]: lies on surface \"wall-south\""),
        "{e}"
    );
}

#[test]
fn a_bad_first_receiver_does_not_stop_a_transmitter_move() {
    let mut server = server(
        "builtin:living-room",
        SolveSettings::default(),
        Limits::default(),
    );
    let lines = [
        json!({"id": 1, "tx": [3, 3, 2], "rx": [[3, 0, 1], [1, 1, 1]]}),
        json!({"id": 2, "tx": [3, 0, 2], "rx": [[1, 1, 1], [2, 2, 1]]}),
    ];
    let answers = ask(&mut server, &lines.map(|l| l.to_string()));
    let results = answers[0]["results"].as_array().unwrap();
    let e = results[0]["error"].as_str().unwrap();
    assert!(
        e.starts_with("rx[0]: lies on surface \"wall-south\""),
        "{e}"
    );
    assert_eq!(results[1]["tx"], json!([3.0, 3.0, 2.0]));
    assert!(
        results[1]["paths"]
            .as_array()
            .is_some_and(|p| !p.is_empty())
    );
    // A transmitter in a wall fails the whole request, naming it.
    let e = error(&answers[1]);
    assert!(e.starts_with("tx: lies on surface \"wall-south\""), "{e}");
}

#[test]
fn bad_poses_name_the_object_and_change_nothing() {
    let s = SolveSettings::default();
    let mut server = server("builtin:living-room-dynamic", s, Limits::default());
    let lines = [
        json!({"id": 1, "objects": {"person": {"angle_deg": 30}}}),
        json!({"id": 2, "objects": {"door": {"offset": [0, 0, 0], "spin": 1}}}),
        // The person walked onto the receiver: the scene refuses, naming the receiver.
        json!({"id": 3, "objects": {"person": {"offset": [-1.1, 1.3, 0]}}, "rx": [2.1, 2.0, 0.72]}),
        json!({"id": 4, "step": 10}),
        json!({"id": 5, "rx": [2.3, 2.1, 0.72]}),
        json!({"id": 6, "step": 0, "rx": [2.3, 2.1, 0.72]}),
    ];
    let answers = ask(&mut server, &lines.map(|l| l.to_string()));
    let has = |i: usize, needle: &str| {
        let e = error(&answers[i]);
        assert!(e.contains(needle), "answer {i}: {e}");
    };
    has(0, "objects.person.angle_deg: the object has no pivot");
    has(1, "objects.door: unknown field `spin`");
    has(2, "rx: lies on surface \"person.");
    has(3, "step: is 10; the scene has 10 step(s), 0 to 9");
    assert_eq!(
        answers[4]["paths"], answers[5]["paths"],
        "the refused moves changed nothing"
    );
}
