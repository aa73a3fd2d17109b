//! Integration tests of bt-serve, one test binary: `same` compares serve's answers with
//! one-shot traces, `batched` compares batched answers with answers one by one, `errors`
//! feeds it bad requests, `budgets` over-budget ones.

mod batched;
mod budgets;
mod common;
mod errors;
mod same;
