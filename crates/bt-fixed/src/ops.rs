//! The arithmetic of one processing element (Algorithm 2 with Algorithm 3 inside).

use crate::{FineCoord, FinePoint, FixedPlane, NORMAL_FRAC, round_shift};

/// Guard (fraction) bits carried by the four registers of Algorithm 3 below the millimetre LSB.
///
/// Floor halving of `L_p` loses < 1 guard LSB per iteration, so the accumulated truncation
/// error of `B_p` stays below `PROPORTION_ITERATIONS / 2^GUARD_BITS` = 0.0005 LSB; the decision
/// error term `|l|·2i/((m+n)·2^G)` of [`halving_proportion`] is 0.02 LSB for |l| = 20 m,
/// m + n = 1 m. (All Algorithm 3 quantities are in fine LSB = 1/256 mm.)
pub const GUARD_BITS: u32 = 16;

/// Maximal number of halving iterations of Algorithm 3 in the full 40-bit design (the hardware
/// always spends this many cycles; iterations after `L` reaches 0 are frozen, as the paper's
/// `while L > 0`). The ratio resolution is then `2^-(PROPORTION_ITERATIONS+1)` ≈ 1.2e-10 when
/// `m + n` is large. A narrower coordinate word needs fewer ([`Widths::iterations`]).
pub const PROPORTION_ITERATIONS: u32 = 32;

/// Bit widths of every intermediate, shared with the RTL generator (`bt-hls` declares its wires
/// with exactly these widths). `tests/it/widths.rs` proves, over the whole input domain (any 32-bit
/// coordinates, any unit normal, any 32-bit offset), that no value leaves its width.
pub mod width {
    use super::GUARD_BITS;
    /// Fine coordinate word (signed, mm × 2^8): |s| ≤ 2^39.
    pub const COORD: u32 = crate::FineCoord::BITS;
    /// Accumulator `Σ n_k s_k − offset·2^30 + 2^29` (signed): |·| < 2^70.45.
    pub const DOT_ACC: u32 = 72;
    /// Signed distance `d`, fine units (signed): |d| < 2^40.45.
    pub const DISTANCE: u32 = 42;
    /// Accumulator `d · n_k + 2^29` (signed): |·| < 2^70.45.
    pub const PROJ_ACC: u32 = 72;
    /// Projection `t_k`, fine units (signed): |t| < 2^40.9.
    pub const PROJECTION: u32 = 42;
    /// `t_next − t_prev`, fine units (signed).
    pub const DELTA: u32 = 43;
    /// `m = |d_prev|`, `n = |d_next|` (unsigned).
    pub const ABS_DISTANCE: u32 = 41;
    /// `m + n` (unsigned).
    pub const DISTANCE_SUM: u32 = 42;
    /// Register `L` of Algorithm 3 (unsigned, guard bits included).
    pub const HALF_SUM: u32 = DISTANCE_SUM + GUARD_BITS - 1;
    /// Register `B` and the compared `m · 2^G` (unsigned): B ∈ [0, 2·L₀].
    pub const SEARCH: u32 = DISTANCE_SUM + GUARD_BITS;
    /// Register `L_p` (signed, guard bits included).
    pub const HALF_DELTA: u32 = DELTA + GUARD_BITS - 1;
    /// Register `B_p` (signed): |B_p| ≤ 2|L_p₀| + iterations, plus rounding headroom.
    pub const ACC_DELTA: u32 = DELTA + GUARD_BITS + 1;
    /// Rounded proportion `round(B_p / 2^G)`, fine units (signed).
    pub const OFFSET: u32 = DELTA + 1;
    /// `t_prev + offset` before saturation (signed).
    pub const SUM_POINT: u32 = 44;
    /// Per-round displacement `|s_new − s_old|` per component (unsigned).
    pub const DISPLACEMENT: u32 = COORD;
    /// The RTL's search register `E = B − m·2^G` (signed), which replaces the pair `B`,
    /// `m·2^G` and the comparator (`B < m·2^G` ⇔ `E < 0`): `E ∈ (−2^SEARCH, 2^SEARCH)`.
    pub const SEARCH_DIFF: u32 = SEARCH + 1;
    /// The RTL's fused output accumulator `t_prev·2^G + 2^(G−1) + B_p` (signed, kept modulo
    /// 2^POINT_ACC): `acc >> G = t_prev + round_half_up(B_p / 2^G)` = the unsaturated point,
    /// which fits [`SUM_POINT`] bits, so the wrap-around of intermediate values is harmless.
    pub const POINT_ACC: u32 = SUM_POINT + GUARD_BITS;
    /// Iteration counter of Algorithm 3 (unsigned).
    pub const ITERATION: u32 = 6;

