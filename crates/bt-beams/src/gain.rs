//! A found path's complex gain: its interactions turned into the channel model's
//! ([`bt_channel::Interaction`]), reflections by their surfaces' responses, a diffraction by
//! its wedge's frame and faces.

use crate::{RadioOptions, ReportError, surface_response};
use bt_channel::{
    Bounce, Complex64, DiffractionCoefficient, RadioMaterial, RadioModel, SurfaceResponse, Wedge,
};
use bt_geom::Real;
use bt_scene::{Scene, SurfaceId};
use bt_solve::{FoundPath, Interaction};

/// The surfaces a report's paths touch, each looked up once per report: its response with
/// the radio model evaluated at the scene's frequency, and its material's reflection loss.
/// An ITU material's (εr', σ) at the frequency (two powers) becomes the same numbers as a
/// custom model, which gives the same bits: a custom model's properties are its numbers, and
/// every coefficient goes through [`RadioMaterial::properties`] at that frequency.
pub(crate) struct Responses<'a> {
    scene: &'a Scene,
    /// Surfaces looked up so far (a few dozen at most are kept; the rest are looked up each
    /// time, so a report of many paths in a large scene stays linear).
    known: Known,
    /// Where a surface may be in `known`: slot `id mod SLOTS` holds the position + 1 of the
    /// first surface kept with that remainder (0: none), so that most look-ups read one entry
    /// instead of scanning `known` (a room's report looks up ~380 times, ~14 surfaces).
    slots: [u8; SLOTS],
    /// The scene's terminals once looked up ([`Responses::terminals`]): each path of a
    /// report needs them twice.
    ends: Option<bt_scene::Endpoints>,
}

/// Slots of [`Responses::slots`].
const SLOTS: usize = 64;

/// The surfaces a [`Responses`] looked up: each one's response and reflection loss.
pub(crate) type Known = Vec<(SurfaceId, SurfaceResponse, Real)>;

/// Surfaces a [`Responses`] keeps.
const KNOWN_SURFACES: usize = 64;

impl<'a> Responses<'a> {
    /// No surface looked up yet in `scene`.
    pub(crate) fn new(scene: &'a Scene) -> Self {
        Self::with_known(scene, Vec::new())
    }

    /// The surfaces of `known` already looked up in `scene`: they were looked up in a scene of
    /// the same [`bt_scene::RadioKey`] (the same surfaces, materials and frequency), or
    /// `known` is empty.
    pub(crate) fn with_known(scene: &'a Scene, mut known: Known) -> Self {
        // As `keep` would have kept them one by one, in `known`'s own memory.
        known.truncate(KNOWN_SURFACES);
        let mut slots = [0; SLOTS];
        for (k, (id, ..)) in known.iter().enumerate() {
            let slot = &mut slots[id.index() % SLOTS];
            if *slot == 0 {
                // At most KNOWN_SURFACES (64) positions: + 1 fits a byte.
                *slot = (k + 1) as u8;
            }
        }
        Responses {
            scene,
            known,
            slots,
            ends: None,
        }
    }

    /// Keep surface `id`'s response and loss, when there is room.
    fn keep(&mut self, id: SurfaceId, response: SurfaceResponse, loss_db: Real) {
        if self.known.len() < KNOWN_SURFACES {
            let slot = &mut self.slots[id.index() % SLOTS];
            if *slot == 0 {
                // At most KNOWN_SURFACES (64) positions: + 1 fits a byte.
                *slot = (self.known.len() + 1) as u8;
            }
            self.known.push((id, response, loss_db));
        }
    }

    /// The surfaces looked up, for [`Responses::with_known`] in a scene of the same key.
    pub(crate) fn into_known(self) -> Known {
        self.known
    }

    /// The scene.
    pub(crate) fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The scene's terminals ([`Scene::terminals`], looked up once).
    pub(crate) fn terminals(&mut self) -> Result<bt_scene::Endpoints, ReportError> {
        if let Some(ends) = self.ends {
            return Ok(ends);
        }
        let ends = self.scene.terminals()?;
        self.ends = Some(ends);
        Ok(ends)
    }

    /// Surface `id`'s response and its material's reflection loss (dB). Inlined: its slot's
    /// hit (almost every call, twice an interaction) costs a few instructions, the look-up
    /// ([`Responses::look_up`]) is a call of its own.
    #[inline]
    pub(crate) fn get(&mut self, id: SurfaceId) -> (SurfaceResponse, Real) {
        let slot = usize::from(self.slots[id.index() % SLOTS]);
        if let Some(&(kept, response, loss_db)) = slot.checked_sub(1).map(|k| &self.known[k])
            && kept == id
        {
            return (response, loss_db);
        }
        self.look_up(id)
    }

