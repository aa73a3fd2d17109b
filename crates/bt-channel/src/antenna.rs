//! Antennas: a power pattern, a polarisation (slant angle) and an orientation. The far field an
//! antenna radiates towards (or receives from) a direction is a real vector transverse to it:
//! √G(θ, φ)·(cos ζ·θ̂ + sin ζ·φ̂) in the antenna's local frame (Sionna RT's polarisation model
//! 2 and 3GPP TR 38.901 §7.3.2 model 2), rotated into the world frame. `docs/channel.md`.

use crate::ChannelError;
use bt_geom::{Real, Vec3};
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_4;
use std::str::FromStr;

/// Power pattern of one element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pattern {
    /// G = 1 (0 dBi) in every direction.
    Isotropic,
    /// 3GPP TR 38.901 Table 7.3-1: 8 dBi at boresight (local +x), 65° half-power beamwidth
    /// in both planes, 30 dB front-to-back ratio and side-lobe limit.
    Tr38901,
}

/// Polarisation: the slant angle ζ of the field from θ̂ towards φ̂.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Polarization {
    /// Vertical, ζ = 0 (field along θ̂).
    V,
    /// Horizontal, ζ = 90° (field along φ̂).
    H,
    /// Slant +45° (one element of a ±45° cross-polarised pair).
    Plus45,
    /// Slant −45° (the other element of the pair).
    Minus45,
}

impl Polarization {
    /// Slant angle ζ, radians.
    pub fn slant(self) -> Real {
        match self {
            Polarization::V => 0.0,
            Polarization::H => 2.0 * FRAC_PI_4,
            Polarization::Plus45 => FRAC_PI_4,
            Polarization::Minus45 => -FRAC_PI_4,
        }
    }

    /// sin ζ and cos ζ of [`Polarization::slant`]: the same bits as `slant().sin_cos()`, without
    /// the call for the vertical polarisation (ζ = 0: exactly 0 and 1), the default at both
    /// ends of every path.
    fn slant_sin_cos(self) -> (Real, Real) {
        match self {
            Polarization::V => (0.0, 1.0),
            other => other.slant().sin_cos(),
        }
    }
}

/// Orientation of an antenna or array: intrinsic rotations yaw about z, then pitch about the
/// new y, then roll about the new x (radians); R = Rz(yaw)·Ry(pitch)·Rx(roll) maps local to
/// world. Zero: boresight along world +x, local z up. Serialised in degrees (`yaw_deg`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Orientation {
    /// Rotation about world z, radians.
    pub yaw: Real,
    /// Rotation about the yawed y axis, radians.
    pub pitch: Real,
    /// Rotation about the resulting x axis, radians.
    pub roll: Real,
}

impl Serialize for Orientation {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Orientation", 3)?;
        st.serialize_field("yaw_deg", &self.yaw.to_degrees())?;
        st.serialize_field("pitch_deg", &self.pitch.to_degrees())?;
        st.serialize_field("roll_deg", &self.roll.to_degrees())?;
        st.end()
    }
}

impl<'de> Deserialize<'de> for Orientation {
    /// Reads what [`Orientation`]'s `Serialize` writes (degrees).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Degrees {
            yaw_deg: Real,
            pitch_deg: Real,
            roll_deg: Real,
        }
        let a = Degrees::deserialize(d)?;
        Ok(Orientation::from_degrees(
            a.yaw_deg,
            a.pitch_deg,
            a.roll_deg,
        ))
    }
}

impl Orientation {
    /// From degrees.
    pub fn from_degrees(yaw: Real, pitch: Real, roll: Real) -> Orientation {
        Orientation {
            yaw: yaw.to_radians(),
            pitch: pitch.to_radians(),
            roll: roll.to_radians(),
        }
    }

    /// Local → world rotation.
    pub fn matrix(&self) -> glam::DMat3 {
        glam::DMat3::from_rotation_z(self.yaw)
            * glam::DMat3::from_rotation_y(self.pitch)
            * glam::DMat3::from_rotation_x(self.roll)
    }
}

/// An antenna element.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Antenna {
    /// Power pattern.
    pub pattern: Pattern,
    /// Polarisation.
    pub polarization: Polarization,
    /// Orientation in the world frame.
    pub orientation: Orientation,
}

impl Default for Antenna {
    /// Isotropic, vertically polarised (the default at both ends).
    fn default() -> Self {
        Antenna {
            pattern: Pattern::Isotropic,
            polarization: Polarization::V,
            orientation: Orientation::default(),
        }
    }
}

