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

/// A bar for the beam tree's build, drawn once the build has run for half a second (a room's
/// tree takes a millisecond; a city's at order 3 takes seconds): depth, parents of the level
/// done, nodes so far.
pub fn tree_progress() -> (ProgressBar, impl FnMut(bt_solve::pipeline::BuildProgress)) {
    let bar = ProgressBar::hidden();
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} beam tree {msg} {bar:30} {pos}/{len} parents [{elapsed_precise}, ETA {eta}]",
        )
        .expect("static template"),
    );
    let feed = bar.clone();
    let start = std::time::Instant::now();
    let callback = move |p: bt_solve::pipeline::BuildProgress| {
        if feed.is_hidden() && start.elapsed() > Duration::from_millis(500) {
            feed.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        feed.set_length(p.parents as u64);
        feed.set_position(p.parents_done as u64);
        feed.set_message(format!(
            "depth {}/{}, {} nodes,",
            p.depth, p.max_order, p.nodes
        ));
    };
    (bar, callback)
}
