//! First-order edge diffraction (UTD): the wedge seen by one path, the Kouyoumjian–Pathak
//! coefficient with Luebbers' finite-conductivity heuristic as Sionna RT documents it (the
//! default) or as Sionna RT 2.2's code combines it ([`DiffractionCoefficient`]), and the
//! Fresnel-integral transition function. Formulas, frames and where we differ from Sionna:
//! `docs/channel.md`, section "Diffraction (UTD)".

use crate::ChannelError;
use crate::gain::{Bounce, Field, SurfaceResponse, add, dot, reflect, scaled};
use crate::material::SPEED_OF_LIGHT;
use bt_geom::{Real, Vec3};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_4, PI};
use std::fmt;
use std::str::FromStr;

/// How far from 1 the length of a unit vector of a [`Wedge`] may be, and how far from 0 the
/// cosine between two of its vectors that must be perpendicular (dimensionless; loose enough
/// for vectors derived from f64 scene geometry, tight enough to catch a wrong argument).
pub const WEDGE_UNIT_TOLERANCE: Real = 1e-6;

/// Smallest sin β0 (β0 = angle between the incident ray and the edge) for which a diffraction
/// is evaluated: below it the ray runs along the edge, the edge-fixed basis is undefined and
/// the gain is an error (dimensionless, ≈ 0.2″ of arc).
pub const MIN_SIN_BETA: Real = 1e-6;

/// How far the diffracted ray may leave Keller's cone: |ŝ·ê − ŝ'·ê| above this is an error
/// (dimensionless cosine; a diffraction point found by an iterative solver is this close).
pub const KELLER_COS_TOLERANCE: Real = 1e-6;

/// How far (rad) a ray may point into the wedge's interior and still be taken as grazing the
/// nearer face (then snapped onto it).
pub const FACE_ANGLE_TOLERANCE: Real = 1e-9;

/// Below this argument the transition function is summed from the power series of the
/// Fresnel integral, above it from a continued fraction (both within 4e-15 there).
const SERIES_LIMIT: Real = 4.0;

/// Depth of the continued fraction of erfcx (converged to 2e-15 for x >= 4).
const FRACTION_DEPTH: usize = 80;

/// Which diffraction coefficient a diffracted path's gain uses (`docs/channel.md` §8). Both
/// share the wedge frame, the four Kouyoumjian–Pathak terms D1..D4 (units √m), the transition
/// function and the faces' reflection matrices R_0, R_n in the edge-fixed bases; they differ in
/// how these are combined into the Jones matrix J.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DiffractionCoefficient {
    /// `utd`: Kouyoumjian–Pathak with Luebbers' heuristic in Sionna RT's documented form,
    /// J = −[(D1 + D2)·I − D3·R_n − D4·R_0]: exactly Kouyoumjian–Pathak for a conductor, and
    /// the total field is continuous across every shadow and reflection boundary.
    #[default]
    #[serde(rename = "utd")]
    Utd,
    /// `sionna-rt-2.2`: Sionna RT 2.2's `RadioMaterial._diffraction_matrix`, for comparing
    /// with Sionna: J = R_0·(D1 − D4) + R_n·(D2 − D3) after swapping the faces so that the
    /// incident wave sees face 0, with R_n := −I when face n is not lit
    /// (`docs/sionna-diffraction-notes.md` §4). Not continuous across face 0's reflection
    /// boundary; for a conductor the hard component gets the soft coefficient. The diffracted
    /// leg s stays UTD's unfolded length; Sionna 2.2's, which depends on its solver's
    /// `max_depth`, is [`crate::path_gain_sionna_rt22`]'s.
    #[serde(rename = "sionna-rt-2.2")]
    SionnaRt22,
}

impl DiffractionCoefficient {
    /// Every coefficient, default first.
    pub const ALL: [DiffractionCoefficient; 2] = [
        DiffractionCoefficient::Utd,
        DiffractionCoefficient::SionnaRt22,
    ];

