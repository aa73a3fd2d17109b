//! Python keyword arguments → the library's trace options, with the CLI's names and checks.

use bt_scene::Scene;
use bt_solve::pipeline::TraceOptions;
use bt_solve::settings::{IpcSettings, SbrSettings, SolveSettings, parse};

/// The trace keywords of `Scene.trace` / `Scene.trace_many` (names and values as the CLI's
/// `beamtrace trace` flags, e.g. `solver="ipc"`, `candidates="beam-tree"`), passed from the
/// Python wrappers as one dict with every key, IPC's and SBR's in their own dicts.
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct TraceKeywords {
    /// Highest reflection order.
    pub max_order: usize,
    /// Path solver: `image`, `ipc` or `sbr`.
    pub solver: String,
    /// Candidate generator: `beam-tree`, `wvrn` or `exhaustive`.
    pub candidates: String,
    /// Budget on candidates (beam-tree nodes).
    pub max_candidates: u64,
    /// Budget on the WVRN's pair tests (`candidates="wvrn"`).
    pub max_wvrn_tests: u64,
    /// Solve on every core (the output is identical either way).
    pub parallel: bool,
    /// Thin-slab transmission through every slab reflector (`--transmission`).
    pub transmission: bool,
    /// `ipc_order` and `ipc_accel`.
    pub ipc: IpcKeywords,
    /// `sbr_step_deg`, `sbr_rays` and `sbr_planar`.
    pub sbr: SbrKeywords,
    /// `diffraction`/`max_diffractions` and `min_edge_length`.
    pub diffraction: DiffractionKeywords,
    /// The antennas and the transmitted power.
    pub antennas: AntennaKeywords,
}

/// The antennas at both ends and the transmitted power (`tx_pattern`, `rx_pattern`,
/// `tx_polarization`, `rx_polarization`, `tx_orientation`, `rx_orientation`, `tx_power_dbm` in
/// Python; the CLI's flags of those names, spelled as there).
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct AntennaKeywords {
    /// `iso` or `tr38901`, each end.
    pub tx_pattern: String,
    pub rx_pattern: String,
    /// `V`, `H`, `+45` or `-45`, each end.
    pub tx_polarization: String,
    pub rx_polarization: String,
    /// Yaw, pitch, roll, degrees, each end.
    pub tx_orientation: [f64; 3],
    pub rx_orientation: [f64; 3],
    /// Transmitted power, dBm.
    pub tx_power_dbm: f64,
}

/// The CLI's bound on `--tx-power-dbm`, dBm either way.
const MAX_POWER_DBM: f64 = 300.0;

impl AntennaKeywords {
    /// The antennas (TX, RX) and the power, each value checked as the CLI checks it.
    fn antennas(&self) -> Result<(bt_beams::Antenna, bt_beams::Antenna, f64), String> {
        let end = |name: &str, pattern: &str, polarization: &str, o: [f64; 3]| {
            let pattern = pattern
                .parse()
                .map_err(|e: bt_beams::ChannelError| format!("{name}_pattern: {e}"))?;
            let polarization = (polarization.parse())
                .map_err(|e: bt_beams::ChannelError| format!("{name}_polarization: {e}"))?;
            if o.iter().any(|v| !v.is_finite()) {
                return Err(format!(
                    "{name}_orientation must be three finite angles in degrees, got {o:?}"
                ));
            }
            let orientation = bt_beams::Orientation::from_degrees(o[0], o[1], o[2]);
            Ok(bt_beams::Antenna::new(pattern, polarization, orientation))
        };
        let tx = end(
            "tx",
            &self.tx_pattern,
            &self.tx_polarization,
            self.tx_orientation,
        )?;
        let rx = end(
            "rx",
            &self.rx_pattern,
            &self.rx_polarization,
            self.rx_orientation,
        )?;
        let p = self.tx_power_dbm;
        if !(p.is_finite() && p.abs() <= MAX_POWER_DBM) {
            return Err(format!(
                "tx_power_dbm must be a finite power within ±{MAX_POWER_DBM} dBm, got {p}"
            ));
        }
        Ok((tx, rx, p))
    }
}

