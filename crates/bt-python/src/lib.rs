//! The native module of the `beamtrace` Python package (`beamtrace._native`).
//!
//! Thin by design, like the CLI: Python arguments → library options → one library call
//! (`bt_scene` loading, a `bt_solve::Tracer` per scene, `bt_beams::report`) → NumPy columns. The
//! Python layer (`python/src/beamtrace`) normalises arrays and wraps the columns in `Paths`.
//! Tracing releases the GIL; `trace_many` traces and reports each receiver in one task,
//! spread over rayon's pool (`Tracer::trace_each_then`).

#![warn(missing_docs)]

mod columns;
mod options;
mod record;
mod sink;
mod tracer;

use bt_geom::Vec3;
use bt_import::LoadOptions;
use bt_scene::{Scene, SceneError, Terminal, Terminals};
use bt_solve::Tracer;
use bt_solve::pipeline::{TraceError, TraceOptions, Traced};
use numpy::PyReadonlyArray2;
use options::TraceKeywords;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};
use std::sync::{Arc, Mutex};

create_exception!(
    beamtrace,
    BeamtraceError,
    PyException,
    "A scene that cannot be loaded or a trace that cannot run; the message is the CLI's."
);

fn error(e: impl std::fmt::Display) -> PyErr {
    BeamtraceError::new_err(e.to_string())
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::from_array(v)
}

/// The terminals Python passes to a load (`tx=`, `rx=`), overriding the scene's.
fn terminals(tx: Option<[f64; 3]>, rx: Option<[f64; 3]>) -> Terminals {
    Terminals {
        tx: tx.map(vec3),
        rx: rx.map(vec3),
    }
}

/// Load any source the CLI reads (`builtin:NAME`, JSON/TOML, OBJ/PLY/STL meshes, glTF, point clouds,
/// Mitsuba XML): the library's one loading entry, through the user's load cache when `cache`
/// (as the CLI's `--cache`); beside the load, the cache's own warnings.
fn load_scene(
    source: &str,
    options: &LoadOptions,
    cache: bool,
) -> Result<(bt_import::Loaded, Vec<String>), bt_import::ImportError> {
    if cache {
        bt_import::cache::LoadCache::user()?.load(source, options, &mut |_| {})
    } else {
        Ok((bt_import::load(source, options)?, Vec::new()))
    }
}

/// A validated scene, ready to trace from any TX to any RX.
#[pyclass(frozen, module = "beamtrace._native", name = "Scene")]
struct PyScene {
    scene: Arc<Scene>,
    /// What `load` was given (file path or `builtin:NAME`): messages name it, as the CLI's do.
    source: String,
    /// How `load` read it: its load options and the carrier it set (`frequency=`), so that a
    /// `Tracer` of this scene reloads the same scene; `None` for an unpickled scene.
    loaded_with: Option<(LoadOptions, Option<f64>)>,
    warnings: Vec<String>,
    /// The load cache's own warnings (a damaged entry replaced), for Python's `warnings`.
    cache_warnings: Vec<String>,
    /// The scene's tracer, kept between calls for its caches (a stream of traces of one
    /// scene reuses the beam tree's hulls and arenas).
    tracer: Mutex<Tracer>,
    /// The column shards of the last `trace_many`, emptied and kept for their memory (up to
    /// [`KEPT_SHARD_BYTES`] each).
    shards: Mutex<Option<columns::Shards>>,
}

/// The most memory a shard of `trace_many`'s columns keeps for the next call: 32 MiB, about
/// 2,000 receivers of the living room at order 3 on one thread.
const KEPT_SHARD_BYTES: usize = 32 << 20;

