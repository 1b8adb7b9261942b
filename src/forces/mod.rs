//! The Forces stage: every force on every particle, accumulated into
//! [`ParticleState::force`](crate::world::state::ParticleState::force). Each force
//! element is a pure kernel on slices in its own module; [`plugin`] holds the thin
//! systems that run them in a fixed order.
//!
//! User forces go in [`StepSet::Forces`](crate::schedule::StepSet::Forces) after
//! [`plugin::apply_tethers`], adding to the accumulator.
//!
//! Imports: [`crate::model`], [`crate::linalg`] (the implicit bending's sparse solve),
//! [`crate::parallel`]; its plugin, [`crate::world`] and [`crate::schedule`].

pub mod bending;
pub mod damping;
pub mod energy;
pub mod gravity;
pub mod implicit_angle;
pub mod implicit_bending;
pub mod plugin;
pub mod quadratic_bending;
pub mod springs;
pub mod tether;

pub use plugin::ForcesPlugin;