    /// `v` fits a two's-complement word of `bits` bits (`1 ≤ bits ≤ 127`).
    pub fn fits_signed(v: i128, bits: u32) -> bool {
        let half = 1i128 << (bits - 1);
        (-half..half).contains(&v)
    }

    /// `v` fits an unsigned word of `bits` bits (`bits ≤ 127`).
    pub fn fits_unsigned(v: i128, bits: u32) -> bool {
        (0..1i128 << bits).contains(&v)
    }
}

/// The datapath widths of one design whose coordinate word has `coord` bits instead of
/// [`width::COORD`] (40): every intermediate of Algorithm 2 and 3 is a fixed combination of
/// coordinates and plane offsets (sums, projections with ‖n‖ ≤ 1, halvings), so its bound
/// scales with theirs and each width shrinks by the same `40 − coord` bits. A room a few tens
/// of metres across needs about 24 bits (`bt_accel` sizes it from the room's extent,
/// [`coord_bits_for`]): about a third less logic per PE. Valid when every coordinate and
/// plane offset fits `coord` bits ([`crate::FixedIpc::with_coord_bits`] checks);
/// `tests/it/widths.rs` and `tests/it/rtl_form.rs` prove it for several `coord`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[allow(missing_docs)] // one field per constant of [`width`], documented there
pub struct Widths {
    pub coord: u32,
    pub dot_acc: u32,
    pub distance: u32,
    pub proj_acc: u32,
    pub projection: u32,
    pub delta: u32,
    pub abs_distance: u32,
    pub distance_sum: u32,
    pub half_sum: u32,
    pub search: u32,
    pub half_delta: u32,
    pub acc_delta: u32,
    pub offset: u32,
    pub sum_point: u32,
    pub displacement: u32,
    pub search_diff: u32,
    pub point_acc: u32,
    /// Halving iterations of Algorithm 3: `min(PROPORTION_ITERATIONS, coord)`. After `i`
    /// iterations the search leaves an error of at most `|l|·2^-(i+1)` in the offset, and a
    /// `coord`-bit word bounds `|l| = |t_next − t_prev| < 2^coord`: `coord` iterations give
    /// the word's resolution (≤ ½ LSB), more would refine below it.
    pub iterations: u32,
}

impl Widths {
    /// The full 40-bit design: exactly the constants of [`width`].
    pub const FULL: Widths = Widths::for_coord(width::COORD);

    /// Narrowest coordinate word accepted, bits (the bus reads `point[coord-1:8]`, and the
    /// early-stopping comparisons are 48 bits wide).
    pub const MIN_COORD: u32 = 16;

    /// The widths for a `coord`-bit coordinate word ([`Widths::MIN_COORD`] ≤ `coord` ≤
    /// [`width::COORD`]; other values are clamped into that range).
    pub const fn for_coord(coord: u32) -> Widths {
        let coord = if coord < Self::MIN_COORD {
            Self::MIN_COORD
        } else if coord > width::COORD {
            width::COORD
        } else {
            coord
        };
        let s = width::COORD - coord;
        Widths {
            coord,
            dot_acc: width::DOT_ACC - s,
            distance: width::DISTANCE - s,
            proj_acc: width::PROJ_ACC - s,
            projection: width::PROJECTION - s,
            delta: width::DELTA - s,
            abs_distance: width::ABS_DISTANCE - s,
            distance_sum: width::DISTANCE_SUM - s,
            half_sum: width::HALF_SUM - s,
            search: width::SEARCH - s,
            half_delta: width::HALF_DELTA - s,
            acc_delta: width::ACC_DELTA - s,
            offset: width::OFFSET - s,
            sum_point: width::SUM_POINT - s,
            displacement: width::DISPLACEMENT - s,
            search_diff: width::SEARCH_DIFF - s,
            point_acc: width::POINT_ACC - s,
            iterations: if coord < PROPORTION_ITERATIONS {
                coord
            } else {
                PROPORTION_ITERATIONS
            },
        }
    }

