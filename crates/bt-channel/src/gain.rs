//! Polarised complex path gains: the transmit antenna's field, one Jones matrix diag(R_TE,
//! R_TM) per reflection in that bounce's s/p basis, the receive antenna's field, and the
//! free-space factor λ/(4π·length). No propagation phase: that is the delay (Sionna RT's
//! convention). Derivation and signs: `docs/channel.md`.

use crate::ChannelError;
use crate::antenna::Antenna;
use crate::diffraction::{
    Caustics, DiffractionCoefficient, Legs, Wedge, diffract, largest_singular_value,
    outgoing_basis, spreading, spreading_twice,
};
use crate::material::{RadioMaterial, Reflection, SPEED_OF_LIGHT, Transmission};
use bt_geom::{Real, Vec3};
use num_complex::Complex64;
use smallvec::SmallVec;
use std::f64::consts::PI;

/// How a surface reflects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceResponse {
    /// A radio material: coefficients from its permittivity and thickness.
    Radio(RadioMaterial),
    /// Only a constant loss is known: a perfect conductor scaled to it, R_TE = −a, R_TM = +a,
    /// a = 10^(−loss_db/20), at every angle.
    ConstantLoss {
        /// Loss per reflection, dB.
        loss_db: Real,
    },
}

impl SurfaceResponse {
    /// Transmission coefficients at `frequency_hz` and cos θ = `cos_incidence`: a radio
    /// material's slab ([`RadioMaterial::transmission`]). A constant loss says nothing about
    /// what passes through: an error naming the material's radio model.
    pub fn transmission(
        &self,
        frequency_hz: Real,
        cos_incidence: Real,
    ) -> Result<Transmission, ChannelError> {
        match self {
            SurfaceResponse::Radio(m) => m.transmission(frequency_hz, cos_incidence),
            SurfaceResponse::ConstantLoss { .. } => Err(ChannelError::Invalid {
                field: "material",
                message: "a material with only a reflection loss has no transmission: give it \
                          a radio model (itu or permittivity and conductivity) and a thickness"
                    .into(),
            }),
        }
    }

    /// Reflection coefficients at `frequency_hz` and cos θ = `cos_incidence`.
    pub fn reflection(
        &self,
        frequency_hz: Real,
        cos_incidence: Real,
    ) -> Result<Reflection, ChannelError> {
        match self {
            SurfaceResponse::Radio(m) => m.reflection(frequency_hz, cos_incidence),
            SurfaceResponse::ConstantLoss { loss_db } => {
                let a = 10f64.powf(-loss_db / 20.0);
                Ok(Reflection {
                    te: Complex64::new(-a, 0.0),
                    tm: Complex64::new(a, 0.0),
                })
            }
        }
    }
}

/// One reflection of a path: the surface's unit normal (either side) and its response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounce {
    /// Unit normal of the reflecting plane (its sign does not matter).
    pub normal: Vec3,
    /// The surface's reflection.
    pub response: SurfaceResponse,
}

/// The free-space amplitude factor of a path and whether it left the far field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeSpace {
    /// λ/(4π·max(length, λ/(4π))): never above 1, i.e. never a negative loss.
    pub amplitude: Real,
    /// Friis loss 20·log10(4π·max(length, λ/(4π))·f/c), dB (>= 0).
    pub loss_db: Real,
    /// The path is shorter than one wavelength: Friis does not hold there (near field), and
    /// below λ/(4π) the amplitude is clamped to 1 (0 dB loss).
    pub near_field: bool,
}

/// The one home of the Friis factor: amplitude λ/(4π·d) for `length` metres at
/// `frequency_hz`. Friis holds in the far field only, so `d` is clamped to one wavelength:
/// amplitude ≤ 1/(4π), loss ≥ 20 log10(4π) ≈ 21.98 dB, and `near_field` says it happened.
pub fn free_space(length: Real, frequency_hz: Real) -> FreeSpace {
    let wavelength = SPEED_OF_LIGHT / frequency_hz;
    let clamped = length.max(wavelength);
    FreeSpace {
        amplitude: wavelength / (4.0 * PI * clamped),
        loss_db: 20.0 * (4.0 * PI * clamped * frequency_hz / SPEED_OF_LIGHT).log10(),
        near_field: length < wavelength,
    }
}

