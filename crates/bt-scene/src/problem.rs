//! Problems found in a scene and the crate's one error type.

use serde::Serialize;
use std::fmt;
use thiserror::Error;

/// One problem found in a scene, located by field path (e.g. `surfaces[3] "sofa.top"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Problem {
    /// Where: a field path into the scene description.
    pub location: String,
    /// What is wrong, lowercase.
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}

/// Errors of scene validation (the importers' errors, files and formats, are `bt-import`'s).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene has one or more problems; all are listed.
    #[error("{source_name}: {} problem(s):\n{}", problems.len(), list(problems))]
    Invalid {
        /// File or scene name.
        source_name: String,
        /// Every problem found.
        problems: Vec<Problem>,
    },
    /// A trace needs a terminal the scene does not have (a bare mesh, XML or point cloud
    /// loaded without `tx`/`rx`). Front ends word it with their own names (CLI `--tx`,
    /// Python `tx=`); this message names only the terminals.
    #[error("{source_name}: no {} given: a trace needs both terminals", missing.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(" and "))]
    MissingTerminal {
        /// File or scene name.
        source_name: String,
        /// The missing terminals, TX first (never empty).
        missing: Vec<Terminal>,
    },
}

/// One of the two terminals of a trace.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Terminal {
    /// The transmitter.
    Tx,
    /// The receiver.
    Rx,
}

impl Terminal {
    /// `tx` or `rx`: the field name in scene files, and the root of every front end's name.
    pub fn name(self) -> &'static str {
        match self {
            Terminal::Tx => "tx",
            Terminal::Rx => "rx",
        }
    }
}

impl Terminal {
    /// The message every front end gives for `missing` terminals of the scene named `source`,
    /// each spelled by `spell` as the front end takes it (CLI `--tx X,Y,Z`, Python
    /// `tx=[x, y, z]`): `SOURCE: no tx and rx given: pass A and B (...)`.
    pub fn missing_message(
        source: &str,
        missing: &[Terminal],
        spell: impl Fn(Terminal) -> String,
    ) -> String {
        let names: Vec<&str> = missing.iter().map(|t| t.name()).collect();
        let spelled: Vec<String> = missing.iter().map(|&t| spell(t)).collect();
        format!(
            "{source}: no {} given: pass {} (meshes, XML scenes and point clouds carry no terminals)",
            names.join(" and "),
            spelled.join(" and ")
        )
    }
}

impl fmt::Display for Terminal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Most problems an error prints: 10,000 problems of one kind are read as their first ones and
/// a count, not as megabytes of text.
pub const MAX_PRINTED_PROBLEMS: usize = 1000;

/// The problems one per line, at most [`MAX_PRINTED_PROBLEMS`] of them, then how many more.
fn list(problems: &[Problem]) -> String {
    let mut lines: Vec<String> = (problems.iter().take(MAX_PRINTED_PROBLEMS))
        .map(|p| format!("  - {p}"))
        .collect();
    if problems.len() > MAX_PRINTED_PROBLEMS {
        lines.push(format!(
            "  ... and {} more",
            problems.len() - MAX_PRINTED_PROBLEMS
        ));
    }
    lines.join("\n")
}

pub(crate) struct Collector(pub Vec<Problem>);

impl Collector {
    pub fn push(&mut self, location: impl Into<String>, message: impl Into<String>) {
        self.0.push(Problem {
            location: location.into(),
            message: message.into(),
        });
    }
}

/// Where validation problems go.
pub(crate) trait ProblemSink {
    fn report(&mut self, location: &str, message: impl Into<String>);
    /// Problems reported so far.
    fn count(&self) -> usize;
}

impl ProblemSink for Collector {
    fn report(&mut self, location: &str, message: impl Into<String>) {
        self.push(location, message);
    }
    fn count(&self) -> usize {
        self.0.len()
    }
}

impl ProblemSink for Vec<Problem> {
    fn report(&mut self, location: &str, message: impl Into<String>) {
        self.push(Problem {
            location: location.to_string(),
            message: message.into(),
        });
    }
    fn count(&self) -> usize {
        self.len()
    }
}