    /// Smallest and largest value of the coordinate word, fine LSB.
    pub const fn coord_range(&self) -> (i64, i64) {
        (-(1 << (self.coord - 1)), (1 << (self.coord - 1)) - 1)
    }

    /// Whether every component of `p` fits the coordinate word.
    pub fn holds(&self, p: &[FineCoord]) -> bool {
        let (lo, hi) = self.coord_range();
        p.iter().all(|c| (lo..=hi).contains(&c.0))
    }
}

/// Bits of headroom [`coord_bits_for`] keeps above a room's extent: IPC points may wander
/// this far (4×) outside before the coordinate saturates and the path is dropped as degenerate.
pub const COORD_HEADROOM_BITS: u32 = 2;

/// The coordinate word for a room whose coordinates, plane offsets, terminals and start points
/// all lie within `max_abs_m` metres of the origin: their magnitude in fine LSB, a sign bit and
/// [`COORD_HEADROOM_BITS`], clamped to [`Widths::MIN_COORD`]..=[`width::COORD`]. A non-finite
/// or out-of-range extent gives the full width.
pub fn coord_bits_for(max_abs_m: f64) -> u32 {
    match FineCoord::quantize(max_abs_m.abs()) {
        Ok(fine) => {
            let magnitude = 64 - (fine.0.unsigned_abs()).leading_zeros();
            (magnitude + 1 + COORD_HEADROOM_BITS).clamp(Widths::MIN_COORD, width::COORD)
        }
        Err(_) => width::COORD,
    }
}

use width::fits_signed;

/// Signed distance of `s` to the plane in fine units (mm × 2^8): `round_half_up((Σ n_k·s_k − offset·2^30) / 2^30)`,
/// the products by CSD shift-add, accumulated at full precision, one rounding shift.
/// Positive on the side the normal points to.
///
/// Verilog twin: `bt_pe_<i>`: `dot` = the per-component CSD networks `net_k` (sums of
/// `±(x_k <<< shift)`, shared by all four products of one evaluation) plus the folded constant
/// `2^29 − offset·2^30`, the constant low bits below the lowest digit dropped; `d` = its slice
/// from bit 30 up.
pub fn signed_distance(plane: &FixedPlane, s: FinePoint) -> i64 {
    let mut acc: i128 = plane
        .normal
        .iter()
        .zip(s)
        .map(|(n, c)| n.csd().mul(c.0))
        .sum();
    acc -= i128::from(plane.offset.0) << NORMAL_FRAC;
    let d = round_shift(acc, NORMAL_FRAC);
    debug_assert!(fits_signed(acc + (1 << (NORMAL_FRAC - 1)), width::DOT_ACC));
    debug_assert!(fits_signed(d, width::DISTANCE));
    d as i64
}

/// Orthogonal projection onto the plane in fine units, per component
/// `t_k = s_k − round_half_up(d · n_k / 2^30)`, `d` from [`signed_distance`].
///
/// Verilog twin: `bt_pe_<i>`: `t_k = a_k − p_round_k[..:30]` where `p_round_k` is the shared
/// network `net_k` applied to `d_prev` (step 2; `d_next` and `b_k` in step 3) plus `2^29`.
pub fn project(plane: &FixedPlane, s: FinePoint, d: i64) -> [i64; 3] {
    std::array::from_fn(|k| {
        let acc = plane.normal[k].csd().mul(d);
        debug_assert!(fits_signed(acc + (1 << (NORMAL_FRAC - 1)), width::PROJ_ACC));
        let t = s[k].0 - round_shift(acc, NORMAL_FRAC) as i64;
        debug_assert!(fits_signed(i128::from(t), width::PROJECTION));
        t
    })
}

