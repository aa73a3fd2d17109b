//! Edge diffraction: the uniform theory of diffraction (UTD) of Kouyoumjian and Pathak, with
//! the finite-conductivity heuristic of Luebbers for lossy wedges, as Sionna RT documents it.
//!
//! For a wedge of exterior angle nπ, incidence angle β0 between the ray and the edge (the same
//! before and after, Keller's law), angles φ' (towards the source) and φ (towards the observer)
//! measured about the edge from face 0, and wavenumber k:
//!
//! ```text
//! D_{s,h} = −e^{−jπ/4} / (2n √(2πk) sin β0) · [ cot((π+(φ−φ'))/2n) F(kL a⁺(φ−φ'))
//!                                              + cot((π−(φ−φ'))/2n) F(kL a⁻(φ−φ'))
//!                                   + R_0^{s,h} · cot((π−(φ+φ'))/2n) F(kL a⁻(φ+φ'))
//!                                   + R_n^{s,h} · cot((π+(φ+φ'))/2n) F(kL a⁺(φ+φ')) ]
//! ```
//!
//! with a±(β) = 2cos²((2nπN± − β)/2), N± the integers nearest to (β ± π)/(2nπ), the distance
//! parameter L = s·s'·sin²β0/(s + s') of a spherical wave (s' from the source to the edge, s
//! from the edge to the observer, both unfolded through reflections), and the transition
//! function F(x) = 2j√x e^{jx} ∫_{√x}^∞ e^{−jτ²} dτ. R_0 and R_n are face 0's and face n's
//! reflection coefficients (TE for the soft coefficient D_s, TM for the hard D_h) at the
//! grazing angles φ' and nπ − φ. A perfect conductor (R_TE = −1, R_TM = +1) gives the exact
//! UTD coefficients. The diffracted field, in the edge-fixed bases (β̂0', φ̂') before and
//! (β̂0, φ̂) after the edge, is E_β0 = −D_s·E_β0', E_φ = −D_h·E_φ', spread by
//! A = √(s'/(s(s'+s))) on top of the incident field's 1/s'. Derivation, frames and the
//! comparison with Sionna RT: `docs/channel.md` §7.

use crate::ChannelError;
use crate::gain::SurfaceResponse;
use bt_geom::{Real, Vec3};
use num_complex::Complex64;
use std::f64::consts::{FRAC_PI_4, PI};

/// A diffracting wedge at one path's diffraction point (local to the path: directions only).
///
/// Frame: `edge` = ê (unit), `face0` = t̂0 (unit, ⊥ ê, in face 0, from the edge into the
/// face), ŷ0 = ê × t̂0. Angles about the edge are measured from t̂0 towards ŷ0; the exterior
/// (free space) is (0, nπ), face 0 at 0 and face n at nπ. A free edge (a screen) is n = 2
/// with both faces the screen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wedge {
    /// Unit edge direction ê.
    pub edge: Vec3,
    /// Unit vector t̂0: in face 0, ⊥ ê, pointing from the edge into face 0.
    pub face0: Vec3,
    /// Exterior angle over π, in (1, 2].
    pub n: Real,
    /// How face 0 reflects.
    pub response0: SurfaceResponse,
    /// How face n reflects.
    pub response_n: SurfaceResponse,
}

/// The soft and hard diffraction coefficients of one diffraction, √m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients {
    /// Soft (E along β̂0; pairs with R_TE).
    pub soft: Complex64,
    /// Hard (E along φ̂; pairs with R_TM).
    pub hard: Complex64,
}

impl Wedge {
    /// The angle (rad, [0, 2π)) about the edge of direction `d` (from the edge outwards).
    fn angle(&self, d: Vec3) -> Real {
        let y0 = self.edge.cross(self.face0);
        let phi = d.dot(y0).atan2(d.dot(self.face0));
        if phi < 0.0 { phi + 2.0 * PI } else { phi }
    }

    /// The UTD coefficients for a ray arriving along unit `k_in` and leaving along unit
    /// `k_out`, with unfolded lengths `s_in` (source to edge) and `s_out` (edge to observer),
    /// metres, at `frequency_hz`.
    pub fn coefficients(
        &self,
        (k_in, k_out): (Vec3, Vec3),
        (s_in, s_out): (Real, Real),
        frequency_hz: Real,
    ) -> Result<Coefficients, ChannelError> {
        let sin_beta = k_in.cross(self.edge).length();
        if sin_beta <= 1e-12 {
            return Err(ChannelError::Invalid {
                field: "diffraction",
                message: "the ray runs along the edge (sin β0 = 0)".into(),
            });
        }
        let k = 2.0 * PI * frequency_hz / crate::SPEED_OF_LIGHT;
        let phi_in = self.angle(-k_in);
        let phi_out = self.angle(k_out);
        let l = s_in * s_out * sin_beta * sin_beta / (s_in + s_out);
        let n = self.n;
        let term = |sign: Real, beta: Real| cot_f(n, sign, beta, k * l);
        let (d1, d2) = (term(1.0, phi_out - phi_in), term(-1.0, phi_out - phi_in));
        let (d3, d4) = (term(-1.0, phi_out + phi_in), term(1.0, phi_out + phi_in));
        let cos0 = phi_in.sin().abs().min(1.0);
        let cos_n = (n * PI - phi_out).sin().abs().min(1.0);
        let r0 = self.response0.reflection(frequency_hz, cos0)?;
        let rn = self.response_n.reflection(frequency_hz, cos_n)?;
        let scale =
            -Complex64::from_polar(1.0, -FRAC_PI_4) / (2.0 * n * (2.0 * PI * k).sqrt() * sin_beta);
        Ok(Coefficients {
            soft: scale * (d1 + d2 + r0.te * d3 + rn.te * d4),
            hard: scale * (d1 + d2 + r0.tm * d3 + rn.tm * d4),
        })
    }
}