impl PyScene {
    /// The scene with other terminals (the scene's own where `None`); a terminal neither
    /// given nor in the scene (a mesh, XML or point cloud) is a `ValueError` naming the
    /// Python keyword.
    fn moved(&self, tx: Option<[f64; 3]>, rx: Option<[f64; 3]>) -> PyResult<Scene> {
        let tx = tx.map(vec3).or(self.scene.tx_world());
        let rx = rx.map(vec3).or(self.scene.rx_world());
        let (Some(tx), Some(rx)) = (tx, rx) else {
            let missing: Vec<Terminal> = [(Terminal::Tx, tx), (Terminal::Rx, rx)]
                .into_iter()
                .filter_map(|(t, p)| p.is_none().then_some(t))
                .collect();
            return Err(PyValueError::new_err(Terminal::missing_message(
                &self.source,
                &missing,
                |t| format!("{t}=[x, y, z]"),
            )));
        };
        self.scene
            .with_terminals(tx, rx)
            .map_err(|e| self.error(TraceError::Scene(e)))
    }

    /// The paths from `tx` to `rx` (the scene's own where `None`) traced under `keywords`
    /// without the GIL and reported as `trace --json` reports them, with the scene they were
    /// traced in (`Scene.trace` and `Scene.view`).
    fn reported(
        &self,
        py: Python<'_>,
        tx: Option<[f64; 3]>,
        rx: Option<[f64; 3]>,
        keywords: &TraceKeywords,
    ) -> PyResult<(Scene, Vec<bt_beams::PathReport>)> {
        let scene = self.moved(tx, rx)?;
        let options = keywords
            .trace_options(&scene)
            .map_err(PyValueError::new_err)?;
        let radio = keywords.radio().map_err(PyValueError::new_err)?;
        let ends = scene.terminals().map_err(error)?;
        let (tx, rx) = (scene.to_world(ends.tx), scene.to_world(ends.rx));
        let paths = py.detach(|| {
            let traced = self.with_tracer(scene.clone(), options, |t| t.trace(tx, rx));
            traced.map(|traced| bt_beams::report(&scene, &traced.result.paths, &radio))
        });
        let paths = paths.map_err(|e| self.error(e))?.map_err(error)?;
        Ok((scene, paths))
    }

    /// `f` on the kept tracer, set to `scene` and `options`; a call made while another thread
    /// traces this scene gets a tracer of its own (the same result, without the caches).
    fn with_tracer<R>(
        &self,
        scene: Scene,
        options: TraceOptions,
        f: impl FnOnce(&mut Tracer) -> R,
    ) -> R {
        match self.tracer.try_lock() {
            Ok(mut tracer) => {
                tracer.set_scene(scene);
                tracer.set_options(options);
                f(&mut tracer)
            }
            Err(_) => f(&mut Tracer::new(scene, options)),
        }
    }

    /// A trace error as the exception, naming the scene's source like the CLI (which
    /// validates terminals while loading `SOURCE --tx .. --rx ..`).
    fn error(&self, e: TraceError) -> PyErr {
        error(self.message(e))
    }

    /// The message of a trace error, a scene problem named after this scene's source.
    fn message(&self, e: TraceError) -> String {
        match e {
            TraceError::Scene(SceneError::Invalid { problems, .. }) => SceneError::Invalid {
                source_name: self.source.clone(),
                problems,
            }
            .to_string(),
            e => e.to_string(),
        }
    }
}

