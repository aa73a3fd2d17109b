//! The IPC loop (Algorithm 1) in fixed point, with the accelerator's Jacobi or red-black update.

use crate::{
    FineCoord, FinePoint, FixedError, FixedPlane, FixedPoint, Widths, dequantize_fine_point,
    displacement_linf, intersection_point_in, quantize_fine_point, quantize_point,
};

/// A plane at the boundary, in metres: `normal · x = offset_m`, `normal` unit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlaneInput {
    /// Unit normal (unitless).
    pub normal: [f64; 3],
    /// Offset along the normal, metres.
    pub offset_m: f64,
}

/// Early stopping (the paper's Section VI proposal): freeze a path once one of its points lies
/// clearly outside its plane's polygon, so its PE slots go to other paths.
///
/// After committing round `r ≥ min_rounds`, the path freezes with `left_bounds` if some point
/// `p` written in that round lies, on some axis `a`, outside the plane's box widened by
/// `margin_lsb + (|Δx| + |Δy| + |Δz|) << displacement_shift`, where `Δ` is that point's move in
/// the round (its L1 norm bounds the L∞ one from above, and needs no comparator). A point that
/// is still moving gets a proportionally wider margin; a stalled point outside its box by more
/// than `margin_lsb` is frozen. Verilog twin: `wb_lb` in `bt_top`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct EarlyStop {
    /// First round after which a path may be frozen (≥ 1).
    pub min_rounds: u32,
    /// `K = 2^displacement_shift`, the factor of the point's displacement in the margin (≤ 4).
    pub displacement_shift: u32,
    /// Fixed margin, fine LSB (1/256 mm), below 2^32.
    pub margin_lsb: u32,
}

impl EarlyStop {
    /// Largest accepted `displacement_shift` (the RTL's comparison is 48 bits wide).
    pub const MAX_SHIFT: u32 = 4;
}

impl Default for EarlyStop {
    /// 8 rounds, K = 4, 200 mm: no valid path frozen on the living room and 12 seeded
    /// furnished rooms, order ≤ 3 (`bt-study/tests/early_stop.rs`); 50 mm froze a slowly
    /// contracting valid path (73 rounds to converge) at round 9.
    fn default() -> Self {
        EarlyStop {
            min_rounds: 8,
            displacement_shift: 2,
            margin_lsb: 200 * 256,
        }
    }
}

/// Axis-aligned bounds of a plane's polygon in metres (`min`, `max`), for [`EarlyStop`].
pub type BoundsM = [[f64; 3]; 2];

/// Quantised early-stopping box of one plane, widened by the fixed margin: a point is outside
/// on axis `a` when `p + slack < lo[a]` or `p − slack > hi[a]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FineBox {
    /// `floor(min) − 1 − margin`, fine LSB.
    pub lo: [i64; 3],
    /// `ceil(max) + 1 + margin`, fine LSB.
    pub hi: [i64; 3],
}

impl FineBox {
    /// A box no 40-bit point can leave (planes without bounds): ±2^41, so the RTL's 48-bit
    /// comparison cannot overflow.
    pub const UNBOUNDED: FineBox = FineBox {
        lo: [-(1 << 41); 3],
        hi: [1 << 41; 3],
    };

    /// Whether `point`, which moved by `move_l1` fine LSB (L1) in its round, is outside.
    ///
    /// Verilog twin: the `lb_*` wires of `bt_top` (48-bit signed comparisons).
    pub fn outside(&self, point: FinePoint, move_l1: u64, shift: u32) -> bool {
        let slack = (move_l1 << shift) as i64;
        (0..3).any(|a| point[a].0 + slack < self.lo[a] || point[a].0 - slack > self.hi[a])
    }
}

/// The order in which a round updates a path's points (Algorithm 1's loop over the points).
///
/// Both orders apply the same Algorithm 2 to every point once per round; they differ in which
/// neighbour values a point reads. A chain's update couples each point to its two neighbours
/// only, so the points of even index (TX side first, 0-based) depend on odd ones alone and
/// vice versa: updating one colour from the other is Gauss-Seidel's convergence (locally
/// ρ_Jacobi², half the rounds for the same displacement) with every phase still parallel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RoundOrder {
    /// Every point from the previous round's values (the paper's PE matrix): one phase.
    #[default]
    Jacobi,
    /// Red-black: first the points of even index from the previous round's values, then the
    /// points of odd index from the even points just computed: two phases, the second reading
    /// the round's new values (the schedule's `late` jobs in `bt_top`).
    RedBlack,
}