/// A complex 3-vector (a field transverse to the propagation direction).
pub(crate) type Field = [Complex64; 3];

pub(crate) fn dot(field: &Field, v: Vec3) -> Complex64 {
    field[0] * v.x + field[1] * v.y + field[2] * v.z
}

pub(crate) fn scaled(v: Vec3, c: Complex64) -> Field {
    [c * v.x, c * v.y, c * v.z]
}

pub(crate) fn add(a: Field, b: Field) -> Field {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// A unit vector perpendicular to unit `k` (for normal incidence, where the plane of
/// incidence is undefined and R_TM = −R_TE makes any choice give the same field).
fn any_perpendicular(k: Vec3) -> Vec3 {
    let helper = if k.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    k.cross(helper).normalize()
}

/// Apply one reflection to `field` travelling along unit `k`: returns the reflected field and
/// direction. s = normalize(k × n), p = s × k before and p' = s × k' after the bounce.
pub(crate) fn reflect(
    field: Field,
    k: Vec3,
    bounce: &Bounce,
    frequency_hz: Real,
) -> Result<(Field, Vec3), ChannelError> {
    let n = bounce.normal;
    let cos = k.dot(n).abs().min(1.0);
    let r = bounce.response.reflection(frequency_hz, cos)?;
    let k_out = k - 2.0 * k.dot(n) * n;
    let cross = k.cross(n);
    let s = if cross.length() > 1e-12 {
        cross.normalize()
    } else {
        any_perpendicular(k)
    };
    let (p_in, p_out) = (s.cross(k), s.cross(k_out));
    let reflected = add(
        scaled(s, r.te * dot(&field, s)),
        scaled(p_out, r.tm * dot(&field, p_in)),
    );
    Ok((reflected, k_out))
}

/// Apply one slab crossing to `field` travelling along unit `k` (which it keeps): its s and p
/// components (s = normalize(k × n), p = s × k, as for [`reflect`]) times T_TE and T_TM.
pub(crate) fn transmit(
    field: Field,
    k: Vec3,
    crossing: &Bounce,
    frequency_hz: Real,
) -> Result<Field, ChannelError> {
    let n = crossing.normal;
    let cos = k.dot(n).abs().min(1.0);
    let t = crossing.response.transmission(frequency_hz, cos)?;
    let cross = k.cross(n);
    let s = if cross.length() > 1e-12 {
        cross.normalize()
    } else {
        any_perpendicular(k)
    };
    let p = s.cross(k);
    Ok(add(
        scaled(s, t.te * dot(&field, s)),
        scaled(p, t.tm * dot(&field, p)),
    ))
}

/// One interaction of a path with the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Interaction {
    /// A specular reflection.
    Reflection(Bounce),
    /// A crossing of a slab (ITU-R P.2040 transmission, no deflection): the surface's normal
    /// and response, as for a reflection.
    Transmission(Bounce),
    /// An edge diffraction (UTD); at most two per path.
    Diffraction(Wedge),
}

/// Complex gain of the path TX → `points` → RX (world frame, metres) with one [`Bounce`] per
/// point, at `frequency_hz`: (λ/(4π·length)) · f_RX(−k_last) · Π_bounces · f_TX(k_first).
/// Without the propagation phase e^{−j2πf·τ}. `length` is clamped as in [`free_space`].
pub fn path_gain(
    tx: Vec3,
    points: &[Vec3],
    rx: Vec3,
    bounces: &[Bounce],
    antennas: (&Antenna, &Antenna),
    frequency_hz: Real,
) -> Result<Complex64, ChannelError> {
    if points.len() != bounces.len() {
        return Err(ChannelError::Invalid {
            field: "bounces",
            message: format!("{} points but {} bounces", points.len(), bounces.len()),
        });
    }
    let interactions: Vec<Interaction> = bounces
        .iter()
        .copied()
        .map(Interaction::Reflection)
        .collect();
    path_gain_mixed(tx, points, rx, &interactions, antennas, frequency_hz)
}

