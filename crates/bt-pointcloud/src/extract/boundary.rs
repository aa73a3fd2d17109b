//! Boundary polygons of planar patches, in the patch's 2-D frame (metres).
//!
//! Pipeline: orient the frame to the minimum-area bounding rectangle (so rectangular
//! patches are axis-aligned), rasterise the points into square cells, close one-cell gaps,
//! keep the largest 4-connected component, fill holes, remove diagonal pinches, trace the
//! outer cell boundary (a simple rectilinear polygon, counter-clockwise), simplify it with
//! Douglas–Peucker, then refit every edge to the outermost points near it so the polygon
//! follows the sampled surface rather than the cell raster. Every step that could break
//! simplicity is checked and falls back to the previous, valid polygon.

use glam::DVec2;

use crate::tol;

/// Largest number of raster cells for one patch; the cell grows beyond it.
const MAX_CELLS: f64 = 4.0e6;

/// A directed 2-D line through `p` with unit direction `d`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line2 {
    pub p: DVec2,
    pub d: DVec2,
}

fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Signed area (positive for counter-clockwise), m².
pub(crate) fn signed_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| cross(poly[i], poly[(i + 1) % n]))
        .sum::<f64>()
        * 0.5
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
pub(crate) fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while h.len() >= start + 2
                && cross(h[h.len() - 1] - h[h.len() - 2], q - h[h.len() - 2]) <= 0.0
            {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
    }
    h
}

/// Minimum-area enclosing rectangle of a convex hull: `(angle_rad, width, length)` where
/// rotating by `-angle` makes the rectangle axis-aligned and `width ≤ length` (metres).
pub(crate) fn min_area_rect(hull: &[DVec2]) -> (f64, f64, f64) {
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
    let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
    for i in 0..n {
        let e = hull[(i + 1) % n] - hull[i];
        let len = e.length();
        if len == 0.0 {
            continue;
        }
        let d = e / len;
        let o = d.perp();
        let (mut a0, mut a1, mut b0, mut b1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
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

/// Whether a closed polygon is simple (no two non-adjacent edges touch, no zero-length edge).
pub(crate) fn is_simple(poly: &[DVec2]) -> bool {
    let n = poly.len();
    if n < 3 || poly.iter().any(|p| !p.is_finite()) {
        return false;
    }
    let seg = |i: usize| (poly[i], poly[(i + 1) % n]);
    for i in 0..n {
        let (a, b) = seg(i);
        if a == b {
            return false;
        }
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (c, d) = seg(j);
            if segments_touch(a, b, c, d) {
                return false;
            }
        }
    }
    // Adjacent edges must not fold back onto each other.
    for i in 0..n {
        let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        if cross(b - a, c - b) == 0.0 && (b - a).dot(c - b) < 0.0 {
            return false;
        }
    }
    true
}

fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| cross(q - p, r - p);
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(c, d, a))
        || (d2 == 0.0 && on(c, d, b))
        || (d3 == 0.0 && on(a, b, c))
        || (d4 == 0.0 && on(a, b, d))
}

/// Intersection of two lines, `None` when they are closer to parallel than
/// [`tol::PARALLEL_SIN`].
pub(crate) fn intersect(l1: Line2, l2: Line2) -> Option<DVec2> {
    let den = cross(l1.d, l2.d);
    if den.abs() < tol::PARALLEL_SIN {
        return None;
    }
    let t = cross(l2.p - l1.p, l2.d) / den;
    Some(l1.p + l1.d * t)
}

