//! The Constrain stage: inextensibility as a velocity filter.
//!
//! After forces and the predictor, before collisions, every island's velocities are
//! projected so that each constrained edge ends the step at its rest length. Islands
//! are found once per topology change ([`islands`]); the kind of an island picks its
//! solver ([`solver`]). The kernels are pure functions on slices: the linear solves
//! (in [`crate::linalg`], on a [`graph`] layout for trees and graphs), the projection with
//! the contact projection of islands in contact ([`projection`]) and the relaxation baselines
//! ([`relaxation`]); [`plugin`] holds the thin systems.
//!
//! Edge inextensibility only: nothing here knows about contacts (the `contact` module
//! builds on it). Imports: [`crate::model`], [`crate::linalg`], [`crate::metrics`]; its
//! plugin, [`crate::world`] and [`crate::schedule`].

pub mod graph;
pub mod island_edge;
pub mod islands;
pub mod plugin;
pub mod projection;
pub mod relaxation;
pub mod solver;

pub use plugin::{ConstraintsPlugin, Islands};
pub use solver::SolverKind;
