//! Progress on stderr for jobs that can take more than a few seconds: indicatif's bars on a
//! terminal, and when stderr is not a terminal (piped, logged), where indicatif draws nothing,
//! one plain line every few seconds from [`heartbeat`].

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::Duration;

/// How often a piped run prints its progress line: every 5 s, or every
/// `BEAMTRACE_HEARTBEAT_MS` milliseconds when that variable holds a number (tests).
fn heartbeat_period() -> Duration {
    std::env::var("BEAMTRACE_HEARTBEAT_MS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .map_or(Duration::from_secs(5), Duration::from_millis)
}

/// When stderr is not a terminal: a thread that prints `what` with `bar`'s position, length,
/// message and elapsed time on stderr every [`heartbeat_period`], until the bar is finished or
/// dropped. Nothing on a terminal, where the bar draws itself.
pub fn heartbeat(bar: &ProgressBar, what: &str) {
    if std::io::stderr().is_terminal() {
        return;
    }
    let (weak, what, period) = (bar.downgrade(), what.to_string(), heartbeat_period());
    std::thread::spawn(move || {
        let tick = period.min(Duration::from_millis(200));
        let mut waited = Duration::ZERO;
        loop {
            std::thread::sleep(tick);
            waited += tick;
            let Some(bar) = weak.upgrade() else { return };
            if bar.is_finished() {
                return;
            }
            if waited >= period {
                waited = Duration::ZERO;
                eprintln!("{}", heartbeat_line(&bar, &what));
            }
        }
    });
}

/// `what: pos/len message (elapsed s)`, the parts the bar has.
fn heartbeat_line(bar: &ProgressBar, what: &str) -> String {
    let mut line = format!("{what}:");
    if let Some(len) = bar.length() {
        line.push_str(&format!(" {}/{len}", bar.position()));
    }
    let message = bar.message();
    if !message.is_empty() {
        line.push_str(&format!(" {message}"));
    }
    line + &format!(" ({:.0} s)", bar.elapsed().as_secs_f64())
}

/// A spinner with elapsed time for work whose length is not known in advance.
pub fn spinner(what: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template(&format!("{{spinner}} {what} [{{elapsed_precise}}] {{msg}}"))
            .expect("static template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    heartbeat(&bar, what);
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
    heartbeat(&bar, units);
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
    /// A hidden bar with `template`, to be drawn once `delay` has passed (and, piped, a
    /// [`heartbeat`] naming `what`).
    pub fn new(template: &str, delay: Duration, what: &str) -> Self {
        let bar = ProgressBar::hidden();
        bar.set_style(ProgressStyle::with_template(template).expect("static template"));
        heartbeat(&bar, what);
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
/// tree takes a millisecond; a city's at order 3 takes seconds): what is built (TX's tree;
/// with diffraction, the edges its nodes reach, RX's tree and its reaches), depth, parents
/// (or nodes) of the level done, nodes so far.
pub fn tree_progress() -> (ProgressBar, impl FnMut(bt_solve::pipeline::BuildProgress)) {
    let deferred = Deferred::new(
        "{spinner} {msg} {bar:30} {pos}/{len} [{elapsed_precise}, ETA {eta}]",
        Duration::from_millis(500),
        "trace",
    );
    let bar = deferred.bar();
    let callback = move |p: bt_solve::pipeline::BuildProgress| {
        use bt_solve::pipeline::BuildStage;
        let feed = deferred.show_after();
        feed.set_length(p.parents as u64);
        feed.set_position(p.parents_done as u64);
        let (what, of) = match p.stage {
            BuildStage::Tree => ("beam tree", "parents"),
            BuildStage::RxTree => ("RX's beam tree (diffraction)", "parents"),
            BuildStage::Reaches => ("edges each node reaches (diffraction)", "nodes"),
        };
        feed.set_message(format!(
            "{what}: {of} of depth {}/{}, {} nodes so far",
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
        "extracting planes",
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