    /// The name users give it (CLI, Python, the report's `radio.diffraction_coefficient`).
    pub const fn name(self) -> &'static str {
        match self {
            DiffractionCoefficient::Utd => "utd",
            DiffractionCoefficient::SionnaRt22 => "sionna-rt-2.2",
        }
    }
}

impl fmt::Display for DiffractionCoefficient {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DiffractionCoefficient {
    type Err = ChannelError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| ChannelError::Invalid {
                field: "diffraction coefficient",
                message: format!("unknown coefficient \"{s}\" (expected utd or sionna-rt-2.2)"),
            })
    }
}

/// A diffracting wedge (or a free edge: a half-plane screen, n = 2), local to one path.
///
/// Frame (world frame, unit vectors): t0 = `face0` lies in face 0 and points from the edge
/// into it; `normal0` is face 0's normal on its free-space side. The exterior angle φ is
/// measured about ê = t0 × `normal0` (so that ê × t0 = `normal0`), from t0 (φ = 0, face 0)
/// through `normal0` (φ = π/2) to face n at φ = nπ; free space is 0 < φ < nπ. Face n lies
/// along cos(nπ)·t0 + sin(nπ)·`normal0`. `edge` is the edge line's direction in either sense:
/// it is checked against ê and otherwise unused, so −`edge` gives the identical gain.
///
/// From two face half-planes meeting at an edge, [`Wedge::from_faces`] builds it; for a
/// half-plane (n = 2, both faces the same half-plane) fill the fields directly: `normal0`
/// picks which side is face 0 (`response0`), the other side is face n (`response_n`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wedge {
    /// Unit direction of the edge line, either sense.
    pub edge: Vec3,
    /// Unit vector t0 ⊥ edge in face 0, pointing from the edge into face 0.
    pub face0: Vec3,
    /// Unit normal of face 0 on its exterior (free-space) side, ⊥ edge and t0.
    pub normal0: Vec3,
    /// Exterior angle / π, in [1, 2] (2 = a half-plane screen, 1.5 = a right-angled corner).
    pub n: Real,
    /// How face 0 reflects (Luebbers' heuristic for lossy wedges).
    pub response0: SurfaceResponse,
    /// How face n reflects.
    pub response_n: SurfaceResponse,
}

/// The wedge's validated orthonormal frame.
pub(crate) struct Frame {
    pub(crate) e: Vec3,
    t0: Vec3,
    n0: Vec3,
    /// A unit normal of face n (its sign does not matter for reflection).
    nn: Vec3,
    n: Real,
}

fn invalid(message: String) -> ChannelError {
    ChannelError::Invalid {
        field: "wedge",
        message,
    }
}

fn is_unit(v: Vec3) -> bool {
    v.is_finite() && (v.length() - 1.0).abs() <= WEDGE_UNIT_TOLERANCE
}

impl Wedge {
    /// The wedge between two faces meeting at an edge: `face0` and `face_n` are unit vectors
    /// ⊥ edge, each in its face and pointing from the edge into it (world frame). The interior
    /// angle α = acos(face0·face_n) gives n = 2 − α/π, and `normal0` is the unit part of
    /// −face_n ⊥ face0 (the exterior side of face 0). Errors when the faces are (anti)parallel
    /// (α ≈ 0: a half-plane, build the struct directly; α ≈ π: a flat surface, no edge).
    pub fn from_faces(
        face0: Vec3,
        face_n: Vec3,
        response0: SurfaceResponse,
        response_n: SurfaceResponse,
    ) -> Result<Wedge, ChannelError> {
        if !(is_unit(face0) && is_unit(face_n)) {
            return Err(invalid(format!(
                "face directions must be unit vectors, got {face0} and {face_n}"
            )));
        }
        let cos = face0.dot(face_n).clamp(-1.0, 1.0);
        let across = face_n - cos * face0;
        if across.length() <= WEDGE_UNIT_TOLERANCE {
            return Err(invalid(format!(
                "faces {face0} and {face_n} are (anti)parallel: no wedge angle (a half-plane needs normal0)"
            )));
        }
        let normal0 = -across.normalize();
        let wedge = Wedge {
            edge: face0.cross(normal0),
            face0,
            normal0,
            n: 2.0 - cos.acos() / PI,
            response0,
            response_n,
        };
        wedge.frame()?;
        Ok(wedge)
    }