/// [`path_gain_detailed`]'s gain alone, with the default [`DiffractionCoefficient::Utd`].
pub fn path_gain_mixed(
    tx: Vec3,
    points: &[Vec3],
    rx: Vec3,
    interactions: &[Interaction],
    antennas: (&Antenna, &Antenna),
    frequency_hz: Real,
) -> Result<Complex64, ChannelError> {
    let coefficient = DiffractionCoefficient::Utd;
    path_gain_detailed(
        tx,
        points,
        rx,
        interactions,
        antennas,
        frequency_hz,
        coefficient,
    )
    .map(|g| g.gain)
}

/// The gain of a path and, for a diffracted one, the diffraction's excess loss.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathGain {
    /// Complex gain (no propagation phase), as [`path_gain_mixed`].
    pub gain: Complex64,
    /// 0 without a diffraction; with one, −20·log10(σ_max(J)·A_UTD/A_Friis), dB: the
    /// strongest polarisation's diffraction matrix J (its largest singular value, √m) with
    /// UTD's spreading A_UTD = λ/(4π)/√(s'·s·(s' + s)), relative to free space over the same
    /// unfolded length, A_Friis = λ/(4π·(s' + s)).
    pub diffraction_loss_db: Real,
}

/// Complex gain of a path of reflections, crossings and at most two edge diffractions: TX →
/// `points` → RX (world frame, metres), one [`Interaction`] per point, at `frequency_hz`.
///
/// Without a diffraction it is [`path_gain`]'s value, bit for bit. With one at point Q, the
/// Jones chain runs through the UTD step of [`Wedge`] with `coefficient`'s combination of the
/// terms ([`DiffractionCoefficient`]) and the spreading is UTD's for a point
/// source, λ/(4π)·1/√(s'·s·(s' + s)) with s' and s the unfolded lengths TX → Q and Q → RX
/// (each clamped to at least one wavelength), instead of λ/(4π·(s' + s)). With two (at Q1,
/// then Q2; legs s0, s1, s2 unfolded) it is UTD's product form: the first edge's coefficient
/// with (s', s) = (s0, s1), the second's with the astigmatic wave the first sends on (its
/// distance parameter from the wave's caustics), and the spreading of both
/// (`docs/channel.md`, "Two diffractions"). No propagation phase. Errors: lengths differ, three or more diffractions, an invalid wedge, a ray along the
/// edge or off Keller's cone, a ray inside the wedge (`docs/channel.md`).
pub fn path_gain_detailed(
    tx: Vec3,
    points: &[Vec3],
    rx: Vec3,
    interactions: &[Interaction],
    antennas: (&Antenna, &Antenna),
    frequency_hz: Real,
    coefficient: DiffractionCoefficient,
) -> Result<PathGain, ChannelError> {
    let radio = (frequency_hz, coefficient);
    path_gain_with_leg(tx, points, rx, interactions, antennas, radio, None)
}

/// Vertices (TX, points, RX) of a path whose vertices and legs [`path_gain_with_leg`] keeps on
/// the stack: order 6 and below.
const PATH_VERTICES: usize = 8;