/// The load budgets of `load` (`max_file_bytes`, `max_xml_substitution`, `max_mesh_elements`
/// in Python; the CLI's `--max-file-bytes`, `--max-xml-substitution`, `--max-mesh-elements`),
/// passed from the Python wrapper as one dict.
#[derive(Debug, Clone, Copy, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct LoadBudgets {
    /// Largest input file, bytes.
    pub max_file_bytes: u64,
    /// Bytes an XML scene's `$parameter` substitutions may produce.
    pub max_xml_substitution: u64,
    /// Vertices and faces of a mesh file, and of all meshes of an XML scene.
    pub max_mesh_elements: u64,
    /// Points a point-cloud file declares.
    pub max_cloud_points: u64,
}

/// `load`'s `material=` and `thickness=` (the CLI's `--material`, `--thickness`): the radio
/// material of every surface, or none; a `thickness=` alone is left to
/// [`bt_import::LoadOptions::thickness`] (every half-space material's slab thickness), checked here as
/// the CLI checks it.
pub fn radio_material(
    material: Option<&str>,
    thickness: Option<f64>,
) -> pyo3::PyResult<Option<bt_beams::RadioMaterial>> {
    let value_error = |e: String| pyo3::exceptions::PyValueError::new_err(e);
    match (material, thickness) {
        (None, None) => Ok(None),
        (None, Some(t)) if !(t.is_finite() && t >= 0.0) => Err(value_error(format!(
            "thickness= must be a finite number of metres >= 0, got {t}"
        ))),
        (None, Some(_)) => Ok(None),
        (Some(spec), thickness) => bt_beams::RadioMaterial::from_spec(spec, thickness)
            .map(Some)
            .map_err(|e| value_error(e.to_string())),
    }
}

/// Diffraction's keywords (`diffraction=True` is `max_diffractions=1` in Python).
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct DiffractionKeywords {
    /// Diffractions per path (0, 1 or 2).
    pub max_diffractions: usize,
    /// Edges shorter than this (metres) do not diffract.
    pub min_edge_length: f64,
    /// The diffraction coefficient of the gains: `utd` or `sionna-rt-2.2`
    /// (`diffraction_coefficient` in Python).
    pub coefficient: String,
}

/// IPC's keywords (`ipc_order`, `ipc_accel` in Python).
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct IpcKeywords {
    /// Update order: `gauss-seidel` or `jacobi`.
    pub order: String,
    /// Acceleration: `none` or `newton`.
    pub accel: String,
    /// Stopping threshold, metres (`None`: scaled to the scene), `ipc_threshold` in Python.
    pub threshold: Option<f64>,
    /// Round cap, `ipc_max_iterations` in Python.
    pub max_iterations: u32,
}

/// SBR's keywords (`sbr_step_deg`, `sbr_rays`, `sbr_planar` in Python).
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct SbrKeywords {
    /// Grid step, degrees (`None`: 1°, unless `rays`).
    pub step_deg: Option<f64>,
    /// Rays on a Fibonacci sphere instead of a grid.
    pub rays: Option<u32>,
    /// Launch only in the horizontal plane through TX.
    pub planar: bool,
    /// Budget on the launched rays, `max_rays` in Python.
    pub max_rays: u64,
}

impl TraceKeywords {
    /// The library's settings these keywords name (every one of the CLI's trace settings).
    pub fn settings(&self) -> Result<SolveSettings, String> {
        let named = || -> Result<SolveSettings, bt_solve::settings::SettingsError> {
            Ok(SolveSettings {
                max_order: self.max_order,
                solver: parse(&self.solver)?,
                ipc: IpcSettings {
                    order: parse(&self.ipc.order)?,
                    acceleration: parse(&self.ipc.accel)?,
                    threshold: self.ipc.threshold,
                    max_iterations: self.ipc.max_iterations,
                },
                sbr: SbrSettings {
                    step_deg: self.sbr.step_deg,
                    rays: self.sbr.rays,
                    planar: self.sbr.planar,
                    max_rays: self.sbr.max_rays,
                },
                candidates: parse(&self.candidates)?,
                max_candidates: self.max_candidates,
                max_wvrn_tests: self.max_wvrn_tests,
                parallel: self.parallel,
                transmission: self.transmission,
                diffraction: bt_solve::pipeline::DiffractionOptions {
                    max_diffractions: self.diffraction.max_diffractions,
                    min_edge_length: self.diffraction.min_edge_length,
                },
            })
        };
        named().map_err(|e| e.to_string())
    }

