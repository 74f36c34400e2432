//! Procedural content: a sculpted head, a furry body, and groom generators, so that the
//! default scenes need no downloads.

pub mod children;
pub mod generators;
pub mod guides;
pub mod head;
pub mod sdf;
pub mod styles;
pub mod surface;

pub use generators::{GeneratedGroom, GroomParams, Region, Style};
pub use head::{BodyParams, HeadParams};
pub use surface::Surface;