/// [`path_gain_detailed`] (`radio` = (frequency, Hz; coefficient)), with the diffraction's
/// diffracted leg s (metres; in the coefficient's distance parameter L and in the spreading)
/// taken as `diffracted_leg` instead of the unfolded length from the diffraction point to RX
/// when it is given (Sionna RT 2.2's, [`crate::sionna`]). The delay and the excess loss's
/// free-space reference keep the path's own length.
pub(crate) fn path_gain_with_leg(
    tx: Vec3,
    points: &[Vec3],
    rx: Vec3,
    interactions: &[Interaction],
    antennas: (&Antenna, &Antenna),
    (frequency_hz, coefficient): (Real, DiffractionCoefficient),
    diffracted_leg: Option<Real>,
) -> Result<PathGain, ChannelError> {
    if points.len() != interactions.len() {
        return Err(ChannelError::Invalid {
            field: "interactions",
            message: format!(
                "{} points but {} interactions",
                points.len(),
                interactions.len()
            ),
        });
    }
    // On the stack for the paths of a room (a report's paths allocate nothing here).
    let diffractions: SmallVec<[usize; 2]> = interactions
        .iter()
        .enumerate()
        .filter(|(_, i)| matches!(i, Interaction::Diffraction(_)))
        .map(|(index, _)| index)
        .collect();
    if diffractions.len() > 2 {
        return Err(ChannelError::Invalid {
            field: "interactions",
            message: format!(
                "{} diffractions in a path (at most two)",
                diffractions.len()
            ),
        });
    }
    let mut vertices: SmallVec<[Vec3; PATH_VERTICES]> = SmallVec::with_capacity(points.len() + 2);
    vertices.push(tx);
    vertices.extend_from_slice(points);
    vertices.push(rx);
    let segments: SmallVec<[Real; PATH_VERTICES]> =
        vertices.windows(2).map(|w| w[0].distance(w[1])).collect();
    let length: Real = segments.iter().sum();
    // Each diffraction's legs run from the source or the diffraction before, to the next
    // diffraction or the observer (Sionna's diffracted leg: one diffraction only).
    let legs = |index: usize| {
        let from = diffractions
            .iter()
            .rev()
            .find(|&&d| d < index)
            .map_or(0, |d| d + 1);
        let to = diffractions.iter().find(|&&d| d > index).copied();
        Legs {
            incident: segments[from..=index].iter().sum(),
            diffracted: match (to, diffracted_leg) {
                (Some(to), _) => segments[index + 1..=to].iter().sum(),
                (None, Some(leg)) if diffractions.len() == 1 => leg,
                (None, _) => segments[index + 1..].iter().sum(),
            },
            astigmatic: None,
        }
    };
    let walk = Walk {
        vertices: &vertices,
        legs: &legs,
        radio: (frequency_hz, coefficient),
    };
    let (field, k, chain) = walk.run(interactions, antennas.0)?;
    let received = dot(&field, antennas.1.field(-k));
    let free = free_space(length, frequency_hz).amplitude;
    let (amplitude, excess_db) = match (diffractions.as_slice(), chain) {
        ([], _) => (free, 0.0),
        ([index], chain) => {
            let amplitude = spreading(legs(*index), frequency_hz);
            (
                amplitude,
                -20.0 * (chain.sigma * (amplitude / free)).log10(),
            )
        }
        (_, chain) => {
            let amplitude = spreading_twice(chain.legs[0], chain.legs[1], frequency_hz);
            (
                amplitude,
                -20.0 * (chain.sigma * (amplitude / free)).log10(),
            )
        }
    };
    Ok(PathGain {
        gain: received * amplitude,
        diffraction_loss_db: excess_db,
    })
}

/// The walk of a field along a path's vertices (TX first), with each diffraction's legs.
struct Walk<'a, L: Fn(usize) -> Legs> {
    vertices: &'a [Vec3],
    legs: &'a L,
    radio: (Real, DiffractionCoefficient),
}

/// What the diffractions of a walk leave: the product of their matrices' largest singular
/// values and their legs (the second's with its incident wave's caustics).
#[derive(Clone, Copy)]
struct Chain {
    sigma: Real,
    legs: [Legs; 2],
}

