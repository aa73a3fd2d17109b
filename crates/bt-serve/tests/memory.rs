//! Memory stays flat over a long stream: the live heap after a warm-up stream and after a
//! 25 times longer one differ by less than three answers' worth.
//!
//! Its own test binary (not a module of `tests/it`): the counting allocator sees every thread
//! of the process, so no other test may run beside it.

use bt_beams::RadioOptions;
use bt_serve::{Limits, Server};
use bt_solve::settings::SolveSettings;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};

/// The system allocator, counting the bytes live.
struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);

// SAFETY: every call is forwarded to the system allocator with the caller's arguments; the
// counter only adds and subtracts the sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        // SAFETY: the caller's layout, as `GlobalAlloc::alloc` requires.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        // SAFETY: `ptr` was allocated by `System` with `layout` (every allocation goes there).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_add(
            new_size as isize - layout.size() as isize,
            Ordering::Relaxed,
        );
        // SAFETY: as `GlobalAlloc::realloc` requires, forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Request `i` of a stream that does everything a client does: receiver moves, lists, a TX
/// moving back and forth, bad lines, a line over its budget.
fn request(i: usize) -> String {
    let t = i as f64;
    let (x, y) = (3.0 + 2.0 * (t * 0.37).sin(), 2.2 + 1.5 * (t * 0.23).cos());
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
        _ => format!("{{\"id\": {i}, \"rx\": [{x}, {y}, 1.2]}}"),
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
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {})
        .unwrap()
        .scene;
    let settings = SolveSettings {
        max_order: 2,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(dynamic.step(0)).unwrap();
    let limits = Limits {
        max_line_bytes: 4096,
        ..Limits::default()
    };
    let mut server = Server::new(dynamic, options, RadioOptions::default(), limits);
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
