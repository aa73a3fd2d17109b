//! Budgets checked before the work (`docs/reliability.md`): the estimate and the option that
//! raises the budget go into the error.

use bt_scene::Scene;
use bt_solve::pipeline::{TraceError, exhaustive_count};

/// Stop before enumerating candidates of `scene` up to `max_order` when their upper bound
/// (every sequence over the reflectors, no surface twice in a row) exceeds `budget`
/// (`--max-candidates`).
pub fn candidates(scene: &Scene, max_order: usize, budget: u64) -> Result<(), TraceError> {
    let reflectors = scene.reflectors().count() as u64;
    let estimate = exhaustive_count(reflectors, max_order);
    if estimate > budget {
        return Err(TraceError::Budget {
            estimate,
            budget,
            max_order,
        });
    }
    Ok(())
}
