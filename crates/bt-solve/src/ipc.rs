//! Iterative path convergence (IPC), Algorithms 1 and 2 of the paper.
//!
//! Each interaction point is recomputed from its two neighbours (Algorithm 2): both are
//! projected on the point's plane (`t_prev`, `t_next`), their distances `m`, `n` to the plane
//! taken, and the new point placed at `t_prev + m / (m + n) (t_next - t_prev)` — the similar
//! triangles of eq. (12)-(13). Rounds repeat until the mean displacement of the points in a
//! round is at most the threshold (Algorithm 1; the paper's listing starts Δ at ∞ and adds to
//! it, we reset it to 0 each round, which is what the text describes).
//!
//! Two update orders: [`UpdateOrder::Jacobi`] computes every point from the previous round
//! (the parallel hardware), [`UpdateOrder::GaussSeidel`] uses each neighbour's newest value
//! (the sequential software loop).
//!
//! Convergence is linear: with contraction rate ρ per round, the remaining error after a round
//! with displacement Δ is about Δ ρ / (1 − ρ), so a small Δ is not a small error when ρ is
//! close to 1 (near-grazing and long chains). `docs/numerics.md` discusses the default
//! threshold chosen so that IPC agrees with the image method to 1e-9 m.

use bt_geom::{Plane, Real, Vec3};
use bt_scene::{Scene, SurfaceId};
use serde::{Deserialize, Serialize};

/// Order in which a round updates the points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum UpdateOrder {
    /// Each point from its neighbours' newest values (sequential software).
    #[default]
    GaussSeidel,
    /// All points from the previous round (parallel hardware, the paper's PE matrix).
    Jacobi,
}

/// What follows the paper's rounds once the path has nearly settled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Acceleration {
    /// Nothing: the paper's rounds until its stopping rule (Algorithms 1-2 alone).
    #[default]
    None,
    /// The paper's rounds until the mean displacement of a round is at most
    /// [`NEWTON_SWITCH_REL`] × extent (also tried once after [`NEWTON_PATIENCE`] rounds),
    /// then Newton steps on the stationarity of the path
    /// length (the reflection law) until a step is at most the threshold ε_N. A Newton step
    /// that fails (singular system, no decrease of the length) hands the run back to the
    /// paper's rounds, so the result is never worse than without acceleration.
    Newton,
}

/// IPC settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IpcOptions {
    /// Update order of a round.
    pub order: UpdateOrder,
    /// Convergence threshold ε_N on the mean displacement of a round, metres.
    pub threshold: Real,
    /// Round cap; a path still moving after it is `NotConverged`.
    pub max_iterations: u32,
    /// Error guard (default on): once the paper's rule holds, also require the estimated
    /// remaining error Δ·ρ/(1−ρ) to be at most `threshold × ERROR_GUARD_FACTOR`, with the
    /// contraction rate ρ measured over the last two rounds. Off = the paper's rule alone.
    pub error_guard: bool,
    /// Early stopping of paths that clearly tend to be invalid (the paper, section VI): stop
    /// a run when a point lies outside its polygon by more than [`EARLY_REJECT_MARGIN`] times
    /// the distance it can still move at the measured contraction rate. The run ends as
    /// [`IpcOutcome::LeftPolygon`]; such a path could not have become valid. Likewise when
    /// every point is inside its polygon and on the reflecting side by more than that reach
    /// and a segment crosses another surface well inside it
    /// ([`crate::validate::blocked_for_good`]): the run ends as [`IpcOutcome::Blocked`], the
    /// verdict validation would give the converged path.
    pub early_reject: bool,
    /// Acceleration after the paper's rounds (default none: the paper's IPC as it is).
    #[serde(default)]
    pub acceleration: Acceleration,
}

/// Safety factor of early rejection over the estimated remaining movement Δ·ρ/(1−ρ) (the
/// estimate can be optimistic where convergence is sublinear, near corners).
pub const EARLY_REJECT_MARGIN: Real = 100.0;

