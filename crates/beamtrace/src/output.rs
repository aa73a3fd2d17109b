//! The table view of a trace; the JSON document itself is `bt_beams::TraceDocument`
//! (documented in `docs/output-format.md`).

use bt_beams::TraceDocument;

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
            p.route()
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
    let diffracted = match s.candidates.diffracted {
        0 => String::new(),
        n => format!(" + {n} diffracted"),
    };
    println!(
        "{} valid paths from {} candidates{diffracted} ({} generated, {} pruned); candidates {:.3} ms, solve {:.3} ms",
        s.valid_paths,
        s.candidates.candidates,
        s.candidates.generated,
        s.candidates.pruned_side + s.candidates.pruned_visibility,
        s.time_s.candidates * 1e3,
        s.time_s.solve * 1e3
    );
}