    /// [`Responses::get`] past its slot: among the surfaces kept, else looked up in the scene
    /// and kept.
    #[inline(never)]
    fn look_up(&mut self, id: SurfaceId) -> (SurfaceResponse, Real) {
        if let Some(&(_, response, loss_db)) = self.known.iter().find(|k| k.0 == id) {
            return (response, loss_db);
        }
        let response = match surface_response(self.scene, id) {
            SurfaceResponse::Radio(radio) => {
                SurfaceResponse::Radio(at_frequency(radio, self.scene.frequency_hz()))
            }
            constant => constant,
        };
        let loss_db = self.scene.material_of(id).reflection_loss_db;
        self.keep(id, response, loss_db);
        (response, loss_db)
    }
}

/// `radio` with its model's (εr', σ) evaluated at `frequency_hz` (unchanged when it has none
/// there: its error then comes where it came before).
fn at_frequency(radio: RadioMaterial, frequency_hz: Real) -> RadioMaterial {
    match radio.properties(frequency_hz) {
        Ok((relative_permittivity, conductivity)) => RadioMaterial {
            model: RadioModel::Custom {
                relative_permittivity,
                conductivity,
            },
            ..radio
        },
        Err(_) => radio,
    }
}

/// The gain of `path` (interactions `interactions`, aligned with its points) in `scene`, and
/// its diffraction's excess loss, dB (0 for a specular path). `channel` is a buffer for the
/// interactions as the channel model takes them (cleared first).
pub(crate) fn path_gain(
    responses: &mut Responses<'_>,
    channel: &mut Vec<bt_channel::Interaction>,
    path: &FoundPath,
    interactions: &[Interaction],
    radio: &RadioOptions,
) -> Result<(Complex64, Real), ReportError> {
    let scene = responses.scene();
    let ends = responses.terminals()?;
    channel.clear();
    channel.extend(interactions.iter().map(|it| match *it {
        Interaction::Reflection(id) => bt_channel::Interaction::Reflection(Bounce {
            normal: scene.surface(id).polygon.plane().normal,
            response: responses.get(id).0,
        }),
        Interaction::Transmission(id) => bt_channel::Interaction::Transmission(Bounce {
            normal: scene.surface(id).polygon.plane().normal,
            response: responses.get(id).0,
        }),
        Interaction::Diffraction(e) => {
            let edge = scene.edges().get(e);
            // The exterior lies from t0 towards e × t0: face 0's free-space side.
            bt_channel::Interaction::Diffraction(Wedge {
                edge: edge.direction,
                face0: edge.t0,
                normal0: edge.direction.cross(edge.t0),
                n: edge.n,
                response0: responses.get(edge.face0).0,
                response_n: responses.get(edge.face_n).0,
            })
        }
    }));
    let antennas = (&radio.tx, &radio.rx);
    let g = match (radio.diffraction_coefficient, radio.sionna_max_depth) {
        (DiffractionCoefficient::SionnaRt22, Some(max_depth)) => bt_channel::path_gain_sionna_rt22(
            ends.tx,
            &path.points,
            ends.rx,
            channel,
            antennas,
            scene.frequency_hz(),
            max_depth,
        )?,
        (coefficient, _) => bt_channel::path_gain_detailed(
            ends.tx,
            &path.points,
            ends.rx,
            channel,
            antennas,
            scene.frequency_hz(),
            coefficient,
        )?,
    };
    Ok((g.gain, g.diffraction_loss_db))
}

