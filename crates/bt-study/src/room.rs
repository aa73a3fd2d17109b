//! The room generator of Table I: L-, T-, U-shaped and convex closed contours inside a
//! 10 m × 10 m square, each with one vertex moving along a trajectory over the time steps
//! (Fig. 5), and TX/RX placed at random inside.
//!
//! Edge counts: a true L has 6 edges and T/U have 8, Table I asks for L 4-6 and T/U 8-10:
//! - L with 5 edges: the far corner of one arm is dropped, so that arm ends in a slanted wall;
//!   with 4 edges the far corners of both arms are dropped, leaving a dart (a concave
//!   quadrilateral whose reflex vertex is the L's inner corner);
//! - T and U with 9 or 10 edges: one or two convex corners are chamfered (cut by a short
//!   diagonal wall, as in real rooms);
//! - convex polygons: 4-10 vertices on an ellipse at random angles.
//!
//! Every contour is counter-clockwise, simple (no two edges meet except neighbours at their
//! shared vertex), has edges of at least [`MIN_EDGE`] and corners turning by at least
//! [`MIN_TURN_DEG`] (no two consecutive walls almost collinear), and stays inside the square.
//! TX and RX keep at least [`CLEARANCE`] from every wall at every time step.

use crate::StudyError;
/// Simplicity and strict (even-odd) containment of a contour: the geometry kernel's predicates.
pub use bt_geom::poly2::{contains, is_simple};
use bt_geom::poly2::{segment_distance_sq, signed_area};
use bt_geom::{Real, Vec2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// Side of the square the rooms live in, metres (the paper's "10 × 10").
pub const SQUARE: Real = 10.0;
/// Minimum distance of TX and RX from every wall, metres.
pub const CLEARANCE: Real = 0.3;
/// Minimum wall length, metres.
pub const MIN_EDGE: Real = 0.3;
/// Minimum turning angle at a corner, degrees (walls closer to collinear are rejected).
pub const MIN_TURN_DEG: Real = 3.0;
/// Minimum distance between TX and RX, metres.
pub const MIN_TERMINAL_DISTANCE: Real = 1.0;
/// Margin kept between the contour and the border of the square, metres.
const BORDER: Real = 0.1;
/// Displacement of the moving vertex per time step: uniform in this range, metres.
const STEP_RANGE: (Real, Real) = (0.15, 0.35);
/// A step that would break the contour is halved up to this many times, then skipped.
const MAX_HALVINGS: u32 = 6;

/// Room shapes of Table I.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Shape {
    /// L-shaped, 4-6 edges.
    L,
    /// T-shaped, 8-10 edges.
    T,
    /// U-shaped, 8-10 edges.
    U,
    /// Convex polygon, 4-10 edges.
    Convex,
}

impl Shape {
    /// All shapes, in the order rooms cycle through them.
    pub const ALL: [Shape; 4] = [Shape::L, Shape::T, Shape::U, Shape::Convex];

    /// Allowed edge counts (Table I).
    pub fn edge_range(self) -> (usize, usize) {
        match self {
            Shape::L => (4, 6),
            Shape::T | Shape::U => (8, 10),
            Shape::Convex => (4, 10),
        }
    }

    /// Name used in outputs: `L`, `T`, `U`, `convex`.
    pub fn name(self) -> &'static str {
        match self {
            Shape::L => "L",
            Shape::T => "T",
            Shape::U => "U",
            Shape::Convex => "convex",
        }
    }
}

/// Shape and edge count of room `index`: shapes cycle L, T, U, convex (so 100 rooms are 25 of
/// each) and within a shape the edge counts cycle through its range (even coverage).
pub fn plan(index: usize) -> (Shape, usize) {
    let shape = Shape::ALL[index % 4];
    let (lo, hi) = shape.edge_range();
    (shape, lo + (index / 4) % (hi - lo + 1))
}

/// A generated room with its motion.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Room {
    /// Room index in the study.
    pub index: usize,
    /// Shape family.
    pub shape: Shape,
    /// Number of edges (walls).
    pub edges: usize,
    /// Index of the moving vertex in every contour.
    pub moving_vertex: usize,
    /// The contour at each time step: counter-clockwise vertices, metres.
    pub contours: Vec<Vec<Vec2>>,
    /// Transmitter, metres (fixed over time).
    pub tx: Vec2,
    /// Receiver, metres (fixed over time).
    pub rx: Vec2,
}

