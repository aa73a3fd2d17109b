//! The validated scene model.

use crate::material::Material;
use crate::problem::{Problem, SceneError, Terminal};
use crate::surface::{Surface, SurfaceId, SurfaceKind};
use bt_geom::{Bvh, Real, Vec3};
use std::collections::BTreeMap;
use std::sync::Arc;

/// A validated scene: bare geometry, or geometry with its terminals. Construct it with
/// [`Scene::from_description`] or [`Scene::from_surfaces`] (importers: the `bt-import` crate);
/// every surface is a valid planar polygon; TX and RX, where the input gives them, are finite,
/// distinct and off every surface. A trace needs both: [`Scene::terminals`] is the checked way
/// to get them, and [`Scene::with_terminals`] places them on a bare scene.
///
/// Positions are stored in the scene-local frame (`local = world − origin()`, see
/// [`Scene::origin`]): [`Scene::tx`], [`Scene::rx`], the surfaces' polygons and every path point
/// a solver finds are local; [`Scene::to_world`] turns them back into the input's coordinates.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(crate) name: String,
    pub(crate) origin: Vec3,
    /// Shared between a scene and its copies with other terminals or frequency
    /// ([`Scene::with_receiver`]): a sweep's receivers do not copy the geometry.
    pub(crate) surfaces: Arc<Vec<Surface>>,
    /// `None` on bare geometry (a mesh, XML or point cloud loaded without a TX).
    pub(crate) tx: Option<Vec3>,
    /// `None` on bare geometry.
    pub(crate) rx: Option<Vec3>,
    pub(crate) frequency_hz: Real,
    pub(crate) materials: Arc<BTreeMap<String, Material>>,
    pub(crate) extent: Real,
    pub(crate) bvh: Arc<Bvh>,
    /// The diffracting edges, derived on first use and shared like `surfaces`.
    pub(crate) edges: Arc<std::sync::OnceLock<crate::edges::Edges>>,
    /// Which surfaces waves cross, and a path's interaction budget (`transmission`).
    pub(crate) penetration: crate::transmission::Penetration,
}

/// The identity of a scene's surfaces ([`Scene::geometry_key`]). It holds no strong reference:
/// the surfaces are freed with their last scene, while the key keeps their address from being
/// reused, so a key never matches other geometry. Surfaces are never changed in place.
/// Which surfaces waves cross (`Scene::penetrable`) belongs to the key too: derived data such
/// as a beam tree's occlusion culling depends on it.
#[derive(Debug, Clone)]
pub struct GeometryKey(
    std::sync::Weak<Vec<Surface>>,
    Option<std::sync::Weak<[bool]>>,
);

impl GeometryKey {
    /// Whether `scene` has exactly the surfaces this key was taken from, with the same
    /// penetrable ones.
    pub fn matches(&self, scene: &Scene) -> bool {
        let mask = scene.penetration.mask();
        self.0.strong_count() > 0
            && std::ptr::eq(self.0.as_ptr(), Arc::as_ptr(&scene.surfaces))
            && match (&self.1, mask) {
                (None, None) => true,
                (Some(kept), Some(mask)) => {
                    kept.strong_count() > 0 && std::ptr::addr_eq(kept.as_ptr(), Arc::as_ptr(mask))
                }
                _ => false,
            }
    }
}

/// The identity of what a surface's radio response depends on ([`Scene::radio_key`]): which
/// material each surface names (its [`GeometryKey`]), the materials, and the frequency. Like
/// the geometry's, it holds no strong reference and keeps the materials' address from being
/// reused; materials are never changed in place while a key to them exists (a change makes a
/// new map), so a key never matches other materials.
#[derive(Debug, Clone)]
pub struct RadioKey {
    geometry: GeometryKey,
    materials: std::sync::Weak<BTreeMap<String, Material>>,
    frequency_hz: Real,
}

impl RadioKey {
    /// Whether `scene` has the surfaces, the materials and the frequency this key was taken
    /// from.
    pub fn matches(&self, scene: &Scene) -> bool {
        self.frequency_hz.to_bits() == scene.frequency_hz.to_bits()
            && self.materials.strong_count() > 0
            && std::ptr::eq(self.materials.as_ptr(), Arc::as_ptr(&scene.materials))
            && self.geometry.matches(scene)
    }
}

