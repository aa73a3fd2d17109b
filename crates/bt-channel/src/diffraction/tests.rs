use super::*;
use crate::antenna::{Antenna, Polarization};
use crate::gain::{Bounce, Interaction, mixed_path_gain};

const F: Real = 3.5e9;

fn metal() -> SurfaceResponse {
    SurfaceResponse::ConstantLoss { loss_db: 0.0 }
}

/// A perfectly conducting half-plane screen: the plane y = 0 for x ≤ 0... expressed as the edge
/// along z through the origin, the screen in x < 0 (face 0 towards −x, n = 2).
fn half_plane() -> Wedge {
    Wedge {
        edge: Vec3::Z,
        face0: -Vec3::X,
        n: 2.0,
        response0: metal(),
        response_n: metal(),
    }
}

/// The Fresnel–Kirchhoff knife-edge field relative to free space (ITU-R P.526 §4.1):
/// ((1+j)/2)·∫_v^∞ e^{−jπt²/2} dt.
fn knife_edge(v: Real) -> Complex64 {
    let (c, s) = fresnel(v);
    Complex64::new(0.5, 0.5) * Complex64::new(0.5 - c, -(0.5 - s))
}

#[test]
fn fresnel_integrals_match_tabulated_values() {
    // Abramowitz & Stegun table 7.7.
    for (u, c, s) in [
        (0.5, 0.492_344_225_871, 0.064_732_432_859),
        (1.0, 0.779_893_400_377, 0.438_259_147_390),
        (1.5, 0.445_261_176_040, 0.697_504_960_879),
        (2.0, 0.488_253_406_075, 0.343_415_678_364),
        (5.0, 0.563_631_188_855, 0.499_191_381_917),
    ] {
        let (cc, ss) = fresnel(u);
        assert!(
            (cc - c).abs() < 1e-9 && (ss - s).abs() < 1e-9,
            "{u}: {cc} {ss}"
        );
    }
    assert!((transition(1e4) - Complex64::new(1.0, 0.0)).norm() < 1e-4);
    // Small x: F(x) ≈ √(πx)·e^{jπ/4}.
    let x = 1e-6;
    let small = (PI * x).sqrt() * Complex64::from_polar(1.0, FRAC_PI_4);
    // The next term, −2x·e^{jπ/2}, is 2√(x/π) of the first: 1.1e-3 at x = 1e-6.
    assert!((transition(x) - small).norm() < 2e-3 * small.norm());
}

/// TX and RX on either side of the half-plane's line, `h` metres into the shadow at mid-way.
fn shadow_gain(h: Real, pol: Polarization) -> (Complex64, Real) {
    let (d1, d2) = (50.0, 40.0);
    // The screen occupies x < 0 in the plane y = 0; TX at y = −d1, RX at y = +d2, both at
    // x = −h' so that the straight line passes h below (behind) the edge at the screen.
    let tx = Vec3::new(-h, -d1, 0.0);
    let rx = Vec3::new(-h, d2, 0.0);
    let d = Vec3::ZERO;
    let antenna = Antenna {
        polarization: pol,
        ..Antenna::default()
    };
    let g = mixed_path_gain(
        tx,
        &[d],
        rx,
        &[Interaction::Diffraction(half_plane())],
        (&antenna, &antenna),
        F,
    )
    .unwrap()
    .gain;
    // Free space over the direct distance; the phase difference of the longer path.
    let lambda = crate::SPEED_OF_LIGHT / F;
    let direct = tx.distance(rx);
    let fs = lambda / (4.0 * PI * direct);
    let k = 2.0 * PI / lambda;
    let excess = tx.distance(d) + d.distance(rx) - direct;
    (g * Complex64::from_polar(1.0, -k * excess) / fs, {
        // v = h √(2/λ (1/d1 + 1/d2)), with h the clearance of the line below the edge.
        h * (2.0 / lambda * (1.0 / d1 + 1.0 / d2)).sqrt()
    })
}

#[test]
fn a_knife_edge_is_within_2_db_of_the_fresnel_integral_in_shadow() {
    for h in [0.5, 1.0, 2.0, 4.0] {
        for pol in [Polarization::V, Polarization::H] {
            let (utd, v) = shadow_gain(h, pol);
            let fk = knife_edge(v);
            let diff = 20.0 * (utd.norm() / fk.norm()).log10();
            assert!(
                diff.abs() < 2.0,
                "h {h} v {v:.2} {pol:?}: UTD {:.2} dB vs FK {:.2} dB",
                20.0 * utd.norm().log10(),
                20.0 * fk.norm().log10()
            );
        }
    }
}

