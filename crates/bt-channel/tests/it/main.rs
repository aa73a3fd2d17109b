//! Integration tests of bt-channel through its public API (one test binary).

mod diffraction;
mod transmission;