#[pymethods]
impl PyScene {
    /// The scene as bytes for [`scene_from_bytes`] (Python's pickling: Ray ships a loaded
    /// scene to its workers this way, no file needed there): postcard of its stored form.
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
        let bytes = postcard::to_allocvec(&self.scene.to_stored()).map_err(error)?;
        Ok(pyo3::types::PyBytes::new(py, &bytes))
    }

    /// Scene name (file stem, or the name inside the scene file).
    #[getter]
    fn name(&self) -> &str {
        self.scene.name()
    }
    /// Transmitter position, metres, world frame; `None` when the scene has none.
    #[getter]
    fn tx(&self) -> Option<[f64; 3]> {
        self.scene.tx_world().map(|p| p.to_array())
    }
    /// Receiver position, metres, world frame; `None` when the scene has none.
    #[getter]
    fn rx(&self) -> Option<[f64; 3]> {
        self.scene.rx_world().map(|p| p.to_array())
    }
    /// What the scene was loaded from (a file path or `builtin:NAME`).
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }
    /// Carrier frequency, Hz.
    #[getter]
    fn frequency_hz(&self) -> f64 {
        self.scene.frequency_hz()
    }
    /// Names of all surfaces (reflectors and blockers), in scene order.
    #[getter]
    fn surface_names(&self) -> Vec<String> {
        self.scene
            .surfaces()
            .iter()
            .map(|s| s.name.clone())
            .collect()
    }
    /// Non-fatal notes of the import (merged faces, unknown materials, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    /// The load cache's warnings of this load (`load cache: FILE: ...`), empty without one.
    #[getter]
    fn cache_warnings(&self) -> Vec<String> {
        self.cache_warnings.clone()
    }

    /// Trace one TX → RX; returns the path columns as a dict (see `beamtrace.Paths`).
    fn trace<'py>(
        &self,
        py: Python<'py>,
        tx: Option<[f64; 3]>,
        rx: Option<[f64; 3]>,
        keywords: TraceKeywords,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (_, paths) = self.reported(py, tx, rx, &keywords)?;
        let batch = py.detach(|| columns::Batch::of(&paths)).map_err(error)?;
        batch.into_dict(py)
    }

    /// The viewer's page (`beamtrace view`: one offline HTML document, three.js inside) of the
    /// scene with the paths traced from `tx` to `rx` under `keywords`; the geometry alone when
    /// a terminal is neither given nor in the scene.
    fn view(
        &self,
        py: Python<'_>,
        tx: Option<[f64; 3]>,
        rx: Option<[f64; 3]>,
        keywords: TraceKeywords,
    ) -> PyResult<String> {
        let placed = tx.is_some() || self.scene.tx().is_some();
        if !placed || (rx.is_none() && self.scene.rx().is_none()) {
            return Ok(bt_view::page(&[&self.scene], &[bt_view::StepPaths::none()]));
        }
        let (scene, paths) = self.reported(py, tx, rx, &keywords)?;
        let step = bt_view::StepPaths::from_reports(&scene, &paths);
        Ok(py.detach(|| bt_view::page(&[&scene], &[step])))
    }

    /// Trace one TX to each row of `receivers` (m × 3, metres) in parallel without the GIL;
    /// returns the columns of all their paths as one flat dict (`columns::Batch`), receivers in
    /// order, a receiver that failed untraced when `skip_errors`.
    fn trace_many<'py>(
        &self,
        py: Python<'py>,
        tx: Option<[f64; 3]>,
        receivers: PyReadonlyArray2<'py, f64>,
        keywords: TraceKeywords,
        skip_errors: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let receivers = receivers_of(&receivers)?;
        if receivers.is_empty() {
            return columns::Batch::new().map_err(error)?.into_dict(py);
        }
        // The scene with the TX and the first receiver it accepts (each receiver gets its own
        // outcome below); when it accepts none, the first one's error.
        let placed = |r: &Vec3| self.moved(tx, Some(r.to_array()));
        let scene = match receivers.iter().find_map(|r| placed(r).ok()) {
            Some(scene) => scene,
            None => {
                return Err(match placed(&receivers[0]) {
                    Err(e) => e,
                    Ok(_) => error("no receiver could be placed in the scene"),
                });
            }
        };
        let options = keywords
            .trace_options(&scene)
            .map_err(PyValueError::new_err)?;
        let radio = keywords.radio().map_err(PyValueError::new_err)?;
        let tx = scene.to_world(scene.terminals().map_err(error)?.tx);
        let reports = py.detach(|| {
            // Each receiver reported, and its columns appended to its thread's shard, in the
            // task that traced it (in parallel when asked); the shards are gathered in
            // receiver order, and only the arrays are made under the GIL.
            // The last call's shards (emptied), unless another thread holds them.
            let kept = self.shards.try_lock().ok().and_then(|mut kept| kept.take());
            let mut shards = match kept {
                Some(kept) => kept,
                None => columns::Shards::new().map_err(|e| (None, Failure::Report(e)))?,
            };
            let report = |moved: &Scene, t: Traced| {
                REPORTS.with_borrow_mut(|records| {
                    let paths = records.report(moved, &t.result.paths, &radio);
                    shards.push(paths.map_err(|e| e.to_string())?)
                })
            };
            let reported = self
                .with_tracer(scene.clone(), options, |t| {
                    t.trace_each_then(tx, &receivers, report)
                })
                .map_err(|e| (None, Failure::Trace(e)))?;
            let rows = first_failure(reported, skip_errors)?;
            let gathered = shards.gather(&rows, options.parallel);
            // Kept emptied, and only up to the bound, so that a large call's memory goes now.
            if let (Ok(()), Ok(mut kept)) = (shards.clear(KEPT_SHARD_BYTES), self.shards.try_lock())
            {
                *kept = Some(shards);
            }
            gathered.map_err(|e| (None, Failure::Report(e)))
        });
        let reports = reports.map_err(|(index, e)| {
            let at = |message: String| match index {
                Some(i) => format!("receiver {i} {:?}: {message}", receivers[i].to_array()),
                None => message,
            };
            match e {
                Failure::Trace(e) => error(at(self.message(e))),
                Failure::Report(message) => error(at(format!("{}: {message}", scene.name()))),
            }
        })?;
        reports.into_dict(py)
    }
}

