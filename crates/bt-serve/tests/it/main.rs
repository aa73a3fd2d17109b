//! Integration tests of bt-serve, one test binary: `same` compares serve's answers with
//! one-shot traces, `errors` feeds it bad requests, `budgets` over-budget ones.

mod budgets;
mod common;
mod errors;
mod same;
