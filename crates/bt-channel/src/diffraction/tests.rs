use super::*;
use crate::material::RadioMaterial;

const UTD: DiffractionCoefficient = DiffractionCoefficient::Utd;

fn conductor() -> SurfaceResponse {
    SurfaceResponse::ConstantLoss { loss_db: 0.0 }
}

/// Abramowitz & Stegun, Table 7.7 (C(x), S(x) to 10 digits).
#[test]
fn fresnel_integrals_match_the_tables() {
    let table = [
        (0.5, 0.492_344_225_9, 0.064_732_432_9),
        (1.0, 0.779_893_400_4, 0.438_259_147_4),
        (1.5, 0.445_261_176_0, 0.697_504_960_1),
        (2.0, 0.488_253_406_1, 0.343_415_678_4),
        (2.5, 0.457_413_009_6, 0.619_181_755_8),
        (3.0, 0.605_720_789_3, 0.496_312_999_0),
        (4.0, 0.498_426_033_0, 0.420_515_754_2),
        (5.0, 0.563_631_188_7, 0.499_191_381_9),
    ];
    for (nu, c, s) in table {
        let (cc, ss) = fresnel_integrals(nu);
        assert!(
            (cc - c).abs() < 1e-9 && (ss - s).abs() < 1e-9,
            "{nu}: {cc} {ss}"
        );
        let (cm, sm) = fresnel_integrals(-nu);
        assert_eq!((cm, sm), (-cc, -ss));
    }
    assert_eq!(fresnel_integrals(0.0), (0.0, 0.0));
    // Large argument: C, S → 1/2 with the leading asymptotic terms.
    let nu: Real = 40.0;
    let (c, s) = fresnel_integrals(nu);
    let x = PI * nu * nu / 2.0;
    let (f, g) = (1.0 / (PI * nu), 1.0 / (PI * PI * nu.powi(3)));
    assert!((c - (0.5 + f * x.sin() - g * x.cos())).abs() < 1e-8, "{c}");
    assert!((s - (0.5 - f * x.cos() - g * x.sin())).abs() < 1e-8, "{s}");
}

/// Series and continued fraction meet at the switch without a step, and both agree with the
/// definition of F through C and S: F(x) = √(πx/2)·e^{jx}·[(1 + j) − 2(S(ν) + jC(ν))].
#[test]
fn transition_function_agrees_with_the_fresnel_integrals() {
    for x in [0.01, 0.3, 1.0, 2.0, 3.9, 4.0, 4.1, 7.0, 20.0, 100.0] {
        let (c, s) = fresnel_integrals((2.0 * x / PI).sqrt());
        let bracket = Complex64::new(1.0 - 2.0 * s, 1.0 - 2.0 * c);
        let expected = (PI * x / 2.0).sqrt() * Complex64::from_polar(1.0, x) * bracket;
        let f = transition(x);
        assert!((f - expected).norm() < 1e-12, "{x}: {f} vs {expected}");
    }
    let below = transition_over_root(SERIES_LIMIT * (1.0 - Real::EPSILON));
    let above = transition_over_root(SERIES_LIMIT);
    assert!((below - above).norm() < 1e-14, "{below} vs {above}");
}

/// Kouyoumjian–Pathak's limits: F(x) ≈ √(πx)·e^{jπ/4}·(1 + ...) for small x, F → 1 with
/// F ≈ 1 + j/(2x) for large x, |F| rising monotonically in between (their Fig. 6).
#[test]
fn transition_function_limits() {
    assert_eq!(transition(0.0), Complex64::new(0.0, 0.0));
    assert_eq!(transition(-1.0), Complex64::new(0.0, 0.0));
    for x in [1e-10, 1e-6, 1e-4] {
        let small = (PI * x).sqrt() * Complex64::from_polar(1.0, FRAC_PI_4);
        assert!((transition(x) - small).norm() < 3.0 * x, "{x}");
    }
    for x in [1e2, 1e4, 1e8] {
        let large = Complex64::new(1.0, 1.0 / (2.0 * x));
        assert!(
            (transition(x) - large).norm() < 1.0 / (x * x) + 1e-15,
            "{x}: {}",
            transition(x)
        );
    }
    let g0 = transition_over_root(0.0);
    assert!((g0 - PI.sqrt() * Complex64::from_polar(1.0, FRAC_PI_4)).norm() < 1e-15);
    let mut previous = 0.0;
    for i in 1..400 {
        let magnitude = transition(i as Real * 0.05).norm();
        assert!(magnitude > previous, "not rising at {}", i as Real * 0.05);
        previous = magnitude;
    }
}

