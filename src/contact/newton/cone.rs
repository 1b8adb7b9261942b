//! A contact row of the contact Newton as Coulomb's cone: its two edges in the row's
//! (normal, tangent) plane, the row's motion along them, and its impulses on the
//! particles.

use bevy::math::DVec2;

use super::kkt::NONE;
use crate::contact::local_row::LocalRow;

/// The edges of a row's cone in its (normal, tangent) plane; without friction one
/// edge, the normal (the second is then unused).
pub(super) fn cone(friction: f64) -> [(f64, f64); 2] {
    let s = (1.0 + friction * friction).sqrt();
    [(1.0 / s, friction / s), (1.0 / s, -friction / s)]
}

/// How many of a row's cone edges act.
pub(super) fn edges(friction: f64) -> usize {
    if friction > 0.0 { 2 } else { 1 }
}

/// `Σ cᵢ d·vᵢ` along the row's normal and tangent.
pub(super) fn row_motion(row: &LocalRow, v: &[DVec2]) -> (f64, f64) {
    motion_of(row, |j| v[j as usize])
}

/// `Σ cᵢ d·vᵢ` along the row's normal and tangent, with `v(j)` particle j's motion.
fn motion_of(row: &LocalRow, v: impl Fn(u32) -> DVec2) -> (f64, f64) {
    let (n, t) = (row.normal, row.normal.perp());
    let (mut a, mut b) = (0.0, 0.0);
    for &(j, c) in &row.entries[..row.count as usize] {
        let d = v(j);
        a += c * n.dot(d);
        b += c * t.dot(d);
    }
    (a, b)
}

/// A row's normal and tangent values `slack + Σ cᵢ d·Δᵢ` for corrections `delta`.
pub(super) fn row_values(row: &LocalRow, delta: &[DVec2]) -> (f64, f64) {
    let (a, b) = row_motion(row, delta);
    (row.slack_n + a, row.slack_t + b)
}

/// A row's motion along its normal and tangent for the particle unknowns in `x`.
pub(super) fn unknown_motion(row: &LocalRow, particle_unknown: &[u32], x: &[f64]) -> (f64, f64) {
    motion_of(row, |j| unknown_vector(particle_unknown, x, j))
}

/// Particle j's motion in the unknowns `x` (zero for a fixed particle).
pub(super) fn unknown_vector(particle_unknown: &[u32], x: &[f64], j: u32) -> DVec2 {
    let u = particle_unknown[j as usize];
    if u == NONE {
        DVec2::ZERO
    } else {
        DVec2::new(x[u as usize], x[u as usize + 1])
    }
}

/// The (normal, tangent) impulse of cone impulses `lambda`.
pub(super) fn impulse(friction: f64, lambda: [f64; 2]) -> (f64, f64) {
    let e = cone(friction);
    let mut out = (0.0, 0.0);
    for (edge, l) in e.iter().zip(lambda).take(edges(friction)) {
        out.0 += l * edge.0;
        out.1 += l * edge.1;
    }
    out
}

/// Add `row`'s impulse `(normal, tangent)` to the particles' impulses `p`.
pub(super) fn push(row: &LocalRow, impulse: (f64, f64), p: &mut [DVec2]) {
    let direction = impulse.0 * row.normal + impulse.1 * row.normal.perp();
    for &(j, c) in &row.entries[..row.count as usize] {
        p[j as usize] += c * direction;
    }
}

/// Add `tension` of the edge from `a` to `b` along `d` to `p`: it pulls the ends
/// together.
pub(super) fn pull(a: u32, b: u32, d: DVec2, tension: f64, p: &mut [DVec2]) {
    p[a as usize] += tension * d;
    p[b as usize] -= tension * d;
}
