//! Render graph compiler (in progress).
