#![allow(dead_code)]
pub mod room;
