//! `strandgraph` as a library: what the CLI, the end-to-end tests and the
//! benches share — preparing a scene's frame for a graph, and turning
//! rendered images into pictures.

pub mod agree;
pub mod compare;
pub mod demo;
pub mod frame;
pub mod images;
pub mod runner;
pub mod sequence;
pub mod tables;
pub mod tonemap;