/// Spherical angles (zenith θ, azimuth φ) of a unit vector, radians.
fn spherical(v: Vec3) -> (Real, Real) {
    (v.z.clamp(-1.0, 1.0).acos(), v.y.atan2(v.x))
}

/// Local spherical unit vectors θ̂ and φ̂ at (θ, φ).
fn spherical_basis(theta: Real, phi: Real) -> (Vec3, Vec3) {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    basis_of(st, ct, sp, cp)
}

/// θ̂ and φ̂ from the sines and cosines of θ and φ.
fn basis_of(st: Real, ct: Real, sp: Real, cp: Real) -> (Vec3, Vec3) {
    (Vec3::new(ct * cp, ct * sp, -st), Vec3::new(-sp, cp, 0.0))
}

/// θ̂ and φ̂ towards the direction `v` (a unit vector, or near one), without trigonometry:
/// sin θ = ρ/|v|, cos θ = z/|v|, (cos φ, sin φ) = (x, y)/ρ with ρ = √(x² + y²). The two roots
/// are taken side by side from the squares, not one from the other as `hypot` would: on a
/// path's gain they were a chain of two roots and five divisions that the CPU waited for
/// (docs/performance.md); for a unit vector the squares neither overflow nor lose precision.
/// Within 1.5e-154 of the z axis (ρ² below the normal range) and on it, where φ is
/// undefined, the basis of [`spherical`]'s angles (atan2 of the components).
fn basis_towards(v: Vec3) -> (Vec3, Vec3) {
    let rho2 = v.x * v.x + v.y * v.y;
    if rho2 < Real::MIN_POSITIVE {
        let (theta, phi) = spherical(v.normalize_or_zero());
        return spherical_basis(theta, phi);
    }
    let (rho, length) = (rho2.sqrt(), (rho2 + v.z * v.z).sqrt());
    basis_of(rho / length, v.z / length, v.y / rho, v.x / rho)
}

impl Pattern {
    /// Power gain (linear) towards local zenith θ and azimuth φ (radians).
    pub fn gain(self, theta: Real, phi: Real) -> Real {
        match self {
            Pattern::Isotropic => 1.0,
            Pattern::Tr38901 => {
                let (t, p) = (theta.to_degrees(), phi.to_degrees());
                let vertical = -(12.0 * ((t - 90.0) / 65.0).powi(2)).min(30.0);
                let horizontal = -(12.0 * (p / 65.0).powi(2)).min(30.0);
                let a_db = -(-(vertical + horizontal)).min(30.0);
                10f64.powf((8.0 + a_db) / 10.0)
            }
        }
    }
}

impl Antenna {
    /// An element with the given pattern, polarisation and world-frame orientation.
    pub fn new(pattern: Pattern, polarization: Polarization, orientation: Orientation) -> Self {
        Antenna {
            pattern,
            polarization,
            orientation,
        }
    }

    /// The field vector (world frame, dimensionless, |·|² = G) towards the world unit direction
    /// `direction` (departure for a transmitter, the direction the wave comes from for a
    /// receiver).
    ///
    /// Unrotated antennas skip the rotation, isotropic ones the angles: the basis comes from
    /// the direction's components.
    pub fn field(&self, direction: Vec3) -> Vec3 {
        let rotation =
            (self.orientation != Orientation::default()).then(|| self.orientation.matrix());
        let local = rotation.map_or(direction, |r| r.transpose() * direction);
        let (t_hat, p_hat) = basis_towards(local);
        let amplitude = match self.pattern {
            Pattern::Isotropic => 1.0,
            pattern => {
                let (theta, phi) = spherical(local);
                pattern.gain(theta, phi).sqrt()
            }
        };
        let (s, c) = self.polarization.slant_sin_cos();
        let field = amplitude * (c * t_hat + s * p_hat);
        rotation.map_or(field, |r| r * field)
    }
}

impl FromStr for Pattern {
    type Err = ChannelError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "iso" | "isotropic" => Ok(Pattern::Isotropic),
            "tr38901" | "38.901" | "3gpp" => Ok(Pattern::Tr38901),
            _ => Err(ChannelError::Invalid {
                field: "pattern",
                message: format!("unknown antenna pattern \"{s}\" (expected iso or tr38901)"),
            }),
        }
    }
}

