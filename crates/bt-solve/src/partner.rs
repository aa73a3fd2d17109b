//! A partner thread for one answer's halves: [`Partner::join`] runs two closures, the second
//! on a thread that waits for work by spinning, so that a lone receiver's answer (`beamtrace
//! serve`) is split over two cores without a sleeping worker's wake-up (tens of µs on a
//! virtual machine's halted core, more than the half it would take; docs/performance.md).
//!
//! The partner spins for [`Partner::new`]'s window after its last half, then parks. The
//! caller never waits for a partner that has not started: when the caller has finished its
//! own half and the second is still on offer, it takes it back and runs it itself. So a
//! parked or busy partner costs an answer nothing but the offer.

use std::cell::UnsafeCell;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::thread::{JoinHandle, Thread};
use std::time::{Duration, Instant};

/// No half on offer.
const EMPTY: u8 = 0;
/// A half on offer (`Shared::job` holds it).
const OFFERED: u8 = 1;
/// The partner runs the half on offer.
const TAKEN: u8 = 2;
/// The partner has run it.
const DONE: u8 = 3;

/// A half as the partner sees it: its lifetime erased while it is on offer ([`Partner::join`]
/// does not return before the half is taken back or done).
trait Half {
    /// Run the half, its panic caught and kept for the caller.
    fn run(&self);
}

/// The state the caller and the partner share.
struct Shared {
    state: AtomicU8,
    /// The half on offer: written by the caller before `state` becomes [`OFFERED`], read by the
    /// partner after it moved `state` from [`OFFERED`] to [`TAKEN`].
    job: UnsafeCell<Option<*const (dyn Half + 'static)>>,
    /// The partner has parked (or is about to): an offer must wake it.
    parked: AtomicBool,
    stop: AtomicBool,
    /// Halves the partner has run ([`Partner::halves_taken`]).
    taken: std::sync::atomic::AtomicU64,
    /// How long the partner spins after its last half before it parks.
    window: Duration,
}

// SAFETY: `job` is written only by the caller that holds `Partner::busy`, while `state` is
// `EMPTY` (the partner does not read it then), and read only by the partner between its
// `OFFERED` → `TAKEN` exchange and its `DONE` store; the half it points to is `Sync`.
unsafe impl Sync for Shared {}
// SAFETY: as above; the pointer is only dereferenced under that protocol.
unsafe impl Send for Shared {}

/// A thread that runs the second closure of [`Partner::join`] calls (see the module docs).
pub struct Partner {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    handle: Thread,
    /// A caller is inside [`Partner::join`]: a second caller runs both halves itself.
    busy: AtomicBool,
}

impl std::fmt::Debug for Partner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Partner")
            .field("window", &self.shared.window)
            .finish_non_exhaustive()
    }
}

/// A half on the caller's stack: the closure until it runs, then its result.
struct StackHalf<F, R> {
    f: UnsafeCell<Option<F>>,
    result: UnsafeCell<Option<std::thread::Result<R>>>,
}

impl<F: FnOnce() -> R + Send, R: Send> Half for StackHalf<F, R> {
    fn run(&self) {
        // SAFETY: run once, by the one thread that took the half (`Partner::join`).
        let f = unsafe { (*self.f.get()).take() };
        if let Some(f) = f {
            let result = catch_unwind(AssertUnwindSafe(f));
            // SAFETY: as above; the caller reads it only after the half is done.
            unsafe { *self.result.get() = Some(result) };
        }
    }
}

impl Partner {
    /// A partner thread that spins for `window` after each half before it parks; `None` when
    /// the thread cannot be started (then callers run both halves themselves).
    pub fn new(window: Duration) -> Option<Partner> {
        let shared = Arc::new(Shared {
            state: AtomicU8::new(EMPTY),
            job: UnsafeCell::new(None),
            parked: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            taken: std::sync::atomic::AtomicU64::new(0),
            window,
        });
        let theirs = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("beamtrace-partner".into())
            .spawn(move || partner_loop(&theirs))
            .ok()?;
        let handle = thread.thread().clone();
        Some(Partner {
            shared,
            thread: Some(thread),
            handle,
            busy: AtomicBool::new(false),
        })
    }

