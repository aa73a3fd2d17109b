//! A validated scene as plain data and back: what bt-import's load cache keeps on disk.
//!
//! [`StoredScene`] holds what validation produced (the surfaces' vertices in the scene-local
//! frame, the frame's origin, terminals, frequency, materials); [`Scene::from_stored`] rebuilds
//! every polygon with [`bt_geom::Polygon::new`] (the polygon checks run again, on all cores)
//! and the BVH, and checks that the data fits together (finite numbers, known materials,
//! unique names), so a stored scene that passes is a scene validation could have made. It does not repeat the
//! scene-level checks whose cost grows with the scene (coplanar duplicates, terminals on
//! surfaces): the cache's checksum and key say the data is what a validated load wrote.

use crate::{Material, Problem, Scene, SceneError, Surface, SurfaceKind};
use bt_geom::{Real, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashSet};

/// A validated [`Scene`] as data (metres; vertices and terminals in the scene-local frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredScene {
    /// Scene name.
    pub name: String,
    /// World position of the scene-local frame's origin, metres.
    pub origin: [Real; 3],
    /// The surfaces in order (their index is their [`crate::SurfaceId`]).
    pub surfaces: Vec<StoredSurface>,
    /// Transmitter, scene-local, if any.
    pub tx: Option<[Real; 3]>,
    /// Receiver, scene-local, if any.
    pub rx: Option<[Real; 3]>,
    /// Carrier frequency, Hz.
    pub frequency_hz: Real,
    /// Materials by name.
    pub materials: BTreeMap<String, Material>,
}

/// One surface of a [`StoredScene`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredSurface {
    /// Unique name.
    pub name: String,
    /// Material name, a key of [`StoredScene::materials`].
    pub material: String,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// Polygon vertices in order, metres, scene-local frame.
    pub vertices: Vec<[Real; 3]>,
}

impl Scene {
    /// This scene as data, for [`Scene::from_stored`].
    pub fn to_stored(&self) -> StoredScene {
        StoredScene {
            name: self.name.clone(),
            origin: self.origin.to_array(),
            surfaces: (self.surfaces.iter())
                .map(|s| StoredSurface {
                    name: s.name.clone(),
                    material: s.material.clone(),
                    kind: s.kind,
                    vertices: s.polygon.vertices().iter().map(|v| v.to_array()).collect(),
                })
                .collect(),
            tx: self.tx.map(|p| p.to_array()),
            rx: self.rx.map(|p| p.to_array()),
            frequency_hz: self.frequency_hz,
            materials: (*self.materials).clone(),
        }
    }

    /// The scene `stored` describes (the inverse of [`Scene::to_stored`]): every polygon
    /// rebuilt and checked, the BVH built anew, the edges derived on first use as always.
    /// Data that does not fit together is an error naming `source` and the first problem.
    pub fn from_stored(mut stored: StoredScene, source: &str) -> Result<Scene, SceneError> {
        let invalid = |location: String, message: String| SceneError::Invalid {
            source_name: source.to_string(),
            problems: vec![Problem { location, message }],
        };
        let finite = |p: &[Real; 3]| p.iter().all(|x| x.is_finite());
        let points = [Some(stored.origin), stored.tx, stored.rx];
        if !points.iter().flatten().all(finite) || !stored.frequency_hz.is_finite() {
            return Err(invalid("scene".into(), "a number is not finite".into()));
        }
        // Each list converted in place (`[Real; 3]` and `Vec3` have one layout), then the
        // polygons built on all cores beside the BVH, as validation does.
        let mut vertices: Vec<Vec<Vec3>> = (stored.surfaces.iter_mut())
            .map(|s| {
                let list = std::mem::take(&mut s.vertices);
                list.into_iter().map(Vec3::from_array).collect()
            })
            .collect();
        let (polygons, bvh) = crate::validate::polygons_and_bvh(&mut vertices);
        let mut surfaces = Vec::with_capacity(stored.surfaces.len());
        for (i, (s, polygon)) in stored.surfaces.into_iter().zip(polygons).enumerate() {
            let location = || format!("surfaces[{i}]");
            if !stored.materials.contains_key(&s.material) {
                return Err(invalid(location(), "an unknown material".into()));
            }
            let polygon = polygon.map_err(|e| invalid(location(), e.to_string()))?;
            surfaces.push(Surface {
                name: s.name,
                material: s.material,
                kind: s.kind,
                polygon,
            });
        }
        let mut names = HashSet::with_capacity(surfaces.len());
        if let Some(i) = surfaces.iter().position(|s| !names.insert(s.name.as_str())) {
            return Err(invalid(format!("surfaces[{i}]"), "a repeated name".into()));
        }
        let geometry = crate::validate::Geometry {
            surfaces,
            bvh: Some(bvh),
        };
        Ok(Scene::assemble(
            stored.name,
            Vec3::from_array(stored.origin),
            geometry,
            stored.tx.map(Vec3::from_array),
            stored.rx.map(Vec3::from_array),
            stored.frequency_hz,
            stored.materials,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room() -> Scene {
        let json = r#"{"name": "r", "tx": [1, 1, 1], "rx": [2, 1.5, 1],
            "boxes": [{"name": "room", "min": [0, 0, 0], "max": [4, 3, 2.5]}]}"#;
        let desc: crate::SceneDescription = serde_json::from_str(json).unwrap();
        Scene::from_description(&desc, "r.json", Default::default()).unwrap()
    }

    #[test]
    fn a_stored_scene_comes_back_equal() {
        let scene = room();
        let back = Scene::from_stored(scene.to_stored(), "cache").unwrap();
        assert_eq!(back.surfaces(), scene.surfaces());
        assert_eq!(back.materials(), scene.materials());
        assert_eq!((back.tx(), back.rx()), (scene.tx(), scene.rx()));
        assert_eq!(back.origin(), scene.origin());
        assert_eq!(back.frequency_hz(), scene.frequency_hz());
        assert_eq!(back.name(), scene.name());
        assert_eq!(back.extent(), scene.extent());
    }

    #[test]
    fn stored_data_that_does_not_fit_is_refused() {
        let good = room().to_stored();
        let mut bad = good.clone();
        bad.surfaces[0].vertices[1] = bad.surfaces[0].vertices[0];
        let mut unknown = good.clone();
        unknown.surfaces[2].material = "nowhere".into();
        let mut twice = good.clone();
        twice.surfaces[1].name = twice.surfaces[0].name.clone();
        let mut nan = good;
        nan.tx = Some([Real::NAN, 0.0, 0.0]);
        for (stored, expected) in [
            (bad, "surfaces[0]"),
            (unknown, "surfaces[2]"),
            (twice, "surfaces[1]"),
            (nan, "not finite"),
        ] {
            let e = Scene::from_stored(stored, "cache").unwrap_err().to_string();
            assert!(e.contains("cache") && e.contains(expected), "{e}");
        }
    }
}
