//! A found path's complex gain: its interactions turned into the channel model's
//! ([`bt_channel::Interaction`]), reflections by their surfaces' responses, a diffraction by
//! its wedge's frame and faces.

use crate::{RadioOptions, ReportError, surface_response};
use bt_channel::{Bounce, Complex64, DiffractionCoefficient, Wedge};
use bt_geom::Real;
use bt_scene::Scene;
use bt_solve::{FoundPath, Interaction};

/// The gain of `path` (interactions `interactions`, aligned with its points) in `scene`, and
/// its diffraction's excess loss, dB (0 for a specular path).
pub(crate) fn path_gain(
    scene: &Scene,
    path: &FoundPath,
    interactions: &[Interaction],
    radio: &RadioOptions,
) -> Result<(Complex64, Real), ReportError> {
    let ends = scene.terminals()?;
    let channel: Vec<bt_channel::Interaction> = interactions
        .iter()
        .map(|it| match *it {
            Interaction::Reflection(id) => bt_channel::Interaction::Reflection(Bounce {
                normal: scene.surface(id).polygon.plane().normal,
                response: surface_response(scene, id),
            }),
            Interaction::Transmission(id) => bt_channel::Interaction::Transmission(Bounce {
                normal: scene.surface(id).polygon.plane().normal,
                response: surface_response(scene, id),
            }),
            Interaction::Diffraction(e) => {
                let edge = scene.edges().get(e);
                // The exterior lies from t0 towards e × t0: face 0's free-space side.
                bt_channel::Interaction::Diffraction(Wedge {
                    edge: edge.direction,
                    face0: edge.t0,
                    normal0: edge.direction.cross(edge.t0),
                    n: edge.n,
                    response0: surface_response(scene, edge.face0),
                    response_n: surface_response(scene, edge.face_n),
                })
            }
        })
        .collect();
    let antennas = (&radio.tx, &radio.rx);
    let g = match (radio.diffraction_coefficient, radio.sionna_max_depth) {
        (DiffractionCoefficient::SionnaRt22, Some(max_depth)) => bt_channel::path_gain_sionna_rt22(
            ends.tx,
            &path.points,
            ends.rx,
            &channel,
            antennas,
            scene.frequency_hz(),
            max_depth,
        )?,
        (coefficient, _) => bt_channel::path_gain_detailed(
            ends.tx,
            &path.points,
            ends.rx,
            &channel,
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
    scene: &Scene,
    vertices: &[bt_geom::Vec3],
    interactions: &[Interaction],
) -> Result<Real, ReportError> {
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
        let t = match surface_response(scene, id) {
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
