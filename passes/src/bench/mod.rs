//! Roofline reference passes for `strandgraph bench`: how fast the device
//! does the operations the hair rasterizers are built on, measured in the
//! same run as the pipelines so raster passes can be reported as a fraction
//! of a ceiling rather than in isolation.
//!
//! - `bench.atomic_min32`: random-address 32-bit `atomicMin`, the operation
//!   of Kulikov's visibility atlas (3 layers by chained atomicMin).
//! - `bench.atomic_min64`: random-address 64-bit `atomicMin` with the result
//!   unused, the operation of Lipp's 64-bit visibility buffer.
//! - `bench.copy`: a buffer-to-buffer copy in a compute shader, the
//!   bandwidth ceiling.
//! - `bench.raster`: triangles and shaded fragments per second through the
//!   hardware rasterizer, the ceiling of every raster pass (few SMs run
//!   vertex and pixel work on Hopper).
//!
//! Addresses and values come from a hash of the invocation's global id, so
//! every backend performs the same sequence of operations.

mod raster;
mod roofline;

pub use raster::{RASTER, RasterBenchParams, pixel_colour};
pub use roofline::{ATOMIC_MIN32, ATOMIC_MIN64, COPY, RooflineParams, pcg};