/// LOS + reflection + diffraction round a right-angled wedge (n = 1.5), each with its
/// propagation phase: the total field is continuous across the shadow boundary.
#[test]
fn the_total_field_is_continuous_across_the_shadow_boundary() {
    // Wedge: faces along −x (face 0, in y = 0... the plane y = 0 for x < 0) and along −y
    // (face n, the plane x = 0 for y < 0); exterior = three quadrants around x > 0 or y > 0.
    let wedge = Wedge {
        edge: Vec3::Z,
        face0: -Vec3::X,
        n: 1.5,
        response0: metal(),
        response_n: metal(),
    };
    let lambda = crate::SPEED_OF_LIGHT / F;
    let k = 2.0 * PI / lambda;
    let tx = Vec3::new(-10.0, 5.0, 0.0);
    let a = Antenna::default();
    let total = |rx: Vec3| {
        let mut sum = Complex64::new(0.0, 0.0);
        let phase = |l: Real| Complex64::from_polar(1.0, -k * l);
        // Direct ray: blocked by face n (x = 0, y < 0) when it crosses x = 0 at y < 0.
        let t = -tx.x / (rx.x - tx.x);
        let y_cross = tx.y + t * (rx.y - tx.y);
        if !(rx.x > 0.0 && y_cross < 0.0) {
            let g = crate::gain::path_gain(tx, &[], rx, &[], (&a, &a), F).unwrap();
            sum += g * phase(tx.distance(rx));
        }
        let d = Vec3::ZERO;
        let g = mixed_path_gain(
            tx,
            &[d],
            rx,
            &[Interaction::Diffraction(wedge)],
            (&a, &a),
            F,
        )
        .unwrap()
        .gain;
        sum + g * phase(tx.distance(d) + d.distance(rx))
    };
    // The shadow boundary: the line from TX through the edge, continued to x > 0.
    let dir = (Vec3::ZERO - tx).normalize();
    let on = dir * 20.0;
    let across = Vec3::new(dir.y, -dir.x, 0.0);
    let (lit, dark) = (total(on - across * 1e-4), total(on + across * 1e-4));
    let go_jump = crate::gain::path_gain(tx, &[], on, &[], (&a, &a), F)
        .unwrap()
        .norm();
    assert!(
        (lit - dark).norm() < 0.01 * go_jump,
        "jump {} vs GO {}",
        (lit - dark).norm(),
        go_jump
    );
    let _ = Bounce {
        normal: Vec3::Y,
        response: metal(),
    };
}

/// A wedge tilted against the terminals' plane, faces of `response0` and `response_n`, and
/// the gain of the path `a → Keller point → b`.
fn tilted_gain(
    response0: SurfaceResponse,
    response_n: SurfaceResponse,
    a_: Vec3,
    b_: Vec3,
) -> Complex64 {
    let edge = Vec3::new(0.0, 0.3, 1.0).normalize();
    let face0 = -Vec3::X;
    let wedge = Wedge {
        edge,
        face0: (face0 - face0.dot(edge) * edge).normalize(),
        n: 1.6,
        response0,
        response_n,
    };
    let (ta, tb) = (a_.dot(edge), b_.dot(edge));
    let (da, db) = ((a_ - ta * edge).length(), (b_ - tb * edge).length());
    let d = edge * ((db * ta + da * tb) / (da + db));
    let a = Antenna::default();
    mixed_path_gain(
        a_,
        &[d],
        b_,
        &[Interaction::Diffraction(wedge)],
        (&a, &a),
        F,
    )
    .unwrap()
    .gain
}

/// Exactly reciprocal on a perfect conductor; on lossy faces Luebbers' heuristic (Sionna's)
/// evaluates face 0's coefficient at the incidence side's angle and face n's at the
/// observer's, so swapping the terminals changes the gain slightly: within 1 dB here.
#[test]
fn diffraction_is_reciprocal() {
    let (tx, rx) = (Vec3::new(-4.0, 3.0, 0.5), Vec3::new(3.0, 2.0, 2.0));
    let (forward, backward) = (
        tilted_gain(metal(), metal(), tx, rx),
        tilted_gain(metal(), metal(), rx, tx),
    );
    assert!(
        (forward - backward).norm() < 1e-9 * forward.norm(),
        "{forward} {backward}"
    );
    let concrete = SurfaceResponse::Radio(crate::RadioMaterial::itu("concrete", None).unwrap());
    let glass = SurfaceResponse::Radio(crate::RadioMaterial::itu("glass", None).unwrap());
    let (forward, backward) = (
        tilted_gain(concrete, glass, tx, rx),
        tilted_gain(concrete, glass, rx, tx),
    );
    let db = 20.0 * (forward.norm() / backward.norm()).log10();
    assert!(db.abs() < 1.0, "{db} dB");
}
