//! bt-dynamic's integration tests, one binary (one link) for all modules.

mod incremental;
mod wvrn_completeness;