thread_local! {
    /// The path records of the last receiver `trace_many` reported on this thread, whose
    /// memory the next receiver's reuse (their columns are copied out in the same task).
    static REPORTS: std::cell::RefCell<bt_beams::Records> = std::cell::RefCell::default();
}

/// The rows of an (m, 3) array as points.
fn receivers_of(array: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Vec3>> {
    let view = array.as_array();
    if view.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "receivers must have shape (m, 3), got {:?}",
            view.shape()
        )));
    }
    Ok(view
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect())
}

/// Why a many-receiver trace or a receiver's report failed: the trace, or a receiver's report (its
/// message).
enum Failure {
    Trace(TraceError),
    Report(String),
}

/// Where one receiver's paths are among the columns of its thread's shard.
type Report = columns::Rows;

/// Why a many-receiver call failed: the receiver's index (none: the call as a whole).
type Failed = (Option<usize>, Failure);

/// Each receiver's report, in order: a receiver that could not be traced is `None` when
/// `skip_errors`, else the first such (in receiver order, whichever failed first in time)
/// fails the call with its index, as does the first report that failed.
fn first_failure(
    reported: Vec<Result<Result<Report, String>, TraceError>>,
    skip_errors: bool,
) -> Result<Vec<Option<Report>>, Failed> {
    (reported.into_iter().enumerate())
        .map(|(i, outcome)| match outcome {
            Ok(Ok(report)) => Ok(Some(report)),
            Ok(Err(message)) => Err((Some(i), Failure::Report(message))),
            Err(_) if skip_errors => Ok(None),
            Err(e) => Err((Some(i), Failure::Trace(e))),
        })
        .collect()
}

/// Load a scene; `tx`/`rx` override the file's (meshes, XML and point clouds carry none: then
/// each trace gives them).
#[pyfunction]
#[pyo3(signature = (source, *, tx=None, rx=None, min_reflector_area=0.25, merge_angle_deg=1.0,
                    merge_distance=1e-3, budgets=None, cache=false, frequency=None,
                    material=None, thickness=None))]
