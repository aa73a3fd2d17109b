//! Python keyword arguments → the library's trace options, with the CLI's names and checks.

use bt_scene::Scene;
use bt_solve::pipeline::{CandidateMode, TraceOptions};
use bt_solve::{Acceleration, IpcOptions, SbrOptions, Solver, UpdateOrder};

/// The trace keywords of `Scene.trace` / `Scene.trace_many` (names and values as the CLI's
/// `beamtrace trace` flags, e.g. `solver="ipc"`, `candidates="beam-tree"`), passed from the
/// Python wrappers as one dict with every key.
#[derive(Debug, Clone, pyo3::FromPyObject)]
#[pyo3(from_item_all)]
pub struct TraceKeywords {
    pub max_order: usize,
    pub solver: String,
    pub candidates: String,
    pub max_candidates: u64,
    pub ipc_order: String,
    pub ipc_accel: String,
    pub sbr_step_deg: Option<f64>,
    pub sbr_rays: Option<u32>,
    pub sbr_planar: bool,
    pub parallel: bool,
}

/// Pick `value` from `choices` (name, meaning) or say which names are allowed.
fn choose<T: Copy>(field: &str, value: &str, choices: &[(&str, T)]) -> Result<T, String> {
    choices
        .iter()
        .find(|(name, _)| *name == value)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<_> = choices.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            format!("{field} must be one of {}, got {value:?}", names.join(", "))
        })
}

impl TraceKeywords {
    /// The solver these keywords select, with defaults scaled to `scene` (as the CLI does).
    pub fn solver(&self, scene: &Scene) -> Result<Solver, String> {
        let kind = choose(
            "solver",
            &self.solver,
            &[("image", 0), ("ipc", 1), ("sbr", 2)],
        )?;
        Ok(match kind {
            0 => Solver::Image,
            1 => {
                let order = choose(
                    "ipc_order",
                    &self.ipc_order,
                    &[
                        ("gauss-seidel", UpdateOrder::GaussSeidel),
                        ("jacobi", UpdateOrder::Jacobi),
                    ],
                )?;
                let acceleration = choose(
                    "ipc_accel",
                    &self.ipc_accel,
                    &[
                        ("none", Acceleration::None),
                        ("newton", Acceleration::Newton),
                    ],
                )?;
                Solver::Ipc(IpcOptions {
                    acceleration,
                    ..IpcOptions::for_scene(scene, order)
                })
            }
            _ => {
                if self.sbr_step_deg.is_some() && self.sbr_rays.is_some() {
                    return Err("give sbr_step_deg or sbr_rays, not both".into());
                }
                Solver::Sbr(SbrOptions::chosen(
                    self.sbr_rays,
                    self.sbr_step_deg,
                    self.sbr_planar,
                )?)
            }
        })
    }

    /// The pipeline options for `scene`.
    pub fn trace_options(&self, scene: &Scene) -> Result<TraceOptions, String> {
        let candidates = choose(
            "candidates",
            &self.candidates,
            &[
                ("beam-tree", CandidateMode::BeamTree),
                ("wvrn", CandidateMode::Wvrn),
                ("exhaustive", CandidateMode::Exhaustive),
            ],
        )?;
        Ok(TraceOptions {
            max_order: self.max_order,
            solver: self.solver(scene)?,
            candidates,
            parallel: self.parallel,
            max_candidates: self.max_candidates,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keywords() -> TraceKeywords {
        TraceKeywords {
            max_order: 2,
            solver: "image".into(),
            candidates: "beam-tree".into(),
            max_candidates: 10,
            ipc_order: "gauss-seidel".into(),
            ipc_accel: "none".into(),
            sbr_step_deg: None,
            sbr_rays: None,
            sbr_planar: false,
            parallel: true,
        }
    }

    fn scene() -> Scene {
        bt_scene::builtin_scene("living-room", Default::default())
            .unwrap()
            .unwrap()
    }

    #[test]
    fn names_map_to_the_cli_meanings() {
        let k = TraceKeywords {
            solver: "ipc".into(),
            ipc_order: "jacobi".into(),
            candidates: "wvrn".into(),
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
            sbr_step_deg: Some(-1.0),
            ..keywords()
        };
        assert!(k.trace_options(&scene()).unwrap_err().contains("sbr step"));
    }
}
