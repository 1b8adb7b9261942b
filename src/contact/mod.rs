//! The contact solve, end to end: which point–edge pairs of a step become rows, and how
//! the strands they touch are projected together with them so that every edge ends the
//! step exact and every row is met, both sides of each contact moving.
//!
//! - [`speculative`]: the rows a step's motion asks for (the builder), [`rows`] what a
//!   row is and the impulse it carries (warm starts keyed by point and strand);
//! - [`active_set`]: which rows are projected, in rounds until none left out acts;
//!   [`groups`]: the independent groups they join; [`driver`]: each group projected on
//!   its own, on two threads when large enough;
//! - [`projection`]: one group's projection, the edges' Newton steps around a contact
//!   solver, with [`scratch`] its buffers, [`local_row`] a row in the group's
//!   numbering, [`split`] a large group cut in two for two threads;
//! - the two contact solvers: [`sweeps`] (projected Gauss–Seidel over each row's
//!   response) and [`newton`] (rows and edges in one sparse system, Coulomb's cone,
//!   exact line search); [`settings`] the `Auto` choice's switch and the stopping rules;
//! - [`plugin`]: the systems — the Speculate sub-stage and the contact loop that
//!   re-projects after the collision stage's impulses.
//!
//! Imports: [`crate::constraints`] (islands, the edge projection's walks and factors),
//! [`crate::linalg`], [`crate::model`], [`crate::parallel`], [`crate::metrics`]; its
//! systems, [`crate::collision`] (the contact loop's impulses), [`crate::world`],
//! [`crate::schedule`] and [`crate::halving`] (the warm starts a halved step puts
//! back). Of the layers below, only [`crate::world`]'s configuration names a type of
//! it ([`ContactSolver`]).

pub mod active_set;
pub mod driver;
pub mod groups;
pub mod local_row;
pub mod newton;
pub mod plugin;
pub mod projection;
pub mod rows;
pub mod scratch;
pub mod settings;
pub mod speculative;
pub mod split;
pub mod sweeps;
pub mod warm;

pub use plugin::{ContactLoopPlugin, ContactRows};
pub use projection::project_with_contacts;
pub use rows::{ContactRow, RowImpulse};
pub use scratch::ContactScratch;
pub use settings::{ContactOutcome, ContactSettings, ContactSolver, Resting};
pub use split::CUT_ROWS;
