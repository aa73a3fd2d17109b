//! A trace's settings as a user gives them (the CLI's flags, Python's keywords), by name, and
//! the one place they become [`TraceOptions`] for a scene.
//!
//! The names (`image`, `gauss-seidel`, `beam-tree`, ...) are the CLI's; [`parse`] reads them
//! for every front end, and [`SolveSettings::trace_options`] checks the values and scales the
//! IPC defaults to the scene, so the CLI and the Python package cannot drift apart.

use crate::pipeline::{CandidateMode, DEFAULT_MAX_CANDIDATES, DiffractionOptions, TraceOptions};
use crate::{Acceleration, IpcOptions, SbrOptions, Solver, UpdateOrder};
use bt_geom::Real;
use bt_scene::Scene;

/// Which solver, by name (its options are in [`IpcSettings`] and [`SbrSettings`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolverKind {
    /// The image method (`image`).
    #[default]
    Image,
    /// Iterative path convergence (`ipc`).
    Ipc,
    /// Shooting and bouncing rays (`sbr`).
    Sbr,
}

/// IPC's settings (used when the solver is [`SolverKind::Ipc`]); defaults in
/// [`SolveSettings::default`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IpcSettings {
    /// Update order of a round.
    pub order: UpdateOrder,
    /// What follows the paper's rounds.
    pub acceleration: Acceleration,
    /// Stopping threshold on the mean displacement of a round, metres (`None`: scaled to the
    /// scene by [`IpcOptions::for_scene`]).
    pub threshold: Option<Real>,
    /// Round cap.
    pub max_iterations: u32,
}

/// SBR's settings (used when the solver is [`SolverKind::Sbr`]); see [`SbrOptions::chosen`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SbrSettings {
    /// Azimuth × elevation grid step, degrees (`None`: 1°, unless `rays` is given).
    pub step_deg: Option<Real>,
    /// Rays on a Fibonacci sphere instead of a grid.
    pub rays: Option<u32>,
    /// Launch only in the horizontal plane through TX.
    pub planar: bool,
    /// Budget: refuse a launch pattern of more rays than this.
    pub max_rays: u64,
}

/// Everything that decides how a scene is traced, before it is scaled to the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveSettings {
    /// Highest reflection order.
    pub max_order: usize,
    /// Path solver.
    pub solver: SolverKind,
    /// IPC's settings.
    pub ipc: IpcSettings,
    /// SBR's settings.
    pub sbr: SbrSettings,
    /// Candidate generator.
    pub candidates: CandidateMode,
    /// Budget on candidates (beam-tree nodes).
    pub max_candidates: u64,
    /// Budget on the WVRN's pair tests (`--max-wvrn-tests`).
    pub max_wvrn_tests: u64,
    /// Spread the work over every core (output identical either way).
    pub parallel: bool,
    /// Edge diffraction (`--diffraction`, `--max-diffractions`, `--min-edge-length`).
    pub diffraction: DiffractionOptions,
    /// Thin-slab transmission through every reflector whose material is a slab
    /// (`--transmission`; [`TraceOptions::transmission`]).
    pub transmission: bool,
}

impl Default for SolveSettings {
    /// The CLI's defaults: the image method up to order 3 over the beam tree, in parallel.
    fn default() -> Self {
        Self {
            max_order: 3,
            solver: SolverKind::default(),
            ipc: IpcSettings {
                order: UpdateOrder::default(),
                acceleration: Acceleration::default(),
                threshold: None,
                max_iterations: crate::ipc::DEFAULT_MAX_ITERATIONS,
            },
            sbr: SbrSettings {
                step_deg: None,
                rays: None,
                planar: false,
                max_rays: crate::sbr::DEFAULT_MAX_RAYS,
            },
            candidates: CandidateMode::default(),
            max_candidates: DEFAULT_MAX_CANDIDATES,
            max_wvrn_tests: crate::pipeline::DEFAULT_MAX_WVRN_TESTS,
            parallel: true,
            diffraction: DiffractionOptions::default(),
            transmission: false,
        }
    }
}

/// Why settings cannot be used; the message names the setting (by its CLI flag where the
/// words differ).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// A name that is not one of the choices.
    #[error("{field} must be one of {choices}, got \"{got}\"")]
    UnknownName {
        /// The setting (`solver`, `ipc_order`, ...).
        field: &'static str,
        /// The name given, as messages show it: escaped and cut after 64 characters
        /// ([`bt_scene::name::shown`]), so a 10 kB value makes a short message.
        got: String,
        /// The allowed names, quoted and comma-separated.
        choices: String,
    },
    /// IPC's threshold is not a positive number.
    #[error("--ipc-threshold must be a positive number of metres, got {0}")]
    IpcThreshold(Real),
    /// IPC's round cap is 0.
    #[error("--ipc-max-iterations must be at least 1")]
    IpcMaxIterations,
    /// SBR's launch pattern is invalid or over its ray budget.
    #[error("{0}")]
    Sbr(String),
    /// More diffractions per path than the tracer does.
    #[error("--max-diffractions must be 0, 1 or 2, got {0}")]
    MaxDiffractions(usize),
    /// The minimum edge length is not a finite non-negative number of metres.
    #[error("--min-edge-length must be a finite number of metres >= 0, got {0}")]
    MinEdgeLength(Real),
    /// SBR finds specular paths only.
    #[error("--diffraction needs an exact solver (--solver image or ipc): sbr does not diffract")]
    SbrDiffraction,
    /// SBR does not transmit.
    #[error("--transmission needs an exact solver (--solver image or ipc): sbr does not transmit")]
    SbrTransmission,
}