/// Rebuild a polygon whose edge `i` lies on `lines[i]` (running from vertex `i` to `i+1`).
/// Where consecutive lines are nearly parallel the old vertex is projected onto both
/// lines and averaged.
pub(crate) fn polygon_from_lines(lines: &[Line2], old: &[DVec2]) -> Vec<DVec2> {
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
pub(crate) fn lines_of(poly: &[DVec2]) -> Vec<Line2> {
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
pub(crate) fn acceptable(old: &[DVec2], new: &[DVec2], max_move: f64) -> bool {
    new.len() == old.len()
        && new.iter().zip(old).all(|(a, b)| a.distance(*b) <= max_move)
        && signed_area(new) > tol::AREA_REL * signed_area(old).abs()
        && is_simple(new)
}

/// Drop vertices where the polygon goes straight on (or doubles back exactly).
fn remove_collinear(poly: &mut Vec<DVec2>) {
    let mut changed = true;
    while changed && poly.len() > 3 {
        changed = false;
        let n = poly.len();
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            if cross(b - a, c - b) == 0.0 {
                poly.remove(i);
                changed = true;
                break;
            }
        }
    }
}

/// Douglas–Peucker on a closed ring, anchored at vertex 0 and the vertex farthest from it.
fn simplify_closed(poly: &[DVec2], tolerance: f64) -> Vec<DVec2> {
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
    let ring: Vec<DVec2> = poly
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
                cross(ab, q - a).abs() / len
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
pub(crate) fn patch_boundary(pts: &[DVec2], cell: f64, simplify_tol: f64) -> Option<Vec<DVec2>> {
    let hull = convex_hull(pts);
    if hull.len() < 3 {
        return None;
    }
    let (angle, _, _) = min_area_rect(&hull);
    let rot = DVec2::from_angle(-angle);
    let back = DVec2::from_angle(angle);
    let q: Vec<DVec2> = pts.iter().map(|p| rot.rotate(*p)).collect();
    let poly = rect_boundary(&q, cell, simplify_tol)?;
    Some(poly.into_iter().map(|p| back.rotate(p)).collect())
}

fn rect_boundary(q: &[DVec2], cell0: f64, simplify_tol: f64) -> Option<Vec<DVec2>> {
    let (lo, hi) = q
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), p| {
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
    let origin = lo - DVec2::splat(margin as f64 * cell);
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
fn merge_collinear(poly: &mut Vec<DVec2>, tolerance: f64, turn_sin: f64) -> bool {
    let mut changed = false;
    loop {
        let n = poly.len();
        if n <= 3 {
            return changed;
        }
        let mut best: Option<(f64, usize)> = None;
        for i in 0..n {
            let (a, b, c) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (e1, e2) = ((b - a).normalize_or_zero(), (c - b).normalize_or_zero());
            let chord = c - a;
            let dev = cross(chord, b - a).abs() / chord.length().max(f64::MIN_POSITIVE);
            if cross(e1, e2).abs() < turn_sin
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
fn trace(g: &[bool], w: usize, h: usize) -> Option<Vec<DVec2>> {
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
        out.push(DVec2::new(
            (v as usize % vw) as f64,
            (v as usize / vw) as f64,
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
fn refine_edges(poly: &[DVec2], pts: &[DVec2], cell: f64) -> Option<Vec<DVec2>> {
    let n = poly.len();
    let band = 1.5 * cell;
    let mut lines = Vec::with_capacity(n);
    let mut ts: Vec<(f64, f64)> = Vec::new();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let len = a.distance(b);
        let d = (b - a) / len;
        let o = DVec2::new(d.y, -d.x); // outward for a counter-clockwise polygon
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
                DVec2::new(d.x.signum(), 0.0)
            } else {
                DVec2::new(0.0, d.y.signum())
            };
            let a = if cross(axis, d).abs() < tol::AXIS_PRIOR_SIN {
                axis
            } else {
                d
            };
            (a, DVec2::new(a.y, -a.x))
        };
        let mut dir = d0;
        let nb = ((len - 2.0 * trim) / cell).floor() as usize;
        if nb >= 4 {
            let mut ext = vec![(f64::NAN, f64::NEG_INFINITY); nb];
            for &(t, s) in &ts {
                let r = d * t + o * s;
                let (t0, s0) = (r.dot(d0), r.dot(o0));
                let k = ((((t - trim) / cell).max(0.0)) as usize).min(nb - 1);
                if s0 > ext[k].1 {
                    ext[k] = (t0, s0);
                }
            }
            let e: Vec<(f64, f64)> = ext.into_iter().filter(|x| x.0.is_finite()).collect();
            if e.len() >= 4 {
                let m = e.len() as f64;
                let (mt, ms) = e
                    .iter()
                    .fold((0.0, 0.0), |(a, b), x| (a + x.0 / m, b + x.1 / m));
                let (sxx, sxy) = e.iter().fold((0.0, 0.0), |(a, b), x| {
                    (a + (x.0 - mt).powi(2), b + (x.0 - mt) * (x.1 - ms))
                });
                if sxx > 0.0 {
                    let slope = sxy / sxx;
                    let sse: f64 = e
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
        let o2 = DVec2::new(dir.y, -dir.x);
        let mut s2: Vec<f64> = ts.iter().map(|&(t, s)| (d * t + o * s).dot(o2)).collect();
        s2.sort_by(|x, y| y.total_cmp(x));
        let k = 3.min(s2.len());
        let depth = s2[0] - s2[s2.len() - 1];
        let lambda = s2.len() as f64 / depth.max(1e-12);
        let c = s2[k - 1] + k as f64 / lambda;
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

    fn grid_points(w: f64, h: f64, step: f64) -> Vec<DVec2> {
        let mut v = Vec::new();
        let (nx, ny) = ((w / step) as usize, (h / step) as usize);
        for i in 0..=nx {
            for j in 0..=ny {
                // Jitter deterministically so points are not on cell borders.
                let jx = ((i * 7 + j * 13) % 10) as f64 * 0.1 * step;
                let jy = ((i * 11 + j * 3) % 10) as f64 * 0.1 * step;
                let p = DVec2::new((i as f64 * step + jx).min(w), (j as f64 * step + jy).min(h));
                v.push(p);
            }
        }
        v
    }

    #[test]
    fn hull_and_rect() {
        let pts = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(1.0, 0.5),
        ];
        let h = convex_hull(&pts);
        assert_eq!(h.len(), 4);
        assert!(signed_area(&h) > 0.0);
        let (_, w, l) = min_area_rect(&h);
        assert!((w - 1.0).abs() < 1e-12 && (l - 2.0).abs() < 1e-12);
    }

    #[test]
    fn rectangle_boundary_is_accurate() {
        let rot = DVec2::from_angle(0.3);
        let pts: Vec<DVec2> = grid_points(1.2, 0.7, 0.02)
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
        let pts: Vec<DVec2> = grid_points(2.0, 2.0, 0.02)
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