impl Scene {
    /// The identity of this scene's surfaces, materials and frequency ([`RadioKey::matches`]):
    /// lets a caller keep the surfaces' radio responses across reports in the same scene (a
    /// serve stream's receivers).
    pub fn radio_key(&self) -> RadioKey {
        RadioKey {
            geometry: self.geometry_key(),
            materials: Arc::downgrade(&self.materials),
            frequency_hz: self.frequency_hz,
        }
    }
    /// Scene name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// All surfaces, reflectors and blockers; indexed by [`SurfaceId`].
    pub fn surfaces(&self) -> &[Surface] {
        &self.surfaces
    }
    /// The identity of this scene's surface geometry, shared by its copies with another
    /// receiver, terminals or frequency ([`GeometryKey::matches`]): lets a caller keep data
    /// derived from the surfaces alone across traces of the same geometry.
    pub fn geometry_key(&self) -> GeometryKey {
        GeometryKey(
            Arc::downgrade(&self.surfaces),
            self.penetration.mask().map(Arc::downgrade),
        )
    }
    /// The surface with id `id`.
    #[inline]
    pub fn surface(&self, id: SurfaceId) -> &Surface {
        &self.surfaces[id.index()]
    }
    /// Ids of the reflecting surfaces, in scene order.
    pub fn reflectors(&self) -> impl Iterator<Item = SurfaceId> + '_ {
        self.surfaces
            .iter()
            .enumerate()
            .filter(|(_, s)| s.kind == SurfaceKind::Reflector)
            .map(|(i, _)| SurfaceId(i as u32))
    }
    /// Both terminals, metres, scene-local frame: the checked value every trace starts from.
    /// A bare scene (a mesh, XML or point cloud loaded without them) lacks one or both, and
    /// the error, [`SceneError::MissingTerminal`], names which; [`Scene::with_terminals`] makes
    /// it traceable.
    pub fn terminals(&self) -> Result<Endpoints, SceneError> {
        match (self.tx, self.rx) {
            (Some(tx), Some(rx)) => Ok(Endpoints { tx, rx }),
            (tx, rx) => Err(SceneError::MissingTerminal {
                source_name: self.name.clone(),
                missing: [(Terminal::Tx, tx), (Terminal::Rx, rx)]
                    .into_iter()
                    .filter(|(_, p)| p.is_none())
                    .map(|(t, _)| t)
                    .collect(),
            }),
        }
    }
    /// One terminal, metres, scene-local frame, or [`SceneError::MissingTerminal`] naming it:
    /// for work that needs only one (a beam tree needs only the TX).
    pub fn terminal(&self, which: Terminal) -> Result<Vec3, SceneError> {
        let p = match which {
            Terminal::Tx => self.tx,
            Terminal::Rx => self.rx,
        };
        p.ok_or_else(|| SceneError::MissingTerminal {
            source_name: self.name.clone(),
            missing: vec![which],
        })
    }
    /// Transmitter position, metres, scene-local frame, if the scene has one.
    pub fn tx(&self) -> Option<Vec3> {
        self.tx
    }
    /// Receiver position, metres, scene-local frame, if the scene has one.
    pub fn rx(&self) -> Option<Vec3> {
        self.rx
    }
    /// Transmitter position, metres, world frame (as given in the input), if the scene has one.
    pub fn tx_world(&self) -> Option<Vec3> {
        self.tx.map(|p| self.to_world(p))
    }
    /// Receiver position, metres, world frame (as given in the input), if the scene has one.
    pub fn rx_world(&self) -> Option<Vec3> {
        self.rx.map(|p| self.to_world(p))
    }
    /// World position of the scene-local frame's origin, metres: zero for scenes near the world
    /// origin, a power-of-two-grid point near the scene's centre for scenes far from it
    /// (`frame` module of this crate).
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
    /// A point of the scene-local frame (solver output) in world coordinates, metres. The
    /// identity (bit for bit, signed zeros kept) when [`Scene::origin`] is zero.
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        crate::frame::to_world(local, self.origin)
    }
    /// A world point (a receiver given later, a grid point) in the scene-local frame, metres.
    pub fn to_local(&self, world: Vec3) -> Vec3 {
        crate::frame::to_local(world, self.origin)
    }
    /// Carrier frequency, Hz.
    pub fn frequency_hz(&self) -> Real {
        self.frequency_hz
    }
    /// Materials by name.
    pub fn materials(&self) -> &BTreeMap<String, Material> {
        &self.materials
    }
    /// The material of a surface.
    pub fn material_of(&self, id: SurfaceId) -> &Material {
        &self.materials[&self.surface(id).material]
    }
    /// Bounding-box diagonal of all surfaces and of the terminals the scene has, metres (scales
    /// length tolerances): a bare scene's comes from its surfaces alone.
    pub fn extent(&self) -> Real {
        self.extent
    }
    /// Length tolerance of geometric decisions for this scene, metres.
    pub fn length_tolerance(&self) -> Real {
        crate::frame::scene_tolerance(self.extent)
    }
    /// BVH over all surfaces (for occlusion tests).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
    /// The diffracting edges of the surfaces (wedges and free edges, [`crate::edges`]),
    /// derived on the first call and shared by the scene's copies with other terminals.
    pub fn edges(&self) -> &crate::edges::Edges {
        self.edges
            .get_or_init(|| crate::edges::Edges::build(&self.surfaces))
    }
    /// `edge`'s name in a path record's `surfaces`: its face's name for a free edge, both
    /// faces' (face 0, then face n) for a wedge, escaped by [`crate::name::edge`] so that
    /// [`crate::name::split_edge`] gives them back.
    pub fn edge_name(&self, edge: &crate::edges::Edge) -> String {
        let name = |id: SurfaceId| self.surface(id).name.as_str();
        let face_n = (!edge.is_free()).then(|| name(edge.face_n));
        crate::name::edge(name(edge.face0), face_n)
    }
    /// Look a surface up by name.
    pub fn find(&self, name: &str) -> Option<SurfaceId> {
        self.surfaces
            .iter()
            .position(|s| s.name == name)
            .map(|i| SurfaceId(i as u32))
    }

    /// Pairs of reflectors (lower id first) that lie in one plane and overlap
    /// ([`bt_geom::Polygon::overlaps_coplanar`]) but name different materials: every path
    /// reflecting there is found twice, with two losses. A warning for imported geometry (a
    /// scene file refuses every overlapping pair).
    pub fn coplanar_conflicts(&self) -> Vec<(SurfaceId, SurfaceId)> {
        let tol = self.length_tolerance();
        let differ = |a: &Surface, b: &Surface| a.material != b.material;
        crate::validate::coplanar_overlaps(&self.surfaces, &self.bvh, tol, differ)
            .into_iter()
            .map(|(i, j)| (SurfaceId(i as u32), SurfaceId(j as u32)))
            .collect()
    }

    /// Pairs of reflectors (lower id first) that are the same polygon twice: as many
    /// vertices, each within the tolerance of one of the other's, overlapping in one plane
    /// ([`bt_geom::Polygon::coincides`]). Every path reflecting there is found twice.
    pub fn duplicates(&self) -> Vec<(SurfaceId, SurfaceId)> {
        let tol = self.length_tolerance();
        crate::validate::coplanar_overlaps(&self.surfaces, &self.bvh, tol, |_, _| true)
            .into_iter()
            .filter(|&(i, j)| (self.surfaces[i].polygon).coincides(&self.surfaces[j].polygon, tol))
            .map(|(i, j)| (SurfaceId(i as u32), SurfaceId(j as u32)))
            .collect()
    }

    /// The scene itself, or its [`Scene::duplicates`] as problems of the scene file
    /// `source_name` ([`Scene::check_duplicates`]).
    pub fn without_duplicates(self, source_name: &str) -> Result<Scene, SceneError> {
        self.check_duplicates(source_name).map(|()| self)
    }

    /// The [`Scene::duplicates`] as problems of the scene file `source_name`, naming both
    /// surfaces: a file written by hand must say which one it means (imported meshes merge
    /// theirs instead).
    pub fn check_duplicates(&self, source_name: &str) -> Result<(), SceneError> {
        let name = |id: SurfaceId| crate::name::escape(&self.surface(id).name);
        let problems: Vec<Problem> = (self.duplicates().into_iter())
            .map(|(a, b)| Problem {
                location: format!("surface \"{}\"", name(b)),
                message: format!(
                    "the same polygon as surface \"{}\": a path would reflect on both \
                     (remove one)",
                    name(a)
                ),
            })
            .collect();
        match problems.is_empty() {
            true => Ok(()),
            false => Err(SceneError::Invalid {
                source_name: source_name.to_string(),
                problems,
            }),
        }
    }

    /// Closed shells (watertight groups of surfaces, e.g. a box with all six faces or a closed
    /// mesh solid) that hold exactly one of TX and RX, with the terminal inside ("tx" or "rx"):
    /// no path can connect the two. A shell holding both (the room itself) is not listed, nor
    /// one whose sides cannot be told within the tolerance (the test only answers when sure).
    /// Empty for a scene without both terminals.
    pub fn separating_shells(&self) -> Vec<(&'static str, Vec<SurfaceId>)> {
        let Ok(Endpoints { tx, rx }) = self.terminals() else {
            return Vec::new();
        };
        let eps = self.length_tolerance();
        let inside =
            |shell: &[SurfaceId], p| crate::enclosure::encloses(&self.surfaces, shell, p, eps);
        crate::enclosure::closed_shells(&self.surfaces)
            .into_iter()
            // A shell whose box holds neither terminal holds neither (a city's buildings).
            .filter(|shell| {
                crate::enclosure::box_holds_either(&self.surfaces, shell, [tx, rx], eps)
            })
            .filter_map(|shell| match (inside(&shell, tx)?, inside(&shell, rx)?) {
                (true, false) => Some(("tx", shell)),
                (false, true) => Some(("rx", shell)),
                _ => None,
            })
            .collect()
    }

    /// Warnings about a valid scene that likely does not mean what it says (printable: names
    /// escaped).
    pub fn warnings(&self) -> Vec<String> {
        // Two independent searches over the whole scene: side by side when cores are free.
        let (shells, conflicts) =
            rayon::join(|| self.separating_shells(), || self.coplanar_conflicts());
        let enclosed = shells.into_iter().map(|(inside, shell)| {
            let names: Vec<String> = (shell.iter().take(3))
                .map(|id| format!("\"{}\"", crate::name::shown(&self.surface(*id).name)))
                .collect();
            let more = if shell.len() > 3 { ", ..." } else { "" };
            let outside = if inside == "tx" { "rx" } else { "tx" };
            format!(
                "{inside} lies inside the closed solid of {} surfaces ({}{more}) and {outside} \
                 outside it: no path can connect them",
                shell.len(),
                names.join(", ")
            )
        });
        let conflicts = conflicts.into_iter().map(|(a, b)| {
                let (a, b) = (self.surface(a), self.surface(b));
                format!(
                    "surfaces \"{}\" ({}) and \"{}\" ({}) overlap in one plane with different materials: \
                     paths reflecting there are found twice",
                    crate::name::shown(&a.name),
                    crate::name::shown(&a.material),
                    crate::name::shown(&b.name),
                    crate::name::shown(&b.material)
                )
            });
        conflicts.chain(enclosed).collect()
    }

    /// [`scene_extent`] of the surfaces with `tx` and `rx`, from the BVH's box instead of a
    /// pass over every surface (the same bits).
    pub(crate) fn extent_with(&self, tx: Vec3, rx: Vec3) -> Real {
        extent_of(self.bvh.bounds(), Some(tx), Some(rx))
    }
}

