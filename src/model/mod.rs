//! The model: what the simulation is made of, as plain data and rules, with no ECS.
//!
//! Edges and bending elements between packed particles, the geometry every stage
//! shares (turning angles, closest points, segment intersection), the linear motion of
//! a step, the point–edge weights of a contact, ray casts and nearest-edge queries,
//! disjoint sets, and the validation rules
//! that every entry point (the builder, the topology rebuild, scene files) applies. Everything above
//! (kernels, the ECS layer, systems) may use this module; it uses nothing of theirs.

pub mod edge;
pub mod geometry;
pub mod motion;
pub mod point_edge;
pub mod queries;
pub mod union_find;
pub mod validate;

pub use edge::{Bend, Edge, bend_count, edge_count};

/// The island of a packed particle that is in none: pinned, or joined by no
/// constrained edge. Islands are the rigid groups of the collision fail-safe too.
pub const NO_ISLAND: u32 = u32::MAX;
pub use point_edge::PointEdgePair;
pub use union_find::UnionFind;
