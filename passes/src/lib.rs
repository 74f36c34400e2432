//! Pass registry (in progress).
