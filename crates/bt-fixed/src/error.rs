/// The one error type of `bt-fixed`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FixedError {
    /// A NaN or infinite value was offered to a quantiser.
    #[error("non-finite value {value} cannot be quantised")]
    NonFinite {
        /// The offending value.
        value: f64,
    },
    /// The quantised value does not fit its 32-bit word.
    #[error("value {value} is out of range for {format}")]
    OutOfRange {
        /// The offending value (metres for coordinates, unitless for normals).
        value: f64,
        /// Name of the target format.
        format: &'static str,
    },
    /// Input validation found problems; every problem is listed, each naming its item.
    #[error("invalid input: {}", problems.join("; "))]
    InvalidInput {
        /// One lowercase message per problem.
        problems: Vec<String>,
    },
}
