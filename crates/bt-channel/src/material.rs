//! Radio materials: the ITU-R P.2040-3 Table 3 list and custom (εr', σ) materials, their
//! complex relative permittivity, and their reflection coefficients (half-space Fresnel or a
//! single-layer slab, P.2040 §2.2.2). Formulas and sign conventions: `docs/channel.md`.

use crate::ChannelError;
use bt_geom::{Real, tol};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;

/// Vacuum permittivity ε0, F/m (CODATA 2018).
pub const VACUUM_PERMITTIVITY: Real = 8.854_187_812_8e-12;
/// Speed of light in vacuum, m/s.
pub const SPEED_OF_LIGHT: Real = 299_792_458.0;

/// One frequency band of a P.2040-3 Table 3 row: εr' = a·f^b, σ = c·f^d (f in GHz, σ in S/m),
/// valid for `f_min_ghz <= f <= f_max_ghz`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ItuBand {
    /// a of εr' = a·f^b.
    pub a: Real,
    /// b of εr' = a·f^b.
    pub b: Real,
    /// c of σ = c·f^d, S/m.
    pub c: Real,
    /// d of σ = c·f^d.
    pub d: Real,
    /// Lowest frequency of validity, GHz.
    pub f_min_ghz: Real,
    /// Highest frequency of validity, GHz.
    pub f_max_ghz: Real,
}

/// A band as a struct literal (promotable to `'static` inside `bands`).
macro_rules! band {
    ($a:expr, $b:expr, $c:expr, $d:expr, $lo:expr, $hi:expr) => {
        ItuBand {
            a: $a,
            b: $b,
            c: $c,
            d: $d,
            f_min_ghz: $lo,
            f_max_ghz: $hi,
        }
    };
}

/// The materials of ITU-R P.2040-3, Table 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ItuMaterial {
    /// Vacuum (≈ air).
    Vacuum,
    /// Concrete.
    Concrete,
    /// Brick.
    Brick,
    /// Plasterboard.
    Plasterboard,
    /// Wood.
    Wood,
    /// Glass (two bands: 0.1–100 GHz and 220–450 GHz).
    Glass,
    /// Ceiling board (two bands: 1–100 GHz and 220–450 GHz).
    CeilingBoard,
    /// Chipboard.
    Chipboard,
    /// Plywood.
    Plywood,
    /// Marble.
    Marble,
    /// Floorboard.
    Floorboard,
    /// Metal (σ = 10⁷ S/m).
    Metal,
    /// Very dry ground.
    VeryDryGround,
    /// Medium dry ground.
    MediumDryGround,
    /// Wet ground.
    WetGround,
}

impl ItuMaterial {
    /// Every material of the table, in table order.
    pub const ALL: [ItuMaterial; 15] = [
        ItuMaterial::Vacuum,
        ItuMaterial::Concrete,
        ItuMaterial::Brick,
        ItuMaterial::Plasterboard,
        ItuMaterial::Wood,
        ItuMaterial::Glass,
        ItuMaterial::CeilingBoard,
        ItuMaterial::Chipboard,
        ItuMaterial::Plywood,
        ItuMaterial::Marble,
        ItuMaterial::Floorboard,
        ItuMaterial::Metal,
        ItuMaterial::VeryDryGround,
        ItuMaterial::MediumDryGround,
        ItuMaterial::WetGround,
    ];