impl RoundOrder {
    /// Phases of a round: point `i` is updated in phase `i % phases`, a phase after the one
    /// before it has been written.
    pub const fn phases(self) -> u32 {
        match self {
            RoundOrder::Jacobi => 1,
            RoundOrder::RedBlack => 2,
        }
    }
}

/// Why a path was frozen as degenerate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DegenerateKind {
    /// Both neighbours of some point lay on its plane (`m + n = 0`, Algorithm 3 returned the
    /// midpoint). Reported when only this flag is set.
    ZeroDistanceSum,
    /// Some coordinate left the 32-bit range and was saturated (takes precedence).
    CoordinateOverflow,
}

/// Outcome of one path, mirroring the hardware status word of `bt-hls`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FixedOutcome {
    /// The displacement of round `rounds` was ≤ the threshold.
    Converged {
        /// Rounds run (≥ 1).
        rounds: u32,
    },
    /// The round budget ran out.
    NotConverged {
        /// Rounds run (= budget).
        rounds: u32,
        /// Displacement of the last round (L∞, fine LSB); 0 if no round ran.
        displacement_lsb: u64,
    },
    /// Early stopping froze the path after round `rounds`: a point left its plane's box
    /// ([`EarlyStop`]). Not a path.
    LeftBounds {
        /// Rounds run including the flagged one.
        rounds: u32,
    },
    /// A degenerate flag was raised in round `rounds`; the path was frozen after it.
    Degenerate {
        /// Which flag (overflow takes precedence).
        kind: DegenerateKind,
        /// Rounds run including the flagged one.
        rounds: u32,
    },
}

/// Result of one path.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PathResult {
    /// Intersection points, fine words (mm × 2^8), TX side first.
    pub points: Vec<FinePoint>,
    /// The same points in metres.
    pub points_m: Vec<[f64; 3]>,
    /// Rounds run.
    pub rounds: u32,
    /// L∞ displacement of the last round, fine LSB (0 if no round ran).
    pub displacement_lsb: u64,
    /// Convergence reached (displacement ≤ threshold, no degenerate flag).
    pub converged: bool,
    /// Sticky `m + n = 0` flag.
    pub zero_sum: bool,
    /// Sticky saturation flag.
    pub overflow: bool,
    /// Frozen by early stopping ([`EarlyStop`]); never set together with `converged`.
    #[serde(default)]
    pub left_bounds: bool,
}

