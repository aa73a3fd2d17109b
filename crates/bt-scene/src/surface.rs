//! Surfaces: the validated [`Surface`] of a scene and the unvalidated [`RawSurface`] an
//! importer or a scene file hands to validation.

use bt_geom::{Polygon, Vec3};
use serde::{Deserialize, Serialize};

/// Index of a surface in [`crate::Scene::surfaces`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SurfaceId(pub u32);

impl SurfaceId {
    /// The index as `usize`.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a surface does to a ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// Reflects specularly from both sides, and occludes.
    Reflector,
    /// Only occludes (small objects, people).
    Blocker,
}

/// A named bounded planar surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Unique name (from the scene file, or generated for meshes).
    pub name: String,
    /// Material name, a key of [`crate::Scene::materials`].
    pub material: String,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// The validated polygon (metres, world frame).
    pub polygon: Polygon,
}

/// A surface as given, before validation (world frame, metres): what a scene file's
/// `surfaces`/`boxes` or an importer (mesh faces, extracted planes) hands to
/// [`crate::Scene::from_surfaces`].
#[derive(Debug, Clone, PartialEq)]
pub struct RawSurface {
    /// Where it came from, for messages (e.g. `surfaces[3] "sofa.top"`, `surface 2 "wall_0"`).
    pub location: String,
    /// Surface name (checked: printable, unique).
    pub name: String,
    /// Material name (`None`: `"default"`).
    pub material: Option<String>,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// Polygon vertices in order, metres, world frame.
    pub vertices: Vec<Vec3>,
}

/// Where a surface awaiting validation came from, written out only for a message: a city has
/// 17,803 surfaces and almost never a problem, so formatting each one's location (its name
/// escaped and cut by [`crate::name::shown`]) up front was work thrown away.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Place {
    /// Written already ([`RawSurface::location`]).
    Given(String),
    /// `surfaces[index]` of a scene description.
    Described(usize),
    /// The face `face` of `boxes[index]`, whose name is the surface's without `.face`.
    BoxFace(usize, &'static str),
}

/// A surface awaiting validation: a [`RawSurface`] whose location is a [`Place`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Pending {
    /// Where it came from.
    pub place: Place,
    /// Surface name (checked: printable, unique).
    pub name: String,
    /// Material name (`None`: `"default"`).
    pub material: Option<String>,
    /// Reflector or blocker.
    pub kind: SurfaceKind,
    /// Polygon vertices in order, metres (world frame, then local once recentred).
    pub vertices: Vec<Vec3>,
}

impl Pending {
    /// The location messages name (e.g. `surfaces[3] "sofa.top"`), as [`RawSurface::location`].
    pub fn location(&self) -> String {
        let shown = crate::name::shown;
        match &self.place {
            Place::Given(location) => location.clone(),
            Place::Described(i) => format!("surfaces[{i}] \"{}\"", shown(&self.name)),
            Place::BoxFace(i, face) => {
                let suffix = format!(".{face}");
                let of_box = self.name.strip_suffix(&suffix).unwrap_or(&self.name);
                format!("boxes[{i}] \"{}\".{face}", shown(of_box))
            }
        }
    }
}

impl From<RawSurface> for Pending {
    fn from(r: RawSurface) -> Pending {
        Pending {
            place: Place::Given(r.location),
            name: r.name,
            material: r.material,
            kind: r.kind,
            vertices: r.vertices,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::name::shown;

    fn pending(place: Place, name: &str) -> Pending {
        Pending {
            place,
            name: name.into(),
            material: None,
            kind: SurfaceKind::Reflector,
            vertices: vec![],
        }
    }

    #[test]
    fn a_location_written_late_is_the_one_written_up_front() {
        let long = "w\"all\u{1b}".repeat(40);
        for name in ["sofa.top", long.as_str(), "a\\b"] {
            let at = pending(Place::Described(3), name).location();
            assert_eq!(at, format!("surfaces[3] \"{}\"", shown(name)));
            let face = format!("{name}.north");
            let at = pending(Place::BoxFace(2, "north"), &face).location();
            assert_eq!(at, format!("boxes[2] \"{}\".north", shown(name)));
        }
        let given = pending(Place::Given("surface 7 \"x\"".into()), "x");
        assert_eq!(given.location(), "surface 7 \"x\"");
    }

    #[test]
    fn problems_of_box_faces_name_the_box_and_the_face() {
        let json = r#"{"boxes": [{"name": "b.top", "min": [0, 0, 0], "max": [1, 1, 1],
            "material": "nowhere", "omit": ["bottom", "west", "east", "south", "north"]}]}"#;
        let desc: crate::SceneDescription = serde_json::from_str(json).unwrap();
        let e = crate::Scene::from_description(&desc, "b.json", Default::default());
        let text = e.unwrap_err().to_string();
        let expected = "boxes[0] \"b.top\".top: unknown material \"nowhere\"";
        assert!(text.contains(expected), "{text}");
    }

    #[test]
    fn problems_come_in_surface_order_whatever_the_threads() {
        // Every third surface repeats a vertex, every fifth repeats a name: their problems
        // interleave, and the polygons are built on all cores.
        let surfaces: Vec<String> = (0..300)
            .map(|i| {
                let name = if i % 5 == 4 { "twice".to_string() } else { format!("s{i}") };
                let y = if i % 3 == 0 { 0 } else { 1 };
                format!(r#"{{"name": "{name}", "vertices": [[{i}, 0, 0], [{i}.5, 0, 0], [{i}, {y}, 0]]}}"#)
            })
            .collect();
        let json = format!(r#"{{"surfaces": [{}]}}"#, surfaces.join(","));
        let desc: crate::SceneDescription = serde_json::from_str(&json).unwrap();
        let check = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let e = pool
                .install(|| crate::Scene::from_description(&desc, "s.json", Default::default()));
            e.unwrap_err().to_string()
        };
        let one = check(1);
        assert!(
            one.contains("surfaces[3] \"s3\".vertices: vertices 0 and 2 are repeated"),
            "{one}"
        );
        assert!(
            one.contains("surfaces[9] \"twice\": duplicate surface name"),
            "{one}"
        );
        assert_eq!(one, check(4));
    }
}