    /// The name in Sionna RT's spelling without its `itu_` prefix (`ceiling_board`,
    /// `very_dry_ground`, ...).
    pub fn name(self) -> &'static str {
        match self {
            ItuMaterial::Vacuum => "vacuum",
            ItuMaterial::Concrete => "concrete",
            ItuMaterial::Brick => "brick",
            ItuMaterial::Plasterboard => "plasterboard",
            ItuMaterial::Wood => "wood",
            ItuMaterial::Glass => "glass",
            ItuMaterial::CeilingBoard => "ceiling_board",
            ItuMaterial::Chipboard => "chipboard",
            ItuMaterial::Plywood => "plywood",
            ItuMaterial::Marble => "marble",
            ItuMaterial::Floorboard => "floorboard",
            ItuMaterial::Metal => "metal",
            ItuMaterial::VeryDryGround => "very_dry_ground",
            ItuMaterial::MediumDryGround => "medium_dry_ground",
            ItuMaterial::WetGround => "wet_ground",
        }
    }

    /// The rows of Table 3 for this material (one band, two for glass and ceiling board).
    pub fn bands(self) -> &'static [ItuBand] {
        match self {
            ItuMaterial::Vacuum => &[band!(1.0, 0.0, 0.0, 0.0, 0.001, 100.0)],
            ItuMaterial::Concrete => &[band!(5.24, 0.0, 0.0462, 0.7822, 1.0, 100.0)],
            ItuMaterial::Brick => &[band!(3.91, 0.0, 0.0238, 0.16, 1.0, 40.0)],
            ItuMaterial::Plasterboard => &[band!(2.73, 0.0, 0.0085, 0.9395, 1.0, 100.0)],
            ItuMaterial::Wood => &[band!(1.99, 0.0, 0.0047, 1.0718, 0.001, 100.0)],
            ItuMaterial::Glass => &[
                band!(6.31, 0.0, 0.0036, 1.3394, 0.1, 100.0),
                band!(5.79, 0.0, 0.0004, 1.658, 220.0, 450.0),
            ],
            ItuMaterial::CeilingBoard => &[
                band!(1.48, 0.0, 0.0011, 1.075, 1.0, 100.0),
                band!(1.52, 0.0, 0.0029, 1.029, 220.0, 450.0),
            ],
            ItuMaterial::Chipboard => &[band!(2.58, 0.0, 0.0217, 0.78, 1.0, 100.0)],
            ItuMaterial::Plywood => &[band!(2.71, 0.0, 0.33, 0.0, 1.0, 40.0)],
            ItuMaterial::Marble => &[band!(7.074, 0.0, 0.0055, 0.9262, 1.0, 60.0)],
            ItuMaterial::Floorboard => &[band!(3.66, 0.0, 0.0044, 1.3515, 50.0, 100.0)],
            ItuMaterial::Metal => &[band!(1.0, 0.0, 1e7, 0.0, 1.0, 100.0)],
            ItuMaterial::VeryDryGround => &[band!(3.0, 0.0, 0.00015, 2.52, 1.0, 10.0)],
            ItuMaterial::MediumDryGround => &[band!(15.0, -0.1, 0.035, 1.63, 1.0, 10.0)],
            ItuMaterial::WetGround => &[band!(30.0, -0.4, 0.15, 1.3, 1.0, 10.0)],
        }
    }

    /// Parse a material name: `concrete`, `itu_concrete`, `itu-concrete`, `ITU Concrete`,
    /// `very_dry_ground`, `ceiling-board`, ... (case, `-`, `_` and spaces do not matter).
    pub fn parse(name: &str) -> Result<ItuMaterial, ChannelError> {
        let key = |s: &str| -> String {
            s.chars()
                .filter(|c| !matches!(c, '_' | '-' | ' '))
                .flat_map(char::to_lowercase)
                .collect()
        };
        let wanted = key(name);
        let wanted = wanted.strip_prefix("itu").unwrap_or(&wanted);
        ItuMaterial::ALL
            .into_iter()
            .find(|m| key(m.name()) == wanted)
            .ok_or_else(|| ChannelError::UnknownMaterial {
                name: name.to_string(),
            })
    }

    /// Relative permittivity εr' and conductivity σ (S/m) at `frequency_hz`, or an error when
    /// the frequency is outside every band of the table.
    pub fn properties(self, frequency_hz: Real) -> Result<(Real, Real), ChannelError> {
        let f = frequency_hz / 1e9;
        let band = self
            .bands()
            .iter()
            .find(|b| f >= b.f_min_ghz && f <= b.f_max_ghz)
            .ok_or_else(|| ChannelError::OutOfRange {
                material: self.name().to_string(),
                frequency_hz,
                valid: self
                    .bands()
                    .iter()
                    .map(|b| format!("{}–{} GHz", b.f_min_ghz, b.f_max_ghz))
                    .collect::<Vec<_>>()
                    .join(" or "),
            })?;
        Ok((band.a * f.powf(band.b), band.c * f.powf(band.d)))
    }
}

