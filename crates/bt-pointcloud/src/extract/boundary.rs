//! Boundary polygons of planar patches, in the patch's 2-D frame (metres).
//!
//! Pipeline: orient the frame to the minimum-area bounding rectangle (so rectangular
//! patches are axis-aligned), rasterise the points into square cells, close one-cell gaps,
//! keep the largest 4-connected component, fill holes, remove diagonal pinches, trace the
//! outer cell boundary (a simple rectilinear polygon, counter-clockwise), simplify it with
//! Douglas–Peucker, then refit every edge to the outermost points near it so the polygon
//! follows the sampled surface rather than the cell raster. Every step that could break
//! simplicity is checked and falls back to the previous, valid polygon.

use crate::tol;
use bt_geom::convex::hull_2d;
pub(crate) use bt_geom::poly2::{is_simple, signed_area};
use bt_geom::{Real, Vec2};

/// Largest number of raster cells for one patch; the cell grows beyond it.
const MAX_CELLS: Real = 4.0e6;

/// A directed 2-D line through `p` with unit direction `d`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line2 {
    pub p: Vec2,
    pub d: Vec2,
}

/// Minimum-area enclosing rectangle of a convex hull: `(angle_rad, width, length)` where
/// rotating by `-angle` makes the rectangle axis-aligned and `width ≤ length` (metres).
pub(crate) fn min_area_rect(hull: &[Vec2]) -> (Real, Real, Real) {
    let n = hull.len();
    if n < 3 {
        let len = if n == 2 {
            hull[0].distance(hull[1])
        } else {
            0.0
        };
        let ang = if n == 2 {
            (hull[1] - hull[0]).to_angle()
        } else {
            0.0
        };
        return (ang, 0.0, len);
    }
    let mut best = (Real::INFINITY, 0.0, 0.0, 0.0);
    for i in 0..n {
        let e = hull[(i + 1) % n] - hull[i];
        let len = e.length();
        if len == 0.0 {
            continue;
        }
        let d = e / len;
        let o = d.perp();
        let (mut a0, mut a1, mut b0, mut b1) = (
            Real::INFINITY,
            Real::NEG_INFINITY,
            Real::INFINITY,
            Real::NEG_INFINITY,
        );
        for &q in hull {
            let (a, b) = (q.dot(d), q.dot(o));
            a0 = a0.min(a);
            a1 = a1.max(a);
            b0 = b0.min(b);
            b1 = b1.max(b);
        }
        let area = (a1 - a0) * (b1 - b0);
        if area < best.0 {
            best = (area, d.to_angle(), a1 - a0, b1 - b0);
        }
    }
    let (_, ang, w1, w2) = best;
    (ang, w1.min(w2), w1.max(w2))
}

/// Intersection of two lines, `None` when they are closer to parallel than
/// [`tol::PARALLEL_SIN`].
pub(crate) fn intersect(l1: Line2, l2: Line2) -> Option<Vec2> {
    let den = l1.d.perp_dot(l2.d);
    if den.abs() < tol::PARALLEL_SIN {
        return None;
    }
    let t = (l2.p - l1.p).perp_dot(l2.d) / den;
    Some(l1.p + l1.d * t)
}

/// Rebuild a polygon whose edge `i` lies on `lines[i]` (running from vertex `i` to `i+1`).
/// Where consecutive lines are nearly parallel the old vertex is projected onto both
/// lines and averaged.
pub(crate) fn polygon_from_lines(lines: &[Line2], old: &[Vec2]) -> Vec<Vec2> {
    let n = lines.len();
    (0..n)
        .map(|i| {
            let (prev, cur) = (lines[(i + n - 1) % n], lines[i]);
            intersect(prev, cur).unwrap_or_else(|| {
                let proj = |l: Line2| l.p + l.d * (old[i] - l.p).dot(l.d);
                (proj(prev) + proj(cur)) * 0.5
            })
        })
        .collect()
}

/// Edge lines of a polygon.
pub(crate) fn lines_of(poly: &[Vec2]) -> Vec<Line2> {
    let n = poly.len();
    (0..n)
        .map(|i| Line2 {
            p: poly[i],
            d: (poly[(i + 1) % n] - poly[i]).normalize_or_zero(),
        })
        .collect()
}

/// Accept `new` in place of `old` if it is simple, counter-clockwise, has the same vertex
/// count and no vertex moved more than `max_move` metres.
pub(crate) fn acceptable(old: &[Vec2], new: &[Vec2], max_move: Real) -> bool {
    new.len() == old.len()
        && new.iter().zip(old).all(|(a, b)| a.distance(*b) <= max_move)
        && signed_area(new) > tol::AREA_REL * signed_area(old).abs()
        && is_simple(new)
}