    /// The report's radio options: the CLI's defaults with the diffraction coefficient named
    /// (an unknown name refused as the settings' are, the value cut short).
    pub fn radio(&self) -> Result<bt_beams::RadioOptions, String> {
        let coefficient = parse(&self.diffraction.coefficient).map_err(|e| e.to_string())?;
        let (tx, rx, tx_power_dbm) = self.antennas.antennas()?;
        let radio = bt_beams::RadioOptions {
            tx,
            rx,
            tx_power_dbm,
            diffraction_coefficient: coefficient,
            ..bt_beams::RadioOptions::default()
        };
        Ok(radio.for_order(self.max_order))
    }

    /// The pipeline options for `scene`.
    pub fn trace_options(&self, scene: &Scene) -> Result<TraceOptions, String> {
        self.settings()?
            .trace_options(scene)
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_solve::pipeline::CandidateMode;
    use bt_solve::{Solver, UpdateOrder};

    fn keywords() -> TraceKeywords {
        TraceKeywords {
            max_order: 2,
            solver: "image".into(),
            candidates: "beam-tree".into(),
            max_candidates: 10,
            max_wvrn_tests: 10,
            parallel: true,
            transmission: false,
            ipc: IpcKeywords {
                order: "gauss-seidel".into(),
                accel: "none".into(),
                threshold: None,
                max_iterations: 256,
            },
            sbr: SbrKeywords {
                step_deg: None,
                rays: None,
                planar: false,
                max_rays: 1_000_000,
            },
            diffraction: DiffractionKeywords {
                max_diffractions: 0,
                min_edge_length: 0.0,
                coefficient: "utd".into(),
            },
            antennas: AntennaKeywords {
                tx_pattern: "iso".into(),
                rx_pattern: "iso".into(),
                tx_polarization: "V".into(),
                rx_polarization: "V".into(),
                tx_orientation: [0.0; 3],
                rx_orientation: [0.0; 3],
                tx_power_dbm: 0.0,
            },
        }
    }

    fn scene() -> Scene {
        bt_import::builtin_scene("living-room", Default::default())
            .unwrap()
            .unwrap()
    }

    #[test]
    fn names_map_to_the_cli_meanings() {
        let k = TraceKeywords {
            solver: "ipc".into(),
            candidates: "wvrn".into(),
            ipc: IpcKeywords {
                order: "jacobi".into(),
                accel: "none".into(),
                threshold: None,
                max_iterations: 256,
            },
            ..keywords()
        };
        let o = k.trace_options(&scene()).unwrap();
        assert_eq!(o.candidates, CandidateMode::Wvrn);
        assert!(matches!(o.solver, Solver::Ipc(i) if i.order == UpdateOrder::Jacobi));
        assert_eq!((o.max_order, o.max_candidates), (2, 10));
    }

    #[test]
    fn bad_names_list_the_choices() {
        let k = TraceKeywords {
            solver: "magic".into(),
            ..keywords()
        };
        let e = k.trace_options(&scene()).unwrap_err();
        assert_eq!(
            e,
            "solver must be one of \"image\", \"ipc\", \"sbr\", got \"magic\""
        );
        let k = TraceKeywords {
            solver: "sbr".into(),
            sbr: SbrKeywords {
                step_deg: Some(-1.0),
                rays: None,
                planar: false,
                max_rays: 1_000_000,
            },
            ..keywords()
        };
        assert!(k.trace_options(&scene()).unwrap_err().contains("sbr step"));
    }

    /// A 10 kB value of a keyword makes a message of a few lines naming the keyword, as the
    /// CLI's (`bt_scene::name::shown`), not 10 kB of exception text.
    #[test]
    fn long_bad_values_are_cut_in_the_message() {
        let long = "z".repeat(10_000);
        let cut = format!("got \"{}…(10000 bytes)\"", "z".repeat(64));
        let mut k = keywords();
        k.ipc.order = long.clone();
        let e = k.trace_options(&scene()).unwrap_err();
        assert!(
            e.starts_with("ipc_order must be one of") && e.ends_with(&cut),
            "{e}"
        );
        assert!(e.len() < 200, "{} bytes", e.len());
        let mut k = keywords();
        k.diffraction.coefficient = long;
        let e = k.radio().unwrap_err();
        assert!(
            e.starts_with("diffraction_coefficient must be one of"),
            "{e}"
        );
        assert!(e.ends_with(&cut) && e.len() < 200, "{e}");
    }
}