impl fmt::Display for ItuMaterial {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for ItuMaterial {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for ItuMaterial {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        ItuMaterial::parse(&name).map_err(serde::de::Error::custom)
    }
}

/// The electrical model of a material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadioModel {
    /// A row of ITU-R P.2040-3 Table 3 (frequency dependent, with a validity range).
    Itu(ItuMaterial),
    /// Constant relative permittivity εr' (> 0) and conductivity σ (S/m, >= 0).
    Custom {
        /// Relative permittivity εr' (real part).
        relative_permittivity: Real,
        /// Conductivity σ, S/m.
        conductivity: Real,
    },
}

/// A radio material: an electrical model and, optionally, a thickness.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RadioMaterial {
    /// εr' and σ.
    pub model: RadioModel,
    /// Slab thickness, metres: `None` is a half-space (Fresnel coefficients), `Some(d)` a
    /// single layer of thickness d in vacuum (P.2040 §2.2.2, multiple internal reflections).
    pub thickness: Option<Real>,
}

/// Reflection coefficients of one interaction, for the TE (s, perpendicular) and TM (p,
/// parallel) components. Basis and the sign of TM: `docs/channel.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reflection {
    /// TE (s) coefficient: field perpendicular to the plane of incidence.
    pub te: Complex64,
    /// TM (p) coefficient: field in the plane of incidence.
    pub tm: Complex64,
}

/// Transmission coefficients of a wave crossing a slab (no deflection: it leaves along the
/// direction it came), for the TE (s) and TM (p) components in the plane-of-incidence basis,
/// which the crossing leaves unchanged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmission {
    /// TE (s) coefficient.
    pub te: Complex64,
    /// TM (p) coefficient.
    pub tm: Complex64,
}

impl RadioMaterial {
    /// A material of P.2040-3 Table 3 by name (see [`ItuMaterial::parse`]), as a half-space
    /// (`thickness = None`) or a slab of `thickness` metres.
    pub fn itu(name: &str, thickness: Option<Real>) -> Result<RadioMaterial, ChannelError> {
        check_thickness(thickness)?;
        Ok(RadioMaterial {
            model: RadioModel::Itu(ItuMaterial::parse(name)?),
            thickness,
        })
    }

    /// A material of constant εr' (> 0, finite) and σ (S/m, >= 0, finite).
    pub fn custom(
        relative_permittivity: Real,
        conductivity: Real,
        thickness: Option<Real>,
    ) -> Result<RadioMaterial, ChannelError> {
        if !(relative_permittivity.is_finite() && relative_permittivity > 0.0) {
            return Err(ChannelError::Invalid {
                field: "relative_permittivity",
                message: format!("must be a finite number > 0, got {relative_permittivity}"),
            });
        }
        if !(conductivity.is_finite() && conductivity >= 0.0) {
            return Err(ChannelError::Invalid {
                field: "conductivity",
                message: format!("must be a finite number >= 0 (S/m), got {conductivity}"),
            });
        }
        check_thickness(thickness)?;
        Ok(RadioMaterial {
            model: RadioModel::Custom {
                relative_permittivity,
                conductivity,
            },
            thickness,
        })
    }

    /// The same material as a slab of `thickness` metres (CLI `--thickness` without
    /// `--material`): a finite number ≥ 0.
    pub fn with_thickness(self, thickness: Real) -> Result<RadioMaterial, ChannelError> {
        check_thickness(Some(thickness))?;
        Ok(RadioMaterial {
            thickness: Some(thickness),
            ..self
        })
    }

    /// εr' and σ (S/m) at `frequency_hz`.
    pub fn properties(&self, frequency_hz: Real) -> Result<(Real, Real), ChannelError> {
        match self.model {
            RadioModel::Itu(m) => m.properties(frequency_hz),
            RadioModel::Custom {
                relative_permittivity,
                conductivity,
            } => Ok((relative_permittivity, conductivity)),
        }
    }

