//! What the allocation tests share (`tests/memory.rs`, `tests/partner.rs`, each its own test
//! binary: a global allocator sees every thread of the process, so no other test may run
//! beside it): the system allocator, counting, the living room's server and a receiver's
//! walk through it.

use bt_beams::RadioOptions;
use bt_serve::{Limits, Server};
use bt_solve::settings::SolveSettings;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicIsize, AtomicU64, Ordering};

/// The system allocator, counting the bytes live ([`LIVE`]) and the allocations and
/// reallocations of the threads not [`MARKED`] ([`ELSEWHERE`]). Install it in a test binary
/// with `#[global_allocator]`.
pub struct Counting;

/// Bytes allocated and not yet freed, by every thread.
pub static LIVE: AtomicIsize = AtomicIsize::new(0);

/// Allocations and reallocations made by threads not [`MARKED`].
pub static ELSEWHERE: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// Whether this thread's allocations are left out of [`ELSEWHERE`] (a test marks its
    /// own thread, the serving one).
    pub static MARKED: Cell<bool> = const { Cell::new(false) };
}

/// One allocation or reallocation of this thread, for [`ELSEWHERE`].
fn count() {
    if !MARKED.with(Cell::get) {
        ELSEWHERE.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call is forwarded to the system allocator with the caller's arguments; the
// counters are atomic adds and a thread-local read, which allocate nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        count();
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
        count();
        // SAFETY: as `GlobalAlloc::realloc` requires, forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// A server of the living room (its dynamic scene) tracing to `max_order` within `limits`.
pub fn living_room(max_order: usize, limits: Limits) -> Server {
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {})
        .unwrap()
        .scene;
    let settings = SolveSettings {
        max_order,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(dynamic.step(0)).unwrap();
    Server::new(dynamic, options, RadioOptions::default(), limits)
}

/// Where request `i` of a walk through the living room puts the receiver in the plan (x, y,
/// metres, the scene's frame).
pub fn walk_xy(i: usize) -> (f64, f64) {
    let t = i as f64;
    (3.0 + 2.0 * (t * 0.37).sin(), 2.2 + 1.5 * (t * 0.23).cos())
}

/// Request `i` of that walk: the receiver moved to its point, 1.2 m up.
pub fn move_request(i: usize) -> String {
    let (x, y) = walk_xy(i);
    format!("{{\"id\": {i}, \"rx\": [{x}, {y}, 1.2]}}")
}
