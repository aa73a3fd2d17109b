//! A lone receiver's answer is split over the serving thread and its partner (the walk, the
//! solve and the report), and the buffers of the split are the serving thread's: once warm,
//! the partner allocates (almost) nothing. Memory one thread allocates and the other frees
//! made glibc's allocator lock arenas across the two threads, which cost the split answers
//! their speed-up (docs/performance.md, session 8).
//!
//! Its own test binary (not a module of `tests/it`): the counting allocator sees every thread
//! of the process, so no other test may run beside it.

#[path = "support/counting.rs"]
mod counting;

use bt_serve::Limits;
use counting::{ELSEWHERE, MARKED};
use std::sync::atomic::Ordering;

#[global_allocator]
static ALLOCATOR: counting::Counting = counting::Counting;

#[test]
fn the_partner_allocates_nothing_once_warm() {
    MARKED.with(|m| m.set(true));
    let server = counting::living_room(3, Limits::default());
    // A long spin, so that the partner is awake for every half of this test.
    let mut server = server.with_partner(std::time::Duration::from_secs(1));
    let mut out = Vec::new();
    let mut answer = |i: usize| {
        server.answer_line(counting::move_request(i).as_bytes(), &mut out);
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
