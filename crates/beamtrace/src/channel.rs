//! `beamtrace channel` (CIR, CFR, power-delay profile) and `beamtrace beams` (codebook sweep).

use crate::args::{ArrayArgs, BeamsArgs, ChannelArgs, PathArgs, RankingArg};
use crate::load::load_scene;
use crate::trace::warn_near_field;
use anyhow::Context;
use bt_beams::{BeamRanking, PathReport, RadioOptions};
use bt_scene::Scene;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Load, trace and report the paths the arguments select, with `radio` (the arguments'
/// radio options, read before: what they refuse stops the run before any trace).
/// The files read come back too: the outputs must not replace them.
fn traced_paths(
    args: &PathArgs,
    radio: &RadioOptions,
) -> anyhow::Result<(Scene, Vec<PathReport>, Vec<PathBuf>)> {
    let loaded = load_scene(&args.scene)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let scene = loaded.scene;
    let (tx, rx) = crate::load::terminals(&scene, &args.scene)?;
    let trace_args = args.trace_args();
    let options = crate::trace::options_for(&trace_args.solve, &scene)?;
    let traced = bt_solve::Tracer::new(scene.clone(), options).trace(tx, rx)?;
    let radio = radio.for_order(options.max_order);
    let paths = bt_beams::report(&scene, &traced.result.paths, &radio)?;
    warn_near_field(&paths, &scene);
    Ok((scene, paths, loaded.sources))
}

/// Write `text` to `path` through the CLI's one writer (atomic, never over an input).
fn write_text(path: &Path, text: &str, inputs: &[PathBuf]) -> anyhow::Result<()> {
    crate::files::write(path, text.as_bytes(), inputs, &[])
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| format!("{v}"))
}

/// The CIR as CSV: one tap per path, sorted by delay.
fn cir_csv(paths: &[PathReport], carrier_hz: f64) -> String {
    let mut by_delay: Vec<&PathReport> = paths.iter().collect();
    by_delay.sort_by(|a, b| a.delay_s.total_cmp(&b.delay_s).then(a.rank.cmp(&b.rank)));
    let mut out = String::from(
        "rank,order,delay_s,gain_re,gain_im,gain_db,power_dbm,baseband_re,baseband_im,surfaces\n",
    );
    for p in by_delay {
        let tap = bt_channel::Tap {
            gain: p.gain,
            delay_s: p.delay_s,
        };
        let bb = tap.baseband(carrier_hz);
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{}",
            p.rank,
            p.order,
            p.delay_s,
            p.gain.re,
            p.gain.im,
            opt(p.gain_db),
            opt(p.power_dbm),
            bb.re,
            bb.im,
            bt_output::csv::text_field(&p.route())
        );
    }
    out
}

/// The CFR's budgets from the arguments.
fn response_budget(args: &ChannelArgs) -> bt_channel::ResponseBudget {
    bt_channel::ResponseBudget {
        max_subcarriers: args.max_subcarriers,
        max_products: args.max_cfr_products,
    }
}

fn cfr_csv(paths: &[PathReport], carrier_hz: f64, args: &ChannelArgs) -> anyhow::Result<String> {
    let n = args.subcarriers;
    // The subcarriers alone were checked before the trace (`run_channel`); what depends on
    // the paths found is checked now.
    response_budget(args)
        .check(n, paths.len())
        .with_context(|| format!("--subcarriers {n} over {} paths", paths.len()))?;
    let offsets = bt_channel::subcarriers(n, args.subcarrier_spacing);
    let h = bt_channel::frequency_response(&bt_beams::taps(paths), carrier_hz, &offsets);
    let mut out = String::from("subcarrier,offset_hz,frequency_hz,re,im,gain_db\n");
    for (k, (df, v)) in offsets.iter().zip(&h).enumerate() {
        let p = v.norm_sqr();
        let db = (p > 0.0).then(|| 10.0 * p.log10());
        let _ = writeln!(
            out,
            "{k},{df},{},{},{},{}",
            carrier_hz + df,
            v.re,
            v.im,
            opt(db)
        );
    }
    Ok(out)
}

