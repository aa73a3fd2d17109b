//! The image method: exact geometric optics for a given surface sequence, the reference.
//!
//! TX is mirrored through the planes in sequence order; walking back from RX, each
//! interaction point is where the line from the current target to the image crosses the
//! plane. The result satisfies the reflection law on the infinite planes; whether the points
//! lie inside their polygons and on the right sides is decided by [`crate::validate`].

use bt_geom::Vec3;
use bt_scene::{Scene, SurfaceId};

/// Why the image method gave no points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ImageFailure {
    /// The line from an image to its target is parallel to the plane (grazing).
    Parallel {
        /// Index of the interaction point, 0-based from TX.
        index: usize,
    },
}

/// Fill `points` (length = sequence length) with the interaction points of `seq` from `tx` to
/// `rx`, metres.
#[inline(always)]
pub fn solve(
    scene: &Scene,
    seq: &[SurfaceId],
    tx: Vec3,
    rx: Vec3,
    points: &mut [Vec3],
) -> Result<(), ImageFailure> {
    debug_assert_eq!(seq.len(), points.len());
    // images[k] = image of TX through planes 0..=k; stored in `points` first to avoid allocation.
    let mut image = tx;
    for (k, id) in seq.iter().enumerate() {
        image = scene.surface(*id).polygon.plane().mirror(image);
        points[k] = image;
    }
    let mut target = rx;
    for k in (0..seq.len()).rev() {
        let plane = scene.surface(seq[k]).polygon.plane();
        let image = points[k];
        let t = plane
            .line_parameter(image, target)
            .ok_or(ImageFailure::Parallel { index: k })?;
        let p = image + t * (target - image);
        points[k] = p;
        target = p;
    }
    Ok(())
}