/// Drop vertices where the polygon goes straight on (or doubles back exactly).
fn remove_collinear(poly: &mut Vec<Vec2>) {
    let mut changed = true;
    while changed && poly.len() > 3 {
        changed = false;
        let n = poly.len();
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            if (b - a).perp_dot(c - b) == 0.0 {
                poly.remove(i);
                changed = true;
                break;
            }
        }
    }
}

/// Douglas–Peucker on a closed ring, anchored at vertex 0 and the vertex farthest from it.
fn simplify_closed(poly: &[Vec2], tolerance: Real) -> Vec<Vec2> {
    let n = poly.len();
    if n <= 4 {
        return poly.to_vec();
    }
    let far = (1..n)
        .max_by(|&i, &j| {
            poly[0]
                .distance_squared(poly[i])
                .total_cmp(&poly[0].distance_squared(poly[j]))
        })
        .unwrap_or(n / 2);
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[far] = true;
    let ring: Vec<Vec2> = poly
        .iter()
        .copied()
        .chain(std::iter::once(poly[0]))
        .collect();
    let mut stack = vec![(0usize, far), (far, n)];
    while let Some((s, e)) = stack.pop() {
        if e <= s + 1 {
            continue;
        }
        let (a, b) = (ring[s], ring[e]);
        let ab = b - a;
        let len = ab.length();
        let mut best = (0.0, s);
        for (k, &q) in ring.iter().enumerate().take(e).skip(s + 1) {
            let d = if len > 0.0 {
                ab.perp_dot(q - a).abs() / len
            } else {
                q.distance(a)
            };
            if d > best.0 {
                best = (d, k);
            }
        }
        if best.0 > tolerance {
            keep[best.1 % n] = true;
            stack.push((s, best.1));
            stack.push((best.1, e));
        }
    }
    poly.iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(p, _)| *p)
        .collect()
}

/// Boundary of the points `pts` (patch frame, metres): a simple counter-clockwise polygon,
/// or `None` if the points do not cover at least one raster cell's worth of area.
pub(crate) fn patch_boundary(pts: &[Vec2], cell: Real, simplify_tol: Real) -> Option<Vec<Vec2>> {
    let hull = hull_2d(pts);
    if hull.len() < 3 {
        return None;
    }
    let (angle, _, _) = min_area_rect(&hull);
    let rot = Vec2::from_angle(-angle);
    let back = Vec2::from_angle(angle);
    let q: Vec<Vec2> = pts.iter().map(|p| rot.rotate(*p)).collect();
    let poly = rect_boundary(&q, cell, simplify_tol)?;
    Some(poly.into_iter().map(|p| back.rotate(p)).collect())
}

fn rect_boundary(q: &[Vec2], cell0: Real, simplify_tol: Real) -> Option<Vec<Vec2>> {
    let (lo, hi) = q
        .iter()
        .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    let ext = hi - lo;
    let mut cell = cell0;
    if (ext.x / cell + 5.0) * (ext.y / cell + 5.0) > MAX_CELLS {
        cell = ((ext.x + 5.0 * cell) * (ext.y + 5.0 * cell) / MAX_CELLS)
            .sqrt()
            .max(cell);
    }
    let margin = 2usize;
    let w = (ext.x / cell).floor() as usize + 1 + 2 * margin;
    let h = (ext.y / cell).floor() as usize + 1 + 2 * margin;
    let origin = lo - Vec2::splat(margin as Real * cell);
    let mut grid = vec![false; w * h];
    for p in q {
        let i = ((p.x - origin.x) / cell).floor() as usize;
        let j = ((p.y - origin.y) / cell).floor() as usize;
        grid[j.min(h - 1) * w + i.min(w - 1)] = true;
    }
    // Closing with a 3×3 square bridges one-cell sampling gaps.
    let grid = morph(&morph(&grid, w, h, true), w, h, false);
    let mut grid = largest_component(&grid, w, h)?;
    for _ in 0..8 {
        fill_holes(&mut grid, w, h);
        if !remove_pinches(&mut grid, w, h) {
            break;
        }
    }
    fill_holes(&mut grid, w, h);
    let mut stair = trace(&grid, w, h)?;
    for p in &mut stair {
        *p = origin + *p * cell;
    }
    remove_collinear(&mut stair);
    if stair.len() < 3 || !is_simple(&stair) {
        return None;
    }
    let mut poly = stair.clone();
    let mut t = simplify_tol;
    for _ in 0..4 {
        let s = simplify_closed(&stair, t);
        if s.len() >= 3 && is_simple(&s) && signed_area(&s) > 0.0 {
            poly = s;
            break;
        }
        t *= 0.5;
    }
    // DP on a ragged raster edge can leave a straight edge in several nearly collinear
    // pieces, whose corners would be ill-conditioned intersections: merge them before and
    // after refitting.
    merge_collinear(&mut poly, simplify_tol, tol::RASTER_MERGE_TURN_SIN);
    let mut poly = refine_edges(&poly, q, cell).unwrap_or(poly);
    if merge_collinear(&mut poly, simplify_tol, tol::MERGE_TURN_SIN) {
        poly = refine_edges(&poly, q, cell).unwrap_or(poly);
    }
    Some(poly)
}

