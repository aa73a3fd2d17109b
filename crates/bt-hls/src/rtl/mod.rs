//! The emitted hardware: the Verilog AST and its one printer ([`verilog`]), the PEs (`pe`:
//! each plane's constant networks around the shared core; `generic`: a PE for any plane,
//! its coefficients loaded with the job; `mult`: the products on the device's 18 × 18
//! multipliers) and `bt_top` (`top`: controller,
//! bus, updater-buffer, write-back).

pub(crate) mod generic;
pub(crate) mod mult;
pub(crate) mod pe;
pub(crate) mod top;
pub mod verilog;
