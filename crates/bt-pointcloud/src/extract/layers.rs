//! Separating parallel surfaces closer than the RANSAC band (a window pane 2 cm in front of
//! a wall, a picture on a wall, a recessed door).
//!
//! Sequential RANSAC hands every point within the distance threshold to the plane found
//! first. When two parallel surfaces are only a few noise σ apart, the first one takes the
//! near tail of the second (biasing its offset and thinning it), and the second then takes
//! the far tail of the first wherever that tail lies next to it, which adds spikes and
//! islands to its boundary. This step re-assigns the points of such a pair competitively
//! (k-planes style: each point to the nearer plane, refit, repeat) with one addition that
//! keeps it local: a point may only go to a plane that is *present around it*, i.e. at
//! least [`tol::LAYER_MIN_SHARE`] of its neighbours within the vote radius are nearer that
//! plane. A lone point of the wall's noise tail beside the window (≈ 2 % of wall points are
//! nearer the window plane) is outvoted by the wall points around it and stays with the
//! wall; a window point has window points around it and goes to the window, wherever it
//! lies within the band.
//!
//! A pair is only re-assigned when the result is two distinct layers: the planes must be
//! at least [`tol::LAYER_SEPARATION_SIGMAS`] noise σ apart, σ measured on the outer
//! (uncontested) side of each layer. Otherwise both patches stay as RANSAC left them.

use bt_geom::{Real, Vec2, Vec3};

use rayon::prelude::*;

use super::{RawPatch, frame};
use crate::linalg::fit_plane;
use crate::spatial::{KeyRanges, key_ranges};
use crate::tol;

/// Rounds of assignment and refit per pair.
const ROUNDS: usize = 4;

/// A patch takes part only with at least this many times the minimum patch size: the plane
/// of a fragment of a few dozen points is too loosely determined (degrees) for the parallel
/// and distance tests, and pairing it only reshuffles slivers.
const LAYER_MIN_POINTS_FACTOR: usize = 4;

#[derive(Clone, Copy)]
struct Layer {
    normal: Vec3,
    offset: Real,
    centroid: Vec3,
    lo: Vec3,
    hi: Vec3,
}

fn layer_of(pts: &[Vec3], idx: &[u32]) -> Option<Layer> {
    let f = fit_plane(idx.iter().map(|&i| pts[i as usize]))?;
    let (lo, hi) = idx
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), &i| {
            (l.min(pts[i as usize]), h.max(pts[i as usize]))
        });
    Some(Layer {
        normal: f.normal,
        offset: f.offset,
        centroid: f.centroid,
        lo,
        hi,
    })
}

/// Re-assign points between every pair of patches whose planes are parallel (within
/// [`tol::LAYER_PARALLEL_COS`]), closer than twice the distance threshold `band` and
/// overlapping in space. `radius` is the vote radius, metres (a few point spacings);
/// patches with fewer than [`LAYER_MIN_POINTS_FACTOR`] × `min_points` points take no part.
/// Pairs are visited in index order, so the result is deterministic. Returns the indices of
/// the patches that changed.
pub(super) fn separate_parallel(
    pts: &[Vec3],
    patches: &mut [RawPatch],
    band: Real,
    radius: Real,
    min_points: usize,
) -> Vec<usize> {
    let layers: Vec<Option<Layer>> = patches
        .par_iter()
        .map(|p| {
            if p.indices.len() >= LAYER_MIN_POINTS_FACTOR * min_points {
                layer_of(pts, &p.indices)
            } else {
                None
            }
        })
        .collect();
    let mut pairs = Vec::new();
    for i in 0..patches.len() {
        for j in i + 1..patches.len() {
            let (Some(a), Some(b)) = (layers[i], layers[j]) else {
                continue;
            };
            if a.normal.dot(b.normal).abs() < tol::LAYER_PARALLEL_COS {
                continue;
            }
            let grow = Vec3::splat(radius + band);
            if (a.hi + grow).cmplt(b.lo).any() || (b.hi + grow).cmplt(a.lo).any() {
                continue;
            }
            // Each centroid within the other's doubled band (a tilted fragment fails this).
            let gap_ab = (a.normal.dot(b.centroid) - a.offset).abs();
            let gap_ba = (b.normal.dot(a.centroid) - b.offset).abs();
            if gap_ab.max(gap_ba) <= 2.0 * band {
                pairs.push((i, j));
            }
        }
    }
    let mut changed = Vec::new();
    for (i, j) in pairs {
        if patches[i].indices.len() < 3 || patches[j].indices.len() < 3 {
            continue;
        }
        if let Some((a, b)) = separate_pair(pts, &patches[i].indices, &patches[j].indices, radius)
            && (a != patches[i].indices || b != patches[j].indices)
        {
            patches[i].indices = a;
            patches[j].indices = b;
            changed.push(i);
            changed.push(j);
        }
    }
    changed.sort_unstable();
    changed.dedup();
    changed
}