/// Generate room `index` of a study with seed `seed`: shape and edges from [`plan`], `steps`
/// time steps (at least 1). Deterministic: room `index` depends only on `seed` and `index`
/// (its own ChaCha8 stream).
pub fn generate(seed: u64, index: usize, steps: usize) -> Result<Room, StudyError> {
    let (shape, edges) = plan(index);
    generate_shape(seed, index, shape, edges, steps)
}

/// Like [`generate`] with an explicit shape and edge count (which must be in the shape's range).
pub fn generate_shape(
    seed: u64,
    index: usize,
    shape: Shape,
    edges: usize,
    steps: usize,
) -> Result<Room, StudyError> {
    let (lo, hi) = shape.edge_range();
    if !(lo..=hi).contains(&edges) {
        return Err(StudyError::Generation {
            room: index,
            message: format!(
                "{} rooms have {lo} to {hi} edges, {edges} requested",
                shape.name()
            ),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index as u64);
    for _ in 0..200 {
        let contour = match shape {
            Shape::L => l_shape(&mut rng, edges),
            Shape::T => {
                let t = t_shape(&mut rng);
                chamfered(&mut rng, t, edges)
            }
            Shape::U => {
                let u = u_shape(&mut rng);
                chamfered(&mut rng, u, edges)
            }
            Shape::Convex => convex(&mut rng, edges),
        };
        let contour = place(&mut rng, contour);
        if !is_valid(&contour) {
            continue;
        }
        let Some((tx, rx)) = terminals(&mut rng, &contour) else {
            continue;
        };
        let (moving_vertex, contours) = trajectory(&mut rng, contour, steps.max(1), tx, rx);
        return Ok(Room {
            index,
            shape,
            edges,
            moving_vertex,
            contours,
            tx,
            rx,
        });
    }
    Err(StudyError::Generation {
        room: index,
        message: "no valid contour in 200 attempts".into(),
    })
}

fn v(x: Real, y: Real) -> Vec2 {
    Vec2::new(x, y)
}

/// Outer box of the rectilinear shapes, metres.
fn outer(rng: &mut ChaCha8Rng, min_w: Real) -> (Real, Real) {
    let max = SQUARE - 4.0 * BORDER;
    (rng.random_range(min_w..max), rng.random_range(6.0..max))
}

fn l_shape(rng: &mut ChaCha8Rng, edges: usize) -> Vec<Vec2> {
    let (w, h) = outer(rng, 6.0);
    let c = w * rng.random_range(0.35..0.65);
    let b = h * rng.random_range(0.35..0.65);
    let mut l = vec![v(0.0, 0.0), v(w, 0.0), v(w, b), v(c, b), v(c, h), v(0.0, h)];
    // Drop the far corner of the vertical arm (5 edges), then of the horizontal one (4).
    if edges <= 5 {
        l.remove(4);
    }
    if edges <= 4 {
        l.remove(1);
    }
    l
}

fn t_shape(rng: &mut ChaCha8Rng) -> Vec<Vec2> {
    let (w, h) = outer(rng, 7.0);
    let s = w * rng.random_range(0.3..0.5);
    let x1 = rng.random_range(1.0..w - s - 1.0);
    let y1 = h * rng.random_range(0.45..0.65);
    vec![
        v(x1, 0.0),
        v(x1 + s, 0.0),
        v(x1 + s, y1),
        v(w, y1),
        v(w, h),
        v(0.0, h),
        v(0.0, y1),
        v(x1, y1),
    ]
}

fn u_shape(rng: &mut ChaCha8Rng) -> Vec<Vec2> {
    let (w, h) = outer(rng, 7.0);
    let w1 = w * rng.random_range(0.25..0.38);
    let w2 = w * rng.random_range(0.25..0.38);
    let y = h * rng.random_range(0.3..0.5);
    vec![
        v(0.0, 0.0),
        v(w, 0.0),
        v(w, h),
        v(w - w2, h),
        v(w - w2, y),
        v(w1, y),
        v(w1, h),
        v(0.0, h),
    ]
}

/// Cut `edges - len` distinct convex corners of `contour` by short diagonal walls.
fn chamfered(rng: &mut ChaCha8Rng, contour: Vec<Vec2>, edges: usize) -> Vec<Vec2> {
    let n = contour.len();
    let mut convex: Vec<usize> = (0..n).filter(|&i| turn(&contour, i) > 0.0).collect();
    let mut cut = Vec::new();
    for _ in n..edges {
        let k = rng.random_range(0..convex.len());
        cut.push(convex.swap_remove(k));
    }
    let mut out = Vec::with_capacity(edges);
    for (i, &p) in contour.iter().enumerate() {
        if !cut.contains(&i) {
            out.push(p);
            continue;
        }
        let prev = contour[(i + n - 1) % n];
        let next = contour[(i + 1) % n];
        // At most 0.35 of either wall, so two chamfers on one wall leave 0.3 of it.
        let e: Real = rng
            .random_range(0.4..0.9_f64)
            .min(0.35 * p.distance(prev))
            .min(0.35 * p.distance(next));
        out.push(p + e * (prev - p).normalize());
        out.push(p + e * (next - p).normalize());
    }
    out
}

fn convex(rng: &mut ChaCha8Rng, edges: usize) -> Vec<Vec2> {
    use std::f64::consts::TAU;
    let a = rng.random_range(3.0..4.7);
    let b = rng.random_range(3.0..4.7);
    let gaps: Vec<Real> = (0..edges).map(|_| rng.random_range(0.5..1.5)).collect();
    let total: Real = gaps.iter().sum();
    let mut angle = rng.random_range(0.0..TAU);
    let mut out = Vec::with_capacity(edges);
    for g in gaps {
        out.push(v(a + a * angle.cos(), b + b * angle.sin()));
        angle += TAU * g / total;
    }
    out
}

/// Translate a shape into the square, then rotate it by a multiple of 90° about the square's
/// centre and mirror it at random (keeping the counter-clockwise order).
fn place(rng: &mut ChaCha8Rng, mut contour: Vec<Vec2>) -> Vec<Vec2> {
    let (lo, hi) = bounds(&contour);
    let size = hi - lo;
    let slack = (Vec2::splat(SQUARE - 2.0 * BORDER) - size).max(Vec2::ZERO);
    let offset = Vec2::new(
        BORDER + rng.random_range(0.0..=slack.x),
        BORDER + rng.random_range(0.0..=slack.y),
    ) - lo;
    let centre = Vec2::splat(0.5 * SQUARE);
    let quarter_turns = rng.random_range(0..4);
    let mirror = rng.random_bool(0.5);
    for p in &mut contour {
        let mut q = *p + offset - centre;
        for _ in 0..quarter_turns {
            q = q.perp();
        }
        if mirror {
            q.x = -q.x;
        }
        *p = q + centre;
    }
    if mirror {
        contour.reverse();
    }
    contour
}

fn bounds(points: &[Vec2]) -> (Vec2, Vec2) {
    points.iter().fold(
        (Vec2::splat(Real::INFINITY), Vec2::splat(Real::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// Signed turn at vertex `i` (cross product of the incoming and outgoing edges): positive for
/// a convex corner of a counter-clockwise contour.
fn turn(contour: &[Vec2], i: usize) -> Real {
    let n = contour.len();
    let (a, b, c) = (contour[(i + n - 1) % n], contour[i], contour[(i + 1) % n]);
    (b - a).perp_dot(c - b)
}

/// All the generator's invariants: counter-clockwise, simple, walls at least [`MIN_EDGE`]
/// long, corners turning by at least [`MIN_TURN_DEG`], inside the square with a margin.
pub fn is_valid(contour: &[Vec2]) -> bool {
    let n = contour.len();
    let min_sin = MIN_TURN_DEG.to_radians().sin();
    let (lo, hi) = bounds(contour);
    n >= 3
        && contour.iter().all(|p| p.is_finite())
        && lo.min_element() >= 0.5 * BORDER
        && hi.max_element() <= SQUARE - 0.5 * BORDER
        && signed_area(contour) > 0.0
        && (0..n).all(|i| contour[i].distance(contour[(i + 1) % n]) >= MIN_EDGE)
        && (0..n).all(|i| {
            let (a, b, c) = (contour[(i + n - 1) % n], contour[i], contour[(i + 1) % n]);
            let (u, w) = ((b - a).normalize(), (c - b).normalize());
            u.perp_dot(w).abs() >= min_sin || u.dot(w) < 0.0
        })
        && is_simple(contour)
}

/// Distance from `p` to the nearest wall, metres.
pub fn wall_distance(contour: &[Vec2], p: Vec2) -> Real {
    let n = contour.len();
    (0..n)
        .map(|i| segment_distance_sq(p, contour[i], contour[(i + 1) % n]).sqrt())
        .fold(Real::INFINITY, Real::min)
}

/// Whether `p` is inside with at least [`CLEARANCE`] to every wall.
pub fn is_clear(contour: &[Vec2], p: Vec2) -> bool {
    contains(contour, p) && wall_distance(contour, p) >= CLEARANCE
}

fn terminals(rng: &mut ChaCha8Rng, contour: &[Vec2]) -> Option<(Vec2, Vec2)> {
    let (lo, hi) = bounds(contour);
    let pick = |rng: &mut ChaCha8Rng| {
        (0..1000)
            .map(|_| Vec2::new(rng.random_range(lo.x..hi.x), rng.random_range(lo.y..hi.y)))
            .find(|p| is_clear(contour, *p))
    };
    let tx = pick(rng)?;
    for _ in 0..100 {
        let rx = pick(rng)?;
        if rx.distance(tx) >= MIN_TERMINAL_DISTANCE {
            return Some((tx, rx));
        }
    }
    None
}

/// Vertex, direction and stride tried per room before settling for the best of them.
const TRAJECTORY_TRIES: usize = 12;

/// The moving vertex and the contour at every step. The vertex advances by a fixed stride per
/// step along a direction pointing roughly away from the room's centre (±60°), so its two
/// walls sweep new area as in Fig. 5. A step that would break an invariant (or bring a wall
/// within [`CLEARANCE`] of TX or RX) is halved until it does not; after [`MAX_HALVINGS`] the
/// vertex stays put for that step. Up to [`TRAJECTORY_TRIES`] (vertex, direction, stride)
/// choices are drawn and the first whose every step moves the full stride is taken, else the
/// one that moved farthest (vertices in a corner of the square cannot move outwards).
fn trajectory(
    rng: &mut ChaCha8Rng,
    start: Vec<Vec2>,
    steps: usize,
    tx: Vec2,
    rx: Vec2,
) -> (usize, Vec<Vec<Vec2>>) {
    let centre = start.iter().copied().sum::<Vec2>() / start.len() as Real;
    let mut best: Option<(Real, usize, Vec<Vec<Vec2>>)> = None;
    for _ in 0..TRAJECTORY_TRIES {
        let moving = rng.random_range(0..start.len());
        let outward = (start[moving] - centre).normalize_or(Vec2::X);
        let turn = rng.random_range(-1.0..1.0) * std::f64::consts::FRAC_PI_3;
        let direction = Vec2::from_angle(turn).rotate(outward);
        let stride = rng.random_range(STEP_RANGE.0..STEP_RANGE.1);
        let mut contours = Vec::with_capacity(steps);
        contours.push(start.clone());
        let mut full = true;
        while contours.len() < steps {
            let mut next = contours.last().cloned().unwrap_or_default();
            let from = next[moving];
            let mut length = stride;
            for _ in 0..=MAX_HALVINGS {
                next[moving] = from + length * direction;
                if is_valid(&next) && is_clear(&next, tx) && is_clear(&next, rx) {
                    break;
                }
                next[moving] = from;
                length *= 0.5;
            }
            full &= length == stride;
            contours.push(next);
        }
        if full {
            return (moving, contours);
        }
        let travelled = contours[contours.len() - 1][moving].distance(start[moving]);
        if best.as_ref().is_none_or(|b| travelled > b.0) {
            best = Some((travelled, moving, contours));
        }
    }
    let (_, moving, contours) = best.unwrap_or((0.0, 0, vec![start; steps]));
    (moving, contours)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_gives_25_rooms_per_shape() {
        let mut counts = std::collections::BTreeMap::new();
        for i in 0..100 {
            let (shape, edges) = plan(i);
            let (lo, hi) = shape.edge_range();
            assert!((lo..=hi).contains(&edges));
            *counts.entry(shape).or_insert(0) += 1;
        }
        assert!(counts.values().all(|&c| c == 25));
    }

    #[test]
    fn simple_polygon_checks() {
        let square = vec![v(0., 0.), v(1., 0.), v(1., 1.), v(0., 1.)];
        assert!(is_simple(&square));
        let bow = vec![v(0., 0.), v(1., 1.), v(1., 0.), v(0., 1.)];
        assert!(!is_simple(&bow));
        // A spike folding back along its own wall.
        let fold = vec![v(0., 0.), v(2., 0.), v(1., 0.), v(1., 1.)];
        assert!(!is_simple(&fold));
        // Touching a non-adjacent edge at a vertex.
        let touch = vec![v(0., 0.), v(2., 0.), v(2., 2.), v(1., 0.), v(0., 2.)];
        assert!(!is_simple(&touch));
    }

    #[test]
    fn rooms_are_deterministic_per_seed_and_index() {
        let a = generate(7, 3, 5).unwrap();
        let b = generate(7, 3, 5).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, generate(8, 3, 5).unwrap());
    }

    #[test]
    fn out_of_range_edge_count_is_an_error() {
        assert!(generate_shape(1, 0, Shape::L, 7, 2).is_err());
    }
}
