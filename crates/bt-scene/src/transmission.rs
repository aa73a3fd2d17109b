//! Which surfaces let waves through (thin-slab transmission, `docs/channel.md`) and how many
//! interactions a path may have in all, crossings included.
//!
//! A surface is penetrable when its material is a slab (a radio model with a thickness) and
//! either its material says so (the scene file's `"transmission": true`, blockers included) or
//! a trace switches transmission on everywhere ([`Scene::with_transmission`], reflectors
//! only: blockers stay opaque unless their material says otherwise). A half-space transmits
//! nothing and stays opaque.

use crate::model::Scene;
use crate::surface::{SurfaceId, SurfaceKind};
use std::sync::Arc;

/// A scene's transmission state: the penetrable surfaces and the interaction budget of a path.
#[derive(Debug, Clone)]
pub(crate) struct Penetration {
    /// Per surface, whether waves cross it; `None` when none does (every surface opaque).
    mask: Option<Arc<[bool]>>,
    /// Transmission switched on for every reflector ([`Scene::with_transmission`]).
    everywhere: bool,
    /// Interactions a path may have in all: reflections, diffractions and crossings.
    max_interactions: usize,
}

impl Default for Penetration {
    fn default() -> Self {
        Penetration {
            mask: None,
            everywhere: false,
            max_interactions: usize::MAX,
        }
    }
}

impl Penetration {
    /// The per-surface mask, `None` when every surface is opaque.
    pub(crate) fn mask(&self) -> Option<&Arc<[bool]>> {
        self.mask.as_ref()
    }

    /// The state of `scene`'s surfaces and materials with transmission `everywhere` or not.
    pub(crate) fn of(scene: &Scene, everywhere: bool, max_interactions: usize) -> Self {
        let mut runs = crate::material::MaterialRuns::new();
        let mask: Vec<bool> = scene
            .surfaces()
            .iter()
            .map(|s| {
                let material = runs.get(&s.material, |name| &scene.materials()[name]);
                let slab = material.radio.is_some_and(|r| r.thickness.is_some());
                slab && (material.transmission || (everywhere && s.kind == SurfaceKind::Reflector))
            })
            .collect();
        Penetration {
            mask: mask.iter().any(|&p| p).then(|| mask.into()),
            everywhere,
            max_interactions,
        }
    }
}

impl Scene {
    /// A copy in which waves cross every reflector whose material is a slab (`everywhere`,
    /// the CLI's `--transmission`) or only those whose material says so, and a path has at most
    /// `max_interactions` interactions in all (the trace's order: crossings count). Half-spaces
    /// and blockers stay opaque unless their material says otherwise.
    pub fn with_transmission(&self, everywhere: bool, max_interactions: usize) -> Scene {
        let mut scene = self.clone();
        scene.penetration = Penetration::of(self, everywhere, max_interactions);
        scene
    }

    /// Whether waves cross surface `id` (thin-slab transmission).
    #[inline(always)]
    pub fn penetrable(&self, id: SurfaceId) -> bool {
        self.penetration
            .mask
            .as_ref()
            .is_some_and(|m| m[id.index()])
    }

    /// Whether waves cross any surface of the scene.
    #[inline(always)]
    pub fn transmits(&self) -> bool {
        self.penetration.mask.is_some()
    }

    /// Whether transmission is switched on for every reflector ([`Scene::with_transmission`]).
    pub fn transmission_everywhere(&self) -> bool {
        self.penetration.everywhere
    }

    /// Interactions a path may have in all, crossings included ([`Scene::with_transmission`];
    /// unbounded until a trace sets it).
    #[inline(always)]
    pub fn max_interactions(&self) -> usize {
        self.penetration.max_interactions
    }

    /// The materials of reflectors that transmission everywhere leaves opaque, by name: those
    /// without a radio model or whose model is a half-space (no thickness).
    pub fn opaque_materials(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self
            .surfaces()
            .iter()
            .filter(|s| s.kind == SurfaceKind::Reflector)
            .map(|s| s.material.as_str())
            .filter(|m| {
                self.materials()[*m]
                    .radio
                    .is_none_or(|r| r.thickness.is_none())
            })
            .collect();
        names.sort_unstable();
        names.dedup();
        names
    }
}