// One argument per Python keyword: pyo3 maps them by name.
#[allow(clippy::too_many_arguments)]
fn load(
    py: Python<'_>,
    source: String,
    tx: Option<[f64; 3]>,
    rx: Option<[f64; 3]>,
    min_reflector_area: f64,
    merge_angle_deg: f64,
    merge_distance: f64,
    budgets: Option<options::LoadBudgets>,
    cache: bool,
    frequency: Option<f64>,
    material: Option<String>,
    thickness: Option<f64>,
) -> PyResult<PyScene> {
    let defaults = LoadOptions::default();
    let radio = options::radio_material(material.as_deref(), thickness)?;
    let budgets = budgets.unwrap_or(options::LoadBudgets {
        max_file_bytes: defaults.max_file_bytes,
        max_xml_substitution: defaults.max_xml_substitution,
        max_mesh_elements: defaults.merge.max_elements,
        max_cloud_points: defaults.cloud.max_points,
    });
    let options = LoadOptions {
        terminals: terminals(tx, rx),
        merge: bt_mesh::MergeOptions {
            angle_tol_deg: merge_angle_deg,
            dist_tol_m: merge_distance,
            max_elements: budgets.max_mesh_elements,
            ..bt_mesh::MergeOptions::default()
        },
        min_reflector_area_m2: min_reflector_area,
        // As the CLI: a cloud's points and its file are budgeted like every other input.
        cloud: bt_import::cloud::ReadOptions {
            max_points: budgets.max_cloud_points,
            max_file_bytes: budgets.max_file_bytes,
            ..defaults.cloud
        },
        max_file_bytes: budgets.max_file_bytes,
        max_xml_substitution: budgets.max_xml_substitution,
        frequency_hz: frequency.unwrap_or(bt_scene::DEFAULT_FREQUENCY_HZ),
        // Used only without `material` (whose slab it is then, in `radio`).
        thickness,
        radio,
        ..defaults
    };
    let (mut loaded, cache_warnings) = py
        .detach(|| load_scene(&source, &options, cache))
        .map_err(error)?;
    // As the CLI's `--frequency`: scene files and built-ins carry their own carrier, replaced.
    if let Some(f) = frequency {
        loaded.scene = loaded.scene.with_frequency(f).map_err(error)?;
    }
    // The options are set by each trace (its keywords).
    let tracer = Tracer::new(loaded.scene.clone(), TraceOptions::new(0));
    Ok(PyScene {
        tracer: Mutex::new(tracer),
        shards: Mutex::default(),
        scene: Arc::new(loaded.scene),
        source,
        loaded_with: Some((options, frequency)),
        warnings: loaded.warnings,
        cache_warnings,
    })
}

/// The scene `data` ([`PyScene::to_bytes`]) holds, named `source` in messages: every polygon
/// rebuilt and checked ([`Scene::from_stored`]); bytes that are not such a scene are a
/// `BeamtraceError` naming `source`.
#[pyfunction]
fn scene_from_bytes(source: String, data: &[u8]) -> PyResult<PyScene> {
    let stored: bt_scene::StoredScene = postcard::from_bytes(data)
        .map_err(|e| error(format!("{source}: not a pickled beamtrace scene: {e}")))?;
    let scene = Scene::from_stored(stored, &source).map_err(error)?;
    let tracer = Tracer::new(scene.clone(), TraceOptions::new(0));
    Ok(PyScene {
        tracer: Mutex::new(tracer),
        shards: Mutex::default(),
        scene: Arc::new(scene),
        source,
        loaded_with: None,
        warnings: Vec::new(),
        cache_warnings: Vec::new(),
    })
}

/// Names of the built-in scenes (`load("builtin:NAME")`).
#[pyfunction]
fn builtin_names() -> Vec<&'static str> {
    bt_import::builtin_names().to_vec()
}