impl<L: Fn(usize) -> Legs> Walk<'_, L> {
    /// The field leaving TX's `antenna` carried through `interactions` (aligned with the
    /// vertices' inner points): the field at RX, its direction of travel, and the chain.
    fn run(
        &self,
        interactions: &[Interaction],
        antenna: &Antenna,
    ) -> Result<(Field, Vec3, Chain), ChannelError> {
        let (frequency_hz, _) = self.radio;
        let vertices = self.vertices;
        let mut k = (vertices[1] - vertices[0]).normalize();
        let mut field = scaled(antenna.field(k), Complex64::new(1.0, 0.0));
        let empty = Legs {
            incident: 0.0,
            diffracted: 0.0,
            astigmatic: None,
        };
        let mut chain = Chain {
            sigma: 1.0,
            legs: [empty; 2],
        };
        // β̂ of the wave leaving the last edge, carried through the reflections since.
        let mut beta: Option<Vec3> = None;
        let mut count = 0;
        for (index, interaction) in interactions.iter().enumerate() {
            match interaction {
                Interaction::Reflection(bounce) => {
                    (field, k) = reflect(field, k, bounce, frequency_hz)?;
                    beta = beta.map(|b| b - 2.0 * b.dot(bounce.normal) * bounce.normal);
                }
                Interaction::Transmission(crossing) => {
                    field = transmit(field, k, crossing, frequency_hz)?;
                }
                Interaction::Diffraction(wedge) => {
                    let e = wedge.frame()?.e;
                    let k_out = (vertices[index + 2] - vertices[index + 1]).normalize();
                    let mut legs = (self.legs)(index);
                    if let Some(b) = beta {
                        let before = chain.legs[0];
                        legs.astigmatic = Some(Caustics::after_edge(
                            (before.incident, before.diffracted),
                            b,
                            (k, e),
                        ));
                    }
                    let matrix;
                    (field, matrix) = diffract(field, (k, k_out), wedge, legs, self.radio)?;
                    chain.sigma *= largest_singular_value(&matrix);
                    chain.legs[count.min(1)] = legs;
                    count += 1;
                    beta = Some(outgoing_basis(k_out, e).1);
                    k = k_out;
                }
            }
        }
        Ok((field, k, chain))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::antenna::{Orientation, Pattern, Polarization};

    const F: Real = 28e9;

    fn concrete_slab() -> SurfaceResponse {
        SurfaceResponse::Radio(RadioMaterial::itu("concrete", Some(0.2)).unwrap())
    }

    #[test]
    fn line_of_sight_is_friis_for_vertical_isotropic_antennas() {
        let a = Antenna::default();
        let g = path_gain(Vec3::ZERO, &[], Vec3::new(10.0, 0.0, 0.0), &[], (&a, &a), F).unwrap();
        let lambda = SPEED_OF_LIGHT / F;
        assert!((g - Complex64::new(lambda / (4.0 * PI * 10.0), 0.0)).norm() < 1e-15);
        // V transmitted, H received: orthogonal, nothing.
        let h = Antenna {
            polarization: Polarization::H,
            ..a
        };
        let g = path_gain(Vec3::ZERO, &[], Vec3::new(10.0, 0.0, 0.0), &[], (&a, &h), F).unwrap();
        assert!(g.norm() < 1e-18);
    }

    #[test]
    fn near_field_never_gains() {
        let fs = free_space(1e-4, F);
        assert!((fs.amplitude - 1.0 / (4.0 * PI)).abs() < 1e-15);
        assert!((fs.loss_db - 20.0 * (4.0 * PI).log10()).abs() < 1e-12);
        assert!(fs.near_field);
        let fs = free_space(1.0, F);
        assert!(fs.amplitude < 1.0 && !fs.near_field);
    }

    #[test]
    fn slanted_antennas_split_the_power() {
        // +45° into V: cos 45° of the amplitude.
        let p = Antenna {
            polarization: Polarization::Plus45,
            ..Antenna::default()
        };
        let v = Antenna::default();
        let rx = Vec3::new(5.0, 0.0, 0.0);
        let g45 = path_gain(Vec3::ZERO, &[], rx, &[], (&p, &v), F).unwrap();
        let gv = path_gain(Vec3::ZERO, &[], rx, &[], (&v, &v), F).unwrap();
        assert!((g45.norm() / gv.norm() - 0.5f64.sqrt()).abs() < 1e-12);
    }

    /// A single reflection off the floor z = 0 in the x-z plane: V is TM and H is TE, and
    /// the reflected/LoS gain ratio is R·r_los/r_refl with the Fresnel coefficient written
    /// out here by hand.
    #[test]
    fn floor_bounce_uses_tm_for_vertical_and_te_for_horizontal() {
        let (h1, h2, d) = (2.0, 1.0, 6.0);
        let (tx, rx) = (Vec3::new(0.0, 0.0, h1), Vec3::new(d, 0.0, h2));
        let x = d * h1 / (h1 + h2);
        let point = Vec3::new(x, 0.0, 0.0);
        let material = RadioMaterial::custom(5.0, 0.0, None).unwrap();
        let bounce = Bounce {
            normal: Vec3::Z,
            response: SurfaceResponse::Radio(material),
        };
        let (r1, r2) = ((tx - rx).length(), d.hypot(h1 + h2));
        let cos = (h1 + h2) / r2;
        let s = (5.0 - (1.0 - cos * cos)).sqrt();
        let (r_te, r_tm) = ((cos - s) / (cos + s), (5.0 * cos - s) / (5.0 * cos + s));
        for (pol, coefficient) in [(Polarization::V, r_tm), (Polarization::H, r_te)] {
            let a = Antenna {
                polarization: pol,
                ..Antenna::default()
            };
            let los = path_gain(tx, &[], rx, &[], (&a, &a), F).unwrap();
            let refl = path_gain(tx, &[point], rx, &[bounce], (&a, &a), F).unwrap();
            let ratio = refl / los;
            assert!(
                (ratio - Complex64::new(coefficient * r1 / r2, 0.0)).norm() < 1e-12,
                "{pol:?}: {ratio}"
            );
        }
    }

    #[test]
    fn reciprocity_over_two_bounces_with_any_antennas() {
        let tx = Vec3::new(1.0, 1.0, 1.5);
        let rx = Vec3::new(4.0, 2.5, 0.8);
        // Floor z = 0 then wall x = 5: image construction.
        let rx_img = Vec3::new(10.0 - rx.x, rx.y, rx.z);
        let tx_img = Vec3::new(tx.x, tx.y, -tx.z);
        let d = rx_img - tx_img;
        let t_floor = -tx_img.z / d.z;
        let p1 = tx_img + t_floor * d;
        let t_wall = (5.0 - tx_img.x) / d.x;
        let p2_img = tx_img + t_wall * d;
        let p2 = Vec3::new(5.0, p2_img.y, p2_img.z);
        assert!(p1.z.abs() < 1e-12 && t_floor < t_wall);
        let floor = Bounce {
            normal: Vec3::Z,
            response: concrete_slab(),
        };
        let wall = Bounce {
            normal: -Vec3::X,
            response: SurfaceResponse::Radio(RadioMaterial::itu("glass", Some(0.01)).unwrap()),
        };
        let facing_a = Orientation::from_degrees(20.0, -10.0, 5.0);
        let facing_b = Orientation::from_degrees(-150.0, 0.0, 30.0);
        let a = Antenna::new(Pattern::Tr38901, Polarization::Plus45, facing_a);
        let b = Antenna::new(Pattern::Isotropic, Polarization::H, facing_b);
        let forward = path_gain(tx, &[p1, p2], rx, &[floor, wall], (&a, &b), F).unwrap();
        let backward = path_gain(rx, &[p2, p1], tx, &[wall, floor], (&b, &a), F).unwrap();
        assert!(forward.norm() > 1e-6);
        assert!(
            (forward - backward).norm() < 1e-15 * forward.norm().max(1.0),
            "{forward} vs {backward}"
        );
    }

    #[test]
    fn normal_incidence_is_well_defined() {
        let a = Antenna::default();
        let bounce = Bounce {
            normal: Vec3::X,
            response: concrete_slab(),
        };
        let (tx, rx) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0));
        let g = path_gain(tx, &[Vec3::ZERO], rx, &[bounce], (&a, &a), F).unwrap();
        let r = concrete_slab().reflection(F, 1.0).unwrap();
        let lambda = SPEED_OF_LIGHT / F;
        // V stays V (−z at departure along −x and at arrival from −x): R_TE applies.
        let expected = r.te * (lambda / (4.0 * PI * 3.0));
        assert!((g - expected).norm() < 1e-15, "{g} vs {expected}");
    }

    #[test]
    fn constant_loss_scales_a_conductor() {
        let r = SurfaceResponse::ConstantLoss { loss_db: 6.0 }
            .reflection(F, 0.3)
            .unwrap();
        assert!(
            (r.te.re + 10f64.powf(-0.3)).abs() < 1e-15
                && (r.tm.re - 10f64.powf(-0.3)).abs() < 1e-15
        );
    }
}