/// The two terminals of a trace, metres, scene-local frame: what [`Scene::terminals`] gives
/// once it has checked that the scene has both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Endpoints {
    /// Transmitter position.
    pub tx: Vec3,
    /// Receiver position.
    pub rx: Vec3,
}

/// Bounding-box diagonal of the surfaces and the terminals given, metres (0 for nothing).
/// With both terminals the box starts from them, as it always did: outputs of scenes with
/// terminals stay bit-identical.
pub(crate) fn scene_extent(surfaces: &[Surface], tx: Option<Vec3>, rx: Option<Vec3>) -> Real {
    extent_of(surfaces_box(surfaces, None), tx, rx)
}

/// The box `(min, max)` around every surface, metres, `None` without surfaces. `bvh`, when
/// given, must be the BVH of `surfaces`' polygons: its root box is taken instead of a pass
/// over the surfaces, the same bits (`min` and `max` are exact in any order).
pub(crate) fn surfaces_box(surfaces: &[Surface], bvh: Option<&Bvh>) -> Option<(Vec3, Vec3)> {
    match bvh {
        Some(bvh) => bvh.bounds(),
        None => (surfaces.iter().map(|s| s.polygon.bounds()))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d))),
    }
}

/// [`scene_extent`] of surfaces whose box is `surfaces` ([`surfaces_box`]).
fn extent_of(surfaces: Option<(Vec3, Vec3)>, tx: Option<Vec3>, rx: Option<Vec3>) -> Real {
    let (mut lo, mut hi) = match (tx, rx) {
        (Some(tx), Some(rx)) => (tx.min(rx), tx.max(rx)),
        (Some(p), None) | (None, Some(p)) => (p, p),
        (None, None) => (Vec3::INFINITY, Vec3::NEG_INFINITY),
    };
    if let Some((a, b)) = surfaces {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if lo.cmpgt(hi).any() {
        return 0.0;
    }
    (hi - lo).length()
}
