//! How a projection is asked to stop, and how it ended.

use bevy::prelude::Reflect;

/// Where the constraint direction is evaluated.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ConstraintDirection {
    /// At the latest iterate: fast projection, a symmetric system.
    #[default]
    EndOfStep,
    /// At the start of the step: torque-free impulses, angular momentum conserved.
    StartOfStep,
}

/// Stopping rule of the projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionSettings {
    /// Stop when every `|C_k| / L_k²` (≈ twice the relative length error) is at most this.
    pub tolerance: f64,
    /// Stop after this many linear solves even if the tolerance is not met.
    pub max_iterations: u32,
    /// Where the constraint direction is evaluated.
    pub direction: ConstraintDirection,
    /// How far (a distance per step) a contact row may fall short of its target.
    pub contact_tolerance: f64,
    /// Reject the projection (change nothing) if it would move any particle by more
    /// than this fraction of the island's shortest rest length in one step; infinite
    /// for no limit. Guards re-projections under contact, where nearly dependent
    /// constraints can ask for absurd corrections.
    pub max_correction: f64,
}

/// How a projection ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionOutcome {
    /// Linear solves performed.
    pub iterations: u32,
    /// Whether the edge tolerance was met. Contacts are met to their tolerance or as
    /// well as the complementarity solve could: see `contact_violation`.
    pub converged: bool,
    /// Final `max |C_k| / L_k²`.
    pub residual: f64,
    /// Final largest contact violation: how far (in distance per step) a contact row
    /// falls short of its target.
    pub contact_violation: f64,
    /// Whether a linear solve met a singular system; the velocities are then left as
    /// the last good iterate gives them.
    pub singular: bool,
    /// Edges of zero length, left as they are (they have no direction to act along).
    pub locked: u32,
    /// Whether the corrections exceeded `max_correction` and were not applied.
    pub rejected: bool,
}

/// The smallest `|C| / L²` asked for whatever the tolerance: edges are formed from
/// coordinate differences, so f64 resolves them to a few ulps of their own length and
/// asking for less would only spin.
pub const ROUND_OFF_FLOOR: f64 = 16.0 * f64::EPSILON;
