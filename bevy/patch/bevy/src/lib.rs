//! bevy 0.20.1's facade: every bevy crate through `bevy_internal` (see
//! `Cargo.toml` for why this copy exists).
#![no_std]

pub use bevy_internal::*;

// As in the published facade: with `dynamic_linking`, bevy is built as a
// dylib.
#[cfg(all(feature = "dynamic_linking", not(target_family = "wasm")))]
#[allow(unused_imports, clippy::single_component_path_imports)]
use bevy_dylib;
