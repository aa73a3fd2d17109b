//! What a beam manager needs from each path: length, delay, departure and arrival directions,
//! incidence angles, loss; and the paper's ranking (order first, then length, then angle).
//!
//! Angle conventions (`docs/conventions.md`): azimuth from +x towards +y, in (-180°, 180°];
//! elevation from the horizontal plane, positive up, in [-90°, 90°]. The departure direction is
//! TX towards the first interaction point (or RX); the arrival direction is RX towards the last
//! interaction point (or TX), i.e. where the wave comes from, as Sionna RT and MATLAB report it.
#![warn(missing_docs)]

use bt_geom::{Real, Vec3};
use bt_scene::{Scene, SurfaceId};
use bt_solve::FoundPath;
use serde::Serialize;

/// Speed of light in vacuum, m/s.
pub const SPEED_OF_LIGHT: Real = 299_792_458.0;

/// A direction as azimuth and elevation, degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Direction {
    /// From +x towards +y, degrees in (-180, 180].
    pub azimuth: Real,
    /// From the horizontal plane, positive up, degrees in [-90, 90].
    pub elevation: Real,
}

impl Direction {
    /// Direction of the (non-zero) vector `v`.
    pub fn of(v: Vec3) -> Self {
        let h = v.x.hypot(v.y);
        let azimuth = if h == 0.0 {
            0.0
        } else {
            v.y.atan2(v.x).to_degrees()
        };
        let azimuth = if azimuth <= -180.0 {
            azimuth + 360.0
        } else {
            azimuth
        };
        Self {
            azimuth,
            elevation: v.z.atan2(h).to_degrees(),
        }
    }

    /// Unit vector of this direction.
    pub fn unit(&self) -> Vec3 {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }
}

/// Everything reported about one path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathReport {
    /// 1-based rank by (order, length, largest incidence angle).
    pub rank: usize,
    /// Number of reflections (0 = line of sight).
    pub order: usize,
    /// Names of the reflecting surfaces, TX side first.
    pub surfaces: Vec<String>,
    /// Surface ids, TX side first.
    #[serde(skip)]
    pub surface_ids: Vec<SurfaceId>,
    /// Interaction points, TX side first, metres (TX and RX excluded).
    pub points: Vec<[Real; 3]>,
    /// Total unfolded length, metres.
    pub length_m: Real,
    /// Propagation delay, seconds.
    pub delay_s: Real,
    /// Angle of departure at TX, degrees.
    pub aod_deg: Direction,
    /// Angle of arrival at RX (direction the wave comes from), degrees.
    pub aoa_deg: Direction,
    /// Angle of incidence at each reflection, from the surface normal, degrees.
    pub incidence_deg: Vec<Real>,
    /// Free-space path loss over the unfolded length at the scene's frequency, dB.
    pub free_space_loss_db: Real,
    /// Sum of the materials' per-reflection losses, dB.
    pub reflection_loss_db: Real,
    /// Total loss: free space plus reflections, dB.
    pub loss_db: Real,
    /// IPC rounds (IPC solver only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<u32>,
    /// IPC's last mean displacement, metres (IPC solver only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_m: Option<Real>,
}

/// Free-space path loss (Friis), dB, for `length` metres at `frequency_hz`. Friis holds in the
/// far field only: below one wavelength it would turn into a gain (−78.6 dB at 100 nm and
/// 28 GHz), so the length is clamped to [`near_field_limit_m`] and the loss is never below
/// 20 log10(4π) ≈ 21.98 dB. The one place the clamp lives; [`in_near_field`] tells callers to
/// warn.
pub fn free_space_loss_db(length: Real, frequency_hz: Real) -> Real {
    let length = length.max(near_field_limit_m(frequency_hz));
    20.0 * (4.0 * std::f64::consts::PI * length * frequency_hz / SPEED_OF_LIGHT).log10()
}

/// The shortest length Friis is used at: one wavelength, metres.
pub fn near_field_limit_m(frequency_hz: Real) -> Real {
    SPEED_OF_LIGHT / frequency_hz
}

/// Whether a path of `length` metres is shorter than [`near_field_limit_m`] (its loss clamped).
pub fn in_near_field(length: Real, frequency_hz: Real) -> bool {
    length < near_field_limit_m(frequency_hz)
}

