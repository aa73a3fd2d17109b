//! Two situations sequential RANSAC gets wrong on its own: a pane 2 cm (4 σ) in front of a
//! wall, whose points the wall's band partly claims, and shelves whose edges stop 3–5 cm
//! short of a wall, which must not be snapped onto the crease. A shelf that does touch the
//! wall must still be snapped (it lost a band of points to the wall).

use crate::common::room::rect;
use bt_pointcloud::{ExtractParams, ExtractedPlane, extract_planes, sample_polygons};
use glam::DVec3;

/// Distance of `c` from the plane of `p`, metres.
fn off(p: &ExtractedPlane, c: DVec3) -> f64 {
    (p.normal.dot(c) - p.offset).abs()
}

/// The extracted plane whose normal is within 2° of `n` and that passes nearest `c`.
fn find(planes: &[ExtractedPlane], n: DVec3, c: DVec3) -> &ExtractedPlane {
    planes
        .iter()
        .filter(|p| p.normal.dot(n).abs() > 2f64.to_radians().cos())
        .min_by(|a, b| off(a, c).total_cmp(&off(b, c)))
        .unwrap_or_else(|| panic!("no plane with normal {n} near {c}: {planes:#?}"))
}

/// Normal within 0.5°, offset at the true centroid `c` within 1.5 mm, area within 3 %.
fn check(p: &ExtractedPlane, n: DVec3, c: DVec3, area: f64, what: &str) {
    let off = off(p, c);
    let angle = p.normal.dot(n).abs().min(1.0).acos().to_degrees();
    let rel = (p.area_m2 - area) / area;
    eprintln!(
        "{what}: angle {angle:.3}°, offset {:.2} mm, area {:+.2} %, {} vertices",
        off * 1e3,
        rel * 100.0,
        p.polygon.len()
    );
    assert!(angle < 0.5, "{what}: normal off by {angle}°");
    assert!(off < 0.0015, "{what}: offset off by {off} m");
    assert!(rel.abs() < 0.03, "{what}: area {} vs {area}", p.area_m2);
}

/// A 4 × 2.5 m wall at y = 0 and a 1.6 × 1.0 m pane at y = 0.02 in front of it: sampled both
/// behind the pane (as a synthetic scan of the scene does) and with the wall occluded there
/// (as a real scanner sees it; the extracted wall then has the hole filled, since boundary
/// polygons have no holes, so its area is the full 10 m² either way).
#[test]
fn pane_two_centimetres_in_front_of_a_wall_is_separated() {
    let wall = |x0: f64, x1: f64, z0: f64, z1: f64| {
        rect([x0, 0.0, z0], [0.0, 0.0, z1 - z0], [x1 - x0, 0.0, 0.0])
    };
    let pane = rect([1.2, 0.02, 0.9], [0.0, 0.0, 1.0], [1.6, 0.0, 0.0]);
    let full = vec![wall(0.0, 4.0, 0.0, 2.5), pane.clone()];
    // The wall around a hole where the pane is (four rectangles).
    let occluded = vec![
        wall(0.0, 1.2, 0.0, 2.5),
        wall(2.8, 4.0, 0.0, 2.5),
        wall(1.2, 2.8, 0.0, 0.9),
        wall(1.2, 2.8, 1.9, 2.5),
        pane,
    ];
    let y = DVec3::Y;
    for (name, polys, wall_area) in [("behind", full, 10.0), ("occluded", occluded, 10.0)] {
        for (cloud_seed, ransac_seed) in [(3, 1), (8, 21)] {
            let cloud = sample_polygons(&polys, 2000.0, 0.005, cloud_seed);
            let params = ExtractParams {
                seed: ransac_seed,
                ..ExtractParams::default()
            };
            let ex = extract_planes(&cloud, &params).unwrap();
            let (wc, pc) = (DVec3::new(2.0, 0.0, 1.25), DVec3::new(2.0, 0.02, 1.4));
            let w = find(&ex.planes, y, wc);
            let p = find(&ex.planes, y, pc);
            assert!(!std::ptr::eq(w, p), "{name}: one plane for wall and pane");
            let tag = format!("{name} (seeds {cloud_seed}, {ransac_seed})");
            check(w, y, wc, wall_area, &format!("wall {tag}"));
            check(p, y, pc, 1.6, &format!("pane {tag}"));
            assert_eq!(p.polygon.len(), 4, "pane {tag}: {:?}", p.polygon);
            // The pane gets its points back: sequential RANSAC alone leaves the wall the
            // pane's near tail (≈ 16 % of them at 4 σ). Near the pane's edges and corners the
            // wall keeps some (moving needs an established layer around the point).
            let expected = 1.6 * 2000.0;
            let share = p.inliers as f64 / expected;
            assert!(
                (0.9..1.04).contains(&share),
                "pane {tag}: {} points of {expected}",
                p.inliers
            );
            assert!(p.reflector && w.reflector);
        }
    }
}

/// A 3 × 2.5 m wall at x = 0, one shelf touching it, and three whose edges stop 3, 4 and
/// 5 cm in front of it, all 0.55 m deep, at different heights.
#[test]
fn edges_a_few_centimetres_from_a_wall_are_not_snapped() {
    let wall = rect([0.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 2.5]);
    let shelf = |gap: f64, y0: f64, z: f64| rect([gap, y0, z], [0.55, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let shelves = [
        (0.0, 0.2, 0.5),
        (0.03, 1.6, 0.9),
        (0.04, 0.2, 1.4),
        (0.05, 1.6, 1.9),
    ];
    let mut polys = vec![wall];
    polys.extend(shelves.iter().map(|&(g, y0, z)| shelf(g, y0, z)));
    let cloud = sample_polygons(&polys, 2000.0, 0.005, 5);
    let ex = extract_planes(
        &cloud,
        &ExtractParams {
            seed: 2,
            ..ExtractParams::default()
        },
    )
    .unwrap();
    let z = DVec3::Z;
    for (gap, y0, h) in shelves {
        let c = DVec3::new(gap + 0.275, y0 + 0.5, h);
        let what = format!("shelf {:.0} cm off the wall", gap * 100.0);
        let p = find(&ex.planes, z, c);
        check(p, z, c, 0.55, &what);
        // The touching shelf shares the crease exactly; the others keep their gaps.
        let xmin = p.polygon.iter().map(|v| v.x).fold(f64::INFINITY, f64::min);
        if gap == 0.0 {
            assert!(xmin.abs() < 0.002, "{what}: ends at x = {xmin}");
        } else {
            assert!((xmin - gap).abs() < 0.008, "{what}: ends at x = {xmin}");
        }
    }
}
