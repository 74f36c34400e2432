//! Passes every pipeline uses.

pub mod clear;
