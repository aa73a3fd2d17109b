//! Memory stays flat over a long stream: the live heap after a warm-up stream and after a
//! 25 times longer one differ by less than three answers' worth.
//!
//! Its own test binary (not a module of `tests/it`): the counting allocator sees every thread
//! of the process, so no other test may run beside it.

#[path = "support/counting.rs"]
mod counting;

use bt_serve::{Limits, Server};
use counting::LIVE;
use std::sync::atomic::Ordering;

#[global_allocator]
static ALLOCATOR: counting::Counting = counting::Counting;

/// Request `i` of a stream that does everything a client does: receiver moves, lists, a TX
/// moving back and forth, bad lines, a line over its budget.
fn request(i: usize) -> String {
    let (x, y) = counting::walk_xy(i);
    match i % 10 {
        3 => format!("{{\"id\": {i}, \"rx\": [[{x}, {y}, 1.1], [{y}, 2.0, 0.9]]}}"),
        5 => format!(
            "{{\"id\": {i}, \"tx\": [{}, 3.5, 2.0]}}",
            2.0 + (i % 20) as f64 / 10.0
        ),
        6 => format!("{{\"id\": {i}, \"tx\": [5.6, 0.6, 2.2], \"rx\": [{x}, {y}, 1.3]}}"),
        7 => format!("{{\"id\": {i}, \"rx\": [3, 0, 1]}}"),
        8 => format!("{{\"id\": {i}, \"rx\": [1, 2]}} not json"),
        9 => format!(
            "{{\"id\": {i}, \"rx\": [{x}, {y}, 1.0]}}{}",
            " ".repeat(5000)
        ),
        _ => counting::move_request(i),
    }
}

fn stream(server: &mut Server, range: std::ops::Range<usize>) -> (u64, usize) {
    let input: Vec<String> = range.map(request).collect();
    let mut output = std::io::sink();
    let summary = server
        .serve(input.join("\n").as_bytes(), &mut output)
        .unwrap();
    (summary.requests, input.len())
}

#[test]
fn memory_stays_flat_over_a_long_stream() {
    let limits = Limits {
        max_line_bytes: 4096,
        ..Limits::default()
    };
    let mut server = counting::living_room(2, limits);
    let (answered, sent) = stream(&mut server, 0..200);
    assert_eq!(answered as usize, sent);
    let warm = LIVE.load(Ordering::Relaxed);
    let (answered, sent) = stream(&mut server, 200..5200);
    assert_eq!(answered as usize, sent);
    let after = LIVE.load(Ordering::Relaxed);
    let growth = after - warm;
    // One answer of the living room at order 2 is ~15 KB; 5,000 requests kept would be tens
    // of MB. What is held between requests may still differ by a few answers' worth: each
    // pool thread keeps the records of the largest report it has made, and which thread
    // gets which receiver of a batch depends on the scheduling (up to 26 KB over 1,000
    // requests in 120 runs). Three answers' worth over 5,000 requests catches any leak of
    // 10 bytes a request or more.
    assert!(
        growth < 48 * 1024,
        "live heap grew by {growth} bytes over 5,000 requests ({warm} -> {after})"
    );
}