/// The error guard accepts an estimated remaining error of up to this many thresholds
/// (1e-13 × extent × 10 = 1e-12 × extent: 0.01 nm in a 10 m room, leaving two orders of
/// magnitude for the inaccuracy of the rate estimate below the 1e-9 m promise).
pub const ERROR_GUARD_FACTOR: Real = 10.0;

/// Early rejection starts after this many rounds (the rate needs a history of
/// [`EARLY_REJECT_SPAN`] rounds).
pub const EARLY_REJECT_FROM: usize = 24;

/// Rounds over which the error guard measures the contraction rate (even, for Jacobi).
pub const RATE_WINDOW: usize = 256;

/// Rounds between two checks for a stalled iteration (see [`solve`]).
pub const STALL_WINDOW: u32 = 64;

/// Relative default threshold: ε_N = 1e-13 × max(scene extent, 1 m). With f64 round-off at
/// ~1e-15 relative this is reachable, and it keeps the true error below 1e-9 m for contraction
/// rates up to 0.999 per round (error ≈ ε ρ/(1−ρ)).
pub const DEFAULT_REL_THRESHOLD: Real = 1e-13;

/// Newton acceleration starts once the mean displacement of a round is at most this times
/// max(scene extent, 1 m): 10 µm in a 10 m room, where Newton's quadratic convergence has
/// taken over for every non-degenerate path while the rounds have not yet slowed down.
pub const NEWTON_SWITCH_REL: Real = 1e-6;

/// Newton acceleration also starts after this many rounds when the displacement has not yet
/// fallen to the switch point: Jacobi rounds oscillate (eigenvalues near −1) on chains that
/// bounce near a corner, and the damped Newton iteration on the convex path length does not
/// need a close start. A failed attempt leaves the points as they were.
pub const NEWTON_PATIENCE: u32 = 64;

/// Newton steps allowed before the run falls back to the paper's rounds (quadratic convergence
/// from 1e-6 × extent needs 2-4; damped steps from a far start need more).
pub const NEWTON_MAX_STEPS: u32 = 32;

/// Default round cap (hard third-order cases need thousands of rounds at the default threshold).
pub const DEFAULT_MAX_ITERATIONS: u32 = 100_000;

impl IpcOptions {
    /// Defaults scaled to a scene: threshold `DEFAULT_REL_THRESHOLD × extent`.
    pub fn for_scene(scene: &Scene, order: UpdateOrder) -> Self {
        Self {
            order,
            threshold: DEFAULT_REL_THRESHOLD * scene.extent().max(1.0),
            max_iterations: DEFAULT_MAX_ITERATIONS,
            error_guard: true,
            early_reject: true,
            acceleration: Acceleration::None,
        }
    }
}

/// How an IPC run ended. Points are only meaningful for `Converged`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "kebab-case")]
pub enum IpcOutcome {
    /// The mean displacement fell to the threshold.
    Converged {
        /// Rounds run.
        iterations: u32,
        /// Mean displacement of the last round, metres.
        residual: Real,
    },
    /// The round cap was reached first, or the measured contraction rate shows it would be
    /// (no progress over [`STALL_WINDOW`] rounds, e.g. Jacobi's two-cycles on invalid
    /// candidates) and Newton steps from where the run stalled did not converge either.
    NotConverged {
        /// Rounds run.
        iterations: u32,
        /// Mean displacement of the last round, metres.
        residual: Real,
    },
    /// Early stopping: point `index` lies outside its polygon by far more than it can still
    /// move, so the converged path would be invalid.
    LeftPolygon {
        /// Index of the interaction point (0-based from TX).
        index: usize,
        /// Rounds run.
        iterations: u32,
    },
    /// Early stopping: segment `segment` crosses surface `by` so far inside it, and every point
    /// lies so far inside its polygon and off its plane, that no movement the run can still
    /// make changes it: the converged path would be valid but for this blocked segment.
    Blocked {
        /// Segment index, 0-based from TX.
        segment: usize,
        /// The occluding surface.
        by: SurfaceId,
        /// Rounds run.
        iterations: u32,
    },
    /// The update is undefined or meaningless for this candidate.
    Degenerate {
        /// What went wrong.
        kind: DegenerateKind,
        /// Index of the interaction point (0-based from TX).
        index: usize,
        /// Rounds run before it was detected.
        iterations: u32,
    },
}

