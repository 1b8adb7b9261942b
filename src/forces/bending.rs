//! The bending force between consecutive edges.
//!
//! Per bending vertex s between edges e₁ = x_s − x_a and e₂ = x_b − x_s, with signed
//! turning angle θ = atan2(e₁ × e₂, e₁ · e₂), the energy is `K (θ − θ̄)²` with
//! K = k_b / ℓ̄. Its gradient: ∂θ/∂x_a = e₁⊥/|e₁|², ∂θ/∂x_b = e₂⊥/|e₂|², and ∂θ/∂x_s
//! their negated sum. Damping acts on the angle rate θ̇ = Σ ∂θ/∂x_i · v_i.

use bevy::math::DVec2;

use crate::model::Bend;
use crate::model::geometry::{turning_angle, wrap_angle};
use crate::parallel::{run_each, split_at_cuts};

/// A bend's edge vectors `x_s − x_a`, `x_b − x_s` and its turning angle's gradient
/// `∂θ/∂(x_a, x_s, x_b)`; none where an edge has zero length.
#[inline]
pub fn bend_gradient(bend: &Bend, position: &[DVec2]) -> Option<([DVec2; 2], [DVec2; 3])> {
    let (a, s, b) = (bend.a as usize, bend.s as usize, bend.b as usize);
    let e1 = position[s] - position[a];
    let e2 = position[b] - position[s];
    let (l1, l2) = (e1.length_squared(), e2.length_squared());
    if l1 == 0.0 || l2 == 0.0 {
        return None;
    }
    let grad_a = e1.perp() / l1;
    let grad_b = e2.perp() / l2;
    Some(([e1, e2], [grad_a, -(grad_a + grad_b), grad_b]))
}

/// Add the bending force of every element.
pub fn add_bending(bends: &[Bend], position: &[DVec2], velocity: &[DVec2], force: &mut [DVec2]) {
    add_bending_from(bends, position, velocity, force, 0);
}

/// [`add_bending`] with `force` starting at particle `base`: every bend's particles
/// must lie in `base..base + force.len()`.
fn add_bending_from(
    bends: &[Bend],
    position: &[DVec2],
    velocity: &[DVec2],
    force: &mut [DVec2],
    base: usize,
) {
    for bend in bends {
        let (a, s, b) = (bend.a as usize, bend.s as usize, bend.b as usize);
        let Some(([e1, e2], [grad_a, grad_s, grad_b])) = bend_gradient(bend, position) else {
            continue;
        };
        let theta = turning_angle(e1, e2);
        let rate = grad_a.dot(velocity[a]) + grad_s.dot(velocity[s]) + grad_b.dot(velocity[b]);
        let magnitude =
            -2.0 * bend.stiffness * wrap_angle(theta - bend.rest_angle) - bend.damping * rate;
        // Shares cut for other bends would reach outside `force`: such a term is
        // dropped, not a panic (the plugin cuts again on every topology change).
        for (i, f) in [(a, grad_a), (s, grad_s), (b, grad_b)] {
            let slot = force.get_mut(i.wrapping_sub(base));
            debug_assert!(slot.is_some(), "a bend outside its share");
            if let Some(slot) = slot {
                *slot += magnitude * f;
            }
        }
    }
}

/// Below this many bends the forces stay on one thread: a bend costs tens of
/// nanoseconds (its `atan2`), starting a thread tens of microseconds.
const PARALLEL_BENDS: usize = 8192;

/// How [`add_bending_shared`] shares the bends between threads: contiguous runs of
/// bends, cut only where no particle is touched on both sides of the cut (between
/// strands, whose particles are contiguous), so that each share writes its own range of
/// the forces and every particle's sum is taken in the same order as on one thread —
/// the result is the same bit for bit whatever the count. Found once per topology.
#[derive(Clone, Debug, Default)]
pub struct BendingShares {
    /// The shares' first bends, then the bend count.
    cuts: Vec<usize>,
    /// Each share's lowest particle (0 for the first), then the particle count.
    bases: Vec<usize>,
    /// `low[k]`: the lowest particle of bends `k..` (scratch).
    low: Vec<u32>,
}

impl BendingShares {
    /// Cut `bends` (over `particles` particles) into at most `threads` shares of about
    /// equal size; one share below `PARALLEL_BENDS` bends or on one thread.
    pub fn cut(&mut self, bends: &[Bend], particles: usize, threads: usize) {
        let n = bends.len();
        let span = |bend: &Bend| {
            let (a, s, b) = (bend.a, bend.s, bend.b);
            (a.min(s).min(b) as usize, a.max(s).max(b) as usize)
        };
        let Self { cuts, bases, low } = self;
        cuts.clear();
        bases.clear();
        cuts.push(0);
        bases.push(0);
        if threads > 1 && n >= PARALLEL_BENDS {
            low.clear();
            low.resize(n + 1, u32::MAX);
            for k in (0..n).rev() {
                low[k] = low[k + 1].min(span(&bends[k]).0 as u32);
            }
            // A cut before bend k is clean when every bend before it stays below low[k].
            let (mut highest, mut k) = (0usize, 0usize);
            for t in 1..threads {
                let target = (n * t / threads).max(cuts[cuts.len() - 1] + 1);
                while k < n && (k < target || highest >= low[k] as usize) {
                    highest = highest.max(span(&bends[k]).1);
                    k += 1;
                }
                if k < n {
                    cuts.push(k);
                    bases.push(low[k] as usize);
                }
            }
        }
        cuts.push(n);
        bases.push(particles);
    }