/// A setting chosen by name from a fixed list (the CLI's value names).
pub trait Named: Copy + 'static {
    /// The setting's name in messages.
    const FIELD: &'static str;
    /// Every value with its name.
    const NAMES: &'static [(&'static str, Self)];
}

/// The value of `T` called `name`, or an error listing the names.
pub fn parse<T: Named>(name: &str) -> Result<T, SettingsError> {
    T::NAMES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let quoted: Vec<_> = T::NAMES.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            SettingsError::UnknownName {
                field: T::FIELD,
                got: bt_scene::name::shown(name),
                choices: quoted.join(", "),
            }
        })
}

/// `impl Named for $type` from the setting's name and each value's name.
macro_rules! named {
    ($type:ty, $field:literal: $($name:literal => $value:ident),+) => {
        impl Named for $type {
            const FIELD: &'static str = $field;
            const NAMES: &'static [(&'static str, Self)] = &[$(($name, Self::$value)),+];
        }
    };
}

named!(SolverKind, "solver": "image" => Image, "ipc" => Ipc, "sbr" => Sbr);
named!(UpdateOrder, "ipc_order": "gauss-seidel" => GaussSeidel, "jacobi" => Jacobi);
named!(Acceleration, "ipc_accel": "none" => None, "newton" => Newton);
named!(CandidateMode, "candidates": "beam-tree" => BeamTree, "wvrn" => Wvrn, "exhaustive" => Exhaustive);

/// The diffraction coefficient of the gains (Python's `diffraction_coefficient`; the CLI's
/// `--diffraction-coefficient`), by the names [`bt_channel::DiffractionCoefficient::name`] gives.
impl Named for bt_channel::DiffractionCoefficient {
    const FIELD: &'static str = "diffraction_coefficient";
    const NAMES: &'static [(&'static str, Self)] = &[
        (Self::Utd.name(), Self::Utd),
        (Self::SionnaRt22.name(), Self::SionnaRt22),
    ];
}

impl SolveSettings {
    /// The solver these settings select, with IPC's defaults scaled to `scene`; checks the
    /// values and SBR's ray budget. The values of the solvers not selected are checked too
    /// (not their budget): a NaN given and ignored is a mistake all the same (Python's
    /// `trace(sbr_step_deg=nan)` with the image solver).
    pub fn solver(&self, scene: &Scene) -> Result<Solver, SettingsError> {
        self.ipc.check()?;
        SbrOptions::chosen(self.sbr.rays, self.sbr.step_deg, self.sbr.planar)
            .map_err(SettingsError::Sbr)?;
        Ok(match self.solver {
            SolverKind::Image => Solver::Image,
            SolverKind::Ipc => Solver::Ipc(self.ipc.options(scene)?),
            SolverKind::Sbr => Solver::Sbr(self.sbr.options()?),
        })
    }

    /// The pipeline options for `scene`.
    pub fn trace_options(&self, scene: &Scene) -> Result<TraceOptions, SettingsError> {
        let d = self.diffraction;
        if d.max_diffractions > 2 {
            return Err(SettingsError::MaxDiffractions(d.max_diffractions));
        }
        if !(d.min_edge_length.is_finite() && d.min_edge_length >= 0.0) {
            return Err(SettingsError::MinEdgeLength(d.min_edge_length));
        }
        if d.max_diffractions > 0 && self.solver == SolverKind::Sbr {
            return Err(SettingsError::SbrDiffraction);
        }
        if self.transmission && self.solver == SolverKind::Sbr {
            return Err(SettingsError::SbrTransmission);
        }
        Ok(TraceOptions {
            max_order: self.max_order,
            solver: self.solver(scene)?,
            candidates: self.candidates,
            parallel: self.parallel,
            max_candidates: self.max_candidates,
            max_wvrn_tests: self.max_wvrn_tests,
            transmission: self.transmission,
            diffraction: d,
        })
    }
}