/// Remove vertices where the boundary turns by an angle whose sine is below `turn_sin` and
/// the vertex lies within `tolerance` of the chord of its neighbours, as long as the polygon
/// stays simple. Returns whether anything was removed.
fn merge_collinear(poly: &mut Vec<Vec2>, tolerance: Real, turn_sin: Real) -> bool {
    let mut changed = false;
    loop {
        let n = poly.len();
        if n <= 3 {
            return changed;
        }
        let mut best: Option<(Real, usize)> = None;
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (e1, e2) = ((b - a).normalize_or_zero(), (c - b).normalize_or_zero());
            let chord = c - a;
            let dev = chord.perp_dot(b - a).abs() / chord.length().max(Real::MIN_POSITIVE);
            if e1.perp_dot(e2).abs() < turn_sin
                && e1.dot(e2) > 0.0
                && dev <= tolerance
                && best.is_none_or(|(d, _)| dev < d)
            {
                best = Some((dev, i));
            }
        }
        let Some((_, i)) = best else { return changed };
        let mut trial = poly.clone();
        trial.remove(i);
        if !is_simple(&trial) {
            return changed;
        }
        *poly = trial;
        changed = true;
    }
}

fn morph(g: &[bool], w: usize, h: usize, dilate: bool) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for j in 1..h - 1 {
        for i in 1..w - 1 {
            let mut any = false;
            let mut all = true;
            for dj in 0..3 {
                for di in 0..3 {
                    let v = g[(j + dj - 1) * w + i + di - 1];
                    any |= v;
                    all &= v;
                }
            }
            out[j * w + i] = if dilate { any } else { all };
        }
    }
    out
}

/// The largest 4-connected set of true cells (ties: the first in row-major order).
fn largest_component(g: &[bool], w: usize, h: usize) -> Option<Vec<bool>> {
    let mut label = vec![u32::MAX; w * h];
    let mut best: Option<(usize, u32)> = None;
    let mut next = 0u32;
    let mut stack = Vec::new();
    for start in 0..w * h {
        if !g[start] || label[start] != u32::MAX {
            continue;
        }
        let mut size = 0;
        label[start] = next;
        stack.push(start);
        while let Some(c) = stack.pop() {
            size += 1;
            let (i, j) = (c % w, c / w);
            let nb = [
                (i > 0).then(|| c - 1),
                (i + 1 < w).then(|| c + 1),
                (j > 0).then(|| c - w),
                (j + 1 < h).then(|| c + w),
            ];
            for n in nb.into_iter().flatten() {
                if g[n] && label[n] == u32::MAX {
                    label[n] = next;
                    stack.push(n);
                }
            }
        }
        if best.is_none_or(|(s, _)| size > s) {
            best = Some((size, next));
        }
        next += 1;
    }
    let (_, l) = best?;
    Some(label.iter().map(|&x| x == l).collect())
}

/// Set every false cell not 4-connected to the grid border to true.
fn fill_holes(g: &mut [bool], w: usize, h: usize) {
    let mut outside = vec![false; w * h];
    let mut stack: Vec<usize> = (0..w)
        .chain((0..w).map(|i| (h - 1) * w + i))
        .chain((0..h).flat_map(|j| [j * w, j * w + w - 1]))
        .collect();
    while let Some(c) = stack.pop() {
        if g[c] || outside[c] {
            continue;
        }
        outside[c] = true;
        let (i, j) = (c % w, c / w);
        if i > 0 {
            stack.push(c - 1);
        }
        if i + 1 < w {
            stack.push(c + 1);
        }
        if j > 0 {
            stack.push(c - w);
        }
        if j + 1 < h {
            stack.push(c + w);
        }
    }
    for (v, o) in g.iter_mut().zip(outside) {
        *v = *v || !o;
    }
}

