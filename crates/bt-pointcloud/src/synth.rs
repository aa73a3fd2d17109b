//! Synthetic scans: points sampled uniformly on planar polygons with Gaussian noise along
//! the normal, from a seeded generator.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cloud::PointCloud;

/// Newell normal (unnormalised; length = twice the area) of a 3-D polygon.
fn newell(poly: &[DVec3]) -> DVec3 {
    let n = poly.len();
    (0..n).fold(DVec3::ZERO, |acc, i| acc + poly[i].cross(poly[(i + 1) % n]))
}

fn inside(poly: &[DVec2], p: DVec2) -> bool {
    let n = poly.len();
    let mut c = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            c = !c;
        }
    }
    c
}

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
    polys: &[Vec<DVec3>],
    density_per_m2: f64,
    noise_sigma_m: f64,
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
        let nn = newell(poly);
        let area = 0.5 * nn.length();
        if !area.is_finite() || area <= 0.0 {
            continue;
        }
        let n = nn.normalize();
        let o = poly.iter().fold(DVec3::ZERO, |a, p| a + *p) / poly.len() as f64;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let p2: Vec<DVec2> = poly
            .iter()
            .map(|p| DVec2::new((*p - o).dot(u), (*p - o).dot(v)))
            .collect();
        let (lo, hi) = p2
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        let count = (area * density_per_m2).round() as usize;
        let mut made = 0;
        while made < count {
            let q = DVec2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
            if !inside(&p2, q) {
                continue;
            }
            // Box–Muller; 1 - x keeps the logarithm's argument in (0, 1].
            let (r1, r2): (f64, f64) = (rng.random(), rng.random());
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
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let c = sample_polygons(&[sq], 100.0, 0.0, 1);
        assert_eq!(c.len(), 200);
        assert!(c.points().iter().all(|p| p.z.abs() < 1e-12
            && (0.0..=2.0).contains(&p.x)
            && (0.0..=1.0).contains(&p.y)));
        assert_eq!(c.normals().unwrap()[0], DVec3::Z);
        let c2 = sample_polygons(&[vec![DVec3::ZERO, DVec3::X]], 100.0, 0.0, 1);
        assert!(c2.is_empty());
    }
}
