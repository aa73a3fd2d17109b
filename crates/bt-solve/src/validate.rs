//! Validation of a found path: points inside their polygons, neighbours on the reflecting side,
//! no segment blocked by another surface.

use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SurfaceId};
use serde::Serialize;

/// Verdict on a path's geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "verdict", rename_all = "kebab-case")]
pub enum Validity {
    /// A real specular path.
    Valid,
    /// Interaction point `index` lies outside its polygon.
    OutsidePolygon {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// The neighbours of point `index` lie on opposite sides of its surface.
    OppositeSides {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// A neighbour of point `index` lies on its plane: a grazing path, not counted as a reflection.
    Grazing {
        /// Point index, 0-based from TX.
        index: usize,
    },
    /// Segment `segment` (0 = TX to first point) crosses surface `by`.
    Blocked {
        /// Segment index, 0-based from TX.
        segment: usize,
        /// The occluding surface.
        by: SurfaceId,
    },
    /// A point is not finite (only reachable from a solver bug; never reported as valid).
    NonFinite,
}

/// Validate the path TX -> points -> RX over the surface sequence `seq`.
#[inline(always)]
pub fn validate(scene: &Scene, seq: &[SurfaceId], tx: Vec3, rx: Vec3, points: &[Vec3]) -> Validity {
    let tol = scene.length_tolerance();
    let n = seq.len();
    if points.iter().any(|p| !p.is_finite()) {
        return Validity::NonFinite;
    }
    for k in 0..n {
        if !scene.surface(seq[k]).polygon.contains(points[k], tol) {
            return Validity::OutsidePolygon { index: k };
        }
    }
    for k in 0..n {
        let plane = scene.surface(seq[k]).polygon.plane();
        let prev = if k == 0 { tx } else { points[k - 1] };
        let next = if k + 1 == n { rx } else { points[k + 1] };
        let (a, b) = (plane.signed_distance(prev), plane.signed_distance(next));
        if a.abs() <= tol || b.abs() <= tol {
            return Validity::Grazing { index: k };
        }
        if (a > 0.0) != (b > 0.0) {
            return Validity::OppositeSides { index: k };
        }
    }
    for segment in 0..=n {
        let (a, from) = if segment == 0 {
            (tx, None)
        } else {
            (points[segment - 1], Some(seq[segment - 1]))
        };
        let (b, to) = if segment == n {
            (rx, None)
        } else {
            (points[segment], Some(seq[segment]))
        };
        if let Some(by) = blocker(scene, a, b, from, to, tol) {
            return Validity::Blocked { segment, by };
        }
    }
    Validity::Valid
}

/// The first surface (other than the segment's own end surfaces) crossing the segment `a -> b`.
#[inline(always)]
pub fn blocker(
    scene: &Scene,
    a: Vec3,
    b: Vec3,
    from: Option<SurfaceId>,
    to: Option<SurfaceId>,
    tol: Real,
) -> Option<SurfaceId> {
    let length = a.distance(b);
    let t_min = tol / length.max(tol);
    scene
        .bvh()
        .any_hit(a, b, |i| {
            let id = SurfaceId(i);
            Some(id) != from
                && Some(id) != to
                && scene.surface(id).polygon.blocks_segment(a, b, t_min, tol)
        })
        .map(SurfaceId)
}

/// Early stopping of IPC (`IpcOptions::early_reject`): the first segment of the path TX ->
/// `points` -> RX that stays blocked, with its blocker, when every point may still move by up
/// to `reach` metres — or `None` when that is not certain. Certain means: every point lies
/// inside its polygon by more than `reach` plus the tolerance and both its neighbours lie off
/// its plane, on its side, by as much (so validation reaches the blocking test whatever the
/// final points), and the segment's crossing with the blocker stays strictly inside it. For a
/// segment `a -> b` at distances `da`, `db` from the blocker's plane on either side
/// (`S = |da| + |db|`, length `L`), moving both ends by up to `r` moves the crossing point by
/// at most `r (1 + L / (S - 2r))` (its parameter moves by at most `r / (S - 2r)`).
#[inline(always)]
pub fn blocked_for_good(
    scene: &Scene,
    seq: &[SurfaceId],
    (tx, rx): (Vec3, Vec3),
    points: &[Vec3],
    reach: Real,
) -> Option<(usize, SurfaceId)> {
    let tol = scene.length_tolerance();
    let margin = reach + tol;
    let n = seq.len();
    let at = |k: usize| match k {
        0 => tx,
        k if k == n + 1 => rx,
        k => points[k - 1],
    };
    for k in 0..n {
        let polygon = &scene.surface(seq[k]).polygon;
        let (a, b) = (
            polygon.plane().signed_distance(at(k)),
            polygon.plane().signed_distance(at(k + 2)),
        );
        let sides = (a > margin && b > margin) || (a < -margin && b < -margin);
        if !sides || polygon.signed_boundary_distance(points[k]) <= margin {
            return None;
        }
    }
    (0..=n).find_map(|segment| {
        let (a, b) = (at(segment), at(segment + 1));
        let from = segment.checked_sub(1).map(|k| seq[k]);
        let to = (segment < n).then(|| seq[segment]);
        let length = a.distance(b);
        let by = scene.bvh().any_hit(a, b, |i| {
            let id = SurfaceId(i);
            if Some(id) == from || Some(id) == to {
                return false;
            }
            let polygon = &scene.surface(id).polygon;
            let (da, db) = (
                polygon.plane().signed_distance(a),
                polygon.plane().signed_distance(b),
            );
            let span = da.abs() + db.abs();
            if (da > 0.0) == (db > 0.0) || da.abs() <= margin || db.abs() <= margin {
                return false;
            }
            let crossing = a + (da / (da - db)) * (b - a);
            let shift = reach * (1.0 + length / (span - 2.0 * reach));
            polygon.signed_boundary_distance(crossing) > tol + shift
        });
        by.map(|i| (segment, SurfaceId(i)))
    })
}
