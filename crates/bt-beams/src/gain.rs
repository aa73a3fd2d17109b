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