impl PathResult {
    /// The outcome as a value.
    pub fn outcome(&self) -> FixedOutcome {
        if self.overflow {
            FixedOutcome::Degenerate {
                kind: DegenerateKind::CoordinateOverflow,
                rounds: self.rounds,
            }
        } else if self.zero_sum {
            FixedOutcome::Degenerate {
                kind: DegenerateKind::ZeroDistanceSum,
                rounds: self.rounds,
            }
        } else if self.left_bounds {
            FixedOutcome::LeftBounds {
                rounds: self.rounds,
            }
        } else if self.converged {
            FixedOutcome::Converged {
                rounds: self.rounds,
            }
        } else {
            FixedOutcome::NotConverged {
                rounds: self.rounds,
                displacement_lsb: self.displacement_lsb,
            }
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
struct FixedPath {
    planes: Vec<u32>,
    init: Vec<FinePoint>,
}

/// "the `bits`-bit coordinate range (±L m)", for errors.
fn range_text(bits: u32) -> String {
    let (_, hi) = Widths::for_coord(bits).coord_range();
    format!(
        "the {bits}-bit coordinate range (±{} m)",
        FineCoord(hi).dequantize()
    )
}

/// The fixed-point IPC model: validated, quantised scene plus candidate paths.
///
/// Semantics (identical in `bt_top`): each round updates every point of a path once by
/// [`crate::intersection_point`] (TX and RX fixed), in the [`RoundOrder`]: Jacobi (every point from
/// the previous round's values) or red-black (even points first, then odd points from them);
/// the round's displacement is the maximum over the path's points of the L∞ norm of the
/// point's move, in fine LSB (1/256 mm). After committing round `r`: if a degenerate flag was raised the path
/// freezes as degenerate, else if early stopping is on, `r ≥ min_rounds` and a point of the
/// round left its box it freezes with `left_bounds` ([`EarlyStop`]), else if displacement ≤
/// `threshold_lsb` it freezes as converged; a path never runs more than its round budget.
#[derive(Debug, Clone, PartialEq)]
pub struct FixedIpc {
    planes: Vec<FixedPlane>,
    paths: Vec<FixedPath>,
    threshold_lsb: u32,
    max_rounds: u32,
    early_stop: Option<(EarlyStop, Vec<FineBox>)>,
    /// Width of the coordinate word, bits ([`crate::Widths`]; 40 unless narrowed).
    coord_bits: u32,
    /// Update order of a round (Jacobi unless set).
    order: RoundOrder,
}

impl FixedIpc {
    /// Validates and quantises. `init_points[p][i]` (metres) is the starting point of point `i`
    /// of path `p` (e.g. its polygon's centroid); `threshold_lsb` is in fine LSB (1/256 mm).
    /// Every problem is reported at once.
    pub fn new(
        planes: &[PlaneInput],
        paths: &[Vec<u32>],
        init_points: &[Vec<[f64; 3]>],
        threshold_lsb: u32,
        max_rounds: u32,
    ) -> Result<FixedIpc, FixedError> {
        let mut problems = Vec::new();
        let mut fixed_planes = Vec::with_capacity(planes.len());
        for (i, p) in planes.iter().enumerate() {
            match FixedPlane::quantize(p.normal, p.offset_m) {
                Ok(fp) => fixed_planes.push(fp),
                Err(e) => problems.push(format!("plane {i}: {e}")),
            }
        }
        if init_points.len() != paths.len() {
            problems.push(format!(
                "{} paths but {} initial-point lists",
                paths.len(),
                init_points.len()
            ));
        }
        let mut fixed_paths = Vec::with_capacity(paths.len());
        for (p, planes_of_path) in paths.iter().enumerate() {
            if planes_of_path.is_empty() {
                problems.push(format!("path {p}: has no reflection point"));
            }
            for &pl in planes_of_path {
                if pl as usize >= planes.len() {
                    problems.push(format!("path {p}: plane index {pl} out of range"));
                }
            }
            let mut init = Vec::new();
            if let Some(pts) = init_points.get(p) {
                if pts.len() != planes_of_path.len() {
                    problems.push(format!(
                        "path {p}: {} initial points for {} planes",
                        pts.len(),
                        planes_of_path.len()
                    ));
                }
                for (i, &pt) in pts.iter().enumerate() {
                    match quantize_fine_point(pt) {
                        Ok(q) => init.push(q),
                        Err(e) => problems.push(format!("path {p} initial point {i}: {e}")),
                    }
                }
            }
            fixed_paths.push(FixedPath {
                planes: planes_of_path.clone(),
                init,
            });
        }
        if !problems.is_empty() {
            return Err(FixedError::InvalidInput { problems });
        }
        Ok(FixedIpc {
            planes: fixed_planes,
            paths: fixed_paths,
            threshold_lsb,
            max_rounds,
            early_stop: None,
            coord_bits: FineCoord::BITS,
            order: RoundOrder::Jacobi,
        })
    }

    /// Narrows the coordinate word to `bits` ([`crate::Widths`]; a room needs far fewer than
    /// 40): points saturate there, raising the overflow flag. Refused, naming each value, when
    /// a plane offset or start point does not fit, or `bits` is outside
    /// [`crate::Widths::MIN_COORD`]..=40.
    pub fn with_coord_bits(mut self, bits: u32) -> Result<FixedIpc, FixedError> {
        let mut problems = Vec::new();
        if !(Widths::MIN_COORD..=FineCoord::BITS).contains(&bits) {
            problems.push(format!(
                "coordinate word of {bits} bits: must be {}..={}",
                Widths::MIN_COORD,
                FineCoord::BITS
            ));
            return Err(FixedError::InvalidInput { problems });
        }
        let wd = Widths::for_coord(bits);
        for (i, p) in self.planes.iter().enumerate() {
            if !wd.holds(&[p.offset]) {
                problems.push(format!(
                    "plane {i}: offset {} m is outside {}",
                    p.offset.dequantize(),
                    range_text(bits)
                ));
            }
        }
        for (p, path) in self.paths.iter().enumerate() {
            for (i, q) in path.init.iter().enumerate() {
                if !wd.holds(q) {
                    problems.push(format!(
                        "path {p} initial point {i}: {:?} m is outside {}",
                        dequantize_fine_point(*q),
                        range_text(bits)
                    ));
                }
            }
        }
        if !problems.is_empty() {
            return Err(FixedError::InvalidInput { problems });
        }
        self.coord_bits = bits;
        Ok(self)
    }

    /// Sets the update order of a round (default [`RoundOrder::Jacobi`]).
    pub fn with_round_order(mut self, order: RoundOrder) -> FixedIpc {
        self.order = order;
        self
    }

    /// Update order of a round.
    pub fn round_order(&self) -> RoundOrder {
        self.order
    }

    /// Width of the coordinate word, bits.
    pub fn coord_bits(&self) -> u32 {
        self.coord_bits
    }

    /// Whether TX or RX `point` (bus words) fits the coordinate word; the error names it.
    pub fn check_terminal(&self, name: &str, point: FixedPoint) -> Result<(), FixedError> {
        let fine = point.map(FineCoord::from_coord);
        if Widths::for_coord(self.coord_bits).holds(&fine) {
            return Ok(());
        }
        Err(FixedError::InvalidInput {
            problems: vec![format!(
                "{name} {:?} m is outside {}",
                dequantize_fine_point(fine),
                range_text(self.coord_bits)
            )],
        })
    }

    /// Turns early stopping on: `bounds[i]` is the polygon box of plane `i` in metres (`None`:
    /// that plane never freezes a path). The box is rounded outwards by one fine LSB more than
    /// the quantisation, so it is conservative. Every problem is reported at once.
    pub fn with_early_stop(
        mut self,
        stop: EarlyStop,
        bounds: &[Option<BoundsM>],
    ) -> Result<FixedIpc, FixedError> {
        let mut problems = Vec::new();
        if bounds.len() != self.planes.len() {
            problems.push(format!(
                "{} planes but {} early-stopping boxes",
                self.planes.len(),
                bounds.len()
            ));
        }
        if stop.min_rounds == 0 {
            problems.push("early stopping: min_rounds must be at least 1".into());
        }
        if stop.displacement_shift > EarlyStop::MAX_SHIFT {
            problems.push(format!(
                "early stopping: displacement_shift {} exceeds {}",
                stop.displacement_shift,
                EarlyStop::MAX_SHIFT
            ));
        }
        let margin = i64::from(stop.margin_lsb);
        let mut boxes = Vec::with_capacity(bounds.len());
        for (i, b) in bounds.iter().enumerate() {
            let Some([min, max]) = b else {
                boxes.push(FineBox::UNBOUNDED);
                continue;
            };
            let mut fb = FineBox::UNBOUNDED;
            for a in 0..3 {
                if min[a].partial_cmp(&max[a]).is_none_or(|o| o.is_gt()) {
                    problems.push(format!("plane {i}: box min > max (or NaN) on axis {a}"));
                    continue;
                }
                match (FineCoord::quantize(min[a]), FineCoord::quantize(max[a])) {
                    (Ok(lo), Ok(hi)) => {
                        fb.lo[a] = lo.0 - 1 - margin;
                        fb.hi[a] = hi.0 + 1 + margin;
                    }
                    (Err(e), _) | (_, Err(e)) => problems.push(format!("plane {i} box: {e}")),
                }
            }
            boxes.push(fb);
        }
        if !problems.is_empty() {
            return Err(FixedError::InvalidInput { problems });
        }
        self.early_stop = Some((stop, boxes));
        Ok(self)
    }

    /// Early-stopping settings and the widened box of every plane, if on.
    pub fn early_stop(&self) -> Option<(&EarlyStop, &[FineBox])> {
        self.early_stop.as_ref().map(|(s, b)| (s, b.as_slice()))
    }

    /// The quantised planes.
    pub fn planes(&self) -> &[FixedPlane] {
        &self.planes
    }

    /// Number of candidate paths.
    pub fn num_paths(&self) -> usize {
        self.paths.len()
    }

    /// Plane indices of path `p`, TX side first.
    pub fn path_planes(&self, p: usize) -> &[u32] {
        &self.paths[p].planes
    }

    /// Quantised initial points of path `p`.
    pub fn init_points(&self, p: usize) -> &[FinePoint] {
        &self.paths[p].init
    }

    /// Convergence threshold on the round displacement, fine LSB (1/256 mm).
    pub fn threshold_lsb(&self) -> u32 {
        self.threshold_lsb
    }

    /// Default round budget per path.
    pub fn max_rounds(&self) -> u32 {
        self.max_rounds
    }

    /// Runs every path with TX/RX in metres and the default budget.
    pub fn run(&self, tx_m: [f64; 3], rx_m: [f64; 3]) -> Result<Vec<PathResult>, FixedError> {
        let tx = quantize_point(tx_m)?;
        let rx = quantize_point(rx_m)?;
        self.check_terminal("TX", tx)?;
        self.check_terminal("RX", rx)?;
        Ok(self.run_fixed(tx, rx, None))
    }

    /// Runs every path with TX/RX as millimetre bus words (which must fit the coordinate word:
    /// [`FixedIpc::check_terminal`]); `budgets[p]` overrides the round budget of path
    /// `p` (the accelerator's budget is the number of rounds its schedule holds for `p`).
    pub fn run_fixed(
        &self,
        tx: FixedPoint,
        rx: FixedPoint,
        budgets: Option<&[u32]>,
    ) -> Vec<PathResult> {
        (0..self.paths.len())
            .map(|p| {
                let budget = budgets
                    .and_then(|b| b.get(p).copied())
                    .unwrap_or(self.max_rounds);
                self.run_path(p, tx, rx, budget)
            })
            .collect()
    }

    /// Runs path `p` for at most `budget` rounds.
    pub fn run_path(&self, p: usize, tx: FixedPoint, rx: FixedPoint, budget: u32) -> PathResult {
        let path = &self.paths[p];
        let tx = tx.map(FineCoord::from_coord);
        let rx = rx.map(FineCoord::from_coord);
        let mut points = path.init.clone();
        let n = points.len();
        let mut result = PathResult {
            points: Vec::new(),
            points_m: Vec::new(),
            rounds: 0,
            displacement_lsb: 0,
            converged: false,
            zero_sum: false,
            overflow: false,
            left_bounds: false,
        };
        let phases = self.order.phases() as usize;
        for _ in 0..budget {
            // Phase h updates points h, h + phases, ...: from the values of the round so far
            // (`next`), whose points are the previous round's until their phase comes.
            let mut next = points.clone();
            let mut disp = 0;
            let mut outside = false;
            let check = self
                .early_stop
                .as_ref()
                .filter(|(s, _)| result.rounds + 1 >= s.min_rounds);
            for i in (0..phases).flat_map(|h| (h..n).step_by(phases)) {
                // A phase's points are not neighbours of each other (Jacobi: the one phase
                // reads the previous round), so the neighbours' values are those before it.
                let neighbour = |j: usize| {
                    if j % phases == i % phases {
                        points[j]
                    } else {
                        next[j]
                    }
                };
                let prev = if i == 0 { tx } else { neighbour(i - 1) };
                let follow = if i + 1 == n { rx } else { neighbour(i + 1) };
                let plane = &self.planes[path.planes[i] as usize];
                let trace = intersection_point_in(plane, prev, follow, self.coord_bits);
                result.zero_sum |= trace.proportion.zero_sum;
                result.overflow |= trace.overflow;
                disp = disp.max(displacement_linf(trace.point, points[i]));
                if let Some((stop, boxes)) = check {
                    let l1: u64 = (0..3)
                        .map(|a| (trace.point[a].0 - points[i][a].0).unsigned_abs())
                        .sum();
                    outside |= boxes[path.planes[i] as usize].outside(
                        trace.point,
                        l1,
                        stop.displacement_shift,
                    );
                }
                next[i] = trace.point;
            }
            points = next;
            result.rounds += 1;
            result.displacement_lsb = disp;
            if result.zero_sum || result.overflow {
                break;
            }
            if outside {
                result.left_bounds = true;
                break;
            }
            if disp <= u64::from(self.threshold_lsb) {
                result.converged = true;
                break;
            }
        }
        result.points_m = points.iter().map(|&q| dequantize_fine_point(q)).collect();
        result.points = points;
        result
    }
}
