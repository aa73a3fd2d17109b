//! Over-budget requests are refused with an error line, before any work, and the stream
//! goes on.

use crate::common::{ask, error, server};
use bt_serve::{Limits, MAX_LINE_BYTES};
use bt_solve::settings::SolveSettings;
use serde_json::json;

#[test]
fn a_line_over_the_budget_is_refused_and_skipped_to_its_end() {
    let mut server = server(
        "builtin:living-room",
        SolveSettings::default(),
        Limits::default(),
    );
    // A valid request padded with spaces past 1 MiB: refused for its length alone.
    let long = format!(
        "{{\"id\": 1, \"rx\": [2.3, 2.1, 0.72]{}}}",
        " ".repeat(MAX_LINE_BYTES)
    );
    let good = json!({"id": 2, "rx": [2.3, 2.1, 0.72]}).to_string();
    let answers = ask(&mut server, &[long.clone(), good]);
    assert_eq!(answers.len(), 2);
    let e = error(&answers[0]);
    let expected = format!(
        "request: the line has {} bytes, more than the budget of 1048576",
        long.len()
    );
    assert!(e.starts_with(&expected), "{e}");
    assert_eq!(answers[0]["id"], json!(null));
    assert_eq!(answers[1]["id"], 2);
    assert!(answers[1]["paths"].is_array());
}

#[test]
fn more_receivers_than_the_budget_are_refused() {
    let limits = Limits {
        max_receivers: 4,
        ..Limits::default()
    };
    let mut server = server("builtin:living-room", SolveSettings::default(), limits);
    let five = vec![[2.3, 2.1, 0.72]; 5];
    let lines = [
        json!({"id": 1, "rx": five}).to_string(),
        json!({"id": 2, "rx": &five[..4]}).to_string(),
    ];
    let answers = ask(&mut server, &lines);
    let e = error(&answers[0]);
    assert!(
        e.starts_with("rx: 5 receivers, more than the budget of 4 per request"),
        "{e}"
    );
    assert_eq!(answers[0]["id"], 1);
    assert_eq!(answers[1]["results"].as_array().map(Vec::len), Some(4));
}

#[test]
fn a_trace_over_the_candidate_budget_is_an_error_line() {
    let settings = SolveSettings {
        max_candidates: 10,
        ..SolveSettings::default()
    };
    let mut server = server("builtin:living-room", settings, Limits::default());
    let line = json!({"id": 1, "rx": [2.3, 2.1, 0.72]}).to_string();
    let answers = ask(&mut server, &[line.clone(), line]);
    for a in &answers {
        assert!(error(a).contains("--max-candidates"), "{a}");
    }
}