impl IpcOutcome {
    /// Rounds (plus Newton steps) the run took, whatever its end.
    pub fn iterations(&self) -> u32 {
        match *self {
            IpcOutcome::Converged { iterations, .. }
            | IpcOutcome::NotConverged { iterations, .. }
            | IpcOutcome::LeftPolygon { iterations, .. }
            | IpcOutcome::Blocked { iterations, .. }
            | IpcOutcome::Degenerate { iterations, .. } => iterations,
        }
    }
}

/// Kinds of degenerate IPC candidates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DegenerateKind {
    /// Both neighbours lie on the point's plane: m + n = 0 (grazing), the proportion is undefined.
    NeighboursOnPlane,
    /// At the fixed point the neighbours lie on opposite sides of the plane: Algorithm 2 then
    /// converges to a transmission point, not a reflection.
    OppositeSides,
}

/// Algorithm 2: the new point on `plane` from its neighbours, or `None` when m + n = 0.
#[inline]
pub fn intersection_point(plane: &Plane, prev: Vec3, next: Vec3, min_sum: Real) -> Option<Vec3> {
    let dp = plane.signed_distance(prev);
    let dn = plane.signed_distance(next);
    let (m, n) = (dp.abs(), dn.abs());
    let sum = m + n;
    if sum <= min_sum {
        return None;
    }
    let t_prev = prev - dp * plane.normal;
    let t_next = next - dn * plane.normal;
    Some(t_prev + (m / sum) * (t_next - t_prev))
}

/// Chains up to this order keep a copy of their planes on the stack (longer ones on the heap).
pub(crate) const LOCAL_PLANES: usize = 8;

/// The planes of `seq` (at most [`LOCAL_PLANES`] long), contiguous and on the stack: the rounds
/// touch nothing else of the scene. Entries past `seq.len()` are unused.
#[inline(always)]
pub(crate) fn local_planes(scene: &Scene, seq: &[SurfaceId]) -> [Plane; LOCAL_PLANES] {
    let mut planes = [Plane {
        normal: Vec3::ZERO,
        offset: 0.0,
    }; LOCAL_PLANES];
    for (plane, id) in planes.iter_mut().zip(seq) {
        *plane = *scene.surface(*id).polygon.plane();
    }
    planes
}

/// Run IPC on `seq` between `tx` and `rx`. `points` holds the initial points on entry (one per
/// surface) and the final ones on return; `scratch` (same length) is kept for API stability
/// (Jacobi rounds now update in place, remembering each point's previous value).
///
/// With [`Acceleration::Newton`], `iterations` in the outcome counts rounds plus Newton steps
/// and `residual` is the mean displacement of the last update (round or Newton step).
#[inline(always)]
pub fn solve(
    scene: &Scene,
    seq: &[SurfaceId],
    tx: Vec3,
    rx: Vec3,
    options: &IpcOptions,
    points: &mut [Vec3],
    scratch: &mut [Vec3],
) -> IpcOutcome {
    let n = seq.len();
    debug_assert!(points.len() == n && scratch.len() == n);
    let _ = scratch;
    if n <= LOCAL_PLANES {
        let planes = local_planes(scene, seq);
        run(scene, seq, &planes[..n], tx, rx, options, points)
    } else {
        let planes: Vec<Plane> = seq
            .iter()
            .map(|id| *scene.surface(*id).polygon.plane())
            .collect();
        run(scene, seq, &planes, tx, rx, options, points)
    }
}

