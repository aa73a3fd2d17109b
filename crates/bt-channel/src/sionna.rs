//! Sionna RT 2.2's gain of a diffracted path exactly as its `PathSolver` reports it, for
//! comparing with Sionna: the `sionna-rt-2.2` coefficient ([`DiffractionCoefficient`]) and
//! the diffracted leg s that Sionna's field calculator actually uses, which for a path that
//! reflects after its diffraction depends on the solver's `max_depth` (a Sionna bug:
//! `docs/channel.md`, "Reflections after the edge in Sionna RT 2.2").
//!
//! What Sionna 2.2 does (`sionna/rt/path_solvers/`): `FieldCalculator.
//! _diffraction_compute_s_s_prime` sums the segment lengths after the diffraction while walking
//! the path's depths, and on the first depth whose interaction is `NONE` (the path has ended)
//! it still adds |vertex(depth) − previous vertex| and then takes that vertex as the start of
//! the last segment to the target. The image method (`ImageMethod.
//! _compute_diffraction_point_images`) leaves in that unused slot the image of the diffraction
//! point through the planes of the reflections after it. So, for a path with fewer
//! interactions than `max_depth` (there is such a slot), s grows from the unfolded length to
//! s − |RX − P| + |X − P| + |RX − X|, P the last interaction point and X the image of the
//! diffraction point; X = P (no change) when the diffraction is the last interaction. The same
//! s enters the coefficient's L = s·s'/(s + s')·sin²β0 and the spreading 1/√(s·s'·(s + s')).
//! Sionna run with `max_depth` equal to the path's number of interactions has no such slot and
//! reports the unfolded s, like [`crate::path_gain_detailed`].

use crate::ChannelError;
use crate::antenna::Antenna;
use crate::diffraction::DiffractionCoefficient;
use crate::gain::{Interaction, PathGain, path_gain_with_leg};
use bt_geom::{Real, Vec3};

/// The diffracted leg s (metres) Sionna RT 2.2 uses for the path TX → `points` → `rx` (world
/// frame, metres; one [`Interaction`] per point) found by a `PathSolver` with `max_depth`
/// interactions at most: the unfolded length from the diffraction point to `rx`, lengthened
/// as the module documentation says when the path has fewer than `max_depth` interactions
/// and reflects after its diffraction. `None` for a path without a diffraction. Errors:
/// `points` and `interactions` differ in length, or the path has more than `max_depth`
/// interactions (the solver cannot have found it).
pub fn sionna_rt22_diffracted_leg(
    points: &[Vec3],
    rx: Vec3,
    interactions: &[Interaction],
    max_depth: usize,
) -> Result<Option<Real>, ChannelError> {
    if points.len() != interactions.len() || points.len() > max_depth {
        return Err(ChannelError::Invalid {
            field: "interactions",
            message: format!(
                "{} points, {} interactions, max_depth {max_depth}",
                points.len(),
                interactions.len()
            ),
        });
    }
    let Some(d) = (interactions.iter()).position(|i| matches!(i, Interaction::Diffraction(_)))
    else {
        return Ok(None);
    };
    let last = points[points.len() - 1];
    let unfolded: Real = (points[d..].windows(2))
        .map(|w| w[0].distance(w[1]))
        .sum::<Real>()
        + last.distance(rx);
    if points.len() == max_depth {
        return Ok(Some(unfolded));
    }
    // The image of the diffraction point through the later reflections' planes, in order.
    let mut image = points[d];
    for (p, interaction) in points[d + 1..].iter().zip(&interactions[d + 1..]) {
        if let Interaction::Reflection(bounce) = interaction {
            let n = bounce.normal;
            image = image - n * (2.0 * (image - *p).dot(n));
        }
    }
    Ok(Some(
        unfolded - last.distance(rx) + image.distance(last) + rx.distance(image),
    ))
}

/// Complex gain of a path as Sionna RT 2.2's `PathSolver` with `max_depth` reports it:
/// [`crate::path_gain_detailed`] with [`DiffractionCoefficient::SionnaRt22`] and the diffracted
/// leg of [`sionna_rt22_diffracted_leg`] (arguments as there; `frequency_hz` in Hz). A path
/// without a diffraction, or whose diffraction is its last interaction, or with `max_depth`
/// interactions, gets exactly [`crate::path_gain_detailed`]'s value. Errors: those of both.
pub fn path_gain_sionna_rt22(
    tx: Vec3,
    points: &[Vec3],
    rx: Vec3,
    interactions: &[Interaction],
    antennas: (&Antenna, &Antenna),
    frequency_hz: Real,
    max_depth: usize,
) -> Result<PathGain, ChannelError> {
    let leg = sionna_rt22_diffracted_leg(points, rx, interactions, max_depth)?;
    let radio = (frequency_hz, DiffractionCoefficient::SionnaRt22);
    path_gain_with_leg(tx, points, rx, interactions, antennas, radio, leg)
}