/// Result of Algorithm 3 on the three components of `l = t_next − t_prev`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Proportion {
    /// `≈ l_k · m / (m + n)` per component, fine LSB (rounded half up from the guard bits).
    pub offset: [i64; 3],
    /// `m + n == 0`: no halving happened and the result is `l / 2` (midpoint).
    pub zero_sum: bool,
    /// Halving iterations that changed the registers (≤ [`PROPORTION_ITERATIONS`]).
    pub iterations: u32,
}

/// Algorithm 3 (halving comparison), exactly as the paper writes it, on `G = GUARD_BITS`
/// guard bits, the three components sharing one decision sequence:
///
/// ```text
/// L ← (m+n)/2; B ← L; L_p ← l/2; B_p ← L_p          (all scaled by 2^G: exact)
/// repeat PROPORTION_ITERATIONS times, frozen once L = 0 (the paper's `while L > 0`):
///     L ← ⌊L/2⌋; L_p ← ⌊L_p/2⌋                          (arithmetic shift: floor)
///     if B < m·2^G: B ← B + L; B_p ← B_p + L_p  else: B ← B − L; B_p ← B_p − L_p
/// return round_half_up(B_p / 2^G)
/// ```
///
/// Rounding and bias: iterated floor halving equals `⌊L_p₀ / 2^i⌋`, so each step is low by
/// < 1 guard LSB; `B_p` carries at most `i` guard LSBs of truncation error (bias towards −∞)
/// after `i` iterations, then one round-half-up. `B` carries the same kind of error, so the
/// decision sequence is a binary search on `m/(m+n)` perturbed by ≤ `i / ((m+n)·2^G)`. The
/// proved bound (`tests/it/algorithm3.rs`), with `i` = iterations run and `L_i` the final `L`:
///
/// `|out − l·m/(m+n)| ≤ 1/2 + i/2^G + |l|·(L_i/((m+n)·2^G) + 2i/((m+n)·2^G))`
///
/// where `L_i/((m+n)·2^G) ≤ 2^-(i+1)`, and `L_i = 0` when the search stopped on `L = 0` (its
/// resolution then being set by `m + n`, 65536 times finer than the LSB quantisation of `m, n`).
/// Degenerate inputs are values: `m = 0` gives `≈ 0` (the point stays at `t_prev`), `n = 0`
/// gives `≈ l`, `m + n = 0` gives `l/2` with `zero_sum` set. `m + n` cannot overflow: both are
/// below 2^32.45, the sum register is [`width::DISTANCE_SUM`] = 34 bits.
///
/// Verilog twin: the `bt_pe_<i>` registers `r_l` (`L`), `r_e` (`E = B − m·2^G`, whose sign is
/// the comparison), `b_{x,y,z}` (`L_p`) and `a_{x,y,z}` (`t_prev·2^G + 2^(G−1) + B_p`, see
/// [`width::POINT_ACC`]), one iteration per clock; `tests/it/rtl_form.rs` proves the re-arrangement
/// exact.
pub fn halving_proportion(m: u64, n: u64, l: [i64; 3]) -> Proportion {
    halving_proportion_in(m, n, l, PROPORTION_ITERATIONS)
}

/// [`halving_proportion`] with at most `iterations` halving steps (a narrower design's
/// [`Widths::iterations`]); the bound above holds with `i` ≤ `iterations`.
pub fn halving_proportion_in(m: u64, n: u64, l: [i64; 3], iterations: u32) -> Proportion {
    let max_iterations = iterations;
    let sum = u128::from(m) + u128::from(n);
    let mut big_l: u128 = sum << (GUARD_BITS - 1);
    let mut b = big_l;
    let target = u128::from(m) << GUARD_BITS;
    let mut lp: [i128; 3] = l.map(|x| i128::from(x) << (GUARD_BITS - 1));
    let mut bp = lp;
    let mut iterations = 0;
    for _ in 0..max_iterations {
        if big_l == 0 {
            break;
        }
        iterations += 1;
        big_l >>= 1;
        let up = b < target;
        for k in 0..3 {
            lp[k] >>= 1;
            if up {
                bp[k] += lp[k];
            } else {
                bp[k] -= lp[k];
            }
        }
        if up {
            b += big_l;
        } else {
            b -= big_l;
        }
        debug_assert!(b >> width::SEARCH == 0);
    }
    debug_assert!(
        bp.iter()
            .all(|&v| fits_signed(v + (1 << (GUARD_BITS - 1)), width::ACC_DELTA))
    );
    Proportion {
        offset: bp.map(|v| round_shift(v, GUARD_BITS) as i64),
        zero_sum: sum == 0,
        iterations,
    }
}