/// One round of Algorithm 1 (lines 9-14): returns the summed displacement, or the index of a
/// point whose neighbours both lie on its plane. Gauss-Seidel (`JACOBI = false`) feeds each new
/// point to its successor; Jacobi computes every point from the previous round, in place: the
/// old value of point k - 1 is kept in a register, point k + 1 is not yet overwritten.
#[inline(always)]
pub(crate) fn round<const JACOBI: bool>(
    planes: &[Plane],
    tx: Vec3,
    rx: Vec3,
    points: &mut [Vec3],
    min_sum: Real,
) -> Result<Real, usize> {
    let n = points.len();
    let mut moved = 0.0;
    let mut prev = tx;
    for k in 0..n {
        let next = if k + 1 == n { rx } else { points[k + 1] };
        let Some(p) = intersection_point(&planes[k], prev, next, min_sum) else {
            return Err(k);
        };
        let old = points[k];
        moved += p.distance(old);
        points[k] = p;
        prev = if JACOBI { old } else { p };
    }
    Ok(moved)
}

#[inline(always)]
/// Mean displacement of `n` points that moved `sum` metres in all; 0 for a chain without points
/// (line of sight), never the NaN of 0/0.
fn mean_displacement(sum: Real, n: usize) -> Real {
    if n == 0 { 0.0 } else { sum / n as Real }
}

/// The smallest summed distance (m) of a point's neighbours from its plane for which
/// Algorithm 2's update is defined in `scene` (below it the run ends as degenerate).
#[inline(always)]
pub(crate) fn min_sum(scene: &Scene) -> Real {
    scene.length_tolerance() * 1e-3
}

// Inlined so that the FMA-compiled candidate loop (`run_range_fma`) compiles it with FMA:
// a call would run every `mul_add` of the rounds through the software fallback.
#[inline(always)]
fn run(
    scene: &Scene,
    seq: &[SurfaceId],
    planes: &[Plane],
    tx: Vec3,
    rx: Vec3,
    options: &IpcOptions,
    points: &mut [Vec3],
) -> IpcOutcome {
    let mut run = IpcRun::new(scene, seq, (tx, rx), options);
    loop {
        if let Some(outcome) = run.step(planes, points) {
            return outcome;
        }
    }
}

/// One IPC run that advances a round at a time ([`IpcRun::step`]), so that a batch can
/// interleave independent runs: a Gauss-Seidel round is one long chain of dependent
/// operations, and the CPU overlaps the chains of different runs. A run's arithmetic does not
/// depend on what it is interleaved with: its outcome and points are bit for bit those of
/// [`solve`].
pub struct IpcRun<'a> {
    scene: &'a Scene,
    seq: &'a [SurfaceId],
    tx: Vec3,
    rx: Vec3,
    options: &'a IpcOptions,
    /// Below this summed distance of a point's neighbours from its plane the update is
    /// undefined (m).
    min_sum: Real,
    /// Newton is tried at most twice: after NEWTON_PATIENCE rounds and at the switch point.
    switch_pending: bool,
    patience_pending: bool,
    /// Summed displacement of a round (m) at which Newton takes over.
    newton_switch: Real,
    newton_steps: u32,
    rule: StoppingRule,
    rounds: u32,
    /// Summed displacement (m) since every point was last found inside its polygon (infinite
    /// before that): while it is at most early rejection's reach, no point can lie outside by
    /// more than the reach, and the test is skipped.
    inside_moved: Real,
}

impl<'a> IpcRun<'a> {
    /// A run of `options` on `seq` between `tx` and `rx`, before its first round.
    #[inline(always)]
    pub fn new(
        scene: &'a Scene,
        seq: &'a [SurfaceId],
        (tx, rx): (Vec3, Vec3),
        options: &'a IpcOptions,
    ) -> Self {
        let n = seq.len();
        let newton = options.acceleration == Acceleration::Newton;
        IpcRun {
            scene,
            seq,
            tx,
            rx,
            options,
            min_sum: min_sum(scene),
            switch_pending: newton,
            patience_pending: newton,
            newton_switch: NEWTON_SWITCH_REL * scene.extent().max(1.0) * n as Real,
            newton_steps: 0,
            rule: StoppingRule::new(options, n),
            rounds: 0,
            inside_moved: Real::INFINITY,
        }
    }