pub fn run_channel(args: &ChannelArgs) -> anyhow::Result<ExitCode> {
    let radio = args.paths.radio.options()?;
    if args.cfr.is_some() {
        // Known from the arguments: the subcarriers, and their products with at least one
        // path, refused before the scene is loaded or traced.
        let n = args.subcarriers;
        (response_budget(args).check(n, 0)).with_context(|| format!("--subcarriers {n}"))?;
    }
    let (scene, paths, inputs) = traced_paths(&args.paths, &radio)?;
    let carrier = scene.frequency_hz();
    // Every output is computed and every output path checked before the first file is
    // written: a refused later option (the CFR's budget, a PDP stem over an input) leaves no
    // CIR behind.
    let cir = cir_csv(&paths, carrier);
    let cfr = match &args.cfr {
        Some(path) => Some((path, cfr_csv(&paths, carrier, args)?)),
        None => None,
    };
    let pdp = args
        .pdp
        .as_ref()
        .map(|stem| (stem, pdp_figure(&scene, &paths, &radio)));
    let mut outputs = vec![args.out.clone()];
    outputs.extend(cfr.as_ref().map(|(path, _)| path.to_path_buf()));
    if let Some((stem, _)) = &pdp {
        outputs.extend(["svg", "png"].map(|e| stem.with_added_extension(e)));
    }
    for path in &outputs {
        crate::files::check(path, &inputs, &[])?;
    }
    write_text(&args.out, &cir, &inputs)?;
    println!("{}: {} taps", args.out.display(), paths.len());
    if let Some((path, text)) = &cfr {
        write_text(path, text, &inputs)?;
        println!("{}: {} subcarriers", path.display(), args.subcarriers);
    }
    if let Some((stem, (title, taps))) = &pdp {
        for written in bt_plot::write_power_delay_profile(stem, title, taps)? {
            println!("{}", written.display());
        }
    }
    match bt_beams::received_power_dbm(&paths, radio.tx_power_dbm) {
        Some(p) => println!(
            "received power {p:.2} dBm (power sum over {} paths)",
            paths.len()
        ),
        None => println!("no power received"),
    }
    Ok(ExitCode::SUCCESS)
}

/// The power-delay profile's title and taps.
fn pdp_figure(
    scene: &Scene,
    paths: &[PathReport],
    radio: &RadioOptions,
) -> (String, Vec<bt_plot::PdpTap>) {
    let taps = paths
        .iter()
        .map(|p| bt_plot::PdpTap {
            delay_ns: p.delay_s * 1e9,
            power_dbm: p.power_dbm.unwrap_or(f64::NEG_INFINITY),
            order: p.order,
        })
        .collect();
    let title = format!(
        "power-delay profile: {} at {:.3} GHz, {} dBm",
        scene.name(),
        scene.frequency_hz() / 1e9,
        radio.tx_power_dbm
    );
    (title, taps)
}

#[derive(Debug, Serialize)]
struct BeamsDocument<'a> {
    scene: &'a str,
    frequency_hz: f64,
    tx_power_dbm: f64,
    diffraction_coefficient: bt_channel::DiffractionCoefficient,
    tx_array: ArrayDoc,
    rx_array: ArrayDoc,
    paths: usize,
    #[serde(flatten)]
    sweep: &'a bt_beams::Sweep,
}

#[derive(Debug, Serialize)]
struct ArrayDoc {
    rows: usize,
    columns: usize,
    spacing_wavelengths: f64,
    orientation: bt_channel::Orientation,
}

impl ArrayDoc {
    fn of(a: &bt_channel::Array) -> ArrayDoc {
        ArrayDoc {
            rows: a.rows,
            columns: a.columns,
            spacing_wavelengths: a.spacing_wavelengths,
            orientation: a.orientation,
        }
    }
}

pub fn run_beams(args: &BeamsArgs) -> anyhow::Result<ExitCode> {
    let radio = args.paths.radio.options()?;
    let beams = beam_options(&args.arrays, &radio, args.top)?;
    let (tx, rx) = (&beams.tx, &beams.rx);
    let (scene, paths, inputs) = traced_paths(&args.paths, &radio)?;
    let sweep = bt_beams::sweep(
        &paths,
        tx,
        rx,
        scene.frequency_hz(),
        radio.tx_power_dbm,
        beams.ranking,
        beams.max_pairs,
    )?;
    let doc = BeamsDocument {
        scene: scene.name(),
        frequency_hz: scene.frequency_hz(),
        tx_power_dbm: radio.tx_power_dbm,
        diffraction_coefficient: radio.diffraction_coefficient,
        tx_array: ArrayDoc::of(tx),
        rx_array: ArrayDoc::of(rx),
        paths: paths.len(),
        sweep: &sweep,
    };
    let json = serde_json::to_string_pretty(&doc).context("serialising the beam sweep")?;
    if let Some(path) = &args.out {
        write_text(path, &format!("{json}\n"), &inputs)?;
    }
    if args.json {
        println!("{json}");
    } else {
        print_beams(&doc, args.top);
    }
    Ok(ExitCode::SUCCESS)
}

