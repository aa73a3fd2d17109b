//! Slab transmission (ITU-R P.2040-4 eq. 43b) against an independent reference, the transfer
//! (characteristic) matrix of a layer, and a path through a wall against free space times T.

use bt_channel::{
    Antenna, Bounce, Complex64, Interaction, Polarization, RadioMaterial, SurfaceResponse,
    free_space, material::slab, path_gain_detailed, slab_transmission,
};
use bt_geom::{Real, Vec3};
use proptest::prelude::*;

/// The transmission of a slab of relative admittances `y0` outside and `y1` inside, phase
/// thickness `delta`, by the layer's characteristic matrix (e^{+jωt}):
/// M = [[cos δ, j·sin δ / y1], [j·y1·sin δ, cos δ]], t = 2·y0 / (y0·m11 + y0²·m12 + m21 + y0·m22).
fn transfer_matrix_t(y0: Complex64, y1: Complex64, delta: Complex64) -> Complex64 {
    let j = Complex64::new(0.0, 1.0);
    let (m11, m12, m21, m22) = (
        delta.cos(),
        j * delta.sin() / y1,
        j * y1 * delta.sin(),
        delta.cos(),
    );
    2.0 * y0 / (y0 * m11 + y0 * y0 * m12 + m21 + y0 * m22)
}

/// √(η − sin²θ) on the decaying branch (imaginary part ≤ 0).
fn inside_cos(eta: Complex64, cos: Real) -> Complex64 {
    let s = (eta - (1.0 - cos * cos)).sqrt();
    if s.im > 0.0 { -s } else { s }
}

proptest! {
    /// TE (admittance cos θ outside, √(η − sin²θ) inside) and TM (cos θ and √(η − sin²θ)/η):
    /// P.2040's closed form equals the transfer matrix for lossy slabs at any angle and
    /// thickness.
    #[test]
    fn slab_transmission_equals_the_transfer_matrix(
        eps in 1.0f64..12.0, loss in 0.0f64..3.0, cos in 0.05f64..1.0, d in 0.0f64..3.0,
    ) {
        let eta = Complex64::new(eps, -loss);
        let t = slab_transmission(eta, cos, d);
        let s = inside_cos(eta, cos);
        let delta = s * (2.0 * std::f64::consts::PI * d);
        let y0 = Complex64::new(cos, 0.0);
        let te = transfer_matrix_t(y0, s, delta);
        let tm = transfer_matrix_t(y0, s / eta, delta);
        prop_assert!((t.te - te).norm() <= 1e-9 * te.norm().max(1e-6), "{:?} vs {te}", t.te);
        prop_assert!((t.tm - tm).norm() <= 1e-9 * tm.norm().max(1e-6), "{:?} vs {tm}", t.tm);
    }

    /// A lossless slab reflects or transmits all the power: |R|² + |T|² = 1 per polarisation.
    #[test]
    fn a_lossless_slab_conserves_power(eps in 1.0f64..12.0, cos in 0.05f64..1.0, d in 0.0f64..3.0) {
        let eta = Complex64::new(eps, 0.0);
        let (r, t) = (slab(eta, cos, d), slab_transmission(eta, cos, d));
        prop_assert!((r.te.norm_sqr() + t.te.norm_sqr() - 1.0).abs() < 1e-12);
        prop_assert!((r.tm.norm_sqr() + t.tm.norm_sqr() - 1.0).abs() < 1e-12);
    }
}

/// A path straight through a 0.2 m concrete wall (the plane x = 5) at 3.5 GHz, TX and RX in the
/// horizontal plane: the gain is free space times T, TE for vertical antennas (E ⟂ the
/// horizontal plane of incidence) and TM for horizontal ones, at normal and oblique incidence,
/// within 0.05 dB (the bound; here to 1e-9 dB).
#[test]
fn a_wall_crossing_is_free_space_times_t() {
    let f = 3.5e9;
    let wall = RadioMaterial::itu("concrete", Some(0.2)).unwrap();
    let crossing = Interaction::Transmission(Bounce {
        normal: Vec3::X,
        response: SurfaceResponse::Radio(wall),
    });
    for angle_deg in [0.0f64, 30.0, 60.0] {
        let (tx, rx) = (Vec3::ZERO, {
            let a = angle_deg.to_radians();
            Vec3::new(10.0, 10.0 * a.tan(), 0.0)
        });
        let point = (tx + rx) * 0.5;
        let cos = angle_deg.to_radians().cos();
        let t = wall.transmission(f, cos).unwrap();
        let fs = free_space(tx.distance(rx), f).amplitude;
        for (polarization, coefficient) in [(Polarization::V, t.te), (Polarization::H, t.tm)] {
            let antenna = Antenna {
                polarization,
                ..Antenna::default()
            };
            let g = path_gain_detailed(
                tx,
                &[point],
                rx,
                &[crossing],
                (&antenna, &antenna),
                f,
                Default::default(),
            )
            .unwrap();
            let got_db = 20.0 * (g.gain.norm() / fs).log10();
            let want_db = 20.0 * coefficient.norm().log10();
            assert!(
                (got_db - want_db).abs() < 1e-9,
                "{angle_deg}°: {got_db} vs {want_db} dB"
            );
            assert!(
                want_db < -1.0 && want_db > -40.0,
                "{want_db} dB through concrete"
            );
        }
    }
    // A half-space lets nothing through; the error names the thickness.
    let half = SurfaceResponse::Radio(RadioMaterial::itu("concrete", None).unwrap());
    let e = half.transmission(f, 1.0).unwrap_err().to_string();
    assert!(e.contains("thickness"), "{e}");
}