    /// One round and the checks after it, on `points` (the run's points, updated in place)
    /// with `planes` (the planes of its sequence): the outcome once the run has ended.
    #[inline(always)]
    pub fn step(&mut self, planes: &[Plane], points: &mut [Vec3]) -> Option<IpcOutcome> {
        if self.at_cap() {
            return Some(self.not_settled(planes, points));
        }
        self.count_round();
        let (tx, rx) = (self.tx, self.rx);
        let round = match self.options.order {
            UpdateOrder::GaussSeidel => round::<false>(planes, tx, rx, points, self.min_sum),
            UpdateOrder::Jacobi => round::<true>(planes, tx, rx, points, self.min_sum),
        };
        self.end_round(planes, points, round)
    }

    /// Whether the run has used its round cap (it then ends with [`IpcRun::not_settled`]).
    #[inline(always)]
    pub(crate) fn at_cap(&self) -> bool {
        self.rounds >= self.options.max_iterations
    }

    /// Counts a round about to run (below the cap).
    #[inline(always)]
    pub(crate) fn count_round(&mut self) {
        self.rounds += 1;
    }

    /// Whether the round just run, which moved the points by `moved` in sum, is a quiet one:
    /// no check after it would look at the points or end the run. A quiet round is recorded;
    /// any other goes through [`IpcRun::end_round`]. Lets a caller that keeps the points
    /// elsewhere ([`crate::lanes`]) hand them over only when they are needed.
    #[inline(always)]
    pub(crate) fn quiet_round(&mut self, moved: Real) -> bool {
        let rounds = self.rounds;
        let looks = self.options.early_reject && early_reject_looks(rounds);
        let quiet = moved.is_finite()
            && moved > self.rule.limit
            && !self.switch_pending
            && !self.patience_pending
            && !looks
            && !rounds.is_multiple_of(STALL_WINDOW);
        if quiet {
            self.inside_moved += moved;
            self.rule.record(rounds, moved);
        }
        quiet
    }

    /// The checks after a round whose result was `round` (the summed displacement, or the
    /// index of a point whose neighbours both lie on its plane): the outcome once the run has
    /// ended.
    #[inline(always)]
    pub(crate) fn end_round(
        &mut self,
        planes: &[Plane],
        points: &mut [Vec3],
        round: Result<Real, usize>,
    ) -> Option<IpcOutcome> {
        let rounds = self.rounds;
        let (tx, rx) = (self.tx, self.rx);
        let moved = match round {
            Ok(moved) => moved,
            Err(index) => {
                return Some(IpcOutcome::Degenerate {
                    kind: DegenerateKind::NeighboursOnPlane,
                    index,
                    iterations: rounds + self.newton_steps,
                });
            }
        };
        if !moved.is_finite() {
            return Some(self.not_settled(planes, points));
        }
        self.inside_moved += moved;
        if let Some(outcome) = self.newton(planes, points, moved) {
            return Some(outcome);
        }
        let scene = self.scene;
        if self.rule.settled(rounds, moved) {
            let residual = mean_displacement(moved, planes.len());
            let iterations = rounds + self.newton_steps;
            return Some(converged(
                scene, planes, tx, rx, points, iterations, residual,
            ));
        }
        if self.rule.stalled(rounds, moved) {
            return Some(self.stalled(planes, points));
        }
        let reach = self
            .options
            .early_reject
            .then(|| {
                self.rule
                    .early_reject_reach(rounds, moved, scene.length_tolerance())
            })
            .flatten();
        let iterations = rounds + self.newton_steps;
        let stop = reach.and_then(|reach| self.early_stop(points, (rounds, iterations, reach)));
        if stop.is_some() {
            return stop;
        }
        self.rule.record(rounds, moved);
        None
    }

