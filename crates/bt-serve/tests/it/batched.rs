//! Consecutive receiver moves answered together over the cores give the very bytes that one
//! thread answering each request alone gives, in request order, whatever the mix of requests
//! around them (errors, lists, a moved TX, receivers left out, moved objects).

use crate::common::server;
use bt_serve::Limits;
use bt_solve::settings::SolveSettings;
use serde_json::json;

/// An answer line without what varies between runs (`latency_us`, `stats.time_s`).
fn steady(line: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(line).expect("an answer is JSON");
    let strip = |v: &mut serde_json::Value| {
        if let Some(stats) = v.get_mut("stats").and_then(|s| s.as_object_mut()) {
            stats.remove("time_s");
        }
    };
    v.as_object_mut().expect("an object").remove("latency_us");
    strip(&mut v);
    if let Some(results) = v.get_mut("results").and_then(|r| r.as_array_mut()) {
        results.iter_mut().for_each(strip);
    }
    v.to_string()
}

#[test]
fn a_stream_answered_in_batches_is_the_stream_answered_one_by_one() {
    let mut lines = Vec::new();
    for i in 0..40 {
        let x = 1.0 + 0.1 * f64::from(i);
        lines.push(json!({"id": i, "rx": [x, 1.5, 1.1]}).to_string());
        match i {
            5 => lines.push("not json".to_string()),
            9 => lines.push(json!({"id": "on", "rx": [3, 0, 1]}).to_string()),
            12 => lines
                .push(json!({"id": "list", "rx": [[1, 1, 1], [3, 0, 1], [2, 2, 1]]}).to_string()),
            17 => lines.push(json!({"id": "tx", "tx": [3, 3, 2]}).to_string()),
            21 => lines.push(json!({"id": "again"}).to_string()),
            26 => lines.push(json!({"id": "step", "step": 4}).to_string()),
            30 => lines.push(
                json!({"id": "person", "objects": {"person": {"offset": [0.5, 1.5, 0]}}})
                    .to_string(),
            ),
            _ => {}
        }
    }
    let input = lines.join("\n");
    let make = |parallel: bool| {
        let settings = SolveSettings {
            max_order: 2,
            parallel,
            ..SolveSettings::default()
        };
        server("builtin:living-room-dynamic", settings, Limits::default())
    };
    // The reference: one thread, each request answered alone by `answer_line` (no stream, so
    // no batch).
    let mut one = make(false);
    let mut out = Vec::new();
    let alone: Vec<String> = (lines.iter())
        .map(|line| {
            one.answer_line(line.as_bytes(), &mut out);
            steady(std::str::from_utf8(&out).expect("UTF-8"))
        })
        .collect();
    // The stream in parallel: the moves that wait in the input are answered together.
    let mut many = make(true);
    let mut out = Vec::new();
    many.serve(input.as_bytes(), &mut out).expect("stream runs");
    let text = String::from_utf8(out).expect("UTF-8");
    let batched: Vec<String> = text.lines().map(steady).collect();
    assert_eq!(alone.len(), lines.len());
    assert_eq!(batched.len(), lines.len());
    let errors = alone.iter().filter(|l| l.contains("\"error\"")).count();
    assert!((2..6).contains(&errors), "{errors} error lines");
    for (i, (a, b)) in alone.iter().zip(&batched).enumerate() {
        assert_eq!(a, b, "answer {i} (request {})", lines[i]);
    }
}

/// A server with a partner thread (half of each lone receiver's report and JSON on a second
/// core) answers a walk of single receivers, lists and a moved TX with the very bytes of a
/// server without one, each request answered alone.
#[test]
fn answers_split_over_a_partner_are_the_answers_of_one_thread() {
    let mut lines = Vec::new();
    for i in 0..60 {
        let x = 0.6 + 0.08 * f64::from(i);
        let y = 1.0 + 0.05 * f64::from(i % 17);
        lines.push(json!({"id": i, "rx": [x, y, 1.1]}).to_string());
        match i {
            20 => lines.push(json!({"id": "list", "rx": [[1, 1, 1], [2, 2, 1]]}).to_string()),
            40 => lines.push(json!({"id": "tx", "tx": [3, 3, 2]}).to_string()),
            _ => {}
        }
    }
    let settings = SolveSettings {
        max_order: 3,
        ..SolveSettings::default()
    };
    let answers = |spin_us: u64| -> Vec<String> {
        let server = server("builtin:living-room", settings, Limits::default());
        let mut server = server.with_partner(std::time::Duration::from_micros(spin_us));
        let mut out = Vec::new();
        (lines.iter())
            .map(|line| {
                server.answer_line(line.as_bytes(), &mut out);
                steady(std::str::from_utf8(&out).expect("UTF-8"))
            })
            .collect()
    };
    let (alone, split) = (answers(0), answers(5_000));
    let paths = |l: &String| l.matches("\"rank\"").count();
    assert!(
        alone.iter().filter(|l| paths(l) >= 16).count() > 50,
        "answers with paths to split"
    );
    for (i, (a, b)) in alone.iter().zip(&split).enumerate() {
        assert_eq!(a, b, "answer {i} (request {})", lines[i]);
    }
}