/// `cot((π + sign·β)/2n) · F(kL·a^sign(β))`, with its finite limit at a shadow or reflection
/// boundary (where the cotangent diverges and F vanishes).
fn cot_f(n: Real, sign: Real, beta: Real, kl: Real) -> Complex64 {
    let big_n = ((beta + sign * PI) / (2.0 * n * PI)).round();
    let eps = PI + sign * beta - 2.0 * PI * n * big_n;
    let arg = (PI + sign * beta) / (2.0 * n);
    if arg.sin().abs() < 1e-9 {
        // K-P eq. (29): cot(·)F(kLa) → n[√(2πkL) sgn ε − 2kLε e^{jπ/4}] e^{jπ/4}.
        let j4 = Complex64::from_polar(1.0, FRAC_PI_4);
        let sgn = if eps >= 0.0 { 1.0 } else { -1.0 };
        return n * (Complex64::new((2.0 * PI * kl).sqrt() * sgn, 0.0) - 2.0 * kl * eps * j4) * j4;
    }
    let a = 2.0 * ((2.0 * n * PI * big_n - beta) / 2.0).cos().powi(2);
    transition(kl * a) * (arg.cos() / arg.sin())
}

/// The UTD transition function F(x) = 2j√x e^{jx} ∫_{√x}^∞ e^{−jτ²} dτ for x ≥ 0 (F(0) = 0,
/// F → 1 as x → ∞).
pub fn transition(x: Real) -> Complex64 {
    if x <= 0.0 {
        return Complex64::new(0.0, 0.0);
    }
    let sqrt_x = x.sqrt();
    // ∫_{√x}^∞ e^{−jτ²} dτ = √(π/2)·[(½ − C(u)) − j(½ − S(u))], u = √(2x/π).
    let (c, s) = fresnel((2.0 * x / PI).sqrt());
    let tail = (PI / 2.0).sqrt() * Complex64::new(0.5 - c, -(0.5 - s));
    Complex64::new(0.0, 2.0 * sqrt_x) * Complex64::from_polar(1.0, x) * tail
}

/// The Fresnel integrals C(u) = ∫₀ᵘ cos(πt²/2) dt and S(u) = ∫₀ᵘ sin(πt²/2) dt for u ≥ 0, to
/// about 1e-12: the power series below u = 1.5, a continued fraction (modified Lentz) above.
pub fn fresnel(u: Real) -> (Real, Real) {
    let x = u.abs();
    if x < 1.5 {
        return fresnel_series(x);
    }
    // erfc-like continued fraction for the auxiliary functions (Numerical Recipes §6.8).
    let pix2 = PI * x * x;
    let b0 = Complex64::new(1.0, -pix2);
    let tiny = 1e-300;
    let mut b = b0;
    let mut c = Complex64::new(1.0 / tiny, 0.0);
    let mut d = Complex64::new(1.0, 0.0) / b;
    let mut h = d;
    let mut n: i32 = -1;
    for _ in 2..200 {
        n += 2;
        let a = -Real::from(n * (n + 1));
        b += Complex64::new(4.0, 0.0);
        d = Complex64::new(1.0, 0.0) / (a * d + b);
        c = b + a / c;
        let del = c * d;
        h *= del;
        if (del.re - 1.0).abs() + del.im.abs() < 1e-15 {
            break;
        }
    }
    h *= Complex64::new(x, -x);
    let cs = Complex64::new(0.5, 0.5)
        * (Complex64::new(1.0, 0.0) - Complex64::from_polar(1.0, 0.5 * pix2) * h);
    (cs.re, cs.im)
}

/// Power series of the Fresnel integrals, for small `x`.
fn fresnel_series(x: Real) -> (Real, Real) {
    let t = PI * x * x / 2.0;
    let (mut c, mut s) = (0.0, 0.0);
    // C = Σ (−1)^m t^{2m} x / ((2m)! (4m+1)), S = Σ (−1)^m t^{2m+1} x / ((2m+1)! (4m+3)).
    let mut term = x; // t^k x / k!
    for k in 0..60 {
        let kk = k as Real;
        let sign = if (k / 2) % 2 == 0 { 1.0 } else { -1.0 };
        if k % 2 == 0 {
            c += sign * term / (2.0 * kk + 1.0);
        } else {
            s += sign * term / (2.0 * kk + 1.0);
        }
        term *= t / (kk + 1.0);
        if term.abs() < 1e-17 {
            break;
        }
    }
    (c, s)
}

/// Apply one diffraction to `field` (a complex 3-vector ⊥ `k_in`) arriving along unit `k_in`
/// and leaving along unit `k_out`: E_β0 = −D_s·E_β0', E_φ = −D_h·E_φ' in the edge-fixed bases.
pub(crate) fn diffract(
    field: [Complex64; 3],
    (k_in, k_out): (Vec3, Vec3),
    edge: Vec3,
    d: Coefficients,
) -> [Complex64; 3] {
    let phi_in = -(edge.cross(k_in)).normalize();
    let beta_in = phi_in.cross(k_in);
    let phi_out = edge.cross(k_out).normalize();
    let beta_out = phi_out.cross(k_out);
    let dot = |v: Vec3| field[0] * v.x + field[1] * v.y + field[2] * v.z;
    let (e_beta, e_phi) = (-d.soft * dot(beta_in), -d.hard * dot(phi_in));
    [
        e_beta * beta_out.x + e_phi * phi_out.x,
        e_beta * beta_out.y + e_phi * phi_out.y,
        e_beta * beta_out.z + e_phi * phi_out.z,
    ]
}

#[cfg(test)]
mod tests;
