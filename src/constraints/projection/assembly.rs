//! Assembling an island's system `J W Dᵀ` at the current iterate and solving it: a
//! tridiagonal (Thomas) or cyclic (Sherman–Morrison) system for a chain, a sparse
//! LDLᵀ in the layout's elimination order for a tree or graph.

use bevy::math::DVec2;

use super::scratch::IslandScratch;
use super::settings::ConstraintDirection;
use crate::constraints::graph::GraphLayout;
use crate::linalg::SingularPivot;
use crate::linalg::tridiagonal::solve_tridiagonal;

/// Assemble the tridiagonal (or cyclic) system of a chain and solve it for the
/// right-hand side in `s.rhs`, keeping the factor when contact columns will follow.
pub(super) fn chain_solve(
    m: usize,
    closed: bool,
    direction_kind: ConstraintDirection,
    keep_factor: bool,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let particles = if closed { m } else { m + 1 };
    let next = |k: usize| if k + 1 == particles { 0 } else { k + 1 };
    let w = &s.inverse_mass;
    let direction: &[DVec2] = match direction_kind {
        ConstraintDirection::EndOfStep => &s.edge[..m],
        ConstraintDirection::StartOfStep => &s.start_direction[..m],
    };
    for k in 0..m {
        let prev_edge = if k == 0 { m - 1 } else { k - 1 };
        let next_edge = if k + 1 == m { 0 } else { k + 1 };
        let e = s.edge[k];
        s.diagonal[k] = 4.0 * (w[k] + w[next(k)]) * e.dot(direction[k]);
        s.lower[k] = -4.0 * w[k] * e.dot(direction[prev_edge]);
        s.upper[k] = -4.0 * w[next(k)] * e.dot(direction[next_edge]);
    }
    // A locked edge gets δ = 0: an identity row, and no coupling into its neighbours.
    for k in (0..m).filter(|&k| s.locked[k]) {
        s.diagonal[k] = 1.0;
        (s.lower[k], s.upper[k]) = (0.0, 0.0);
        if k + 1 < m || closed {
            s.lower[if k + 1 == m { 0 } else { k + 1 }] = 0.0;
        }
        if k > 0 || closed {
            s.upper[if k == 0 { m - 1 } else { k - 1 }] = 0.0;
        }
    }
    if !closed {
        // An open chain's first and last rows have no outer neighbours.
        s.lower[0] = 0.0;
        s.upper[m - 1] = 0.0;
    }
    if closed && m >= 3 {
        s.factors
            .cyclic
            .factor(&s.lower[..m], &s.diagonal[..m], &s.upper[..m])?;
        s.factors.cyclic.solve(&mut s.rhs[..m]);
    } else if keep_factor {
        s.factors
            .open
            .factor(&s.lower[..m], &s.diagonal[..m], &s.upper[..m])?;
        s.factors.open.solve(&mut s.rhs[..m]);
    } else {
        // One right-hand side: the fused single-pass Thomas solve is fastest.
        solve_tridiagonal(
            &s.lower[..m],
            &s.diagonal[..m],
            &s.upper[..m],
            &mut s.rhs[..m],
            &mut s.thomas[..m],
        )?;
    }
    Ok(())
}

/// Assemble `J W Jᵀ` of a tree or graph (end-of-step direction) into its sparse factor,
/// factor it and solve for the right-hand side in `s.rhs`.
pub(super) fn graph_solve(
    m: usize,
    layout: &GraphLayout,
    s: &mut IslandScratch,
) -> Result<(), SingularPivot> {
    let w = &s.inverse_mass;
    let values = s.factors.sparse.values_mut(&layout.plan);
    let edges = layout.ends.iter().zip(&s.edge[..m]).zip(&s.locked[..m]);
    for (value, ((&(a, b), e), &locked)) in values.iter_mut().zip(edges) {
        *value = if locked {
            1.0
        } else {
            4.0 * (w[a as usize] + w[b as usize]) * e.length_squared()
        };
    }
    for c in &layout.couplings {
        let (k, l) = (c.k as usize, c.l as usize);
        if !s.locked[k] && !s.locked[l] {
            values[c.value as usize] +=
                4.0 * w[c.particle as usize] * c.sign * s.edge[k].dot(s.edge[l]);
        }
    }
    s.factors.sparse.factor(&layout.plan)?;
    s.factors.sparse.solve(&layout.plan, &mut s.rhs[..m]);
    Ok(())
}
