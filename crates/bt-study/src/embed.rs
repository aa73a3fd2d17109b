//! 2-D rooms as 3-D scenes, so the same image method, IPC and SBR code serves the 2-D study.
//!
//! Each wall of the closed contour becomes a vertical rectangle from z = 0 to z = h; TX and RX
//! sit at z = h/2 and there is no floor or ceiling. Every specular path between two points at
//! the same height off vertical walls stays in the horizontal plane z = h/2 (a vertical mirror
//! keeps the z component of a direction, which is 0), so the 3-D solvers compute exactly the
//! 2-D paths, with interaction points at mid-height, far from the rectangles' edges.

use crate::StudyError;
use bt_geom::{Real, Vec2, Vec3};
use bt_scene::{Scene, SceneDescription, Terminals};

/// Height of the embedded walls, metres.
pub const WALL_HEIGHT: Real = 3.0;

/// Name of the wall from contour vertex `i` to vertex `i + 1`.
pub fn wall_name(i: usize) -> String {
    format!("wall-{i}")
}

/// The 3-D point of a plan position at terminal height (h/2), metres.
pub fn lift(p: Vec2) -> Vec3 {
    Vec3::new(p.x, p.y, 0.5 * WALL_HEIGHT)
}

/// The scene of a contour (counter-clockwise vertices, metres) with TX and RX: wall `i` runs
/// from vertex `i` to vertex `i + 1`, so surface ids equal edge indices.
pub fn scene(name: &str, contour: &[Vec2], tx: Vec2, rx: Vec2) -> Result<Scene, StudyError> {
    let n = contour.len();
    let surfaces: Vec<serde_json::Value> = (0..n)
        .map(|i| {
            let (a, b) = (contour[i], contour[(i + 1) % n]);
            serde_json::json!({
                "name": wall_name(i),
                "vertices": [
                    [a.x, a.y, 0.0], [b.x, b.y, 0.0],
                    [b.x, b.y, WALL_HEIGHT], [a.x, a.y, WALL_HEIGHT]
                ],
            })
        })
        .collect();
    let json = serde_json::json!({
        "name": name,
        "tx": lift(tx).to_array(),
        "rx": lift(rx).to_array(),
        "surfaces": surfaces,
    });
    // Built through the file format so the scene is validated like any user scene.
    let desc: SceneDescription = serde_json::from_value(json).map_err(|e| StudyError::Scene {
        name: name.to_string(),
        message: e.to_string(),
    })?;
    Scene::from_description(&desc, name, Terminals::default()).map_err(|e| StudyError::Scene {
        name: name.to_string(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_paths::{AllVisible, enumerate};
    use bt_solve::{Solver, trace};

    #[test]
    fn square_room_paths_stay_in_the_plane() {
        let contour = [[1., 1.], [6., 1.], [6., 5.], [1., 5.]].map(Vec2::from);
        let scene = scene("square", &contour, Vec2::new(2., 2.), Vec2::new(4., 3.)).unwrap();
        assert_eq!(scene.find("wall-2").map(|id| id.0), Some(2));
        let candidates = enumerate(&scene, 2, &AllVisible).unwrap();
        let paths = trace(&scene, &candidates, &Solver::Image, false)
            .unwrap()
            .paths;
        // LOS + 4 first order + 2 × 2 between parallel walls + 4 perpendicular pairs (one
        // order each).
        assert_eq!(paths.len(), 1 + 4 + 4 + 4);
        for p in &paths {
            assert!(p.points.iter().all(|q| (q.z - 1.5).abs() < 1e-12));
        }
    }
}