    /// Check the fields (units, orthogonality, n in [1, 2]) and build the frame.
    pub(crate) fn frame(&self) -> Result<Frame, ChannelError> {
        let (t0, n0) = (self.face0, self.normal0);
        if !(is_unit(self.edge) && is_unit(t0) && is_unit(n0)) {
            return Err(invalid(format!(
                "edge, face0 and normal0 must be unit vectors, got {}, {t0} and {n0}",
                self.edge
            )));
        }
        if t0.dot(n0).abs() > WEDGE_UNIT_TOLERANCE || self.edge.dot(t0).abs() > WEDGE_UNIT_TOLERANCE
        {
            return Err(invalid(format!(
                "face0 {t0} must be perpendicular to the edge {} and to normal0 {n0}",
                self.edge
            )));
        }
        let e = t0.cross(n0);
        if self.edge.cross(e).length() > WEDGE_UNIT_TOLERANCE {
            return Err(invalid(format!(
                "the edge {} is not along face0 × normal0 = {e}",
                self.edge
            )));
        }
        if !(1.0..=2.0).contains(&self.n) {
            return Err(invalid(format!(
                "n (exterior angle / π) must lie in [1, 2], got {}",
                self.n
            )));
        }
        let (sin, cos) = (self.n * PI).sin_cos();
        let tn = cos * t0 + sin * n0;
        Ok(Frame {
            e,
            t0,
            n0,
            nn: e.cross(tn),
            n: self.n,
        })
    }
}

/// Fresnel integrals C(ν) = ∫₀^ν cos(πt²/2) dt and S(ν) = ∫₀^ν sin(πt²/2) dt (odd in ν),
/// to about 1e-14 absolute.
pub fn fresnel_integrals(nu: Real) -> (Real, Real) {
    let a = nu.abs();
    let x = PI * a * a / 2.0;
    let (c, s) = if x < SERIES_LIMIT {
        let phi = fresnel_series(a);
        (phi.re, phi.im)
    } else {
        // Auxiliary functions: G = √(2π)·(f + j·g); C = ½ + f sin x − g cos x,
        // S = ½ − f cos x − g sin x.
        let fg = transition_over_root(x) / (2.0 * PI).sqrt();
        let (sin, cos) = x.sin_cos();
        (
            0.5 + fg.re * sin - fg.im * cos,
            0.5 - fg.re * cos - fg.im * sin,
        )
    };
    if nu < 0.0 { (-c, -s) } else { (c, s) }
}

/// C(ν) + j·S(ν) = Σ (jπ/2)^m ν^(2m+1) / (m!·(2m+1)) for ν >= 0 with πν²/2 below
/// [`SERIES_LIMIT`] (terms at most e⁴ ≈ 55 times the sum: 1e-14 relative).
fn fresnel_series(nu: Real) -> Complex64 {
    let step = Complex64::new(0.0, PI / 2.0 * nu * nu);
    let mut power = Complex64::new(nu, 0.0);
    let mut sum = power;
    for m in 1..200 {
        power = power * step / m as Real;
        let term = power / (2 * m + 1) as Real;
        sum += term;
        if term.norm() <= 1e-17 * sum.norm() {
            break;
        }
    }
    sum
}

/// G(x) = F(x)/√x for x >= 0, finite at 0 (G(0) = √π·e^{jπ/4}) and ~ 1/√x for large x.
/// G(x) = √π·e^{jπ/4}·erfcx(√x·e^{jπ/4}): the power series of C + jS below
/// [`SERIES_LIMIT`], the Laplace continued fraction of erfcx above.
fn transition_over_root(x: Real) -> Complex64 {
    let x = x.max(0.0);
    let rotation = Complex64::from_polar(1.0, FRAC_PI_4);
    if x < SERIES_LIMIT {
        // G = j·√(2π)·e^{jx}·[(1 − j)/2 − conj(C + jS)] at ν = √(2x/π).
        let phi = fresnel_series((2.0 * x / PI).sqrt());
        let bracket = Complex64::new(0.5, -0.5) - phi.conj();
        Complex64::new(0.0, (2.0 * PI).sqrt()) * Complex64::from_polar(1.0, x) * bracket
    } else {
        // erfcx(z) = 1/(√π·(z + (1/2)/(z + (2/2)/(z + (3/2)/(z + …))))).
        let z = x.sqrt() * rotation;
        let mut t = z;
        for m in (1..=FRACTION_DEPTH).rev() {
            t = z + (m as Real / 2.0) / t;
        }
        rotation / t
    }
}

