//! Hair data model and loaders (in progress).