/// The loss of a path's crossings, dB ([`crate::PathReport::transmission_loss_db`]): for each
/// crossing of `interactions` (aligned with `vertices[1..]`, the path TX → points → RX, local
/// frame), −10·log10 of the mean of |T_TE|² and |T_TM|² at its incidence.
pub(crate) fn transmission_loss_db(
    responses: &mut Responses<'_>,
    vertices: &[bt_geom::Vec3],
    interactions: &[Interaction],
) -> Result<Real, ReportError> {
    let scene = responses.scene();
    let mut loss = 0.0;
    for (k, it) in interactions.iter().enumerate() {
        let Interaction::Transmission(id) = *it else {
            continue;
        };
        let normal = scene.surface(id).polygon.plane().normal;
        let cos = (vertices[k + 1] - vertices[k])
            .normalize()
            .dot(normal)
            .abs();
        let t = match responses.get(id).0 {
            bt_channel::SurfaceResponse::Radio(radio) => {
                radio.transmission(scene.frequency_hz(), cos.min(1.0))?
            }
            // Only slabs are penetrable (`Scene::penetrable`): a constant loss has no model.
            bt_channel::SurfaceResponse::ConstantLoss { .. } => continue,
        };
        let power = 0.5 * (t.te.norm_sqr() + t.tm.norm_sqr());
        loss += -10.0 * power.log10();
    }
    Ok(loss)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_channel::ItuMaterial;

    /// Every ITU material, as a half-space and as a slab, gives the same bits once evaluated
    /// at the frequency as it gives itself, reflected and crossed at any angle; a frequency
    /// outside its bands leaves it as it is.
    #[test]
    fn a_material_evaluated_at_the_frequency_gives_the_same_bits() {
        let cosines = (0..=64).map(|k| f64::from(k) / 64.0).chain([1e-9, 0.3333]);
        let cosines: Vec<f64> = cosines.collect();
        let mut compared = 0;
        for material in ItuMaterial::ALL {
            for thickness in [None, Some(0.004), Some(0.2)] {
                let radio = RadioMaterial::itu(material.name(), thickness).unwrap();
                for f in [1e9, 5.8e9, 28e9, 60e9] {
                    let Ok(at) = radio.properties(f).map(|_| at_frequency(radio, f)) else {
                        assert_eq!(at_frequency(radio, f), radio);
                        continue;
                    };
                    assert!(matches!(at.model, RadioModel::Custom { .. }));
                    for &cos in &cosines {
                        let (a, b) = (radio.reflection(f, cos), at.reflection(f, cos));
                        let (a, b) = (a.unwrap(), b.unwrap());
                        assert_eq!(bits(a.te, a.tm), bits(b.te, b.tm), "{material} {f} {cos}");
                        if thickness.is_some() {
                            let (a, b) = (radio.transmission(f, cos), at.transmission(f, cos));
                            let (a, b) = (a.unwrap(), b.unwrap());
                            assert_eq!(bits(a.te, a.tm), bits(b.te, b.tm));
                        }
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared > 1000, "{compared}");
    }

    /// The slots and the kept surfaces give every surface its own response: 200 surfaces of
    /// three materials (ids that share a slot, more than are kept), looked up in a scrambled
    /// order by one [`Responses`], and by another started from its kept surfaces, each
    /// against a fresh look-up.
    #[test]
    fn kept_and_slotted_responses_are_each_surfaces_own() {
        let surfaces: Vec<String> = (0..200)
            .map(|i| {
                let (x, m) = (f64::from(i) * 0.5, ["a", "b", "c"][i as usize % 3]);
                format!(
                    r#"{{ "name": "s{i}", "material": "{m}", "vertices": [[{x}, 0, 0], [{x}, 0.4, 0], [{x}, 0.4, 0.4]] }}"#
                )
            })
            .collect();
        let json = format!(
            r#"{{ "tx": [1, 5, 1], "rx": [3, 5, 1], "materials": {{
                "a": {{ "itu": "concrete", "thickness": 0.2 }},
                "b": {{ "relative_permittivity": 5.0, "conductivity": 0.1 }},
                "c": {{ "itu": "glass" }} }},
                "surfaces": [{}] }}"#,
            surfaces.join(",")
        );
        let desc: bt_scene::SceneDescription = serde_json::from_str(&json).unwrap();
        let scene = Scene::from_description(&desc, "slots", Default::default()).unwrap();
        let order: Vec<SurfaceId> = (0..600u32).map(|k| SurfaceId(k * 37 % 200)).collect();
        let check = |responses: &mut Responses<'_>, ids: &mut dyn Iterator<Item = SurfaceId>| {
            for id in ids {
                let (fresh, fresh_loss) = Responses::new(&scene).get(id);
                let (got, loss) = responses.get(id);
                assert_eq!(
                    (got, loss.to_bits()),
                    (fresh, fresh_loss.to_bits()),
                    "{id:?}"
                );
            }
        };
        let mut first = Responses::new(&scene);
        check(&mut first, &mut order.iter().copied());
        let mut again = Responses::with_known(&scene, first.into_known());
        check(&mut again, &mut order.iter().rev().copied());
        assert_eq!(again.known.len(), KNOWN_SURFACES);
    }

    fn bits(te: Complex64, tm: Complex64) -> [u64; 4] {
        [te.re, te.im, tm.re, tm.im].map(f64::to_bits)
    }
}