/// The UTD transition function F(x) = 2j·√x·e^{jx}·∫_{√x}^∞ e^{−jτ²} dτ (Kouyoumjian–Pathak),
/// x >= 0 (negative x is taken as 0): F(0) = 0, F(x) ≈ √(πx)·e^{jπ/4} for small x, F → 1
/// for large x.
pub fn transition(x: Real) -> Complex64 {
    let x = x.max(0.0);
    transition_over_root(x) * x.sqrt()
}

/// cot(w/(2n))·F(kL·a(w)) of one UTD term, w = π ± (φ ∓ φ'), with a(w) = 2cos²((2nπN − β)/2)
/// written as 2 sin²(u/2), u = w − 2nπ·round(w/(2nπ)) ∈ [−nπ, nπ]. Its only pole is u = 0
/// (a shadow or reflection boundary), where cot → ∞ and F → 0: the product is evaluated as
/// cos(u/2n)·[√(2kL)·|sin(u/2)|/sin(u/2n)]·G(x), exact for every u ≠ 0 and, at u = 0, the
/// limit from u > 0, which is the lit side for all four terms.
fn cot_transition(w: Real, n: Real, kl: Real) -> Complex64 {
    let period = 2.0 * n * PI;
    let u = w - period * (w / period).round();
    let half = (u / 2.0).sin();
    let x = 2.0 * kl * half * half;
    let root = (2.0 * kl).sqrt();
    let ratio = if u == 0.0 {
        n * root
    } else {
        root * half.abs() / (u / (2.0 * n)).sin()
    };
    (u / (2.0 * n)).cos() * ratio * transition_over_root(x)
}

/// φ of direction `d` about the edge (rad, in [0, nπ]), snapped onto a face within
/// [`FACE_ANGLE_TOLERANCE`]; an error inside the wedge.
fn exterior_angle(frame: &Frame, d: Vec3, what: &str) -> Result<Real, ChannelError> {
    let mut phi = d.dot(frame.n0).atan2(d.dot(frame.t0));
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let limit = frame.n * PI;
    if phi <= limit {
        return Ok(phi);
    }
    if 2.0 * PI - phi <= FACE_ANGLE_TOLERANCE {
        Ok(0.0)
    } else if phi - limit <= FACE_ANGLE_TOLERANCE {
        Ok(limit)
    } else {
        Err(invalid(format!(
            "the {what} lies inside the wedge (φ = {phi} rad > nπ = {limit} rad)"
        )))
    }
}

/// Edge-fixed basis (φ̂', β̂0') of a ray arriving along `k`: φ̂' = k × ê/|k × ê|, β̂0' = φ̂' × k.
fn incident_basis(k: Vec3, e: Vec3) -> (Vec3, Vec3) {
    let phi = k.cross(e).normalize();
    (phi, phi.cross(k))
}

/// Edge-fixed basis (φ̂, β̂0) of a ray leaving along `k`: φ̂ = ê × k/|ê × k|, β̂0 = φ̂ × k.
pub(crate) fn outgoing_basis(k: Vec3, e: Vec3) -> (Vec3, Vec3) {
    let phi = e.cross(k).normalize();
    (phi, phi.cross(k))
}

type Matrix = [[Complex64; 2]; 2];

