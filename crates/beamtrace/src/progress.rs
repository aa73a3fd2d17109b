//! Progress on stderr for jobs that can take more than a few seconds (hidden when stderr is
//! not a terminal, as indicatif does).

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A spinner with elapsed time for work whose length is not known in advance.
pub fn spinner(what: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template(&format!("{{spinner}} {what} [{{elapsed_precise}}] {{msg}}"))
            .expect("static template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// A bar over `len` units called `units` ("room-steps", "time steps"), with the elapsed time
/// and an estimate of the rest.
pub fn counter(len: u64, units: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {units}  {{elapsed}} (eta {{eta}})"
        ))
        .expect("static template"),
    );
    bar
}

/// A bar in the style `template`, hidden until [`Deferred::show_after`] finds that the work
/// has run for `delay` (the first report, for a zero delay).
pub struct Deferred {
    bar: ProgressBar,
    start: std::time::Instant,
    delay: Duration,
}

impl Deferred {
    /// A hidden bar with `template`, to be drawn once `delay` has passed.
    pub fn new(template: &str, delay: Duration) -> Self {
        let bar = ProgressBar::hidden();
        bar.set_style(ProgressStyle::with_template(template).expect("static template"));
        Deferred {
            bar,
            start: std::time::Instant::now(),
            delay,
        }
    }

    /// The bar (for `finish_and_clear`).
    pub fn bar(&self) -> ProgressBar {
        self.bar.clone()
    }

    /// The bar, drawn on stderr from now on if the delay has passed.
    pub fn show_after(&self) -> &ProgressBar {
        if self.bar.is_hidden() && self.start.elapsed() >= self.delay {
            self.bar
                .set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        &self.bar
    }
}

/// A bar for the beam tree's build, drawn once the build has run for half a second (a room's
/// tree takes a millisecond; a city's at order 3 takes seconds): depth, parents of the level
/// done, nodes so far.
pub fn tree_progress() -> (ProgressBar, impl FnMut(bt_solve::pipeline::BuildProgress)) {
    let deferred = Deferred::new(
        "{spinner} beam tree {msg} {bar:30} {pos}/{len} parents [{elapsed_precise}, ETA {eta}]",
        Duration::from_millis(500),
    );
    let bar = deferred.bar();
    let callback = move |p: bt_solve::pipeline::BuildProgress| {
        let feed = deferred.show_after();
        feed.set_length(p.parents as u64);
        feed.set_position(p.parents_done as u64);
        feed.set_message(format!(
            "depth {}/{}, {} nodes,",
            p.depth, p.max_order, p.nodes
        ));
    };
    (bar, callback)
}

/// A progress bar for plane extraction on stderr, shown from the first report on, and the
/// callback that feeds it.
pub fn extraction_progress() -> (ProgressBar, impl FnMut(bt_pointcloud::Progress)) {
    let deferred = Deferred::new(
        "{spinner} extracting planes {bar:30} {pos}/{len} points assigned, {msg} [{elapsed_precise}, ETA {eta}]",
        std::time::Duration::ZERO,
    );
    let bar = deferred.bar();
    let callback = move |p: bt_pointcloud::Progress| {
        let feed = deferred.show_after();
        feed.set_length(p.points_total as u64);
        feed.set_position(p.points_assigned as u64);
        feed.set_message(format!("{} planes", p.ransac_planes));
    };
    (bar, callback)
}