/// A plane as (unit normal, offset).
type PlaneEq = (Vec3, Real);

/// Competitive, locally voted assignment of two parallel patches' points; `None` when the
/// two do not form distinct layers (then nothing should change).
fn separate_pair(
    pts: &[Vec3],
    pa: &[u32],
    pb: &[u32],
    radius: Real,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let la = layer_of(pts, pa)?;
    let lb = layer_of(pts, pb)?;
    let contest = Contest::new(pts, (pa, &la), (pb, &lb), radius)?;
    let centre = contest.centre;
    let (flat, adjacency) = contest.neighbours(pts, la.normal, radius);

    let (mut a, mut b) = (
        (la.normal, la.offset),
        facing(lb.normal, lb.offset, la.normal),
    );
    // Start from "nearer plane"; then each round decides by the posterior with the local
    // prior (share of neighbours currently in each layer) and Gaussian residuals.
    let mut to_b: Vec<bool> = contest
        .points
        .par_iter()
        .map(|&i| {
            let p = pts[i as usize];
            (b.0.dot(p) - b.1).abs() < (a.0.dot(p) - a.1).abs()
        })
        .collect();
    let share0_b = presence_of_b(&flat, &to_b, radius);
    let mut sigma = outer_sigma(pts, &contest.points, &to_b, centre, a, b)?;
    for _ in 0..ROUNDS {
        let next = contest.vote(pts, (&adjacency, &share0_b), &to_b, (a, b), sigma);
        (a, b) = contest.refit(pts, &next)?;
        let done = next == to_b;
        to_b = next;
        sigma = outer_sigma(pts, &contest.points, &to_b, centre, a, b)?;
        if done {
            break;
        }
    }

    // Distinct layers? Separation measured where the points are.
    let sep = ((b.0.dot(centre) - b.1) - (a.0.dot(centre) - a.1)).abs();
    if sep < tol::LAYER_SEPARATION_SIGMAS * sigma {
        return None;
    }
    Some(contest.assign(&to_b))
}

/// The plane `(normal, offset)` oriented so its normal points the way of `towards`.
fn facing(normal: Vec3, offset: Real, towards: Vec3) -> PlaneEq {
    if normal.dot(towards) < 0.0 {
        (-normal, -offset)
    } else {
        (normal, offset)
    }
}

/// The points two parallel patches compete for (each patch's points inside the other's grown
/// bounding box) and those each keeps whatever the vote.
struct Contest {
    /// Contested point indices: A's, then B's.
    points: Vec<u32>,
    /// Whether each contested point came from patch B (RANSAC's choice).
    orig_b: Vec<bool>,
    /// Mean of the contested points.
    centre: Vec3,
    fixed_a: Vec<u32>,
    fixed_b: Vec<u32>,
}

