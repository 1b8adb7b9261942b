//! The ECS layer: what the simulation is, as components and resources on a Bevy world.
//!
//! Particles and strands are entities ([`particle`], [`strand`]), built by
//! [`builder`] and edited by [`edit`]; component [`hooks`] mark the [`topology`] for a
//! rebuild, which packs the simulated particles into the arrays of [`state`] that the
//! stages run on ([`sync`] copies between the two). [`config`] holds every setting,
//! [`clock`] the simulated time and [`problems`] what was refused and why.
//!
//! Imports: [`crate::model`], and from the kernels only the setting types its
//! configuration holds (solver kinds, the broad phase's method).

pub mod builder;
pub mod clock;
pub mod config;
pub mod edit;
pub mod hooks;
pub mod particle;
pub mod problems;
pub mod state;
pub mod strand;
pub mod sync;
pub mod topology;
