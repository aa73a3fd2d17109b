use super::*;
use bt_geom::Polygon;

fn surface(name: &str, vertices: &[[Real; 3]]) -> Surface {
    Surface {
        name: name.into(),
        material: "default".into(),
        kind: SurfaceKind::Reflector,
        polygon: Polygon::new(vertices.iter().map(|v| Vec3::from(*v)).collect()).unwrap(),
    }
}

/// Axis-aligned rectangle in the plane `axis = at`, spanning `lo..hi` in the other two axes.
fn rect(name: &str, axis: usize, at: Real, lo: [Real; 2], hi: [Real; 2]) -> Surface {
    let point = |u: Real, v: Real| {
        let mut p = [0.0; 3];
        p[axis] = at;
        p[(axis + 1) % 3] = u;
        p[(axis + 2) % 3] = v;
        p
    };
    surface(
        name,
        &[
            point(lo[0], lo[1]),
            point(hi[0], lo[1]),
            point(hi[0], hi[1]),
            point(lo[0], hi[1]),
        ],
    )
}

/// The six faces of the unit cube.
fn cube() -> Vec<Surface> {
    (0..3)
        .flat_map(|axis| {
            [0.0, 1.0].map(|at| rect(&format!("f{axis}{at}"), axis, at, [0.0; 2], [1.0; 2]))
        })
        .collect()
}

fn is_close(a: Real, b: Real) -> bool {
    (a - b).abs() < 1e-9
}

#[test]
fn a_cube_has_twelve_right_angled_wedges() {
    let edges = Edges::build(&cube());
    assert_eq!(edges.len(), 12);
    for e in edges.all() {
        assert!(is_close(e.n, 1.5), "n = {}", e.n);
        assert!(is_close(e.length, 1.0));
        assert!(!e.is_free());
        assert_eq!(e.touching.len(), 2);
        // The exterior is outside the cube: the centre is inside the wedge, a point beyond
        // the edge's corner is outside.
        let mid = 0.5 * (e.start + e.end);
        assert!(!e.in_exterior(Vec3::splat(0.5), 1e-9));
        let away = mid - Vec3::splat(0.5);
        let corner = mid + away - away.dot(e.direction) * e.direction;
        assert!(e.in_exterior(corner, 1e-9), "{corner}");
    }
}

#[test]
fn a_screen_has_four_free_edges() {
    let edges = Edges::build(&[rect("screen", 2, 0.0, [0.0; 2], [2.0, 1.0])]);
    assert_eq!(edges.len(), 4);
    for e in edges.all() {
        assert!(e.is_free());
        assert!(is_close(e.n, 2.0));
        // Everything off the screen's plane is exterior; the screen itself is not.
        let mid = 0.5 * (e.start + e.end);
        assert!(e.in_exterior(mid + Vec3::Z, 1e-9));
        assert!(e.in_exterior(mid - Vec3::Z, 1e-9));
        assert!(!e.in_exterior(Vec3::new(1.0, 0.5, 0.0), 1e-9));
    }
}

#[test]
fn coplanar_seams_do_not_diffract() {
    let edges = Edges::build(&[
        rect("a", 2, 0.0, [0.0; 2], [1.0; 2]),
        rect("b", 2, 0.0, [1.0, 0.0], [2.0, 1.0]),
    ]);
    // The outline: 2 + 2 sides of length 1 along y = 0 and y = 1, and the two ends.
    assert_eq!(edges.len(), 6);
    assert!(
        edges
            .all()
            .iter()
            .all(|e| is_close(e.length, 1.0) && e.is_free())
    );
    assert!(
        !edges
            .all()
            .iter()
            .any(|e| is_close(e.start.x, 1.0) && is_close(e.end.x, 1.0))
    );
}

#[test]
fn two_walls_meeting_diffract_on_the_reflex_side_only() {
    // Walls x = 0 (y in 0..1) and y = 0 (x in 0..1), height 1: a corner seen from inside
    // (x, y > 0) is concave, from outside it is a 270° wedge.
    let edges = Edges::build(&[
        rect("wx", 0, 0.0, [0.0; 2], [1.0; 2]),
        rect("wy", 1, 0.0, [0.0; 2], [1.0; 2]),
    ]);
    let corner: Vec<&Edge> = edges
        .all()
        .iter()
        .filter(|e| {
            is_close(e.start.x, 0.0)
                && is_close(e.start.y, 0.0)
                && is_close(e.end.x, 0.0)
                && is_close(e.end.y, 0.0)
        })
        .collect();
    assert_eq!(corner.len(), 1);
    let e = corner[0];
    assert!(is_close(e.n, 1.5));
    assert!(!e.in_exterior(Vec3::new(0.5, 0.5, 0.5), 1e-9));
    assert!(e.in_exterior(Vec3::new(-0.5, -0.5, 0.5), 1e-9));
    assert!(e.in_exterior(Vec3::new(-0.5, 0.5, 0.5), 1e-9));
    // 3 free edges per wall besides the corner.
    assert_eq!(edges.len(), 7);
}