    /// Complex relative permittivity η = εr' − j·σ/(ε0·2πf) at `frequency_hz` (time
    /// convention e^{+jωt}: losses make the imaginary part negative).
    pub fn permittivity(&self, frequency_hz: Real) -> Result<Complex64, ChannelError> {
        if !(frequency_hz.is_finite() && frequency_hz > 0.0) {
            return Err(ChannelError::Invalid {
                field: "frequency_hz",
                message: format!("must be a positive finite number, got {frequency_hz:e}"),
            });
        }
        let (eps, sigma) = self.properties(frequency_hz)?;
        Ok(Complex64::new(
            eps,
            -sigma / (VACUUM_PERMITTIVITY * 2.0 * PI * frequency_hz),
        ))
    }

    /// Reflection coefficients at `frequency_hz` for a wave hitting the surface with
    /// `cos_incidence` = cos θ (θ from the normal, 0 = normal incidence; clamped to [0, 1]).
    pub fn reflection(
        &self,
        frequency_hz: Real,
        cos_incidence: Real,
    ) -> Result<Reflection, ChannelError> {
        let eta = self.permittivity(frequency_hz)?;
        let wavelength = SPEED_OF_LIGHT / frequency_hz;
        Ok(match self.thickness {
            None => fresnel(eta, cos_incidence),
            Some(d) => slab(eta, cos_incidence, d / wavelength),
        })
    }

    /// The material a user names as the CLI's `--material` and Python's `material=` spell it:
    /// `itu:NAME` (P.2040-3 Table 3, [`ItuMaterial::parse`]) or `custom:EPS_R,SIGMA` (relative
    /// permittivity, conductivity in S/m), a slab of `thickness` metres or a half-space.
    /// Errors name the `material` (or the thickness) and what was expected.
    pub fn from_spec(spec: &str, thickness: Option<Real>) -> Result<RadioMaterial, ChannelError> {
        let invalid = |message: String| ChannelError::Invalid {
            field: "material",
            message,
        };
        if let Some(name) = spec.strip_prefix("itu:") {
            return RadioMaterial::itu(name, thickness);
        }
        if let Some(values) = spec.strip_prefix("custom:") {
            let number = |text: &str| {
                (text.trim().parse::<Real>())
                    .map_err(|_| invalid(format!("\"{}\" is not a number", text.trim())))
            };
            if let [eps, sigma] = values.split(',').collect::<Vec<_>>()[..] {
                return RadioMaterial::custom(number(eps)?, number(sigma)?, thickness);
            }
        }
        let got = match spec.chars().count() {
            n if n <= 64 => format!("\"{}\"", spec.escape_default()),
            _ => format!("{} bytes", spec.len()),
        };
        Err(invalid(format!(
            "expected itu:NAME (e.g. itu:concrete) or custom:EPS_R,SIGMA, got {got}"
        )))
    }

    /// Transmission coefficients at `frequency_hz` for a wave crossing the surface with
    /// `cos_incidence` = cos θ ([`slab_transmission`]). A half-space (no thickness) lets
    /// nothing through to the far side: an error naming the thickness.
    pub fn transmission(
        &self,
        frequency_hz: Real,
        cos_incidence: Real,
    ) -> Result<Transmission, ChannelError> {
        let eta = self.permittivity(frequency_hz)?;
        let wavelength = SPEED_OF_LIGHT / frequency_hz;
        match self.thickness {
            Some(d) => Ok(slab_transmission(eta, cos_incidence, d / wavelength)),
            None => Err(ChannelError::Invalid {
                field: "thickness",
                message: "a half-space (no thickness) transmits nothing: give the material a \
                          thickness to let waves through it"
                    .into(),
            }),
        }
    }