/// cot·F across a pole: finite, equal to the analytic one-sided limits ±n√(2πkL)·e^{jπ/4},
/// and the value exactly on the pole is the lit side's (u → 0+).
#[test]
fn cot_transition_is_finite_and_jumps_by_the_known_amount_at_a_pole() {
    let (n, kl) = (1.5, 80.0);
    let limit = n * (2.0 * PI * kl).sqrt() * Complex64::from_polar(1.0, FRAC_PI_4);
    for w in [0.0, 2.0 * n * PI] {
        let on = cot_transition(w, n, kl);
        let plus = cot_transition(w + 1e-9, n, kl);
        let minus = cot_transition(w - 1e-9, n, kl);
        assert!(
            (on - limit).norm() < 1e-6 && (plus - limit).norm() < 1e-6,
            "{on} {plus}"
        );
        assert!((minus + limit).norm() < 1e-6, "{minus}");
    }
    // Away from the pole it is the plain product.
    for w in [0.7, 2.0, -3.0, 5.5] {
        let plain = Complex64::from((w / (2.0 * n)).tan().recip()) * {
            let u = w - 2.0 * n * PI * (w / (2.0 * n * PI)).round();
            transition(2.0 * kl * (u / 2.0).sin().powi(2))
        };
        assert!((cot_transition(w, n, kl) - plain).norm() < 1e-12, "{w}");
    }
}

fn corner() -> Wedge {
    Wedge::from_faces(Vec3::X, -Vec3::Y, conductor(), conductor()).unwrap()
}

#[test]
fn from_faces_gives_the_exterior_angle_and_side() {
    let w = corner();
    assert!((w.n - 1.5).abs() < 1e-15);
    assert_eq!(w.normal0, Vec3::Y);
    assert_eq!(w.edge, Vec3::Z);
    let acute = Wedge::from_faces(
        Vec3::X,
        Vec3::new(1.0, 1.0, 0.0).normalize(),
        conductor(),
        conductor(),
    )
    .unwrap();
    assert!((acute.n - 1.75).abs() < 1e-15);
    assert_eq!(acute.normal0, -Vec3::Y);
    for bad in [Vec3::X, -Vec3::X, Vec3::new(2.0, 0.0, 0.0)] {
        assert!(Wedge::from_faces(Vec3::X, bad, conductor(), conductor()).is_err());
    }
}

#[test]
fn invalid_wedges_are_errors() {
    let good = corner();
    let cases = [
        Wedge { n: 0.9, ..good },
        Wedge { n: 2.1, ..good },
        Wedge {
            n: Real::NAN,
            ..good
        },
        Wedge {
            edge: Vec3::X,
            ..good
        },
        Wedge {
            normal0: Vec3::X,
            ..good
        },
        Wedge {
            face0: Vec3::new(1.0, 0.1, 0.0),
            ..good
        },
    ];
    for wedge in cases {
        assert!(wedge.frame().is_err(), "{wedge:?}");
    }
    assert!(good.frame().is_ok());
}

/// The direction on Keller's cone of `k_in` about the z edge whose projection is along `across`.
fn on_cone(k_in: Vec3, across: Vec3) -> Vec3 {
    let radial = Vec3::new(across.x, across.y, 0.0).normalize() * (1.0 - k_in.z * k_in.z).sqrt();
    Vec3::new(radial.x, radial.y, k_in.z)
}

fn diffract_v(wedge: &Wedge, k_in: Vec3, k_out: Vec3) -> Result<Field, ChannelError> {
    let one = Complex64::new(1.0, 0.0);
    let field = scaled(k_in.cross(Vec3::Z).cross(k_in).normalize(), one);
    let legs = Legs {
        incident: 3.0,
        diffracted: 4.0,
        astigmatic: None,
    };
    diffract(field, (k_in, k_out), wedge, legs, (3.5e9, UTD)).map(|(f, _)| f)
}

#[test]
fn the_sense_of_the_edge_does_not_matter() {
    let w = corner();
    let k_in = Vec3::new(-1.0, -0.5, -0.3).normalize();
    let k_out = on_cone(k_in, Vec3::new(-0.2, -0.8, 0.0));
    let a = diffract_v(&w, k_in, k_out).unwrap();
    let b = diffract_v(&Wedge { edge: -w.edge, ..w }, k_in, k_out).unwrap();
    assert_eq!(a, b);
    assert!(dot(&a, Vec3::Z).norm() > 0.0);
}

#[test]
fn degenerate_rays_are_errors_not_nan() {
    let w = corner();
    // Along the edge.
    assert!(diffract_v(&w, Vec3::Z, Vec3::Z).is_err());
    // Off Keller's cone.
    let k_in = Vec3::new(-1.0, -1.0, 0.0).normalize();
    assert!(diffract_v(&w, k_in, Vec3::new(0.0, 0.6, 0.8)).is_err());
    // The diffracted ray points into the wedge (x > 0, y < 0 is the interior).
    assert!(diffract_v(&w, k_in, Vec3::new(1.0, -1.0, 0.0).normalize()).is_err());
    // NaN directions.
    let nan = Vec3::new(Real::NAN, 0.0, 0.0);
    assert!(diffract_v(&w, nan, nan).is_err());
}

