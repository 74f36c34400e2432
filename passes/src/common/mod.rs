//! Passes every pipeline uses.

pub mod clear;
pub mod clip;