/// Break diagonal-only contacts (2×2 blocks with exactly two true cells on a diagonal) by
/// setting one more cell, so the boundary trace is a simple polygon. Returns whether
/// anything changed.
fn remove_pinches(g: &mut [bool], w: usize, h: usize) -> bool {
    let mut changed = false;
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            let (a, b, c, d) = (
                j * w + i,
                j * w + i + 1,
                (j + 1) * w + i,
                (j + 1) * w + i + 1,
            );
            if g[a] && g[d] && !g[b] && !g[c] {
                g[b] = true;
                changed = true;
            } else if g[b] && g[c] && !g[a] && !g[d] {
                g[a] = true;
                changed = true;
            }
        }
    }
    changed
}

/// Trace the outer boundary of a hole-free, pinch-free cell set as a counter-clockwise
/// polygon in cell units (vertices at cell corners).
fn trace(g: &[bool], w: usize, h: usize) -> Option<Vec<Vec2>> {
    let vw = w + 1;
    let mut next = vec![u32::MAX; vw * (h + 1)];
    let vid = |i: usize, j: usize| (j * vw + i) as u32;
    let at = |i: isize, j: isize| {
        i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h && g[j as usize * w + i as usize]
    };
    let mut start = None;
    for j in 0..h {
        for i in 0..w {
            if !g[j * w + i] {
                continue;
            }
            let (ii, jj) = (i as isize, j as isize);
            if !at(ii, jj - 1) {
                next[vid(i, j) as usize] = vid(i + 1, j);
                start.get_or_insert(vid(i, j));
            }
            if !at(ii + 1, jj) {
                next[vid(i + 1, j) as usize] = vid(i + 1, j + 1);
            }
            if !at(ii, jj + 1) {
                next[vid(i + 1, j + 1) as usize] = vid(i, j + 1);
            }
            if !at(ii - 1, jj) {
                next[vid(i, j + 1) as usize] = vid(i, j);
            }
        }
    }
    let start = start?;
    let mut out = Vec::new();
    let mut v = start;
    loop {
        out.push(Vec2::new(
            (v as usize % vw) as Real,
            (v as usize / vw) as Real,
        ));
        v = next[v as usize];
        if v == u32::MAX || out.len() > vw * (h + 1) {
            return None;
        }
        if v == start {
            break;
        }
    }
    Some(out)
}