/// Grazing incidence along face 0 (φ' = 0): the soft coefficient vanishes (the field
/// parallel to a conducting face is zero on it) and the hard one stays finite.
#[test]
fn grazing_incidence_is_finite_and_soft_vanishes() {
    let w = corner();
    let k_in = -Vec3::X; // arriving along face 0 towards the edge
    let k_out = Vec3::new(-0.3, -0.95, 0.0).normalize();
    let soft = diffract_v(&w, k_in, k_out).unwrap(); // V ∥ edge: soft
    assert!(soft.iter().all(|c| c.is_finite()));
    assert!(dot(&soft, Vec3::Z).norm() < 1e-12, "{soft:?}");
    let one = Complex64::new(1.0, 0.0);
    let legs = Legs {
        incident: 3.0,
        diffracted: 4.0,
        astigmatic: None,
    };
    let (hard, _) = diffract(scaled(Vec3::Y, one), (k_in, k_out), &w, legs, (3.5e9, UTD)).unwrap();
    let magnitude = hard.iter().map(|c| c.norm_sqr()).sum::<Real>().sqrt();
    assert!(magnitude.is_finite() && magnitude > 1e-3, "{hard:?}");
}

/// A lossless dielectric wedge gives coefficients between the absorbing (reflection terms
/// zero) and conducting extremes, and a vacuum "wedge" keeps only the incident terms.
#[test]
fn vacuum_faces_keep_only_the_incident_terms() {
    let vacuum = SurfaceResponse::Radio(RadioMaterial::itu("vacuum", None).unwrap());
    let w = Wedge {
        response0: vacuum,
        response_n: vacuum,
        ..corner()
    };
    let k_in = Vec3::new(-1.0, -0.5, 0.0).normalize();
    let k_out = Vec3::new(-0.4, -1.0, 0.0).normalize();
    let v = diffract_v(&w, k_in, k_out).unwrap();
    let h = {
        let one = Complex64::new(1.0, 0.0);
        let legs = Legs {
            incident: 3.0,
            diffracted: 4.0,
            astigmatic: None,
        };
        diffract(
            scaled(k_in.cross(Vec3::Z), one),
            (k_in, k_out),
            &w,
            legs,
            (3.5e9, UTD),
        )
        .unwrap()
        .0
    };
    // Same magnitude for both polarisations: −(D1 + D2)·I.
    let mv = v.iter().map(|c| c.norm_sqr()).sum::<Real>().sqrt();
    let mh = h.iter().map(|c| c.norm_sqr()).sum::<Real>().sqrt();
    assert!((mv - mh).abs() < 1e-12 * mv, "{mv} {mh}");
}

#[test]
fn coefficient_names_round_trip_and_bad_names_list_the_choices() {
    for c in DiffractionCoefficient::ALL {
        assert_eq!(c.name().parse::<DiffractionCoefficient>(), Ok(c));
        assert_eq!(c.to_string(), c.name());
    }
    assert_eq!(
        DiffractionCoefficient::default(),
        DiffractionCoefficient::Utd
    );
    let e = "sionna".parse::<DiffractionCoefficient>().unwrap_err();
    assert_eq!(
        e.to_string(),
        "diffraction coefficient: unknown coefficient \"sionna\" (expected utd or sionna-rt-2.2)"
    );
}

/// Sionna swaps the faces so that the incident wave sees face 0; the same wedge described
/// from its other face must give the same matrix, up to the sign of the edge-fixed bases
/// (ê flips with the description): for every source position, lit faces or not.
#[test]
fn sionna_coefficient_does_not_depend_on_which_face_is_face_0() {
    let concrete = SurfaceResponse::Radio(RadioMaterial::itu("concrete", Some(0.2)).unwrap());
    let metal = conductor();
    let a = Wedge::from_faces(Vec3::X, -Vec3::Y, concrete, metal).unwrap();
    let b = Wedge::from_faces(-Vec3::Y, Vec3::X, metal, concrete).unwrap();
    let legs = Legs {
        incident: 20.0,
        diffracted: 15.0,
        astigmatic: None,
    };
    let sionna = DiffractionCoefficient::SionnaRt22;
    // Sources behind face n, in front of both faces, behind face 0 (standard angles).
    for (phi_i, phi) in [(30.0, 200.0), (135.0, 60.0), (240.0, 100.0)] {
        let (phi_i, phi): (Real, Real) = (Real::to_radians(phi_i), Real::to_radians(phi));
        let k_in = -Vec3::new(phi_i.cos(), phi_i.sin(), 0.2).normalize();
        let k_out = on_cone(k_in, Vec3::new(phi.cos(), phi.sin(), 0.0));
        let ja = jones((k_in, k_out), &a, legs, 3.5e9, sionna).unwrap();
        let jb = jones((k_in, k_out), &b, legs, 3.5e9, sionna).unwrap();
        for (x, y) in ja.iter().flatten().zip(jb.iter().flatten()) {
            assert!(
                (x - y).norm() <= 1e-12 * x.norm().max(1e-3),
                "{ja:?} vs {jb:?}"
            );
        }
    }
}
