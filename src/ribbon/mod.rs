//! Ribbons: strands drawn as textured triangle strips. [`geometry`] is the pure kernel
//! (points in, vertex buffers out); with the `ribbons` feature, `plugin` keeps a
//! `Mesh2d` per strand on it.
//!
//! Imports: [`crate::world`] and [`crate::transforms`], nothing of the solve.

pub mod geometry;
#[cfg(feature = "ribbons")]
pub mod plugin;

#[cfg(feature = "ribbons")]
pub use plugin::{StrandRibbon, StrandRibbonPlugin};