/// Every intermediate of one PE evaluation (Algorithm 2), for tests and debugging.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PeTrace {
    /// Signed distance of the leading point, fine LSB.
    pub d_prev: i64,
    /// Signed distance of the following point, fine LSB.
    pub d_next: i64,
    /// Projection of the leading point, fine LSB.
    pub t_prev: [i64; 3],
    /// Projection of the following point, fine LSB.
    pub t_next: [i64; 3],
    /// `m = |d_prev|`, fine LSB.
    pub m: u64,
    /// `n = |d_next|`, fine LSB.
    pub n: u64,
    /// `t_next − t_prev`, fine LSB.
    pub delta: [i64; 3],
    /// Algorithm 3 output.
    pub proportion: Proportion,
    /// `t_prev + offset` before saturation, fine LSB.
    pub unsaturated: [i64; 3],
    /// The new intersection point (saturated to the coordinate word, 40 bits by default).
    pub point: FinePoint,
    /// Some component did not fit the coordinate word and was saturated.
    pub overflow: bool,
}

/// Algorithm 2 in fixed point: the new intersection point on `plane` from the leading point
/// `prev` and following point `next`, with the proportion applied component-wise
/// (`s = t_prev + (m/(m+n))·(t_next − t_prev)`: no norm, no square root).
///
/// Verilog twin: one `bt_pe_<i>` evaluation (`load`, `start` → `s_sum`, `zero_sum`) followed by
/// `bt_top`'s saturation after its PE select (`sat_{x,y,z}`, `pe_sel_ov`).
pub fn intersection_point(plane: &FixedPlane, prev: FinePoint, next: FinePoint) -> PeTrace {
    intersection_point_in(plane, prev, next, width::COORD)
}

/// [`intersection_point`] of a design with a `coord_bits`-bit coordinate word ([`Widths`]):
/// the point saturates (and `overflow` is raised) at that width instead of 40 bits.
pub fn intersection_point_in(
    plane: &FixedPlane,
    prev: FinePoint,
    next: FinePoint,
    coord_bits: u32,
) -> PeTrace {
    let d_prev = signed_distance(plane, prev);
    let d_next = signed_distance(plane, next);
    let t_prev = project(plane, prev, d_prev);
    let t_next = project(plane, next, d_next);
    let m = d_prev.unsigned_abs();
    let n = d_next.unsigned_abs();
    let delta: [i64; 3] = std::array::from_fn(|k| t_next[k] - t_prev[k]);
    let wd = Widths::for_coord(coord_bits);
    let proportion = halving_proportion_in(m, n, delta, wd.iterations);
    let unsaturated: [i64; 3] = std::array::from_fn(|k| t_prev[k] + proportion.offset[k]);
    let mut overflow = false;
    let (lo, hi) = wd.coord_range();
    let point = unsaturated.map(|v| {
        let clamped = v.clamp(lo, hi);
        overflow |= clamped != v;
        FineCoord(clamped)
    });
    PeTrace {
        d_prev,
        d_next,
        t_prev,
        t_next,
        m,
        n,
        delta,
        proportion,
        unsaturated,
        point,
        overflow,
    }
}

/// Per-round displacement of one point: L∞ norm `max_k |a_k − b_k|` in fine LSB (1/256 mm).
///
/// Verilog twin: `bt_top`'s write-back stage (`wb_disp`), compared against the threshold.
pub fn displacement_linf(a: FinePoint, b: FinePoint) -> u64 {
    (0..3)
        .map(|k| (a[k].0 - b[k].0).unsigned_abs())
        .max()
        .unwrap_or(0)
}
