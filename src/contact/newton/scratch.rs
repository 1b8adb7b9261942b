//! The contact Newton's buffers, reused from one contact projection to the next.

use bevy::math::DVec2;

use super::kkt::{Kkt, RowModel};

/// The buffers of the contact Newton, reused.
#[derive(Clone, Debug, Default)]
pub(in crate::contact) struct NewtonScratch {
    pub(super) kkt: Kkt,
    pub(super) model: Vec<RowModel>,
    /// Which rows the system's pattern holds.
    pub(super) included: Vec<bool>,
    /// Which of each row's cone edges the model presses.
    pub(super) pressed: Vec<[bool; 2]>,
    /// Each row's stiffness (zero: the row is inert).
    pub(super) stiffness: Vec<f64>,
    /// Impulses (mass × length) on each local particle: Δ = W P.
    pub(super) momentum: Vec<DVec2>,
    pub(super) start: Vec<DVec2>,
    pub(super) step: Vec<DVec2>,
    /// Each row's cone impulses λ± at the iterate, at the line's start and along it.
    pub(super) lambda: Vec<[f64; 2]>,
    pub(super) start_lambda: Vec<[f64; 2]>,
    pub(super) step_lambda: Vec<[f64; 2]>,
    /// Whether this Newton step is taken whole (see `newton::edge_force`).
    pub(super) whole: bool,
    /// Each row's shifts λ̄± / k, and its lift.
    pub(super) shift: Vec<[f64; 2]>,
    pub(super) lift: Vec<f64>,
    /// Each local edge's impulse (tension positive) at the iterate, the line's start
    /// and along it.
    pub(super) tension: Vec<f64>,
    pub(super) start_tension: Vec<f64>,
    pub(super) step_tension: Vec<f64>,
    /// Each local edge's curvature in this step's system.
    pub(super) curvature: Vec<f64>,
    /// Each row's shifted cone values at the line's start, their change along it, and
    /// their values at the end of the last step when the line search stopped short.
    pub(super) value: Vec<[f64; 2]>,
    pub(super) slope: Vec<[f64; 2]>,
    pub(super) ahead: Vec<[f64; 2]>,
    pub(super) full: Vec<f64>,
    pub(super) feasible: Vec<f64>,
}