    /// Normal-incidence power loss of one reflection, dB (>= 0): −20·log10|R_TE(0°)|;
    /// infinite when nothing reflects.
    pub fn normal_loss_db(&self, frequency_hz: Real) -> Result<Real, ChannelError> {
        let r = self.reflection(frequency_hz, 1.0)?;
        Ok(-20.0 * modulus(r.te).log10())
    }
}

fn check_thickness(thickness: Option<Real>) -> Result<(), ChannelError> {
    match thickness {
        Some(d) if !(d.is_finite() && d >= 0.0) => Err(ChannelError::Invalid {
            field: "thickness",
            message: format!("must be a finite number of metres >= 0, got {d}"),
        }),
        _ => Ok(()),
    }
}

/// √(η − sin²θ) on the branch with a non-positive imaginary part (a wave decaying into the
/// material under e^{+jωt}).
fn transmitted_cos(eta: Complex64, cos: Real) -> Complex64 {
    let s = principal_sqrt(eta - (1.0 - cos * cos));
    if s.im > 0.0 { -s } else { s }
}

/// The principal square root of `z` (real part ≥ 0, the imaginary part's sign that of
/// `z.im`, −0 included), computed algebraically: with m = |z|, t = √((m + |Re z|)/2) is
/// the larger part and Im z/(2t) the other, so neither cancels. `Complex64::sqrt` goes
/// through polar form (an `atan2` and a `sincos` more).
fn principal_sqrt(z: Complex64) -> Complex64 {
    // On every reflection's chain of roots and divisions (docs/performance.md).
    let m = bt_geom::real::root_sum_squares(z.re, z.im);
    if m == 0.0 {
        return Complex64::new(0.0, z.im);
    }
    let t = (0.5 * (m + z.re.abs())).sqrt();
    let other = 0.5 * z.im.abs() / t;
    match z.re >= 0.0 {
        true => Complex64::new(t, z.im.signum() * other),
        false => Complex64::new(other, t.copysign(z.im)),
    }
}

/// |z|, with [`bt_geom::real::hypot`] (`Complex64::norm` calls the C library's).
#[inline(always)]
fn modulus(z: Complex64) -> Real {
    bt_geom::real::hypot(z.re, z.im)
}

/// Whether `den` is too small to divide by: |den| ≤ [`tol::COEFFICIENT_DENOMINATOR`], compared
/// squared (no `hypot`).
fn vanishes(den: Complex64) -> bool {
    den.norm_sqr() <= tol::COEFFICIENT_DENOMINATOR * tol::COEFFICIENT_DENOMINATOR
}

fn ratio(num: Complex64, den: Complex64) -> Complex64 {
    if vanishes(den) {
        Complex64::new(0.0, 0.0)
    } else {
        num / den
    }
}

/// Half-space Fresnel coefficients (P.2040 eqs. 31a-b) for complex relative permittivity
/// `eta` and cos θ = `cos_incidence`:
/// r_TE = (cos θ − s)/(cos θ + s), r_TM = (η cos θ − s)/(η cos θ + s), s = √(η − sin²θ).
pub fn fresnel(eta: Complex64, cos_incidence: Real) -> Reflection {
    half_space(eta, cos_incidence.clamp(0.0, 1.0)).0
}

/// [`fresnel`] at cos θ = `cos` (already clamped to [0, 1]) and s = √(η − sin²θ) beside it,
/// which the slab formulas reuse.
fn half_space(eta: Complex64, cos: Real) -> (Reflection, Complex64) {
    let s = transmitted_cos(eta, cos);
    let r = Reflection {
        te: ratio(cos - s, cos + s),
        tm: ratio(eta * cos - s, eta * cos + s),
    };
    (r, s)
}

/// Single-layer slab in vacuum (P.2040 §2.2.2): R = r·(1 − e^{−j2q}) / (1 − r²·e^{−j2q}) with
/// q = 2π·(d/λ)·√(η − sin²θ), per polarisation, r the half-space coefficient.
/// `thickness_wavelengths` = d/λ.
pub fn slab(eta: Complex64, cos_incidence: Real, thickness_wavelengths: Real) -> Reflection {
    let (half, s) = half_space(eta, cos_incidence.clamp(0.0, 1.0));
    let q = s * (2.0 * PI * thickness_wavelengths);
    let phase = (Complex64::new(0.0, -2.0) * q).exp();
    let layer = |r: Complex64| {
        let den = 1.0 - r * r * phase;
        if vanishes(den) {
            r
        } else {
            r * (1.0 - phase) / den
        }
    };
    Reflection {
        te: layer(half.te),
        tm: layer(half.tm),
    }
}