    /// Newton acceleration after a round that moved the points by `moved` in sum: at the
    /// switch point or after [`NEWTON_PATIENCE`] rounds, the outcome if Newton converged.
    #[inline(always)]
    fn newton(&mut self, planes: &[Plane], points: &mut [Vec3], moved: Real) -> Option<IpcOutcome> {
        let at_switch = self.switch_pending && moved <= self.newton_switch;
        let at_patience = self.patience_pending && self.rounds >= NEWTON_PATIENCE;
        if !(at_switch || at_patience) {
            return None;
        }
        self.switch_pending &= !at_switch;
        self.patience_pending = false;
        let (tx, rx) = (self.tx, self.rx);
        match crate::newton::polish(planes, tx, rx, points, self.options.threshold) {
            crate::newton::Polish::Converged { steps, last_step } => {
                let residual = mean_displacement(last_step, planes.len());
                let iterations = self.rounds + steps;
                Some(converged(
                    self.scene, planes, tx, rx, points, iterations, residual,
                ))
            }
            // The points are unchanged; the paper's rounds carry on.
            crate::newton::Polish::Failed { steps } => {
                self.newton_steps += steps;
                None
            }
        }
    }

    /// Early stopping at round `rounds` when the points can still move by up to `reach` metres:
    /// a point outside its polygon by more than that ([`IpcOutcome::LeftPolygon`]), or, every
    /// [`EARLY_BLOCK_EVERY`] rounds, a segment blocked for good ([`IpcOutcome::Blocked`]), after
    /// `iterations` rounds plus Newton steps.
    #[inline(always)]
    fn early_stop(
        &mut self,
        points: &[Vec3],
        (rounds, iterations, reach): (u32, u32, Real),
    ) -> Option<IpcOutcome> {
        let (scene, seq) = (self.scene, self.seq);
        if self.inside_moved > reach {
            // A point inside its polygon needs no margin; one outside is rejected beyond `reach`.
            let mut inside = true;
            for (k, id) in seq.iter().enumerate() {
                let polygon = &scene.surface(*id).polygon;
                if polygon.contains(points[k], 0.0) {
                    continue;
                }
                if !polygon.contains(points[k], reach) {
                    return Some(IpcOutcome::LeftPolygon {
                        index: k,
                        iterations,
                    });
                }
                inside = false;
            }
            if inside {
                self.inside_moved = 0.0;
            }
        }
        if !rounds.is_multiple_of(EARLY_BLOCK_EVERY) {
            return None;
        }
        let (tx, rx) = (self.tx, self.rx);
        crate::validate::blocked_for_good(scene, seq, (tx, rx), points, reach).map(
            |(segment, by)| IpcOutcome::Blocked {
                segment,
                by,
                iterations,
            },
        )
    }

    /// The end of a run that stalled (the measured rate cannot reach the threshold in the
    /// rounds left): [`IpcRun::not_settled`], unless the paper's rule never held and Newton
    /// steps from the points converge ([`crate::newton::polish`]). Bounces a fraction of a
    /// millimetre from a corner's edge make the paper's rounds converge sublinearly: they
    /// stall tens of nanometres from the image-method path, where Newton's steps converge
    /// quadratically. Without this rescue the path was lost (a random nasty scene of the
    /// beam-tree property tests: two paths 14 µm from an edge, not converged after 87,000
    /// rounds). The outcome counts the Newton steps in its iterations.
    ///
    /// Jacobi's rounds stall in a two-cycle around the path (eigenvalues near −1): Newton
    /// starts from the mean of the points and their next round's, where the cycle centres.
    #[cold]
    fn stalled(&self, planes: &[Plane], points: &mut [Vec3]) -> IpcOutcome {
        if !self.rule.rule_met && points.iter().all(|p| p.is_finite()) {
            let (tx, rx) = (self.tx, self.rx);
            let mut start = points.to_vec();
            if self.options.order == UpdateOrder::Jacobi {
                let mut next = start.clone();
                if round::<true>(planes, tx, rx, &mut next, self.min_sum).is_ok() {
                    for (p, q) in start.iter_mut().zip(&next) {
                        *p = 0.5 * (*p + *q);
                    }
                }
            }
            let threshold = self.options.threshold;
            if let crate::newton::Polish::Converged { steps, last_step } =
                crate::newton::polish(planes, tx, rx, &mut start, threshold)
            {
                points.copy_from_slice(&start);
                let iterations = self.rounds + self.newton_steps + steps;
                let residual = mean_displacement(last_step, planes.len());
                return converged(self.scene, planes, tx, rx, points, iterations, residual);
            }
        }
        self.not_settled(planes, points)
    }

