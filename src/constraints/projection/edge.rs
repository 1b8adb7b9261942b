//! One edge in a projection: what every projection — an island's, each substep of a
//! re-stepped one's, a contact group's — does with an edge, written once. Per edge k
//! from a to b, `C_k = |d|² − L²` with `d` the edge at the predicted end of the step
//! moved by the corrections; a Newton step's multiplier `λ` moves its ends by the
//! impulse `2λd`, weighted by their inverse masses.

use bevy::math::DVec2;

/// An edge with no direction to act along: of zero length where it is taken, or with
/// no free end (`free` is its ends' inverse masses summed). It is left as it is.
#[inline]
pub(crate) fn locked(edge: DVec2, free: f64) -> bool {
    edge.length_squared() * free <= 0.0
}

/// The edge from its predicted vector and its ends' corrections, and its constraint
/// value `|d|² − L²`.
#[inline]
pub(crate) fn at(predicted: DVec2, from: DVec2, to: DVec2, rest_squared: f64) -> (DVec2, f64) {
    let d = predicted + (to - from);
    (d, d.length_squared() - rest_squared)
}

/// The impulse `2λd` applied to the edge's ends (a pulled back, b pushed on), each by
/// its inverse mass: equal and opposite, so momentum is kept.
#[inline]
pub(crate) fn apply(
    motion: &mut [DVec2],
    inverse_mass: &[f64],
    (a, b): (usize, usize),
    impulse: DVec2,
) {
    motion[a] -= inverse_mass[a] * impulse;
    motion[b] += inverse_mass[b] * impulse;
}
