//! A contact row as the contact projection holds it: its particles and coefficients, its
//! normal and slacks, and its impulses so far.

use bevy::math::DVec2;

/// A contact row in local terms. Its normal part `Σ cᵢ n·(v + Δᵢ/dt) ≥ target` reads
/// `slack_n + Σ cᵢ n·Δᵢ ≥ 0`; its tangent part asks for no sliding, `slack_t +
/// Σ cᵢ t·Δᵢ = 0`, with an impulse no larger than `friction` times the normal one.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LocalRow {
    /// `(local particle, coefficient)` of each free particle.
    pub(super) entries: [(u32, f64); 3],
    pub(super) count: u8,
    pub(super) normal: DVec2,
    pub(super) slack_n: f64,
    pub(super) slack_t: f64,
    pub(super) friction: f64,
    /// Total impulses so far, times dt (mass × length).
    pub(super) mu_n: f64,
    pub(super) mu_t: f64,
    /// The totals at the start of the Newton step.
    pub(super) start_n: f64,
    pub(super) start_t: f64,
    /// The row's own stiffness `N r` along the normal and the tangent, and the
    /// tangent's response to a normal impulse.
    pub(super) diag_n: f64,
    pub(super) diag_t: f64,
    pub(super) cross: f64,
    /// Whether its responses are computed (this projection).
    pub(super) ready: bool,
    /// Each part the row touches: `(part, offset in particle responses, offset in
    /// edge responses)`; the offsets are placed when the row first takes an impulse.
    pub(super) links: [(u32, u32, u32); 2],
    pub(super) link_count: u8,
}
