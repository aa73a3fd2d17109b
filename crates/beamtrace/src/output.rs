//! The JSON document of a trace (documented in `docs/output-format.md`) and the table view.

use bt_beams::{PathReport, RadioOptions};
use bt_channel::Antenna;
use bt_paths::CandidateStats;
use bt_paths::beamtree::TreeStats;
use bt_scene::Scene;
use bt_solve::{OutcomeCounts, Solver};
use serde::Serialize;
use std::time::Duration;

/// Version of the JSON document layout; bump on any incompatible change.
pub const FORMAT_VERSION: u32 = 1;

#[derive(Debug, Serialize)]
pub struct TraceDocument {
    pub format_version: u32,
    pub scene: String,
    pub tx: [f64; 3],
    pub rx: [f64; 3],
    pub frequency_hz: f64,
    pub max_order: usize,
    pub solver: Solver,
    pub radio: Radio,
    pub paths: Vec<PathReport>,
    pub stats: Stats,
}

/// Antennas and transmitted power of the gains.
#[derive(Debug, Serialize)]
pub struct Radio {
    pub tx_antenna: Antenna,
    pub rx_antenna: Antenna,
    pub tx_power_dbm: f64,
}

#[derive(Debug, Serialize)]
pub struct Stats {
    pub candidates: CandidateStats,
    /// Beam-tree node counts (beam-tree candidates only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tree: Option<TreeStats>,
    pub outcomes: OutcomeCounts,
    pub valid_paths: usize,
    /// Total received power (power sum over the paths), dBm; null without any power.
    pub received_power_dbm: Option<f64>,
    /// Wall-clock seconds per stage (the only part of the document that varies between runs).
    pub time_s: StageTimes,
}

#[derive(Debug, Serialize)]
pub struct StageTimes {
    pub load: f64,
    pub candidates: f64,
    pub solve: f64,
    pub report: f64,
}

impl TraceDocument {
    pub fn new(
        scene: &Scene,
        solver: &Solver,
        max_order: usize,
        radio: &RadioOptions,
        paths: Vec<PathReport>,
        (candidates, tree, outcomes): (CandidateStats, Option<TreeStats>, OutcomeCounts),
        times: [Duration; 4],
    ) -> Self {
        let [load, cand, solve, report] = times.map(|d| d.as_secs_f64());
        Self {
            format_version: FORMAT_VERSION,
            scene: scene.name().to_string(),
            tx: scene.tx_world().to_array(),
            rx: scene.rx_world().to_array(),
            frequency_hz: scene.frequency_hz(),
            max_order,
            solver: *solver,
            radio: Radio {
                tx_antenna: radio.tx,
                rx_antenna: radio.rx,
                tx_power_dbm: radio.tx_power_dbm,
            },
            stats: Stats {
                candidates,
                tree,
                outcomes,
                valid_paths: paths.len(),
                received_power_dbm: bt_beams::received_power_dbm(&paths, radio.tx_power_dbm),
                time_s: StageTimes {
                    load,
                    candidates: cand,
                    solve,
                    report,
                },
            },
            paths,
        }
    }
}

pub fn print_table(doc: &TraceDocument) {
    println!(
        "scene {}  tx {:?}  rx {:?}  {:.2} GHz  max order {}",
        bt_scene::name::escape(&doc.scene),
        doc.tx,
        doc.rx,
        doc.frequency_hz / 1e9,
        doc.max_order
    );
    println!(
        "{:>4} {:>3} {:>8} {:>8} {:>8} {:>7} {:>8} {:>7} {:>7} {:>8}  surfaces",
        "rank",
        "ord",
        "length_m",
        "delay_ns",
        "aod_az",
        "aod_el",
        "aoa_az",
        "aoa_el",
        "loss_db",
        "gain_db"
    );
    for p in &doc.paths {
        let names = if p.surfaces.is_empty() {
            "(line of sight)".to_string()
        } else {
            p.surfaces
                .iter()
                .map(|n| bt_scene::name::escape(n))
                .collect::<Vec<_>>()
                .join(" > ")
        };
        println!(
            "{:>4} {:>3} {:>8.3} {:>8.3} {:>8.2} {:>7.2} {:>8.2} {:>7.2} {:>7.2} {:>8}  {}",
            p.rank,
            p.order,
            p.length_m,
            p.delay_s * 1e9,
            p.aod_deg.azimuth,
            p.aod_deg.elevation,
            p.aoa_deg.azimuth,
            p.aoa_deg.elevation,
            p.loss_db,
            p.gain_db
                .map_or_else(|| "-inf".to_string(), |g| format!("{g:.2}")),
            names
        );
    }
    let s = &doc.stats;
    println!(
        "{} valid paths from {} candidates ({} generated, {} pruned); candidates {:.3} ms, solve {:.3} ms",
        s.valid_paths,
        s.candidates.candidates,
        s.candidates.generated,
        s.candidates.pruned_side + s.candidates.pruned_visibility,
        s.time_s.candidates * 1e3,
        s.time_s.solve * 1e3
    );
}
