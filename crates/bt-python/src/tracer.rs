//! `beamtrace.Tracer`: the loop of `beamtrace serve` in Python. One `bt_serve::Server` (one
//! long-lived `Tracer`) per object; each update is one request line of the serve protocol,
//! answered by the same code, so Python gets exactly what `serve` prints (`docs/serve.md`).

use crate::options::TraceKeywords;
use crate::{error, terminals};
use bt_import::LoadOptions;
use bt_serve::{Limits, Server};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Mutex;

/// `source` loaded with its time steps and objects, as `load` read it when `loaded_with`
/// (its options and `frequency=`) is given, with `tx`/`rx` overriding its terminals.
fn reload(
    py: Python<'_>,
    source: &str,
    loaded_with: Option<(LoadOptions, Option<f64>)>,
    (tx, rx): (Option<[f64; 3]>, Option<[f64; 3]>),
) -> PyResult<bt_scene::dynamic::DynamicScene> {
    let (loaded_with, frequency) = loaded_with.unwrap_or_default();
    let options = LoadOptions {
        terminals: terminals(tx, rx),
        ..loaded_with
    };
    let loaded = py.detach(|| bt_import::load_dynamic(source, &options, &mut |_| {}));
    let dynamic = loaded.map_err(error)?.scene;
    // As `load(frequency=)`: the carrier replaces a scene file's own.
    match frequency {
        Some(f) => dynamic.with_frequency(f).map_err(error),
        None => Ok(dynamic),
    }
}

/// An unpickled `scene` (its load options are not in the pickle) as the tracer's scene, with
/// `tx`/`rx` overriding its terminals: the scene itself, which a reload of its source with
/// default options need not equal. `None` (reload it) for a scene loaded in this process, or
/// when a terminal is neither given nor in the scene (a bare mesh moved by updates).
fn unpickled(
    scene: &crate::PyScene,
    tx: Option<[f64; 3]>,
    rx: Option<[f64; 3]>,
) -> Option<PyResult<bt_scene::Scene>> {
    if scene.loaded_with.is_some() {
        return None;
    }
    if tx.is_none() && rx.is_none() {
        return Some(Ok((*scene.scene).clone()));
    }
    let has =
        |given: Option<[f64; 3]>, own: Option<bt_scene::Vec3>| given.is_some() || own.is_some();
    (has(tx, scene.scene.tx_world()) && has(rx, scene.scene.rx_world()))
        .then(|| scene.moved(tx, rx))
}

/// A scene kept loaded with one tracer, answering the requests of `beamtrace serve`.
#[pyclass(frozen, module = "beamtrace._native", name = "Tracer")]
pub struct PyTracer {
    server: Mutex<Server>,
}

#[pymethods]
impl PyTracer {
    /// Load `source` with its time steps and objects (`builtin:NAME` or a file), `tx`/`rx`
    /// overriding its terminals, and trace under `keywords` (the trace keywords of
    /// `Scene.trace`). With `scene` (the `Scene` that `load` read from `source`), the load
    /// takes the same options (mesh, radio material, thickness, carrier) as it did.
    #[new]
    #[pyo3(signature = (source, keywords, tx, rx, beams=None, partner_spin_us=bt_serve::PARTNER_SPIN_US, scene=None))]
    // One argument per Python keyword: pyo3 maps them by name.
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        source: String,
        keywords: TraceKeywords,
        tx: Option<[f64; 3]>,
        rx: Option<[f64; 3]>,
        beams: Option<BeamKeywords>,
        partner_spin_us: u64,
        scene: Option<PyRef<'_, crate::PyScene>>,
    ) -> PyResult<Self> {
        let dynamic = match scene.as_deref().and_then(|s| unpickled(s, tx, rx)) {
            Some(scene) => bt_scene::dynamic::DynamicScene::from_static(scene?),
            None => reload(
                py,
                &source,
                scene.and_then(|s| s.loaded_with.clone()),
                (tx, rx),
            )?,
        };
        let trace_options = keywords
            .trace_options(dynamic.step(0))
            .map_err(PyValueError::new_err)?;
        let radio = keywords.radio().map_err(PyValueError::new_err)?;
        let spin = std::time::Duration::from_micros(partner_spin_us);
        let mut server =
            Server::new(dynamic, trace_options, radio, Limits::default()).with_partner(spin);
        if let Some(beams) = beams {
            server = server.with_beams(beams.options(&radio)?);
        }
        Ok(PyTracer {
            server: Mutex::new(server),
        })
    }

    /// Answer one request line of the serve protocol (JSON) with its answer line (JSON),
    /// without the GIL; an error answer is `{"id", "error"}`, as `serve` prints it.
    fn answer(&self, py: Python<'_>, line: &str) -> PyResult<String> {
        py.detach(|| {
            let mut server = self.server.lock().map_err(|_| {
                error("the tracer was poisoned by a panic in another thread; make a new one")
            })?;
            let mut out = Vec::new();
            server.answer_line(line.as_bytes(), &mut out);
            String::from_utf8(out).map_err(error)
        })
    }
}

/// `Tracer`'s beam keywords, `serve`'s flags by the same names: `tx_array`/`rx_array` as
/// (rows, columns) (one given: the other 1 × 8), `tx_spacing`/`rx_spacing` in wavelengths,
/// `ranking` (`power` or `paper`), `top` and `max_beam_pairs`.
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct BeamKeywords {
    tx_array: Option<(usize, usize)>,
    rx_array: Option<(usize, usize)>,
    tx_spacing: f64,
    rx_spacing: f64,
    ranking: String,
    top: usize,
    max_beam_pairs: u64,
}

impl BeamKeywords {
    /// The server's beam options; a bad value is a `ValueError` naming its keyword.
    fn options(&self, radio: &bt_beams::RadioOptions) -> PyResult<bt_serve::BeamOptions> {
        let ranking = match self.ranking.as_str() {
            "power" => bt_beams::BeamRanking::Power,
            "paper" => bt_beams::BeamRanking::Paper,
            other => {
                return Err(PyValueError::new_err(format!(
                    "ranking must be one of \"power\", \"paper\", got {}",
                    bt_scene::name::shown(other)
                )));
            }
        };
        let arrays = [
            (self.tx_array, self.tx_spacing),
            (self.rx_array, self.rx_spacing),
        ];
        bt_serve::BeamOptions::new(arrays, radio, ranking, (self.top, self.max_beam_pairs))
            .map_err(|(which, e)| PyValueError::new_err(format!("{which}: {e}")))
    }
}