/// Single-layer slab in vacuum, transmission (ITU-R P.2040-4 eq. 43b, as Sionna RT's thin
/// slab): T = (1 − r²)·e^{−jq} / (1 − r²·e^{−j2q}) per polarisation, with r and q as in
/// [`slab`]. The wave leaves undeflected; e^{−jq} is the phase across the slab relative to the
/// unfolded path's own propagation phase, which the delay carries. `thickness_wavelengths`
/// = d/λ.
pub fn slab_transmission(
    eta: Complex64,
    cos_incidence: Real,
    thickness_wavelengths: Real,
) -> Transmission {
    let (half, s) = half_space(eta, cos_incidence.clamp(0.0, 1.0));
    let q = s * (2.0 * PI * thickness_wavelengths);
    let (once, twice) = (
        (Complex64::new(0.0, -1.0) * q).exp(),
        (Complex64::new(0.0, -2.0) * q).exp(),
    );
    let layer = |r: Complex64| ratio((1.0 - r * r) * once, 1.0 - r * r * twice);
    Transmission {
        te: layer(half.te),
        tm: layer(half.tm),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn c(re: Real, im: Real) -> Complex64 {
        Complex64::new(re, im)
    }

    fn close(a: Complex64, b: Complex64, eps: Real) -> bool {
        (a - b).norm() <= eps
    }

    proptest! {
        /// The algebraic root agrees with `Complex64::sqrt` (polar form) to a few ulps of |z|,
        /// and squares back to z.
        #[test]
        fn principal_sqrt_is_the_principal_root(
            re in -1e3f64..1e3, im in -1e3f64..1e3, zero_im in any::<bool>(), neg in any::<bool>(),
        ) {
            let im = match (zero_im, neg) {
                (true, true) => -0.0,
                (true, false) => 0.0,
                _ => im,
            };
            let z = c(re, im);
            let (mine, polar) = (principal_sqrt(z), z.sqrt());
            let scale = z.norm().sqrt().max(Real::MIN_POSITIVE);
            prop_assert!(close(mine, polar, 1e-14 * scale), "{z}: {mine} vs {polar}");
            prop_assert!(close(mine * mine, z, 1e-14 * z.norm().max(1e-300)), "{z}: {mine}");
            prop_assert!(mine.re >= 0.0);
            prop_assert_eq!(mine.im.is_sign_negative(), im.is_sign_negative());
        }
    }

    #[test]
    fn names_parse_in_every_spelling() {
        for m in ItuMaterial::ALL {
            assert_eq!(ItuMaterial::parse(m.name()).unwrap(), m);
            assert_eq!(ItuMaterial::parse(&format!("itu_{}", m.name())).unwrap(), m);
        }
        assert_eq!(
            ItuMaterial::parse("ITU-Very-Dry-Ground").unwrap(),
            ItuMaterial::VeryDryGround
        );
        assert_eq!(
            ItuMaterial::parse("ceilingboard").unwrap(),
            ItuMaterial::CeilingBoard
        );
        let e = ItuMaterial::parse("unobtainium").unwrap_err().to_string();
        assert!(e.contains("unobtainium") && e.contains("concrete"), "{e}");
    }

    #[test]
    fn table_values_at_one_ghz_and_28_ghz() {
        // At 1 GHz, f^b = f^d = 1: εr' = a, σ = c.
        let (eps, sigma) = ItuMaterial::Concrete.properties(1e9).unwrap();
        assert_eq!((eps, sigma), (5.24, 0.0462));
        // 28 GHz: σ = 0.0462 · 28^0.7822 = 0.0462 · 13.5925... (hand: ln 28 = 3.33220,
        // × 0.7822 = 2.60645, e^ = 13.5508) = 0.62605 S/m.
        let (_, sigma) = ItuMaterial::Concrete.properties(28e9).unwrap();
        assert!((sigma - 0.0462 * 28f64.powf(0.7822)).abs() < 1e-15);
        assert!((sigma - 0.62605).abs() < 1e-4, "{sigma}");
        // Medium dry ground has b != 0: εr' = 15 · 5^-0.1 = 15 · e^(−0.160944) = 12.7701.
        let (eps, _) = ItuMaterial::MediumDryGround.properties(5e9).unwrap();
        assert!((eps - 12.7701).abs() < 1e-4, "{eps}");
        // The second glass band.
        let (eps, _) = ItuMaterial::Glass.properties(300e9).unwrap();
        assert_eq!(eps, 5.79);
    }

    #[test]
    fn outside_the_validity_range_is_a_clear_error() {
        let e = ItuMaterial::Glass
            .properties(150e9)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("glass") && e.contains("0.1–100 GHz or 220–450 GHz") && e.contains("150"),
            "{e}"
        );
        assert!(ItuMaterial::Brick.properties(41e9).is_err());
        assert!(ItuMaterial::Brick.properties(40e9).is_ok());
    }

    #[test]
    fn permittivity_imaginary_part_is_sigma_over_eps0_omega() {
        let m = RadioMaterial::custom(4.0, 0.1, None).unwrap();
        let eta = m.permittivity(1e9).unwrap();
        // P.2040 eq. 9b: εr'' = 17.98 σ / f_GHz = 1.798.
        assert!((eta.re - 4.0).abs() < 1e-15);
        assert!((eta.im + 1.798).abs() < 1e-3, "{eta}");
    }

    #[test]
    fn invalid_parameters_are_rejected_with_their_field() {
        for (e, field) in [
            (
                RadioMaterial::custom(-1.0, 0.0, None),
                "relative_permittivity",
            ),
            (RadioMaterial::custom(2.0, Real::NAN, None), "conductivity"),
            (RadioMaterial::custom(2.0, 0.0, Some(-0.1)), "thickness"),
            (
                RadioMaterial::itu("wood", Some(Real::INFINITY)),
                "thickness",
            ),
        ] {
            assert!(e.unwrap_err().to_string().starts_with(field));
        }
    }

    #[test]
    fn normal_incidence_matches_the_textbook_formula() {
        // Lossless εr = 4: r_TE = (1 − 2)/(1 + 2) = −1/3; r_TM = (4 − 2)/(4 + 2) = +1/3.
        let r = fresnel(c(4.0, 0.0), 1.0);
        assert!(close(r.te, c(-1.0 / 3.0, 0.0), 1e-15));
        assert!(close(r.tm, c(1.0 / 3.0, 0.0), 1e-15));
    }

    #[test]
    fn oblique_incidence_hand_computed() {
        // εr = 4, θ = 60°: cos = 0.5, s = √(4 − 0.75) = √3.25 = 1.802776.
        // r_TE = (0.5 − 1.802776)/(0.5 + 1.802776) = −0.565741
        // r_TM = (2 − 1.802776)/(2 + 1.802776) = 0.051863
        let r = fresnel(c(4.0, 0.0), 0.5);
        assert!(close(r.te, c(-0.565741, 0.0), 1e-6), "{}", r.te);
        assert!(close(r.tm, c(0.051863, 0.0), 1e-6), "{}", r.tm);
    }

    #[test]
    fn brewster_angle_cancels_tm_only() {
        let eps: Real = 5.24;
        let theta_b = eps.sqrt().atan();
        let r = fresnel(c(eps, 0.0), theta_b.cos());
        assert!(r.tm.norm() < 1e-14, "{}", r.tm);
        assert!(r.te.norm() > 0.5);
        // The TM coefficient changes sign across the Brewster angle.
        let before = fresnel(c(eps, 0.0), (theta_b - 0.1).cos()).tm.re;
        let after = fresnel(c(eps, 0.0), (theta_b + 0.1).cos()).tm.re;
        assert!(before > 0.0 && after < 0.0);
    }

    #[test]
    fn grazing_incidence_tends_to_minus_one() {
        for eta in [c(5.24, -0.3), c(2.0, 0.0), c(1.0, -1e6)] {
            let r = fresnel(eta, 1e-9);
            assert!(close(r.te, c(-1.0, 0.0), 1e-6), "{eta}: {}", r.te);
            assert!(close(r.tm, c(-1.0, 0.0), 1e-3), "{eta}: {}", r.tm);
        }
    }

    #[test]
    fn perfect_conductor_limit() {
        // σ → ∞: r_TE → −1, r_TM → +1 away from grazing (with this basis, docs/channel.md).
        let pec = RadioMaterial::custom(1.0, 1e12, None).unwrap();
        let metal = RadioMaterial::itu("metal", None).unwrap();
        for cos in [1.0, 0.7, 0.3] {
            let r = pec.reflection(28e9, cos).unwrap();
            assert!(close(r.te, c(-1.0, 0.0), 1e-5), "{}", r.te);
            assert!(close(r.tm, c(1.0, 0.0), 1e-5), "{}", r.tm);
            // ITU metal (σ = 1e7 S/m) is within 0.3 % of it.
            let r = metal.reflection(28e9, cos).unwrap();
            assert!(close(r.te, c(-1.0, 0.0), 3e-3) && close(r.tm, c(1.0, 0.0), 3e-3));
        }
    }

    #[test]
    fn zero_thickness_slab_does_not_reflect_and_thick_lossy_slab_is_a_half_space() {
        let eta = c(5.24, -0.4);
        for cos in [1.0, 0.6, 0.1] {
            let r = slab(eta, cos, 0.0);
            assert!(r.te.norm() < 1e-15 && r.tm.norm() < 1e-15);
            let thick = slab(eta, cos, 200.0);
            let half = fresnel(eta, cos);
            assert!(close(thick.te, half.te, 1e-9) && close(thick.tm, half.tm, 1e-9));
        }
    }

    #[test]
    fn half_wave_lossless_slab_is_transparent_at_normal_incidence() {
        // d = λ/(2√εr): q = π, e^{−j2q} = 1, R = 0 (the classic radome condition).
        let eps: Real = 4.0;
        let r = slab(c(eps, 0.0), 1.0, 0.5 / eps.sqrt());
        assert!(r.te.norm() < 1e-12 && r.tm.norm() < 1e-12);
        // Quarter wave: q = π/2, e^{−j2q} = −1, R = 2r/(1 + r²) = (−2/3)/(10/9) = −0.6.
        let r = slab(c(eps, 0.0), 1.0, 0.25 / eps.sqrt());
        assert!(close(r.te, c(-0.6, 0.0), 1e-12), "{}", r.te);
    }

    #[test]
    fn vacuum_never_reflects_and_never_gives_nan() {
        let vacuum = RadioMaterial::itu("vacuum", None).unwrap();
        for cos in [1.0, 0.5, 0.0] {
            let r = vacuum.reflection(28e9, cos).unwrap();
            assert_eq!(r.te.norm(), 0.0);
            assert_eq!(r.tm.norm(), 0.0);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]
        #[test]
        fn passive_materials_never_amplify(
            eps in 1.0f64..80.0,
            sigma_exp in -6.0f64..7.0,
            cos in 0.0f64..=1.0,
            thickness in proptest::option::of(0.0f64..0.5),
            f_ghz in 0.5f64..100.0,
        ) {
            let m = RadioMaterial::custom(eps, 10f64.powf(sigma_exp), thickness).unwrap();
            let r = m.reflection(f_ghz * 1e9, cos).unwrap();
            prop_assert!(r.te.is_finite() && r.tm.is_finite());
            prop_assert!(r.te.norm() <= 1.0 + 1e-12, "te {}", r.te);
            prop_assert!(r.tm.norm() <= 1.0 + 1e-12, "tm {}", r.tm);
        }
    }
}
