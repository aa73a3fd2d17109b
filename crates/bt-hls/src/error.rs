/// The one error type of `bt-hls`.
#[derive(Debug, thiserror::Error)]
pub enum HlsError {
    /// The input failed validation; every problem is listed.
    #[error("invalid hls input: {}", problems.join("; "))]
    InvalidInput {
        /// One lowercase message per problem.
        problems: Vec<String>,
    },
    /// The schedule does not fit the input (see `bt_schedule::Schedule::check`).
    #[error("schedule does not fit the input: {0}")]
    Schedule(String),
    /// The scheduler rejected the problem or the budget.
    #[error("scheduling failed: {0}")]
    Scheduling(#[from] bt_schedule::ScheduleError),
    /// The design exceeds a structural limit of the generator.
    #[error("design too large: {0}")]
    TooLarge(String),
    /// An external tool (verilator, iverilog, yosys) is not installed.
    #[error("tool `{tool}` not found on PATH: install it (e.g. `apt-get install {package}`)")]
    ToolMissing {
        /// Executable name.
        tool: String,
        /// Debian package that provides it.
        package: String,
    },
    /// An external tool ran and failed.
    #[error("`{tool}` failed: {message}")]
    ToolFailed {
        /// Executable name.
        tool: String,
        /// Its diagnostics (stderr and stdout tail).
        message: String,
    },
    /// Reading or writing a file in the output directory failed.
    #[error("i/o on {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A generated or simulator file could not be parsed.
    #[error("cannot parse {what}: {message}")]
    Parse {
        /// The file or stream.
        what: String,
        /// What was wrong.
        message: String,
    },
    /// An output could not be written safely.
    #[error(transparent)]
    Output(#[from] bt_output::OutputError),
    /// The fixed-point model rejected the input.
    #[error(transparent)]
    Fixed(#[from] bt_fixed::FixedError),
}

pub(crate) fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> HlsError + '_ {
    move |source| HlsError::Io {
        path: path.display().to_string(),
        source,
    }
}
