//! A furnished 4 × 5 × 2.6 m room as named planar polygons (world frame, metres, z up),
//! shared by the extraction tests and the benchmark.

use glam::DVec3;

/// Rectangle with corner `c` and edge vectors `e1`, `e2` (normal `e1 × e2`).
pub fn rect(c: [f64; 3], e1: [f64; 3], e2: [f64; 3]) -> Vec<DVec3> {
    let (c, a, b) = (DVec3::from(c), DVec3::from(e1), DVec3::from(e2));
    vec![c, c + a, c + a + b, c + b]
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The room's surfaces: name and polygon. 30 surfaces: 6 room faces (the south wall has a
/// door opening), a recessed door, coplanar-but-separate furniture faces (two cabinet
/// fronts, two cabinet tops, table top and a shelf at the same height), tilted panels
/// (sofa back 15°, whiteboard 10°, laptop lid 20°), a panel rotated 30° about z, a picture
/// 4 cm in front of a wall, and a small box whose faces are all below 0.25 m².
pub fn furnished_room() -> Vec<(&'static str, Vec<DVec3>)> {
    let (s15, c15) = (15f64.to_radians().sin(), 15f64.to_radians().cos());
    let (s10, c10) = (10f64.to_radians().sin(), 10f64.to_radians().cos());
    let (s20, c20) = (20f64.to_radians().sin(), 20f64.to_radians().cos());
    let (s30, c30) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    // One surface per line: (name, polygon); rect(corner, edge 1, edge 2).
    #[rustfmt::skip]
    let mut r: Vec<(&'static str, Vec<DVec3>)> = vec![
        ("floor",                   rect([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 5.0, 0.0])),
        ("ceiling",                 rect([0.0, 0.0, 2.6], [0.0, 5.0, 0.0], [4.0, 0.0, 0.0])),
        ("wall south (door opening)", vec![
            v(0.0, 0.0, 0.0), v(1.5, 0.0, 0.0), v(1.5, 0.0, 2.0), v(2.4, 0.0, 2.0),
            v(2.4, 0.0, 0.0), v(4.0, 0.0, 0.0), v(4.0, 0.0, 2.6), v(0.0, 0.0, 2.6),
        ]),
        ("door (recessed 4 cm)",    rect([1.5, -0.04, 0.0], [0.9, 0.0, 0.0], [0.0, 0.0, 2.0])),
        ("wall north",              rect([0.0, 5.0, 0.0], [0.0, 0.0, 2.6], [4.0, 0.0, 0.0])),
        ("wall west",               rect([0.0, 0.0, 0.0], [0.0, 0.0, 2.6], [0.0, 5.0, 0.0])),
        ("wall east",               rect([4.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 2.6])),
        ("table top",               rect([1.2, 2.0, 0.75], [1.2, 0.0, 0.0], [0.0, 0.8, 0.0])),
        ("shelf (table height)",    rect([3.7, 0.8, 0.75], [0.3, 0.0, 0.0], [0.0, 1.0, 0.0])),
        ("sofa seat",               rect([0.1, 1.0, 0.45], [0.8, 0.0, 0.0], [0.0, 2.0, 0.0])),
        ("sofa front",              rect([0.9, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.45])),
        // Bottom edge on the seat at x = 0.3, leaning 15° towards the west wall.
        ("sofa back (15 deg)",      rect([0.3, 1.0, 0.45], [0.0, 2.0, 0.0], [-0.5 * s15, 0.0, 0.5 * c15])),
        ("tv",                      rect([1.4, 4.95, 1.0], [0.0, 0.0, 0.7], [1.2, 0.0, 0.0])),
        ("picture (4 cm off wall)", rect([0.04, 3.5, 1.3], [0.0, 0.8, 0.0], [0.0, 0.0, 0.6])),
        ("whiteboard (10 deg)",     rect([3.4, 3.4, 0.6], [0.0, 0.9, 0.0], [s10, 0.0, c10])),
        ("screen (30 deg yaw)",     rect([2.2 - 0.4 * c30, 3.9 - 0.4 * s30, 0.2], [0.8 * c30, 0.8 * s30, 0.0], [0.0, 0.0, 1.5])),
        ("laptop lid (20 deg)",     rect([1.6, 2.6, 0.76], [0.35, 0.0, 0.0], [0.0, 0.25 * s20, 0.25 * c20])),
    ];
    // Two cabinets against the north wall (A at x = 0.2, B at 2.9): coplanar fronts and
    // tops, separate patches.
    for x0 in [0.2, 2.9] {
        let (y0, y1, h, w) = (4.55, 5.0, 0.9, 0.8);
        #[rustfmt::skip]
        r.extend([
            ("cabinet front",      rect([x0, y0, 0.0],     [w, 0.0, 0.0],      [0.0, 0.0, h])),
            ("cabinet top",        rect([x0, y0, h],       [w, 0.0, 0.0],      [0.0, y1 - y0, 0.0])),
            ("cabinet side left",  rect([x0, y0, 0.0],     [0.0, 0.0, h],      [0.0, y1 - y0, 0.0])),
            ("cabinet side right", rect([x0 + w, y0, 0.0], [0.0, y1 - y0, 0.0], [0.0, 0.0, h])),
        ]);
    }
    // Small box on the floor: every face below 0.25 m².
    let (bx, by, bw, bd, bh) = (2.8, 2.0, 0.4, 0.3, 0.3);
    #[rustfmt::skip]
    r.extend([
        ("box top",   rect([bx, by, bh],       [bw, 0.0, 0.0], [0.0, bd, 0.0])),
        ("box south", rect([bx, by, 0.0],      [bw, 0.0, 0.0], [0.0, 0.0, bh])),
        ("box north", rect([bx, by + bd, 0.0], [0.0, 0.0, bh], [bw, 0.0, 0.0])),
        ("box west",  rect([bx, by, 0.0],      [0.0, 0.0, bh], [0.0, bd, 0.0])),
        ("box east",  rect([bx + bw, by, 0.0], [0.0, bd, 0.0], [0.0, 0.0, bh])),
    ]);
    r
}
