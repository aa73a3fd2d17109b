//! Integration tests of `bt-fixed`, one test binary for the crate (one link): each module was
//! once its own file under `tests/`; `common` holds the shared proptest strategies.

mod algorithm3;
mod common;
mod ipc;
mod oracle;
mod rtl_form;
mod vs_f64;
mod widths;
