//! Synthetic scans: points sampled uniformly on planar polygons with Gaussian noise along
//! the normal, from a seeded generator.

use bt_geom::{Real, Vec2, Vec3, poly2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cloud::PointCloud;

/// Sample `round(area · density_per_m2)` points uniformly on each planar polygon
/// (vertices in metres, world frame; any orientation, convex or not, no holes), displaced
/// along the polygon normal by Gaussian noise of standard deviation `noise_sigma_m`
/// (Box–Muller on a `ChaCha8Rng` seeded with `seed`). The result carries, as per-point
/// normals, the noise-free polygon normal (right-hand rule on the vertex order).
///
/// Points are drawn by rejection in the polygon's bounding rectangle. Polygons with fewer
/// than three vertices, non-finite coordinates or zero area are skipped, as are all
/// polygons when `density_per_m2` is not a positive finite number; a negative or
/// non-finite `noise_sigma_m` is treated as zero. Same inputs and seed ⇒ same cloud.
pub fn sample_polygons(
    polys: &[Vec<Vec3>],
    density_per_m2: Real,
    noise_sigma_m: Real,
    seed: u64,
) -> PointCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sigma = if noise_sigma_m.is_finite() && noise_sigma_m > 0.0 {
        noise_sigma_m
    } else {
        0.0
    };
    let mut points = Vec::new();
    let mut normals = Vec::new();
    if !(density_per_m2.is_finite() && density_per_m2 > 0.0) {
        return PointCloud::default();
    }
    for poly in polys {
        if poly.len() < 3 || poly.iter().any(|p| !p.is_finite()) {
            continue;
        }
        let nn = poly2::newell(poly);
        let area = 0.5 * nn.length();
        if !area.is_finite() || area <= 0.0 {
            continue;
        }
        let n = nn.normalize();
        let o = poly.iter().fold(Vec3::ZERO, |a, p| a + *p) / poly.len() as Real;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let p2: Vec<Vec2> = poly
            .iter()
            .map(|p| Vec2::new((*p - o).dot(u), (*p - o).dot(v)))
            .collect();
        let (lo, hi) = p2
            .iter()
            .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        let count = (area * density_per_m2).round() as usize;
        let mut made = 0;
        while made < count {
            let q = Vec2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
            if !poly2::contains(&p2, q) {
                continue;
            }
            // Box–Muller; 1 - x keeps the logarithm's argument in (0, 1].
            let (r1, r2): (Real, Real) = (rng.random(), rng.random());
            let g = (-2.0 * (1.0 - r1).ln()).sqrt() * (std::f64::consts::TAU * r2).cos();
            points.push(o + u * q.x + v * q.y + n * (g * sigma));
            normals.push(n);
            made += 1;
        }
    }
    PointCloud::from_parts_unchecked(points, Some(normals))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_lie_on_polygon_and_count_matches_area() {
        let sq = vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let c = sample_polygons(&[sq], 100.0, 0.0, 1);
        assert_eq!(c.len(), 200);
        assert!(c.points().iter().all(|p| p.z.abs() < 1e-12
            && (0.0..=2.0).contains(&p.x)
            && (0.0..=1.0).contains(&p.y)));
        assert_eq!(c.normals().unwrap()[0], Vec3::Z);
        let c2 = sample_polygons(&[vec![Vec3::ZERO, Vec3::X]], 100.0, 0.0, 1);
        assert!(c2.is_empty());
    }
}