#[test]
fn a_wall_standing_on_a_floor_does_not_diffract_at_its_foot() {
    let edges = Edges::build(&[
        rect("floor", 2, 0.0, [-2.0; 2], [2.0; 2]),
        rect("wall", 1, 0.0, [0.0, -1.0], [1.0, 1.0]),
    ]);
    // Floor: 4 free edges; wall: top and two sides (its foot runs through the floor).
    assert_eq!(edges.len(), 7);
    assert!(edges.all().iter().all(|e| e.is_free()));
    assert!(
        !edges
            .all()
            .iter()
            .any(|e| is_close(e.start.z, 0.0) && is_close(e.end.z, 0.0) && e.face0.0 == 1)
    );
}

#[test]
fn faces_of_different_shapes_are_matched_along_collinear_pieces() {
    // The cube's top split in two pieces (two shapes): the top sides along x of the walls
    // y = 0 and y = 1 each meet two roof pieces, so they become two wedges each; the seam
    // between the roof pieces is no edge.
    let mut faces: Vec<Surface> = cube().into_iter().filter(|s| s.name != "f21").collect();
    faces.push(rect("roof_a", 2, 1.0, [0.0, 0.0], [0.5, 1.0]));
    faces.push(rect("roof_b", 2, 1.0, [0.5, 0.0], [1.0, 1.0]));
    let edges = Edges::build(&faces);
    assert_eq!(edges.len(), 14);
    assert!(edges.all().iter().all(|e| is_close(e.n, 1.5)));
    let on_roof = edges
        .all()
        .iter()
        .filter(|e| is_close(e.start.z, 1.0) && is_close(e.end.z, 1.0))
        .count();
    assert_eq!(on_roof, 6);
}

#[test]
fn the_keller_point_makes_equal_angles() {
    let edges = Edges::build(&[rect("screen", 2, 0.0, [0.0; 2], [4.0, 1.0])]);
    let e = edges
        .all()
        .iter()
        .find(|e| is_close(e.length, 4.0))
        .unwrap();
    let (a, b) = (Vec3::new(0.5, -2.0, 1.0), Vec3::new(3.0, -0.5, -3.0));
    let t = e.keller(a, b).unwrap();
    let p = e.point(t);
    let cos_in = (p - a).normalize().dot(e.direction);
    let cos_out = (b - p).normalize().dot(e.direction);
    assert!((cos_in - cos_out).abs() < 1e-12, "{cos_in} {cos_out}");
}

/// The exterior test without trigonometry agrees with its definition by the angle φ
/// (φ ∈ (0, nπ), more than `tol` from the edge line and from both faces' half-planes), on a
/// deterministic spiral of points around wedges of several angles, away from the boundaries.
#[test]
fn the_exterior_test_agrees_with_the_angle_definition() {
    let tol = 1e-3;
    for gap_deg in [185.0_f64, 225.0, 270.0, 300.0, 360.0] {
        let gap = gap_deg.to_radians();
        let (e, t0) = (Vec3::Z, Vec3::X);
        let tn = face_direction(e, t0, gap);
        let edge = Edge {
            start: Vec3::ZERO,
            end: Vec3::Z,
            direction: e,
            length: 1.0,
            face0: SurfaceId(0),
            face_n: SurfaceId(1),
            t0,
            n: gap / PI,
            tn,
            y0: e.cross(t0),
            yn: tn.cross(e),
            touching: vec![],
        };
        let mut checked = 0;
        for k in 0..20_000 {
            let phi = (k as Real * 0.618_033_988_75 % 1.0) * 2.0 * PI;
            let r = 1e-4 + (k % 97) as Real * 0.01;
            let p = Vec3::new(r * phi.cos(), r * phi.sin(), 0.3);
            let clear = |angle: Real| angle >= PI / 2.0 || r * angle.sin() > tol;
            let by_angle = r > tol && phi > 0.0 && phi < gap && clear(phi) && clear(gap - phi);
            let near = |x: Real| (x.abs() - tol).abs() < 1e-9;
            if near(r * phi.sin()) || near(r * (gap - phi).sin()) || near(r) {
                continue;
            }
            assert_eq!(
                edge.in_exterior(p, tol),
                by_angle,
                "gap {gap_deg}° φ {phi} r {r}"
            );
            checked += 1;
        }
        assert!(checked > 19_000);
    }
}

/// The edges are found in chunks of boundary segments on all cores: the same edges, in the
/// same order, as on one thread, for a row of cubes with many chunks' segments (some cubes
/// touching their neighbours, so that wedges span two cubes' faces).
#[test]
fn edges_found_on_all_cores_are_those_found_on_one() {
    let surfaces: Vec<Surface> = (0..400)
        .flat_map(|k| {
            let x = k as Real * if k % 3 == 0 { 1.0 } else { 1.5 };
            cube().into_iter().map(move |mut s| {
                let moved = s
                    .polygon
                    .vertices()
                    .iter()
                    .map(|v| *v + Vec3::new(x, 0.0, 0.0));
                s.polygon = Polygon::new(moved.collect()).unwrap();
                s.name = format!("{}-{k}", s.name);
                s
            })
        })
        .collect();
    let sides: usize = surfaces.iter().map(|s| s.polygon.vertices().len()).sum();
    assert!(
        sides > 2 * SEGMENTS_PER_TASK,
        "{sides} sides: more than two tasks"
    );
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| Edges::build(&surfaces));
    let all = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| Edges::build(&surfaces));
    assert!(one.len() > 3000, "{} edges", one.len());
    assert_eq!(one.all(), all.all());
}