impl IpcSettings {
    /// IPC's options for `scene`.
    pub fn options(&self, scene: &Scene) -> Result<IpcOptions, SettingsError> {
        self.check()?;
        let mut options = IpcOptions::for_scene(scene, self.order);
        if let Some(t) = self.threshold {
            options.threshold = t;
        }
        options.max_iterations = self.max_iterations;
        options.acceleration = self.acceleration;
        Ok(options)
    }
}

impl IpcSettings {
    /// The values' ranges, without a scene: a threshold that is a positive finite number of
    /// metres, at least one round.
    fn check(&self) -> Result<(), SettingsError> {
        if let Some(t) = self.threshold
            && !(t.is_finite() && t > 0.0)
        {
            return Err(SettingsError::IpcThreshold(t));
        }
        if self.max_iterations == 0 {
            return Err(SettingsError::IpcMaxIterations);
        }
        Ok(())
    }
}

impl SbrSettings {
    /// SBR's options, refused when invalid or over [`SbrSettings::max_rays`].
    pub fn options(&self) -> Result<SbrOptions, SettingsError> {
        let options = SbrOptions::chosen(self.rays, self.step_deg, self.planar)
            .map_err(SettingsError::Sbr)?;
        match options.over_budget(self.max_rays) {
            Some(problem) => Err(SettingsError::Sbr(problem)),
            None => Ok(options),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room() -> Scene {
        bt_testkit::random_scene(1, 4)
    }

    #[test]
    fn values_of_a_solver_not_chosen_are_checked_too() {
        let mut s = SolveSettings::default();
        s.sbr.step_deg = Some(Real::NAN);
        assert!(matches!(s.solver(&room()), Err(SettingsError::Sbr(_))));
        let mut s = SolveSettings::default();
        s.ipc.threshold = Some(-1.0);
        assert!(matches!(
            s.solver(&room()),
            Err(SettingsError::IpcThreshold(_))
        ));
        // A budget belongs to the solver that launches: a fine grid is no error for the image method.
        let mut s = SolveSettings::default();
        s.sbr.step_deg = Some(1e-3);
        assert!(s.solver(&room()).is_ok());
    }

    #[test]
    fn every_name_reads_back_its_value() {
        fn round_trip<T: Named + PartialEq + std::fmt::Debug>() {
            for (name, value) in T::NAMES {
                assert_eq!(parse::<T>(name).unwrap(), *value);
            }
        }
        round_trip::<SolverKind>();
        round_trip::<UpdateOrder>();
        round_trip::<Acceleration>();
        round_trip::<CandidateMode>();
        round_trip::<bt_channel::DiffractionCoefficient>();
        let all = bt_channel::DiffractionCoefficient::ALL;
        assert_eq!(all.len(), bt_channel::DiffractionCoefficient::NAMES.len());
    }

    #[test]
    fn an_unknown_name_lists_the_choices() {
        let e = parse::<SolverKind>("magic").unwrap_err();
        assert_eq!(
            e.to_string(),
            "solver must be one of \"image\", \"ipc\", \"sbr\", got \"magic\""
        );
    }

    #[test]
    fn a_long_unknown_name_is_cut_in_the_message() {
        let long = format!("x\"{}", "y".repeat(10_000));
        let e = parse::<CandidateMode>(&long).unwrap_err().to_string();
        assert!(e.starts_with("candidates must be one of"), "{e}");
        // The quote escaped (2 characters), then as many as fit in 64.
        let shown = format!("x\\\"{}…(10002 bytes)", "y".repeat(61));
        assert!(e.ends_with(&format!("got \"{shown}\"")), "{e}");
        assert!(e.len() < 200, "{} bytes", e.len());
    }

    #[test]
    fn ipc_defaults_scale_to_the_scene_and_bad_values_are_refused() {
        let scene = room();
        let settings = SolveSettings {
            solver: SolverKind::Ipc,
            ..Default::default()
        };
        let Solver::Ipc(o) = settings.solver(&scene).unwrap() else {
            panic!("not IPC")
        };
        assert_eq!(o, IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel));
        for (threshold, max_iterations, error) in [
            (Some(-1.0), 5, SettingsError::IpcThreshold(-1.0)),
            (None, 0, SettingsError::IpcMaxIterations),
        ] {
            let ipc = IpcSettings {
                threshold,
                max_iterations,
                ..SolveSettings::default().ipc
            };
            assert_eq!(ipc.options(&scene).unwrap_err(), error);
        }
    }

    #[test]
    fn sbr_patterns_over_the_ray_budget_are_refused() {
        let sbr = SbrSettings {
            step_deg: Some(0.5),
            max_rays: 1000,
            ..SolveSettings::default().sbr
        };
        let e = sbr.options().unwrap_err().to_string();
        assert!(e.contains("sbr ray budget exceeded"), "{e}");
        let both = SbrSettings {
            rays: Some(10),
            ..sbr
        };
        assert!(both.options().unwrap_err().to_string().contains("not both"));
    }
}