    /// Shares found by the last [`BendingShares::cut`].
    pub fn len(&self) -> usize {
        self.cuts.len().saturating_sub(1)
    }

    /// Whether [`BendingShares::cut`] has not run.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// [`add_bending`] in the shares `shares`, each on its own thread (the first on this
/// one). `shares` must be cut for these `bends` and `force.len()` particles; cut for a
/// different topology, they are used only if the counts agree, and then a bend that
/// reaches outside its share loses its force.
pub fn add_bending_shared(
    bends: &[Bend],
    position: &[DVec2],
    velocity: &[DVec2],
    force: &mut [DVec2],
    shares: &BendingShares,
) {
    let valid = shares.cuts.last() == Some(&bends.len())
        && shares.bases.last() == Some(&force.len())
        && shares.len() > 1;
    if !valid {
        add_bending(bends, position, velocity, force);
        return;
    }
    let parts = split_at_cuts(force, &shares.bases);
    run_each(parts, |i, force| {
        let bends = &bends[shares.cuts[i]..shares.cuts[i + 1]];
        add_bending_from(bends, position, velocity, force, shares.bases[i]);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bend() -> Bend {
        Bend {
            a: 0,
            s: 1,
            b: 2,
            rest_angle: 0.0,
            stiffness: 0.7,
            damping: 0.0,
            rest_lengths: [1.0, 1.0],
        }
    }

    fn energy(position: &[DVec2]) -> f64 {
        let e1 = position[1] - position[0];
        let e2 = position[2] - position[1];
        0.7 * e1.perp_dot(e2).atan2(e1.dot(e2)).powi(2)
    }

    #[test]
    fn force_is_minus_the_energy_gradient() {
        let position = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.2),
            DVec2::new(1.7, 0.9),
        ];
        let mut force = [DVec2::ZERO; 3];
        add_bending(&[bend()], &position, &[DVec2::ZERO; 3], &mut force);
        let h = 1e-6;
        for i in 0..3 {
            for axis in [DVec2::X, DVec2::Y] {
                let mut plus = position;
                let mut minus = position;
                plus[i] += h * axis;
                minus[i] -= h * axis;
                let numeric = -(energy(&plus) - energy(&minus)) / (2.0 * h);
                assert!((force[i].dot(axis) - numeric).abs() < 1e-7, "particle {i}");
            }
        }
        let total: DVec2 = force.iter().sum();
        assert!(total.length() < 1e-12);
    }

    /// `strands` wiggly strands of `particles`, moving, with a bend per vertex; and
    /// `links` bends joining strand ends far apart (as a tree's joints do).
    fn many_strands(strands: usize, particles: usize) -> (Vec<Bend>, Vec<DVec2>, Vec<DVec2>) {
        let (mut bends, mut position, mut velocity) = (Vec::new(), Vec::new(), Vec::new());
        for s in 0..strands {
            let first = position.len() as u32;
            for i in 0..particles {
                let t = (s * 31 + i * 7) as f64;
                position.push(DVec2::new(i as f64 * 0.01, 0.002 * t.sin() + s as f64));
                velocity.push(DVec2::new(0.1 * t.cos(), -0.05 * (1.3 * t).sin()));
                if i >= 2 {
                    let b = first + i as u32;
                    bends.push(Bend {
                        a: b - 2,
                        s: b - 1,
                        b,
                        rest_angle: 0.01 * (t % 3.0),
                        stiffness: 0.5,
                        damping: 1e-3,
                        rest_lengths: [0.01, 0.01],
                    });
                }
            }
        }
        (bends, position, velocity)
    }

    /// The forces on `threads` threads, and the shares they were cut into.
    fn forces(
        bends: &[Bend],
        position: &[DVec2],
        velocity: &[DVec2],
        threads: usize,
    ) -> (Vec<DVec2>, usize) {
        let mut force = vec![DVec2::ZERO; position.len()];
        let mut shares = BendingShares::default();
        shares.cut(bends, position.len(), threads);
        add_bending_shared(bends, position, velocity, &mut force, &shares);
        (force, shares.len())
    }

    #[test]
    fn threads_give_the_same_forces_bit_for_bit() {
        let (mut bends, position, velocity) = many_strands(700, 16); // 9 800 bends
        let (one, _) = forces(&bends, &position, &velocity, 1);
        for threads in [2, 3, 8] {
            assert_eq!(
                forces(&bends, &position, &velocity, threads),
                (one.clone(), threads)
            );
        }
        // A bend joining the first strand to the last leaves no clean cut: one share.
        let mut joint = bends[0];
        (joint.a, joint.s, joint.b) = (0, 1, position.len() as u32 - 1);
        bends.push(joint);
        let (one, _) = forces(&bends, &position, &velocity, 1);
        assert_eq!(forces(&bends, &position, &velocity, 2), (one, 1));
        // One joining two neighbouring strands only moves the cut.
        bends.pop();
        (joint.a, joint.s, joint.b) = (16 * 349 + 15, 16 * 350, 16 * 350 + 1);
        bends.insert(349 * 14 + 5, joint);
        let (one, _) = forces(&bends, &position, &velocity, 1);
        assert_eq!(forces(&bends, &position, &velocity, 2), (one.clone(), 2));
        assert!(one.iter().all(|f| f.is_finite()) && one.iter().any(|f| *f != DVec2::ZERO));
    }
}
