//! Procedural content: star-shaped heads and bodies, and groom generators, so that the
//! default scenes need no downloads.

pub mod generators;
pub mod head;
pub mod surface;

pub use generators::{GeneratedGroom, GroomParams, Region, Style};
pub use head::{BodyParams, HeadParams};
pub use surface::Surface;
