//! The one stateful front door: a [`Tracer`] holds a scene, the options of its traces, the beam
//! tree it keeps for a fixed TX, the previous time step and the beam tree's caches. The CLI,
//! the Python package, the coverage sweep and the viewer all trace through it.
//!
//! Every cache is a field: nothing lives in a thread-local that a caller cannot see or reset.
//! A cache only saves work; a fresh `Tracer` gives bit-identical results.

use crate::partner::Partner;
use crate::pipeline::{
    BuildProgress, KeptTx, TraceError, TraceOptions, Traced, trace_each_receiver, trace_scene_in,
    walks_one_tree,
};
use crate::steps::{Incremental, StepTrace, trace_scratch};
use bt_geom::Vec3;
use bt_paths::beamtree::TreeCache;
use bt_scene::Scene;
use std::sync::Arc;

/// Traces one scene (as its options see it, [`TraceOptions::scene_of`]): one TX–RX pair ([`Tracer::trace`]), one TX to many receivers with one beam
/// tree ([`Tracer::trace_many`]), or the next time step of a dynamic scene, incrementally
/// ([`Tracer::update`]).
///
/// Terminals are given in the scene's input (world) frame, metres; paths come back in the
/// scene-local frame ([`Scene::to_world`] converts). The scene may be bare geometry (no TX or
/// RX): `trace`, `trace_many` and `trace_each` place the terminals of each call
/// ([`Scene::with_terminals`]); `update` traces the step's own terminals and fails with
/// [`TraceError::Scene`] ([`bt_scene::SceneError::MissingTerminal`]) when it lacks one. Cloning keeps the scene, the kept tree and
/// the previous step (to branch, or to time one step) and starts with empty caches.
#[derive(Clone)]
pub struct Tracer {
    /// The scene traced (the last step given to [`Tracer::update`]).
    scene: Scene,
    options: TraceOptions,
    /// The beam tree's per-surface shapes and arenas, reused while the geometry stays.
    cache: TreeCache,
    /// The beam tree of `scene`'s own TX (built with the solver's tree options) that
    /// [`Tracer::trace_many`] walks for every receiver, with its diffraction side; dropped when
    /// the scene or the options change.
    kept: Option<KeptTx>,
    /// The previous time step, for [`Tracer::update`].
    previous: Incremental,
    /// Index of the next time step.
    next_step: usize,
    /// The thread that takes half of a lone receiver's walk of the kept tree
    /// ([`Tracer::set_partner`]); clones share it.
    partner: Option<Arc<Partner>>,
}

impl Tracer {
    /// A tracer of `scene` under `options`, with nothing kept yet.
    pub fn new(scene: Scene, options: TraceOptions) -> Self {
        Tracer {
            scene: options.scene_of(&scene),
            options,
            cache: TreeCache::default(),
            kept: None,
            previous: Incremental::default(),
            next_step: 0,
            partner: None,
        }
    }

    /// The scene traced: the one given to [`Tracer::new`] or the last step of
    /// [`Tracer::update`].
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The options of every trace.
    pub fn options(&self) -> &TraceOptions {
        &self.options
    }

    /// Trace `scene` from now on (another scene, or the same with other terminals or
    /// frequency). The kept tree and the previous step are dropped; the caches stay and are
    /// reused while the geometry is the same.
    pub fn set_scene(&mut self, scene: Scene) {
        self.scene = self.options.scene_of(&scene);
        self.kept = None;
        self.previous = Incremental::default();
    }

    /// Trace under other options from now on (the kept tree and the previous step, which
    /// depend on them, are dropped when they differ).
    pub fn set_options(&mut self, options: TraceOptions) {
        if options != self.options {
            self.options = options;
            self.scene = options.scene_of(&self.scene);
            self.kept = None;
            self.previous = Incremental::default();
        }
    }

    /// Trace from `tx` to `rx` (metres, world frame). The scene itself is traced when they are
    /// its own terminals (no round trip through the local frame), else a copy with them.
    pub fn trace(&mut self, tx: Vec3, rx: Vec3) -> Result<Traced, TraceError> {
        self.trace_with_progress(tx, rx, &mut |_| {})
    }

    /// [`Tracer::trace`], reporting the beam tree's build to `progress`.
    pub fn trace_with_progress(
        &mut self,
        tx: Vec3,
        rx: Vec3,
        progress: &mut dyn FnMut(BuildProgress),
    ) -> Result<Traced, TraceError> {
        if Some(tx) == self.scene.tx_world() && Some(rx) == self.scene.rx_world() {
            return trace_scene_in(&self.scene, &self.options, &mut self.cache, progress);
        }
        let moved = self.scene.with_terminals(tx, rx)?;
        trace_scene_in(&moved, &self.options, &mut self.cache, progress)
    }