    /// The end of a run that stopped without its rule holding in the last round (round cap,
    /// stall, non-finite displacement): converged if the paper's rule held in some round,
    /// else not converged.
    #[cold]
    pub(crate) fn not_settled(&self, planes: &[Plane], points: &[Vec3]) -> IpcOutcome {
        let iterations = self.rounds + self.newton_steps;
        let residual = mean_displacement(self.rule.last, planes.len());
        if self.rule.rule_met && residual.is_finite() {
            return converged(
                self.scene, planes, self.tx, self.rx, points, iterations, residual,
            );
        }
        IpcOutcome::NotConverged {
            iterations,
            residual: if residual.is_finite() {
                residual
            } else {
                Real::MAX
            },
        }
    }
}

/// Whether early rejection looks at the points after round `rounds` (from 1).
#[inline(always)]
fn early_reject_looks(rounds: u32) -> bool {
    rounds as usize >= EARLY_REJECT_FROM && rounds.is_multiple_of(EARLY_REJECT_EVERY)
}

/// Early rejection looks at the points every this many rounds (a divisor of [`RATE_WINDOW`]).
pub const EARLY_REJECT_EVERY: u32 = 8;

/// Early stopping looks for a segment blocked for good every this many rounds (a multiple of
/// [`EARLY_REJECT_EVERY`]): the test walks the BVH along every segment, about as much work as
/// 30 rounds of a third-order chain, and it only pays on the long runs.
pub const EARLY_BLOCK_EVERY: u32 = 64;

/// Rounds over which early rejection measures the contraction rate; [`EARLY_REJECT_FROM`]
/// leaves at least this much history.
pub const EARLY_REJECT_SPAN: usize = 16;

/// The stopping rules of one run and the displacement history they read: the paper's rule
/// with the error guard ([`StoppingRule::settled`]), the stall check
/// ([`StoppingRule::stalled`]) and the reach of early rejection
/// ([`StoppingRule::early_reject_reach`]).
struct StoppingRule {
    /// The paper's threshold on the summed displacement of a round: threshold × chain length (m).
    limit: Real,
    error_guard: bool,
    max_iterations: u32,
    /// Displacement sums of the last RATE_WINDOW rounds (ring, indexed by round).
    recent: [Real; RATE_WINDOW],
    /// Displacement of the round that opened the current STALL_WINDOW.
    window_start: Real,
    /// Displacement of the last recorded round.
    last: Real,
    /// Whether the paper's rule held in some round: a run that then stalls under the error
    /// guard (near-corner paths converge sublinearly) still counts as converged, as the
    /// paper's algorithm would have stopped there.
    rule_met: bool,
}

impl StoppingRule {
    fn new(options: &IpcOptions, n: usize) -> Self {
        Self {
            limit: options.threshold * n as Real,
            error_guard: options.error_guard,
            max_iterations: options.max_iterations,
            recent: [Real::INFINITY; RATE_WINDOW],
            window_start: Real::INFINITY,
            last: Real::INFINITY,
            rule_met: false,
        }
    }

    /// The paper's rule, then the error guard: whether round `rounds` (from 1), which moved
    /// the points by `moved` in sum, ends the run as converged. The rate is measured over
    /// RATE_WINDOW (even) rounds so that Jacobi's alternating displacements and round-off
    /// noise do not fake a fast rate; a rate >= 1 means the displacement has reached
    /// round-off noise, where more rounds cannot help.
    #[inline(always)]
    fn settled(&mut self, rounds: u32, moved: Real) -> bool {
        if moved > self.limit {
            return false;
        }
        self.rule_met = true;
        // Before a full window, measure over the rounds run so far (from the first).
        let (base, window) = if rounds as usize > RATE_WINDOW {
            (
                self.recent[rounds as usize % RATE_WINDOW],
                RATE_WINDOW as Real,
            )
        } else {
            (self.recent[1 % RATE_WINDOW], (rounds - 1).max(1) as Real)
        };
        let rate = (moved / base).powf(1.0 / window);
        // `!(rate < 1.0)` on purpose: a NaN rate (0/0 at exact convergence) counts as settled.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let settled = !self.error_guard
            || !(rate < 1.0)
            || moved * rate / (1.0 - rate) <= self.limit * ERROR_GUARD_FACTOR;
        settled
    }