impl FromStr for Polarization {
    type Err = ChannelError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "v" | "vertical" => Ok(Polarization::V),
            "h" | "horizontal" => Ok(Polarization::H),
            "+45" | "plus45" => Ok(Polarization::Plus45),
            "-45" | "minus45" => Ok(Polarization::Minus45),
            _ => Err(ChannelError::Invalid {
                field: "polarization",
                message: format!("unknown polarisation \"{s}\" (expected V, H, +45 or -45)"),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The shortcut of the vertical polarisation gives `sin_cos`'s bits, and the others are
    /// `sin_cos` itself.
    #[test]
    fn slant_sin_cos_is_sin_cos() {
        for p in [
            Polarization::V,
            Polarization::H,
            Polarization::Plus45,
            Polarization::Minus45,
        ] {
            let (s, c) = p.slant_sin_cos();
            let (rs, rc) = p.slant().sin_cos();
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (rs.to_bits(), rc.to_bits()),
                "{p:?}"
            );
        }
    }

    proptest! {
        /// The trigonometry-free basis is the basis at the direction's angles, near and on
        /// the poles too (to 3e-8 there: the reference's acos of z ≈ ±1 is good to about
        /// √ε).
        #[test]
        fn basis_towards_a_direction_is_the_basis_at_its_angles(
            x in -1.0f64..1.0, y in -1.0f64..1.0, z in -1.0f64..1.0,
            tiny in 0usize..4, scale in 0.5f64..2.0,
        ) {
            let (x, y) = match tiny {
                0 => (x * 1e-9, y * 1e-9),
                1 => (0.0, 0.0),
                2 => (-0.0, y * 1e-300),
                _ => (x, y),
            };
            let v = Vec3::new(x, y, z + if z == 0.0 { 0.5 } else { 0.0 });
            let (theta, phi) = spherical(v.normalize());
            let (t, p) = spherical_basis(theta, phi);
            let (t2, p2) = basis_towards(v * scale);
            let tol = if x.hypot(y) < 1e-6 { 3e-8 } else { 1e-12 };
            prop_assert!((t - t2).length() < tol, "{v}: {t} vs {t2}");
            prop_assert!((p - p2).length() < tol, "{v}: {p} vs {p2}");
        }
    }

    #[test]
    fn vertical_isotropic_field_is_minus_z_at_the_horizon() {
        let a = Antenna::default();
        let f = a.field(Vec3::X);
        assert!((f - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-15);
        let h = Antenna {
            polarization: Polarization::H,
            ..a
        };
        assert!((h.field(Vec3::X) - Vec3::Y).length() < 1e-15);
        // Transverse to the direction everywhere.
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        assert!(a.field(d).dot(d).abs() < 1e-15 && h.field(d).dot(d).abs() < 1e-15);
    }

    #[test]
    fn tr38901_pattern_values() {
        let p = Pattern::Tr38901;
        let db = |t: Real, ph: Real| 10.0 * p.gain(t.to_radians(), ph.to_radians()).log10();
        assert!((db(90.0, 0.0) - 8.0).abs() < 1e-12);
        // Half-power at ±32.5° in azimuth: 12 (32.5/65)² = 3 dB.
        assert!((db(90.0, 32.5) - 5.0).abs() < 1e-12);
        assert!((db(90.0 + 32.5, 0.0) - 5.0).abs() < 1e-12);
        // Backwards: limited to 30 dB below the peak.
        assert!((db(90.0, 180.0) - (8.0 - 30.0)).abs() < 1e-12);
    }

    #[test]
    fn orientation_turns_the_boresight() {
        let a = Antenna {
            pattern: Pattern::Tr38901,
            orientation: Orientation::from_degrees(90.0, 0.0, 0.0),
            ..Antenna::default()
        };
        assert!((a.field(Vec3::Y).length_squared() - 10f64.powf(0.8)).abs() < 1e-9);
        assert!((a.field(-Vec3::Y).length_squared() - 10f64.powf(-2.2)).abs() < 1e-12);
        // Pitch 90° points the boresight down (-z).
        let down = Orientation::from_degrees(0.0, 90.0, 0.0).matrix() * Vec3::X;
        assert!((down - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-15);
    }

    #[test]
    fn names_parse() {
        assert_eq!("ISO".parse::<Pattern>().unwrap(), Pattern::Isotropic);
        assert_eq!("tr38901".parse::<Pattern>().unwrap(), Pattern::Tr38901);
        assert_eq!(
            "-45".parse::<Polarization>().unwrap(),
            Polarization::Minus45
        );
        assert!(
            "x".parse::<Polarization>()
                .unwrap_err()
                .to_string()
                .contains("polarization")
        );
    }
}