/// Describe one found path (rank 0 until [`rank`] runs).
pub fn describe(scene: &Scene, path: &FoundPath) -> PathReport {
    let (tx, rx) = (scene.tx(), scene.rx());
    let mut vertices = Vec::with_capacity(path.points.len() + 2);
    vertices.push(tx);
    vertices.extend_from_slice(&path.points);
    vertices.push(rx);
    let length_m: Real = vertices
        .windows(2)
        .map(|w| w[0].distance(w[1]))
        .fold(0.0, |a, b| a + b);
    let incidence_deg = path
        .surfaces
        .iter()
        .enumerate()
        .map(|(k, id)| {
            let normal = scene.surface(*id).polygon.plane().normal;
            let incoming = (vertices[k] - vertices[k + 1]).normalize();
            incoming.dot(normal).abs().min(1.0).acos().to_degrees()
        })
        .collect();
    // Fold from +0.0: an empty f64 sum is -0.0, which would print as -0.0 for line of sight.
    let reflection_loss_db = path
        .surfaces
        .iter()
        .map(|id| scene.material_of(*id).reflection_loss_db)
        .fold(0.0, |a, b| a + b);
    let free_space_loss_db = free_space_loss_db(length_m, scene.frequency_hz());
    let n = vertices.len();
    PathReport {
        rank: 0,
        order: path.surfaces.len(),
        surfaces: path
            .surfaces
            .iter()
            .map(|id| scene.surface(*id).name.clone())
            .collect(),
        surface_ids: path.surfaces.clone(),
        points: path.points.iter().map(|p| p.to_array()).collect(),
        length_m,
        delay_s: length_m / SPEED_OF_LIGHT,
        aod_deg: Direction::of(vertices[1] - vertices[0]),
        aoa_deg: Direction::of(vertices[n - 2] - vertices[n - 1]),
        incidence_deg,
        free_space_loss_db,
        reflection_loss_db,
        loss_db: free_space_loss_db + reflection_loss_db,
        iterations: path.iterations,
        residual_m: path.residual,
    }
}

/// Describe and rank all paths: by order, then length, then the largest incidence angle
/// (closer to normal first), then surface ids — the paper's principles, made total.
pub fn report(scene: &Scene, paths: &[FoundPath]) -> Vec<PathReport> {
    let mut reports: Vec<PathReport> = paths.iter().map(|p| describe(scene, p)).collect();
    let key = |r: &PathReport| r.incidence_deg.iter().copied().fold(0.0, Real::max);
    reports.sort_by(|a, b| {
        a.order
            .cmp(&b.order)
            .then(a.length_m.total_cmp(&b.length_m))
            .then(key(a).total_cmp(&key(b)))
            .then(a.surface_ids.cmp(&b.surface_ids))
    });
    for (i, r) in reports.iter_mut().enumerate() {
        r.rank = i + 1;
    }
    reports
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_conventions() {
        let d = Direction::of(Vec3::new(0.0, 1.0, 0.0));
        assert!((d.azimuth - 90.0).abs() < 1e-12 && d.elevation.abs() < 1e-12);
        let d = Direction::of(Vec3::new(-1.0, 0.0, 1.0));
        assert!((d.azimuth - 180.0).abs() < 1e-12 && (d.elevation - 45.0).abs() < 1e-12);
        let v = Vec3::new(0.3, -0.4, 0.2).normalize();
        assert!((Direction::of(v).unit() - v).length() < 1e-12);
    }

    #[test]
    fn friis_is_clamped_below_one_wavelength() {
        let f = 28e9;
        let lambda = SPEED_OF_LIGHT / f;
        let floor = 20.0 * (4.0 * std::f64::consts::PI).log10();
        // Unclamped, 100 nm would give 20 log10(4π · 1e-7 / λ) ≈ -78.6 dB: a gain.
        for length in [1e-7, 1e-3, lambda * 0.5, lambda] {
            let l = free_space_loss_db(length, f);
            assert!((l - floor).abs() < 1e-9, "{length}: {l}");
            assert_eq!(in_near_field(length, f), length < lambda);
        }
        assert!(free_space_loss_db(2.0 * lambda, f) > floor + 6.0);
    }

    #[test]
    fn friis_at_one_metre_and_28_ghz() {
        // 20 log10(4 pi f / c) at 28 GHz = 20 log10(1173.68) = 61.391 dB
        assert!((free_space_loss_db(1.0, 28e9) - 61.391).abs() < 1e-3);
        assert!(
            (free_space_loss_db(10.0, 28e9) - free_space_loss_db(1.0, 28e9) - 20.0).abs() < 1e-9
        );
    }
}
