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
    /// An island whose projection does not converge is stepped again in substeps,
    /// halved down to `dt / 2^max_restep_depth` where they fail; 0: never (the
    /// projection then ends capped).
    pub max_restep_depth: u32,
}

/// The deepest re-stepping [`ProjectionSettings::max_restep_depth`] may ask for:
/// substeps of `dt / 2^30`.
pub const MAX_RESTEP_DEPTH: u32 = 30;

/// How a projection ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProjectionOutcome {
    /// Linear solves performed.
    pub iterations: u32,
    /// Whether the edge tolerance was met.
    pub converged: bool,
    /// Final `max |C_k| / L_k²`.
    pub residual: f64,
    /// Whether a linear solve met a singular system; the velocities are then left as
    /// the last good iterate gives them.
    pub singular: bool,
    /// Edges of zero length, left as they are (they have no direction to act along).
    pub locked: u32,
    /// Whether the corrections were too large to be applied (a contact projection's
    /// guard) and were not.
    pub rejected: bool,
    /// Whether the island was stepped again in substeps after one projection failed.
    pub restepped: bool,
    /// The substeps it then took (0 when not re-stepped).
    pub substeps: u32,
}

/// The smallest `|C| / L²` asked for whatever the tolerance: edges are formed from
/// coordinate differences, so f64 resolves them to a few ulps of their own length and
/// asking for less would only spin.
pub const ROUND_OFF_FLOOR: f64 = 16.0 * f64::EPSILON;