    /// `(a(), b())`, `a` on the calling thread and `b` on the partner when it is free to take
    /// it before the caller has finished `a` (else on the calling thread after `a`). A panic
    /// of either is resumed on the caller once both are over.
    pub fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        if self.busy.swap(true, Ordering::Acquire) {
            return (a(), b());
        }
        let half = StackHalf {
            f: UnsafeCell::new(Some(b)),
            result: UnsafeCell::new(None),
        };
        self.offer(&half);
        let ra = catch_unwind(AssertUnwindSafe(a));
        self.take_back_or_wait(&half);
        self.busy.store(false, Ordering::Release);
        let rb = half.result.into_inner();
        match (ra, rb) {
            (Ok(ra), Some(Ok(rb))) => (ra, rb),
            (Err(p), _) | (_, Some(Err(p))) => resume_unwind(p),
            (Ok(_), None) => unreachable!("a half is run before join returns"),
        }
    }

    /// How many second halves the partner thread has run (the rest ran on their callers).
    pub fn halves_taken(&self) -> u64 {
        self.shared.taken.load(Ordering::Relaxed)
    }

    /// Put `half` on offer and wake the partner if it parked.
    fn offer<H: Half>(&self, half: &H) {
        let erased: *const (dyn Half + '_) = half;
        // SAFETY: only the lifetime is erased; `join` does not return (nor unwind) before the
        // half is taken back or done, so the pointer never outlives `half`.
        let erased: *const (dyn Half + 'static) = unsafe { std::mem::transmute(erased) };
        // SAFETY: `state` is `EMPTY` and this caller holds `busy` (`Shared`'s protocol).
        unsafe { *self.shared.job.get() = Some(erased) };
        // SeqCst with the load of `parked` below and the partner's own pair: either the
        // partner sees the offer before it parks, or this sees that it parked.
        self.shared.state.store(OFFERED, Ordering::SeqCst);
        if self.shared.parked.load(Ordering::SeqCst) {
            self.handle.unpark();
        }
    }

    /// Run `half` here if it is still on offer, else wait until the partner has run it.
    fn take_back_or_wait<H: Half>(&self, half: &H) {
        let state = &self.shared.state;
        let mine = state.compare_exchange(OFFERED, EMPTY, Ordering::Acquire, Ordering::Acquire);
        if mine.is_ok() {
            half.run();
            return;
        }
        let mut spins = 0u32;
        while state.load(Ordering::Acquire) != DONE {
            spins = spins.saturating_add(1);
            match spins < 1 << 12 {
                true => std::hint::spin_loop(),
                // The partner may share this core (no affinity is set): let it run.
                false => std::thread::yield_now(),
            }
        }
        state.store(EMPTY, Ordering::Release);
    }
}

impl Drop for Partner {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        self.handle.unpark();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// Where `n` pieces of work split into a [`Partner::join`]'s two halves: the first count `k`
/// of pieces whose work (`weight(i)` each, in any unit) reaches half of the whole: the
/// caller's half `0..k` holds at least half, and less than half without its last piece; 0
/// when `n` is 0. Both threads work at the same rate once the halves' buffers are the
/// caller's (timed for the serve report's halves: docs/performance.md, session 9).
pub fn half_of_work(n: usize, weight: impl Fn(usize) -> usize) -> usize {
    let whole: usize = (0..n).map(&weight).sum();
    let mut sum = 0;
    (0..n)
        .position(|i| {
            sum += weight(i);
            2 * sum >= whole
        })
        .map_or(n, |i| i + 1)
}

/// The partner: take each half on offer and run it; spin for the window after the last one,
/// then park until an offer wakes it.
fn partner_loop(shared: &Shared) {
    let mut last = Instant::now();
    let mut spins = 0u32;
    while !shared.stop.load(Ordering::Relaxed) {
        let state = &shared.state;
        if state.load(Ordering::Relaxed) == OFFERED
            && state
                .compare_exchange(OFFERED, TAKEN, Ordering::Acquire, Ordering::Relaxed)
                .is_ok()
        {
            // SAFETY: taken under `Shared`'s protocol: the caller waits for `DONE`.
            if let Some(job) = unsafe { *shared.job.get() } {
                // SAFETY: the half lives until the caller sees `DONE`.
                unsafe { (*job).run() };
            }
            shared.taken.fetch_add(1, Ordering::Relaxed);
            state.store(DONE, Ordering::Release);
            last = Instant::now();
            continue;
        }
        std::hint::spin_loop();
        spins = spins.wrapping_add(1);
        if spins.is_multiple_of(256) && last.elapsed() > shared.window {
            shared.parked.store(true, Ordering::SeqCst);
            if state.load(Ordering::SeqCst) != OFFERED && !shared.stop.load(Ordering::SeqCst) {
                std::thread::park_timeout(Duration::from_secs(1));
            }
            shared.parked.store(false, Ordering::SeqCst);
            last = Instant::now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_of_work_is_where_the_work_before_reaches_half() {
        let split = |w: &[usize]| half_of_work(w.len(), |i| w[i]);
        assert_eq!(split(&[]), 0);
        assert_eq!(split(&[1, 1, 1, 1]), 2);
        assert_eq!(split(&[1, 1, 1, 1, 1]), 3);
        assert_eq!(split(&[3, 1, 1, 1]), 1);
        assert_eq!(split(&[1, 2, 3, 4]), 3);
        // A piece heavier than all the others: the caller takes it and everything before.
        assert_eq!(split(&[1, 1, 1, 5]), 4);
    }

    /// Both halves run, each exactly once, whether the partner takes the second or not, and
    /// the second sees and fills borrowed memory.
    #[test]
    fn both_halves_run_once_with_borrowed_data() {
        let partner = Partner::new(Duration::from_millis(5)).unwrap();
        for n in 0..2_000usize {
            let mut left = vec![0usize; n % 7];
            let mut right = vec![0usize; n % 5];
            let (a, b) = partner.join(
                || {
                    left.iter_mut().for_each(|x| *x += n);
                    left.len()
                },
                || {
                    right.iter_mut().for_each(|x| *x += 2 * n);
                    right.len()
                },
            );
            assert_eq!((a, b), (n % 7, n % 5));
            assert!(left.iter().all(|&x| x == n) && right.iter().all(|&x| x == 2 * n));
        }
        // A caller that waits for its second half to start (up to 10 s, for a loaded
        // machine): the partner takes it, and runs it on its own thread.
        let before = partner.halves_taken();
        for _ in 0..20 {
            let started = AtomicBool::new(false);
            let me = std::thread::current().id();
            let (_, there) = partner.join(
                || {
                    let t0 = Instant::now();
                    while !started.load(Ordering::Acquire) && t0.elapsed().as_secs() < 10 {
                        std::thread::yield_now();
                    }
                },
                || {
                    started.store(true, Ordering::Release);
                    std::thread::current().id()
                },
            );
            assert_ne!(there, me, "a half ran on the caller");
        }
        assert_eq!(partner.halves_taken(), before + 20);
    }

    /// A panic of the second half reaches the caller, and the partner goes on serving.
    #[test]
    fn a_panic_reaches_the_caller() {
        let partner = Partner::new(Duration::from_millis(5)).unwrap();
        let caught = catch_unwind(AssertUnwindSafe(|| {
            partner.join(
                || std::thread::sleep(Duration::from_millis(2)),
                || panic!("half"),
            )
        }));
        assert!(caught.is_err());
        assert_eq!(partner.join(|| 1, || 2), (1, 2));
    }

    /// A parked partner is woken by an offer (or the caller runs the half), and dropping
    /// the partner stops its thread.
    #[test]
    fn a_parked_partner_still_answers() {
        let partner = Partner::new(Duration::from_micros(50)).unwrap();
        std::thread::sleep(Duration::from_millis(20));
        for k in 0..50 {
            assert_eq!(partner.join(|| k, || k + 1), (k, k + 1));
        }
        drop(partner);
    }
}
