//! Scheuermann 2004, "Hair Rendering and Shading" (ATI): polygonal hair, the
//! baseline the strand pipelines are measured against.
//!
//! - The hair model is layers of textured ribbon patches with per-vertex
//!   ambient occlusion; the paper's were authored, ours are built from any
//!   groom (`strandgraph_assets::hairpatch`) so every pipeline draws the same
//!   scene, and packed by [`upload`].
//! - [`shading`] is the paper's `HairLighting`: tweaked diffuse, two
//!   shifted Kajiya-Kay highlights, the second tinted and sparkling.
//! - [`hair`] draws one stage of the paper's optimized scheme per graph
//!   pass (prime Z, opaque, back faces, front faces) through the hardware
//!   rasterizer, patches in their static inside-to-outside order
//!   (`scenes/graphs/scheuermann.ron`).
//! - [`kernel`] is the stages' CPU kernel: the hardware pipeline emulated.
//! - [`texture`] filters the generated textures, the same on every backend.

pub mod hair;
#[cfg(test)]
mod hair_tests;
mod kernel;
pub mod reference_shade;
pub mod shading;
pub mod texture;
pub mod upload;