impl Contest {
    /// `None` when no point is contested.
    fn new(
        pts: &[Vec3],
        (pa, la): (&[u32], &Layer),
        (pb, lb): (&[u32], &Layer),
        radius: Real,
    ) -> Option<Contest> {
        let grow = Vec3::splat(radius);
        let within =
            |p: Vec3, l: &Layer| !(p.cmplt(l.lo - grow).any() || p.cmpgt(l.hi + grow).any());
        let (contested_a, fixed_a): (Vec<u32>, Vec<u32>) =
            pa.iter().partition(|&&i| within(pts[i as usize], lb));
        let (contested_b, fixed_b): (Vec<u32>, Vec<u32>) =
            pb.iter().partition(|&&i| within(pts[i as usize], la));
        let points: Vec<u32> = contested_a.into_iter().chain(contested_b).collect();
        if points.is_empty() {
            return None;
        }
        let centre =
            points.iter().fold(Vec3::ZERO, |c, &i| c + pts[i as usize]) / points.len() as Real;
        let orig_b = points
            .iter()
            .map(|&i| pb.binary_search(&i).is_ok())
            .collect();
        Some(Contest {
            points,
            orig_b,
            centre,
            fixed_a,
            fixed_b,
        })
    }

    /// The contested points in the 2-D frame of `normal` and each one's neighbours within
    /// `radius`, computed once (the points do not move, only their labels change).
    fn neighbours(&self, pts: &[Vec3], normal: Vec3, radius: Real) -> (Vec<Vec2>, Vec<Vec<u32>>) {
        let (u, v) = frame(normal);
        let flat: Vec<Vec2> = self
            .points
            .iter()
            .map(|&i| Vec2::new(pts[i as usize].dot(u), pts[i as usize].dot(v)))
            .collect();
        let near = Grid::new(&flat, radius);
        let adjacency = (0..self.points.len())
            .into_par_iter()
            .map(|k| {
                let mut out = Vec::new();
                near.visit(&flat, k, |m| out.push(m));
                out
            })
            .collect();
        (flat, adjacency)
    }

    /// One round of the vote: each contested point's layer by the posterior with the local
    /// prior (`adjacency`: share of neighbours in B now; `share0_b`: presence of B around the
    /// point from the start) and Gaussian residuals of width `sigma` to planes `(a, b)`.
    fn vote(
        &self,
        pts: &[Vec3],
        (adjacency, share0_b): (&[Vec<u32>], &[Real]),
        to_b: &[bool],
        ((na, da), (nb, db)): (PlaneEq, PlaneEq),
        sigma: Real,
    ) -> Vec<bool> {
        let inv = 0.5 / (sigma * sigma);
        let share = |k: usize| {
            let nb_k = &adjacency[k];
            nb_k.iter().filter(|&&m| to_b[m as usize]).count() as Real / nb_k.len().max(1) as Real
        };
        (0..self.points.len())
            .into_par_iter()
            .map(|k| {
                // A layer absent around the point (share of "nearer" neighbours, fixed by the
                // geometry, not by the labels, so corners do not erode round by round).
                if share0_b[k] < tol::LAYER_MIN_SHARE {
                    return false;
                }
                if share0_b[k] > 1.0 - tol::LAYER_MIN_SHARE {
                    return true;
                }
                let wb = share(k).clamp(tol::LAYER_MIN_SHARE, 1.0 - tol::LAYER_MIN_SHARE);
                let wa = 1.0 - wb;
                let p = pts[self.points[k] as usize];
                let (ra, rb) = (na.dot(p) - da, nb.dot(p) - db);
                let want_b = wb.ln() - rb * rb * inv > wa.ln() - ra * ra * inv;
                // Leaving the patch RANSAC gave it for the other takes a layer that is
                // established around the point, not just present nearby.
                let target = if want_b { wb } else { wa };
                if want_b != self.orig_b[k] && target < tol::LAYER_JOIN_SHARE {
                    self.orig_b[k]
                } else {
                    want_b
                }
            })
            .collect()
    }

    /// Both planes refitted to the fixed points and the contested ones labelled for each,
    /// B's normal facing A's; `None` when a side cannot be fitted.
    fn refit(&self, pts: &[Vec3], to_b: &[bool]) -> Option<(PlaneEq, PlaneEq)> {
        let fit = |fixed: &[u32], want_b: bool| {
            let contested = self
                .points
                .iter()
                .zip(to_b)
                .filter(move |(_, b)| **b == want_b);
            fit_plane(
                fixed
                    .iter()
                    .chain(contested.map(|(i, _)| i))
                    .map(|&i| pts[i as usize]),
            )
        };
        let fa = fit(&self.fixed_a, false)?;
        let fb = fit(&self.fixed_b, true)?;
        Some((
            (fa.normal, fa.offset),
            facing(fb.normal, fb.offset, fa.normal),
        ))
    }

