//! The real-time loop of `beamtrace serve` (issue 30): one JSON request per line in, one JSON
//! answer per line out, in request order, traced by one long-lived [`bt_solve::Tracer`] that
//! keeps its TX tree and caches between requests. The protocol is `docs/serve.md`.
//!
//! - [`request`] turns a line into a checked [`Request`] (every error names its field);
//! - [`Server`] holds the tracer and the session's state (TX, last receivers, object poses)
//!   and answers a request with the path records of `trace --json` ([`bt_beams::PathReport`],
//!   filled by the same [`bt_beams::TraceDocument::report`]);
//! - [`Server::serve`] is the loop over any `BufRead` / `Write`: lines bounded by
//!   [`Limits::max_line_bytes`], one flush per answer, nothing kept per request.
//!
//! No request can stop the stream: malformed lines, unknown fields, bad positions and
//! over-budget requests each get an error line `{"id", "error"}`. Only the transport's own
//! read and write errors end [`Server::serve`].
#![warn(missing_docs)]

mod batch;
mod json;
pub mod request;
mod server;
mod stream;

pub use request::{Receivers, Request};
pub use server::Server;
pub use stream::{Summary, read_bounded_line};

/// Longest request line read, bytes (1 MiB: about 20,000 receivers written with full
/// precision); a longer line is skipped to its end and answered with an error.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Most receivers in one request (each answer holds every path record of its receiver:
/// about 32 KB for the living room at order 3, so 1,024 receivers make a 32 MB line).
pub const MAX_RECEIVERS: usize = 1024;

/// Most connections `beamtrace serve --listen` serves at a time (`--max-connections`): each
/// holds its own [`Server`] (a tracer with its kept tree and caches, about 7 MB in the living
/// room), so the number bounds the memory.
pub const MAX_CONNECTIONS: usize = 16;

/// How long, µs, the partner of a lone receiver's answer spins for the next one before it
/// sleeps (`serve --partner-spin-us`, [`Server::with_partner`]): requests that follow each
/// other within it get their tree walk, report and JSON split over two cores.
pub const PARTNER_SPIN_US: u64 = 1000;

/// The bounds every request is checked against before any work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Longest request line, bytes (without its line break).
    pub max_line_bytes: usize,
    /// Most receivers in one request.
    pub max_receivers: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_line_bytes: MAX_LINE_BYTES,
            max_receivers: MAX_RECEIVERS,
        }
    }
}

/// Beam answers (`serve --tx-array/--rx-array`): every answer also sweeps the DFT codebooks of
/// the two arrays over its paths, as `beamtrace beams` does, and holds the best pair and the
/// first `top` pairs of the ranking.
#[derive(Debug, Clone)]
pub struct BeamOptions {
    /// The TX array (its orientation is the TX antenna's).
    pub tx: bt_channel::Array,
    /// The RX array.
    pub rx: bt_channel::Array,
    /// How pairs are ranked.
    pub ranking: bt_beams::BeamRanking,
    /// Pairs of the ranking each answer holds.
    pub top: usize,
    /// Budget on TX beams × RX beams (`--max-beam-pairs`).
    pub max_pairs: u64,
}

/// The array (rows, columns) a beam sweep takes when none is given (`beams`, Python's
/// `Tracer`): a horizontal 8-element ULA.
pub const DEFAULT_ARRAY: (usize, usize) = (1, 8);

impl BeamOptions {
    /// The sweep of a TX and an RX array, each `(shape, spacing in wavelengths)` with the shape
    /// `(rows, columns)` or, when missing, [`DEFAULT_ARRAY`], oriented as `radio`'s antennas, ranked by
    /// `ranking`, `top` pairs per answer, at most `max_pairs` pairs: the pairs follow from the
    /// arrays alone, so an over-budget sweep is refused here, before any trace. An error
    /// names the array (`tx_array`, `rx_array`) or the budget.
    pub fn new(
        arrays: [(Option<(usize, usize)>, f64); 2],
        radio: &bt_beams::RadioOptions,
        ranking: bt_beams::BeamRanking,
        (top, max_pairs): (usize, u64),
    ) -> Result<Self, (&'static str, bt_channel::ChannelError)> {
        let array = |(shape, spacing): (Option<(usize, usize)>, f64), which, orientation| {
            let (rows, columns) = shape.unwrap_or(DEFAULT_ARRAY);
            bt_channel::Array::new(rows, columns, spacing, orientation).map_err(|e| (which, e))
        };
        let tx = array(arrays[0], "tx_array", radio.tx.orientation)?;
        let rx = array(arrays[1], "rx_array", radio.rx.orientation)?;
        bt_channel::check_beam_pairs(&tx, &rx, max_pairs).map_err(|e| ("max_beam_pairs", e))?;
        Ok(BeamOptions {
            tx,
            rx,
            ranking,
            top,
            max_pairs,
        })
    }
}

/// What can go wrong: a request's own problem (answered with an error line, the stream goes
/// on) or the transport's (the stream ends).
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// A request field is malformed, refers to nothing or is over its budget.
    #[error("{field}: {message}")]
    Request {
        /// The field, as the request spells it (`rx`, `rx[2]`, `objects.door.angle_deg`), or
        /// `request` for the line as a whole.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// The scene refuses a position or pose (a receiver on a surface, a moved object through
    /// the transmitter); the message lists its problems, each with its field.
    #[error("{0}")]
    Scene(String),
    /// Tracing failed (a budget).
    #[error(transparent)]
    Trace(#[from] bt_solve::pipeline::TraceError),
    /// The paths could not be reported (a material without a radio model).
    #[error(transparent)]
    Report(#[from] bt_beams::ReportError),
    /// The beam sweep failed (over its pair budget).
    #[error(transparent)]
    Beams(#[from] bt_channel::ChannelError),
    /// Serialising an answer failed.
    #[error("serialising the answer: {0}")]
    Json(#[from] serde_json::Error),
    /// Reading the request stream failed.
    #[error("reading requests: {0}")]
    Read(std::io::Error),
    /// Writing the answer stream failed (the client went away).
    #[error("writing answers: {0}")]
    Write(std::io::Error),
}

impl ServeError {
    /// A request error on `field`.
    pub fn request(field: impl Into<String>, message: impl Into<String>) -> Self {
        ServeError::Request {
            field: field.into(),
            message: message.into(),
        }
    }
}
