//! Linear algebra with no physics in it: the solvers the edge projection, implicit
//! bending and the contact Newton factor their systems with. Slices in, slices out;
//! nothing here imports from the rest of the crate.
//!
//! - [`tridiagonal`]: Thomas' algorithm, a chain's edges in O(n);
//! - [`cyclic`]: a loop's, the tridiagonal solve and a Sherman–Morrison correction;
//! - [`sparse`]: LDLᵀ of a tree's or graph's SPD system, with its own minimum-degree
//!   ordering and a flat list of updates planned once per topology change (also the
//!   implicit bending's system);
//! - [`symbolic`] and [`supernodal`]: the analysis (elimination tree, column counts) and
//!   the supernodal multifrontal LDLᵀ of a quasi-definite system `[H Jᵀ; J 0]`, ordered
//!   by approximate minimum degree (`amd`), for the contact Newton;
//! - [`pivot`]: the error and the dependent-pivot rule all of them share.
//!
//! Two sparse factorizations remain on purpose: an island's system is small and
//! refactored every projection with a fixed plan (a flat update list is fastest there),
//! the contact Newton's is a 2D contact graph of thousands of unknowns (dense fronts
//! are). Their orderings differ too, and changing either would change every result's
//! round-off.

pub mod cyclic;
pub mod pivot;
pub mod sparse;
pub mod supernodal;
pub mod symbolic;
pub mod tridiagonal;

pub use pivot::SingularPivot;