/// The CLI's `study beam-management` with its defaults but for the arguments given: run the
/// study over `scenarios` (`living-room`, `city` or scene files; default both built-ins),
/// write its files into `out` and return `summary.json`'s text. Bad settings raise
/// `ValueError` naming the CLI's option; a scene or output problem `BeamtraceError`.
#[pyfunction]
#[pyo3(signature = (out, *, scenarios=None, seed=1, positions=1000, scan_density=2000.0))]
fn study_beam_management(
    py: Python<'_>,
    out: std::path::PathBuf,
    scenarios: Option<Vec<String>>,
    seed: u64,
    positions: usize,
    scan_density: f64,
) -> PyResult<String> {
    use bt_study::beam_management::{self as study, BeamManagementConfig, scenario};
    let defaults = BeamManagementConfig::default();
    let config = BeamManagementConfig {
        positions,
        seed,
        scan: scenario::ScanSettings {
            density_per_m2: scan_density,
            seed,
            ..defaults.scan
        },
        ..defaults
    };
    let problems = config.problems();
    if !problems.is_empty() {
        return Err(PyValueError::new_err(problems.join("; ")));
    }
    let names = scenarios.unwrap_or_else(|| vec!["living-room".into(), "city".into()]);
    py.detach(|| {
        let (mut built, mut inputs) = (Vec::new(), Vec::new());
        for name in &names {
            let source = scenario::source_of(name);
            let loaded = bt_import::load_dynamic(source, &LoadOptions::default(), &mut |_| {})
                .map_err(|e| error(format!("scenario {name}: {e}")))?;
            let s = scenario::Scenario::named(name, loaded.scene, positions, &config.scan)
                .map_err(|e| error(format!("scenario {name}: {e}")))?;
            built.push(s);
            inputs.extend(loaded.sources);
        }
        let results = study::run(&built, &config, &mut |_, _| {}).map_err(error)?;
        bt_study::io::write_beam_management(&out, &results, &inputs).map_err(error)?;
        serde_json::to_string(&study::report::summary(&results)).map_err(error)
    })
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("BeamtraceError", m.py().get_type::<BeamtraceError>())?;
    m.add("PATH_COLUMNS", columns::names()?)?;
    m.add("PER_INTERACTION_COLUMNS", columns::per_interaction()?)?;
    m.add("OPTIONAL_PATH_COLUMNS", columns::optional()?)?;
    m.add("TEXT_COLUMNS", columns::texts()?)?;
    m.add(
        "DEFAULT_MAX_CANDIDATES",
        bt_solve::pipeline::DEFAULT_MAX_CANDIDATES,
    )?;
    m.add(
        "DEFAULT_MAX_WVRN_TESTS",
        bt_solve::pipeline::DEFAULT_MAX_WVRN_TESTS,
    )?;
    m.add("DEFAULT_MAX_FILE_BYTES", bt_import::MAX_FILE_BYTES.limit)?;
    m.add(
        "DEFAULT_IPC_MAX_ITERATIONS",
        bt_solve::ipc::DEFAULT_MAX_ITERATIONS,
    )?;
    m.add("DEFAULT_MAX_RAYS", bt_solve::sbr::DEFAULT_MAX_RAYS)?;
    m.add(
        "DEFAULT_MAX_XML_SUBSTITUTION",
        bt_import::xml::MAX_XML_SUBSTITUTION.limit,
    )?;
    m.add("DEFAULT_MAX_MESH_ELEMENTS", bt_mesh::DEFAULT_MAX_ELEMENTS)?;
    m.add(
        "DEFAULT_MAX_CLOUD_POINTS",
        bt_import::cloud::DEFAULT_MAX_POINTS,
    )?;
    m.add("DEFAULT_MAX_BEAM_PAIRS", bt_channel::MAX_BEAM_PAIRS.limit)?;
    m.add("PARTNER_SPIN_US", bt_serve::PARTNER_SPIN_US)?;
    m.add_class::<PyScene>()?;
    m.add_class::<tracer::PyTracer>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_names, m)?)?;
    m.add_function(wrap_pyfunction!(scene_from_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(study_beam_management, m)?)?;
    Ok(())
}