    /// Trace `tx` to each of `receivers` (metres, world frame), in parallel when the options
    /// say so; fails with the first receiver that cannot be traced (see [`Tracer::trace_each`]).
    pub fn trace_many(&mut self, tx: Vec3, receivers: &[Vec3]) -> Result<Vec<Traced>, TraceError> {
        self.trace_each(tx, receivers)?.into_iter().collect()
    }

    /// Trace `tx` to each of `receivers` (metres, world frame), one outcome per receiver: a
    /// receiver on a surface or at the TX gets its own [`TraceError::Scene`] and the others are
    /// still traced (a coverage sweep marks such grid points). In beam-tree mode one tree of
    /// the TX answers every receiver by a walk; for the scene's own TX the tree is kept for the
    /// next call (a sweep in chunks builds it once), and walked even for a single receiver (a
    /// stream of receiver moves, `beamtrace serve`). Another TX is placed with the first
    /// receiver ([`Scene::with_terminals`]). Fails as a whole when the TX is not valid or the
    /// tree exceeds its budget.
    pub fn trace_each(
        &mut self,
        tx: Vec3,
        receivers: &[Vec3],
    ) -> Result<Vec<Result<Traced, TraceError>>, TraceError> {
        self.trace_each_then(tx, receivers, |_, traced| traced)
    }

    /// A lone receiver's walk of the kept tree split over `partner` from now on
    /// ([`Partner::join`]; `None`: on the calling thread): the same candidates.
    pub fn set_partner(&mut self, partner: Option<Arc<Partner>>) {
        self.partner = partner;
    }

    /// The partner of [`Tracer::set_partner`], if any.
    pub fn partner(&self) -> Option<Arc<Partner>> {
        self.partner.clone()
    }

    /// [`Tracer::trace_each`], with `then` applied to each receiver's trace, beside the scene
    /// it was traced in (the scene with `tx` and that receiver), in the task that traced it:
    /// a caller that reports each receiver does so on the thread that traced it, in parallel
    /// when the receivers are, with no second placement of the receiver and no second pass
    /// over the cores.
    pub fn trace_each_then<T: Send>(
        &mut self,
        tx: Vec3,
        receivers: &[Vec3],
        then: impl Fn(&Scene, Traced) -> T + Sync,
    ) -> Result<Vec<Result<T, TraceError>>, TraceError> {
        let Some(first) = receivers.first() else {
            return Ok(Vec::new());
        };
        let options = self.options;
        let own = Some(tx) == self.scene.tx_world();
        let walk = walks_one_tree(&options, receivers, own);
        if !own {
            let base = self.scene.with_terminals(tx, *first)?;
            let tree = match walk {
                true => Some(KeptTx::build(&base, &options, &mut self.cache)?),
                false => None,
            };
            let cache = &mut self.cache;
            return Ok(trace_each_receiver(
                &base,
                receivers,
                &options,
                (tree.as_ref(), cache),
                self.partner.as_deref(),
                &then,
            ));
        }
        if walk && self.kept.is_none() {
            self.kept = Some(KeptTx::build(&self.scene, &options, &mut self.cache)?);
        }
        let tree = if walk { self.kept.as_ref() } else { None };
        Ok(trace_each_receiver(
            &self.scene,
            receivers,
            &options,
            (tree, &mut self.cache),
            self.partner.as_deref(),
            &then,
        ))
    }

    /// Trace `scene`, the next time step of the scene held (the same surfaces, some moved),
    /// incrementally: only what the motion can have changed is computed again
    /// ([`crate::steps`]); the result equals a from-scratch trace. A scene that is not a next
    /// step (other surfaces), or the first step, is traced in full. `scene` becomes the
    /// scene held.
    pub fn update(&mut self, scene: &Scene) -> Result<StepTrace, TraceError> {
        let step = self.advance(scene);
        self.previous
            .step(&self.options, &self.scene, step, &mut self.cache)
    }

    /// Trace `scene` as the next time step from scratch (the reference [`Tracer::update`]
    /// reproduces; `--from-scratch`). Nothing of the previous step is used or kept.
    pub fn update_from_scratch(&mut self, scene: &Scene) -> Result<StepTrace, TraceError> {
        let step = self.advance(scene);
        self.previous = Incremental::default();
        trace_scratch(&self.scene, step, &self.options)
    }

    /// Hold `scene` as the next step: the kept tree is dropped; returns the step's index. (A
    /// step without terminals is held too; its trace fails and the last traced step stays the
    /// one the next step is compared with.)
    fn advance(&mut self, scene: &Scene) -> usize {
        self.scene = self.options.scene_of(scene);
        self.kept = None;
        self.next_step += 1;
        self.next_step - 1
    }
}