    /// The two patches' sorted point lists after the vote `to_b`.
    fn assign(self, to_b: &[bool]) -> (Vec<u32>, Vec<u32>) {
        let mut a = self.fixed_a;
        let mut b = self.fixed_b;
        for (&i, &tb) in self.points.iter().zip(to_b) {
            if tb { b.push(i) } else { a.push(i) }
        }
        a.sort_unstable();
        b.sort_unstable();
        (a, b)
    }
}

/// Presence of layer B around each contested point over twice the radius (four times the
/// neighbours, so the share is steady enough to test against a floor even at a layer's
/// corner, a quarter disk), from the starting labels `to_b`.
fn presence_of_b(flat: &[Vec2], to_b: &[bool], radius: Real) -> Vec<Real> {
    let wide = Grid::new(flat, 2.0 * radius);
    (0..flat.len())
        .into_par_iter()
        .map(|k| {
            let (mut all, mut b) = (0usize, 0usize);
            wide.visit(flat, k, |m| {
                all += 1;
                b += usize::from(to_b[m as usize]);
            });
            b as Real / all.max(1) as Real
        })
        .collect()
}

/// Noise σ of two parallel layers, metres: RMS residual of each layer's points on the side
/// away from the other plane (those are not contested, so their spread is the plain noise),
/// the larger of the two. `None` if a side has fewer than three points.
fn outer_sigma(
    pts: &[Vec3],
    contested: &[u32],
    to_b: &[bool],
    centre: Vec3,
    (na, da): (Vec3, Real),
    (nb, db): (Vec3, Real),
) -> Option<Real> {
    // Which side of A the layer B lies on, where the points are (`centre`).
    let b_above = nb.dot(centre) - db < na.dot(centre) - da;
    let side = |want_b: bool| -> Option<Real> {
        let (n, d) = if want_b { (nb, db) } else { (na, da) };
        let away = if want_b == b_above { 1.0 } else { -1.0 };
        let (s, c) = contested
            .iter()
            .zip(to_b)
            .filter(|(_, b)| **b == want_b)
            .map(|(&i, _)| (n.dot(pts[i as usize]) - d) * away)
            .filter(|&r| r > 0.0)
            .fold((0.0, 0usize), |(s, c), r| (s + r * r, c + 1));
        (c >= 3).then(|| (s / c as Real).sqrt())
    };
    let sigma = side(false)?.max(side(true)?);
    (sigma > 0.0).then_some(sigma)
}

/// 2-D points bucketed into square cells of edge `radius`, for neighbour visits within it.
struct Grid {
    radius: Real,
    keyed: Vec<((i64, i64), u32)>,
    cells: KeyRanges<(i64, i64)>,
}

impl Grid {
    fn key(p: Vec2, radius: Real) -> (i64, i64) {
        ((p.x / radius).floor() as i64, (p.y / radius).floor() as i64)
    }

    fn new(flat: &[Vec2], radius: Real) -> Self {
        let mut keyed: Vec<((i64, i64), u32)> = flat
            .iter()
            .enumerate()
            .map(|(k, p)| (Self::key(*p, radius), k as u32))
            .collect();
        keyed.sort_unstable();
        Self {
            radius,
            cells: key_ranges(&keyed),
            keyed,
        }
    }

    /// Call `f` with every point within the radius of point `k`, `k` itself excluded.
    fn visit(&self, flat: &[Vec2], k: usize, mut f: impl FnMut(u32)) {
        let q = flat[k];
        let (ci, cj) = Self::key(q, self.radius);
        let r2 = self.radius * self.radius;
        for di in -1..=1 {
            for dj in -1..=1 {
                if let Some(&(s, e)) = self.cells.get(&(ci + di, cj + dj)) {
                    for &(_, m) in &self.keyed[s as usize..e as usize] {
                        if m as usize != k && flat[m as usize].distance_squared(q) <= r2 {
                            f(m);
                        }
                    }
                }
            }
        }
    }
}