/// The sweep `arrays` give (a missing array [`bt_serve::DEFAULT_ARRAY`]) with the antennas'
/// orientations of `radio`, `top` pairs per `serve` answer; refused before any scene is loaded
/// or traced when over its pair budget ([`bt_serve::BeamOptions::new`]).
pub fn beam_options(
    arrays: &ArrayArgs,
    radio: &bt_beams::RadioOptions,
    top: usize,
) -> anyhow::Result<bt_serve::BeamOptions> {
    let ranking = match arrays.ranking {
        RankingArg::Power => BeamRanking::Power,
        RankingArg::Paper => BeamRanking::Paper,
    };
    let specs = [
        (arrays.tx_array, arrays.tx_spacing),
        (arrays.rx_array, arrays.rx_spacing),
    ];
    let budget = (top, arrays.max_beam_pairs);
    bt_serve::BeamOptions::new(specs, radio, ranking, budget).map_err(|(which, e)| {
        anyhow::Error::new(e).context(format!("--{}", which.replace('_', "-")))
    })
}

fn print_beams(doc: &BeamsDocument<'_>, top: usize) {
    let dir = |d: &Option<bt_beams::Direction>| {
        d.map_or_else(
            || "no direction".to_string(),
            |d| format!("{:7.2} {:6.2}", d.azimuth, d.elevation),
        )
    };
    println!(
        "scene {}  {:.2} GHz  {} paths  tx {}x{} ({} beams)  rx {}x{} ({} beams)  ranking {:?}",
        doc.scene,
        doc.frequency_hz / 1e9,
        doc.paths,
        doc.tx_array.rows,
        doc.tx_array.columns,
        doc.sweep.tx_beams,
        doc.rx_array.rows,
        doc.rx_array.columns,
        doc.sweep.rx_beams,
        doc.sweep.ranking
    );
    println!(
        "{:>4} {:>7} {:>7} {:>14} {:>14} {:>10} {:>5}",
        "rank", "tx_beam", "rx_beam", "tx_az/el", "rx_az/el", "power_dbm", "path"
    );
    for p in doc.sweep.pairs.iter().take(top) {
        println!(
            "{:>4} {:>7} {:>7} {:>14} {:>14} {:>10} {:>5}",
            p.rank,
            p.tx_beam,
            p.rx_beam,
            dir(&p.tx_direction_deg),
            dir(&p.rx_direction_deg),
            p.power_dbm
                .map_or_else(|| "-inf".to_string(), |v| format!("{v:.2}")),
            p.path_rank
                .map_or_else(|| "-".to_string(), |r| r.to_string())
        );
    }
    let Some(first) = doc.sweep.pairs.first() else {
        return;
    };
    let label = match doc.sweep.ranking {
        bt_beams::BeamRanking::Power => "best pair (strongest received power)",
        // The paper ranks paths, not powers: its first pair serves the best-ranked path
        // (lowest order, then shortest), which need not be the strongest pair.
        bt_beams::BeamRanking::Paper => {
            "first pair (paper ranking: the pair for the best-ranked path, lowest order then \
             shortest, not the strongest; --ranking power ranks by power)"
        }
    };
    println!(
        "{label}: tx beam {}, rx beam {} ({} pairs ranked)",
        first.tx_beam,
        first.rx_beam,
        doc.sweep.pairs.len()
    );
    let shown = doc.sweep.pairs.iter().take(top);
    if shown
        .clone()
        .any(|p| p.tx_direction_deg.is_none() || p.rx_direction_deg.is_none())
    {
        println!(
            "no direction: the beam's main lobe lies outside the visible region \
             (docs/channel.md §7)"
        );
    }
}
