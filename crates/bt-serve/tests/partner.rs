//! A lone receiver's answer is split over the serving thread and its partner (the walk, the
//! solve and the report), and the buffers of the split are the serving thread's: once warm,
//! the partner allocates (almost) nothing. Memory one thread allocates and the other frees
//! made glibc's allocator lock arenas across the two threads, which cost the split answers
//! their speed-up (docs/performance.md, session 8).
//!
//! Its own test binary (not a module of `tests/it`): the counting allocator sees every thread
//! of the process, so no other test may run beside it.

use bt_beams::RadioOptions;
use bt_serve::{Limits, Server};
use bt_solve::settings::SolveSettings;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};

/// The system allocator, counting the allocations and reallocations of every thread but
/// the one that marked itself [`SERVING`].
struct Counting;

static ELSEWHERE: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// Whether this thread is the test's (the serving thread).
    static SERVING: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if !SERVING.with(Cell::get) {
        ELSEWHERE.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call is forwarded to the system allocator with the caller's arguments; the
// counter is a thread-local read and an atomic add, which allocate nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's layout, as `GlobalAlloc::alloc` requires.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout` (every allocation goes there).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: as `GlobalAlloc::realloc` requires, forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Request `i` of a walk of one receiver through the living room.
fn request(i: usize) -> String {
    let t = i as f64;
    let (x, y) = (3.0 + 2.0 * (t * 0.37).sin(), 2.2 + 1.5 * (t * 0.23).cos());
    format!("{{\"id\": {i}, \"rx\": [{x}, {y}, 1.2]}}")
}

#[test]
fn the_partner_allocates_nothing_once_warm() {
    SERVING.with(|s| s.set(true));
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {})
        .unwrap()
        .scene;
    let settings = SolveSettings {
        max_order: 3,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(dynamic.step(0)).unwrap();
    let server = Server::new(dynamic, options, RadioOptions::default(), Limits::default());
    // A long spin, so that the partner is awake for every half of this test.
    let mut server = server.with_partner(std::time::Duration::from_secs(1));
    let mut out = Vec::new();
    let mut answer = |i: usize| {
        server.answer_line(request(i).as_bytes(), &mut out);
        assert!(out.starts_with(b"{\"id\":"), "request {i}: {out:?}");
    };
    (0..100).for_each(&mut answer);
    let warm = ELSEWHERE.load(Ordering::Relaxed);
    let answers = 1000;
    (100..100 + answers).for_each(&mut answer);
    let allocations = ELSEWHERE.load(Ordering::Relaxed) - warm;
    // Before the split's buffers were the serving thread's, the partner allocated or grew
    // about 9 blocks an answer; now a record the partner fills may still grow for a path
    // longer than any its slot held before (about one answer in ten).
    assert!(
        allocations * 4 < answers as u64,
        "{allocations} allocations off the serving thread over {answers} answers"
    );
}