/// Face ν's reflection as a 2×2 matrix from (φ̂', β̂0') of the incident ray to (φ̂, β̂0) of
/// that face's specular direction, with the face's coefficients at the true incidence angle
/// cos θ = |ŝ'·n̂ν| (Sionna RT 2.2's choice). The same numbers are then applied to the
/// diffracted ray's basis (Sionna's "Hashimoto" basis). A perfect conductor gives exactly
/// diag(−1, +1), i.e. Kouyoumjian–Pathak's soft/hard signs.
fn face_matrix(
    normal: Vec3,
    response: SurfaceResponse,
    k_in: Vec3,
    e: Vec3,
    frequency_hz: Real,
) -> Result<Matrix, ChannelError> {
    let bounce = Bounce { normal, response };
    let one = Complex64::new(1.0, 0.0);
    let (phi_in, beta_in) = incident_basis(k_in, e);
    let mut m = [[Complex64::new(0.0, 0.0); 2]; 2];
    for (column, v) in [phi_in, beta_in].into_iter().enumerate() {
        let (out, k_out) = reflect(scaled(v, one), k_in, &bounce, frequency_hz)?;
        let (phi_out, beta_out) = outgoing_basis(k_out, e);
        m[0][column] = dot(&out, phi_out);
        m[1][column] = dot(&out, beta_out);
    }
    Ok(m)
}

/// Lengths of the path on each side of the diffraction point, metres (unfolded through the
/// reflections on that side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Legs {
    /// s': source (or the previous diffraction point) to diffraction point.
    pub incident: Real,
    /// s: diffraction point to observer (or the next diffraction point).
    pub diffracted: Real,
    /// The incident wave's curvature when it is not a point source's sphere of radius
    /// `incident`: a wave diffracted by an edge before.
    pub astigmatic: Option<Caustics>,
}

/// An astigmatic incident wave at a diffraction point: its principal radii of curvature ρ1,
/// ρ2 and ρ_e, its radius in the edge-fixed plane of incidence (the plane of the incident ray
/// and the edge), metres (Kouyoumjian and Pathak 1974, eqs. 25 and 29).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Caustics {
    /// ρ1, ρ2: the principal radii.
    pub principal: (Real, Real),
    /// ρ_e: the radius in the edge-fixed plane of incidence.
    pub in_plane: Real,
}

impl Caustics {
    /// The wave a first diffraction sends on, at the second edge (unit direction `edge`): its
    /// rays leave a line (the first edge, `from_edge` metres back along the ray: radius s1 in
    /// the direction around that edge) and spread along it as the source's sphere did (radius
    /// s0 + s1 in the direction `beta`, unit, ⊥ the ray `k`, in the plane of the first edge
    /// and the ray). Euler's formula gives the radius in the plane of `k` and `edge`:
    /// 1/ρ_e = cos²α/(s0 + s1) + sin²α/s1, α the angle between `beta` and the edge's
    /// direction seen across the ray.
    pub fn after_edge((s0, s1): (Real, Real), beta: Vec3, (k, edge): (Vec3, Vec3)) -> Caustics {
        let along = (s0 + s1, s1);
        let u = (edge - edge.dot(k) * k).normalize_or_zero();
        let cos2 = u.dot(beta).powi(2).min(1.0);
        Caustics {
            principal: along,
            in_plane: 1.0 / (cos2 / along.0 + (1.0 - cos2) / along.1),
        }
    }
}

impl Legs {
    /// The legs clamped to at least one wavelength (the far-field floor of
    /// [`crate::free_space`]), the radii too.
    fn clamped(self, wavelength: Real) -> Legs {
        Legs {
            incident: self.incident.max(wavelength),
            diffracted: self.diffracted.max(wavelength),
            astigmatic: self.astigmatic.map(|c| Caustics {
                principal: (c.principal.0.max(wavelength), c.principal.1.max(wavelength)),
                in_plane: c.in_plane.max(wavelength),
            }),
        }
    }