    /// Whether to give up: every STALL_WINDOW rounds, when the rate measured over the last
    /// window cannot reach the threshold within the remaining rounds (with a factor 4 of
    /// slack for rates that improve near the fixed point).
    #[inline(always)]
    fn stalled(&mut self, rounds: u32, moved: Real) -> bool {
        let window_end = rounds.is_multiple_of(STALL_WINDOW);
        if window_end && rounds > STALL_WINDOW {
            let rate = root_of_power_of_two(moved / self.window_start, STALL_WINDOW);
            let remaining = (self.max_iterations - rounds) as Real;
            let needed = if rate < 1.0 {
                (self.limit / moved).ln() / rate.ln()
            } else {
                Real::INFINITY
            };
            if needed > 4.0 * remaining {
                return true;
            }
        }
        if window_end {
            self.window_start = moved;
        }
        false
    }

    /// On the rounds where early rejection looks, the distance (m) a point may still lie
    /// outside its polygon: the remaining movement at the rate measured over the last
    /// EARLY_REJECT_SPAN rounds, times the margin, plus the scene's length tolerance. `None`
    /// on other rounds and while the displacement is not shrinking.
    #[inline(always)]
    fn early_reject_reach(&self, rounds: u32, moved: Real, length_tolerance: Real) -> Option<Real> {
        if !early_reject_looks(rounds) {
            return None;
        }
        let base = self.recent[(rounds as usize - EARLY_REJECT_SPAN) % RATE_WINDOW];
        let rate = root_of_power_of_two(moved / base, EARLY_REJECT_SPAN as u32);
        (rate < 1.0).then(|| EARLY_REJECT_MARGIN * moved * rate / (1.0 - rate) + length_tolerance)
    }

    /// Remembers the displacement of round `rounds`.
    #[inline(always)]
    fn record(&mut self, rounds: u32, moved: Real) {
        self.recent[rounds as usize % RATE_WINDOW] = moved;
        self.last = moved;
    }
}

/// `x^(1/span)` for a power of two `span`, by repeated square roots: several times cheaper
/// than `powf`, and as good for the rates it measures (estimates used with a wide margin).
#[inline(always)]
fn root_of_power_of_two(x: Real, span: u32) -> Real {
    debug_assert!(span.is_power_of_two());
    (0..span.trailing_zeros()).fold(x, |r, _| r.sqrt())
}

const _: () = assert!(EARLY_REJECT_SPAN.is_power_of_two() && STALL_WINDOW.is_power_of_two());

/// The outcome of a run whose stopping rule held: converged, unless some point ends with its
/// neighbours on opposite sides of its plane (a transmission, not a reflection).
fn converged(
    scene: &Scene,
    planes: &[Plane],
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
    iterations: u32,
    residual: Real,
) -> IpcOutcome {
    match opposite_sides(scene, planes, tx, rx, points) {
        Some(index) => IpcOutcome::Degenerate {
            kind: DegenerateKind::OppositeSides,
            index,
            iterations,
        },
        None => IpcOutcome::Converged {
            iterations,
            residual,
        },
    }
}

fn opposite_sides(
    scene: &Scene,
    planes: &[Plane],
    tx: Vec3,
    rx: Vec3,
    points: &[Vec3],
) -> Option<usize> {
    let tol = scene.length_tolerance();
    let n = planes.len();
    (0..n).find(|&k| {
        let plane = &planes[k];
        let prev = if k == 0 { tx } else { points[k - 1] };
        let next = if k + 1 == n { rx } else { points[k + 1] };
        let (a, b) = (plane.signed_distance(prev), plane.signed_distance(next));
        (a > tol && b < -tol) || (a < -tol && b > tol)
    })
}
