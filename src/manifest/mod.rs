//! The manifest: TOML text in, a validated [`Manifest`] out, or every error found.

pub mod model;

pub use model::*;