    /// k·L, UTD's distance parameter L (metres) times the wavenumber `k` (rad/m), for the
    /// ray's sin β0: L = s·s'/(s + s')·sin²β0 for a point source; s·(ρ_e + s)·ρ1·ρ2·sin²β0 /
    /// (ρ_e·(ρ1 + s)·(ρ2 + s)) for an astigmatic wave.
    fn kl(self, k: Real, sin_beta: Real) -> Real {
        let (s_i, s) = (self.incident, self.diffracted);
        match self.astigmatic {
            None => k * s_i * s / (s_i + s) * sin_beta * sin_beta,
            Some(c) => {
                let ((r1, r2), re) = (c.principal, c.in_plane);
                k * s * (re + s) * r1 * r2 * sin_beta * sin_beta / (re * (r1 + s) * (r2 + s))
            }
        }
    }
}

/// UTD amplitude factor of a point source diffracted once: λ/(4π)·1/√(s'·s·(s' + s)) =
/// λ/(4π)·(1/s')·√(s'/(s·(s' + s))), s' and s each clamped to at least one wavelength (the
/// far-field floor of [`crate::free_space`]). Units: 1/m³ᐟ²·m, multiplied by D (√m).
pub(crate) fn spreading(legs: Legs, frequency_hz: Real) -> Real {
    let wavelength = SPEED_OF_LIGHT / frequency_hz;
    let (s_i, s_d) = (
        legs.incident.max(wavelength),
        legs.diffracted.max(wavelength),
    );
    wavelength / (4.0 * PI) / (s_i * s_d * (s_i + s_d)).sqrt()
}

/// UTD amplitude factor of a point source diffracted twice (the product form): λ/(4π)·(1/s0)
/// ·√(s0/(s1·(s0 + s1)))·√(ρ_e/(s2·(ρ_e + s2))), with the first edge's legs (s0, s1), the
/// second's s2 and its incident wave's ρ_e ([`Caustics::after_edge`]), each clamped to at
/// least one wavelength. For parallel edges ρ_e = s0 + s1 and the factor is
/// λ/(4π)/√(s0·s1·s2·(s0 + s1 + s2)), the same read from either end.
pub(crate) fn spreading_twice(first: Legs, second: Legs, frequency_hz: Real) -> Real {
    let wavelength = SPEED_OF_LIGHT / frequency_hz;
    let (first, second) = (first.clamped(wavelength), second.clamped(wavelength));
    let (s0, s1) = (first.incident, first.diffracted);
    let s2 = second.diffracted;
    let re = second.astigmatic.map_or(s0 + s1, |c| c.in_plane);
    wavelength / (4.0 * PI) / s0 * (s0 / (s1 * (s0 + s1))).sqrt() * (re / (s2 * (re + s2))).sqrt()
}

/// The diffraction's Jones matrix J from the incident ray's edge-fixed basis (φ̂', β̂0') to the
/// diffracted ray's (φ̂, β̂0), √m, for a ray arriving along unit `k_in` and leaving along unit
/// `k_out`, combined as `coefficient` says ([`DiffractionCoefficient`]).
pub(crate) fn jones(
    (k_in, k_out): (Vec3, Vec3),
    wedge: &Wedge,
    legs: Legs,
    frequency_hz: Real,
    coefficient: DiffractionCoefficient,
) -> Result<Matrix, ChannelError> {
    let frame = wedge.frame()?;
    let e = frame.e;
    let sin_beta = k_in.cross(e).length();
    if !(sin_beta.is_finite() && sin_beta >= MIN_SIN_BETA) {
        return Err(invalid(format!(
            "the incident ray runs along the edge (sin β0 = {sin_beta:e})"
        )));
    }
    let keller = (k_out.dot(e) - k_in.dot(e)).abs();
    if !(keller.is_finite() && keller <= KELLER_COS_TOLERANCE) {
        return Err(invalid(format!(
            "the diffracted ray leaves Keller's cone (|ŝ·ê − ŝ'·ê| = {keller:e})"
        )));
    }
    let phi_i = exterior_angle(&frame, -k_in, "source side of the incident ray")?;
    let phi = exterior_angle(&frame, k_out, "diffracted ray")?;
    let wavelength = SPEED_OF_LIGHT / frequency_hz;
    let k = 2.0 * PI / wavelength;
    let kl = legs.clamped(wavelength).kl(k, sin_beta);
    let n = frame.n;
    let factor =
        -Complex64::from_polar(1.0, -FRAC_PI_4) / (2.0 * n * (2.0 * PI * k).sqrt() * sin_beta);
    let d = [
        PI + (phi - phi_i),
        PI - (phi - phi_i),
        PI + (phi + phi_i),
        PI - (phi + phi_i),
    ]
    .map(|w| factor * cot_transition(w, n, kl));
    let r0 = face_matrix(frame.n0, wedge.response0, k_in, e, frequency_hz)?;
    let rn = face_matrix(frame.nn, wedge.response_n, k_in, e, frequency_hz)?;
    Ok(match coefficient {
        DiffractionCoefficient::Utd => combine(&[(MINUS_I2, d[0] + d[1]), (rn, d[2]), (r0, d[3])]),
        DiffractionCoefficient::SionnaRt22 => {
            // Sionna swaps the faces so that face 0 is lit, then takes R_n := −I when face n is
            // not (nπ > π + φ'). The swap maps φ' → nπ − φ', φ → nπ − φ, which exchanges
            // D1 ↔ D2, D3 ↔ D4 and R_0 ↔ R_n, leaving R_0(D1 − D4) + R_n(D2 − D3) unchanged; so
            // in our labelling the rule is: the face the source is strictly behind gets −I.
            let r0 = if phi_i > PI { MINUS_I2 } else { r0 };
            let rn = if phi_i < (n - 1.0) * PI { MINUS_I2 } else { rn };
            combine(&[(r0, d[0] - d[3]), (rn, d[1] - d[2])])
        }
    })
}