/// Move every edge onto the outermost sampled points next to it (direction refitted from
/// per-cell extremes, position from the k-th extreme plus its expected gap), then rebuild
/// corners as intersections of consecutive edges. `None` if the result is not acceptable.
fn refine_edges(poly: &[Vec2], pts: &[Vec2], cell: Real) -> Option<Vec<Vec2>> {
    let n = poly.len();
    let band = 1.5 * cell;
    let mut lines = Vec::with_capacity(n);
    let mut ts: Vec<(Real, Real)> = Vec::new();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let len = a.distance(b);
        let d = (b - a) / len;
        let o = Vec2::new(d.y, -d.x); // outward for a counter-clockwise polygon
        let trim = cell.min(0.25 * len);
        ts.clear();
        ts.extend(pts.iter().filter_map(|p| {
            let r = *p - a;
            let (t, s) = (r.dot(d), r.dot(o));
            (t >= trim && t <= len - trim && s.abs() <= band).then_some((t, s))
        }));
        if ts.len() < 8 || len < 3.0 * cell {
            lines.push(Line2 { p: a, d });
            continue;
        }
        // Direction: least-squares line through the per-cell outermost points.
        // Prior direction: the nearest axis of the minimum-area rectangle frame if within
        // ≈ 15° (exact for rectangles; merged raster steps are slightly slanted), else the
        // simplified edge. The per-cell outermost points may tilt it, but only when the
        // tilt is statistically significant (beyond three standard errors).
        let (d0, o0) = {
            let axis = if d.x.abs() >= d.y.abs() {
                Vec2::new(d.x.signum(), 0.0)
            } else {
                Vec2::new(0.0, d.y.signum())
            };
            let a = if axis.perp_dot(d).abs() < tol::AXIS_PRIOR_SIN {
                axis
            } else {
                d
            };
            (a, Vec2::new(a.y, -a.x))
        };
        let mut dir = d0;
        let nb = ((len - 2.0 * trim) / cell).floor() as usize;
        if nb >= 4 {
            let mut ext = vec![(Real::NAN, Real::NEG_INFINITY); nb];
            for &(t, s) in &ts {
                let r = d * t + o * s;
                let (t0, s0) = (r.dot(d0), r.dot(o0));
                let k = ((((t - trim) / cell).max(0.0)) as usize).min(nb - 1);
                if s0 > ext[k].1 {
                    ext[k] = (t0, s0);
                }
            }
            let e: Vec<(Real, Real)> = ext.into_iter().filter(|x| x.0.is_finite()).collect();
            if e.len() >= 4 {
                let m = e.len() as Real;
                let (mt, ms) = e
                    .iter()
                    .fold((0.0, 0.0), |(a, b), x| (a + x.0 / m, b + x.1 / m));
                let (sxx, sxy) = e.iter().fold((0.0, 0.0), |(a, b), x| {
                    (a + (x.0 - mt).powi(2), b + (x.0 - mt) * (x.1 - ms))
                });
                if sxx > 0.0 {
                    let slope = sxy / sxx;
                    let sse: Real = e
                        .iter()
                        .map(|x| (x.1 - ms - slope * (x.0 - mt)).powi(2))
                        .sum();
                    let se = (sse / (m - 2.0) / sxx).sqrt();
                    if slope.abs() > 3.0 * se && slope.abs() < 0.3 {
                        dir = (d0 + o0 * slope).normalize();
                    }
                }
            }
        }
        let o2 = Vec2::new(dir.y, -dir.x);
        let mut s2: Vec<Real> = ts.iter().map(|&(t, s)| (d * t + o * s).dot(o2)).collect();
        s2.sort_by(|x, y| y.total_cmp(x));
        let k = 3.min(s2.len());
        let depth = s2[0] - s2[s2.len() - 1];
        let lambda = s2.len() as Real / depth.max(tol::MIN_BAND_DEPTH);
        let c = s2[k - 1] + k as Real / lambda;
        lines.push(Line2 {
            p: a + o2 * c,
            d: dir,
        });
    }
    let new = polygon_from_lines(&lines, poly);
    acceptable(poly, &new, 2.0 * cell).then_some(new)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_points(w: Real, h: Real, step: Real) -> Vec<Vec2> {
        let mut v = Vec::new();
        let (nx, ny) = ((w / step) as usize, (h / step) as usize);
        for i in 0..=nx {
            for j in 0..=ny {
                // Jitter deterministically so points are not on cell borders.
                let jx = ((i * 7 + j * 13) % 10) as Real * 0.1 * step;
                let jy = ((i * 11 + j * 3) % 10) as Real * 0.1 * step;
                let p = Vec2::new(
                    (i as Real * step + jx).min(w),
                    (j as Real * step + jy).min(h),
                );
                v.push(p);
            }
        }
        v
    }

    #[test]
    fn hull_and_rect() {
        let pts = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0], [1.0, 0.5]].map(Vec2::from);
        let h = hull_2d(&pts);
        assert_eq!(h.len(), 4);
        assert!(signed_area(&h) > 0.0);
        let (_, w, l) = min_area_rect(&h);
        assert!((w - 1.0).abs() < 1e-12 && (l - 2.0).abs() < 1e-12);
    }

    #[test]
    fn rectangle_boundary_is_accurate() {
        let rot = Vec2::from_angle(0.3);
        let pts: Vec<Vec2> = grid_points(1.2, 0.7, 0.02)
            .into_iter()
            .map(|p| rot.rotate(p))
            .collect();
        let poly = patch_boundary(&pts, 0.05, 0.05).unwrap();
        assert!(is_simple(&poly));
        assert!(signed_area(&poly) > 0.0);
        assert_eq!(poly.len(), 4, "{poly:?}");
        let a = signed_area(&poly);
        assert!((a - 0.84).abs() / 0.84 < 0.02, "area {a}");
    }

    #[test]
    fn notch_boundary_is_simple_and_concave() {
        let pts: Vec<Vec2> = grid_points(2.0, 2.0, 0.02)
            .into_iter()
            .filter(|p| !(p.x > 0.6 && p.x < 1.4 && p.y < 1.2))
            .collect();
        let poly = patch_boundary(&pts, 0.05, 0.05).unwrap();
        assert!(is_simple(&poly));
        let a = signed_area(&poly);
        let truth = 4.0 - 0.8 * 1.2;
        assert!(
            (a - truth).abs() / truth < 0.03,
            "area {a} vs {truth}, {poly:?}"
        );
        assert_eq!(poly.len(), 8, "{poly:?}");
    }
}
