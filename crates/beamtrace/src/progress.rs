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