/// −I, the 2×2 matrix of a wave continuing straight on in the edge-fixed bases.
const MINUS_I2: Matrix = [
    [Complex64::new(-1.0, 0.0), Complex64::new(0.0, 0.0)],
    [Complex64::new(0.0, 0.0), Complex64::new(-1.0, 0.0)],
];

/// Σ cᵢ·Mᵢ over (matrix, weight) pairs.
fn combine(terms: &[(Matrix, Complex64)]) -> Matrix {
    let mut j = [[Complex64::new(0.0, 0.0); 2]; 2];
    for (m, c) in terms {
        for (row, line) in j.iter_mut().enumerate() {
            for (column, value) in line.iter_mut().enumerate() {
                *value += c * m[row][column];
            }
        }
    }
    j
}

/// Diffract `field` (travelling along unit `k_in`) at `wedge` into unit direction `k_out` by
/// its [`jones`] matrix (`coefficient` at `frequency_hz`). Returns the diffracted field without the spreading factor (applied by
/// the caller) and the matrix.
pub(crate) fn diffract(
    field: Field,
    (k_in, k_out): (Vec3, Vec3),
    wedge: &Wedge,
    legs: Legs,
    (frequency_hz, coefficient): (Real, DiffractionCoefficient),
) -> Result<(Field, Matrix), ChannelError> {
    let j = jones((k_in, k_out), wedge, legs, frequency_hz, coefficient)?;
    let e = wedge.frame()?.e;
    let (phi_in, beta_in) = incident_basis(k_in, e);
    let (phi_out, beta_out) = outgoing_basis(k_out, e);
    let (ep, eb) = (dot(&field, phi_in), dot(&field, beta_in));
    let out = add(
        scaled(phi_out, j[0][0] * ep + j[0][1] * eb),
        scaled(beta_out, j[1][0] * ep + j[1][1] * eb),
    );
    Ok((out, j))
}

/// The largest singular value of a 2×2 complex matrix: the gain of its strongest
/// polarisation.
pub(crate) fn largest_singular_value(m: &Matrix) -> Real {
    // Eigenvalues of MᴴM: (t ± √(t² − 4·det)) / 2, t = ‖M‖²_F, det = |det M|².
    let t: Real = m.iter().flatten().map(|c| c.norm_sqr()).sum();
    let det = (m[0][0] * m[1][1] - m[0][1] * m[1][0]).norm_sqr();
    (0.5 * (t + (t * t - 4.0 * det).max(0.0).sqrt())).sqrt()
}

#[cfg(test)]
mod tests;
