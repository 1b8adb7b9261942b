//! Splitting ahead: a step that follows a hard one is taken in parts from the start.
//!
//! Step halving (`halving`) takes a step again in halves once it has ended in the
//! fail-safe: it pays for the whole step first. At a game's step a landing makes
//! step after step hard — the speculative rows miss approaches that the collision
//! impulses and the contact loop's passes then mend, the contact projection runs out of
//! Newton steps — and each such step costs many times its share (measured in
//! docs/step-size.md: a 1/60 s step of a landing pile cost 16 times a 1/300 s step).
//! So the step itself adapts, as an ODE step-size controller does: a hard step sends
//! the next ones down a level (each level halves the part), and a run of easy steps
//! brings them back up one level, where a hard step sends them down again. Nothing
//! but the world's own figures decides, so the parts, like the rest of a step, are the
//! same whatever the thread count.

use crate::metrics::StrandMetrics;

/// Easy steps in a row after which the parts grow back one level.
pub const EASY_STEPS_TO_GROW: u32 = 8;

/// A step with more collision impulses than one per this many particles is hard.
pub const PARTICLES_PER_MISS: u64 = 256;

/// A step in which more than one contact projection in this many ran out of Newton
/// steps is hard.
pub const SOLVES_PER_CAP: u64 = 8;

/// What makes a step hard, read from the running totals before and after it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepWork {
    collisions: u64,
    solves: u64,
    capped: u64,
    failsafe: u64,
    halved: u64,
    particles: u64,
}

impl StepWork {
    /// The totals of `metrics` now.
    pub fn of(metrics: &StrandMetrics) -> Self {
        Self {
            collisions: metrics.collisions,
            solves: metrics.contact_projection.solves,
            capped: metrics.contact_projection.capped,
            failsafe: metrics.failsafe_steps,
            halved: metrics.halved_steps,
            particles: metrics.particles as u64,
        }
    }

    /// Whether the step between `before` and `self` was hard: the contact solve left
    /// approaches to the collision impulses at more than one particle in
    /// [`PARTICLES_PER_MISS`], or more than one of its projections in
    /// [`SOLVES_PER_CAP`] ran out of Newton steps, or the step needed halving or the
    /// fail-safe. (A few misses in a large world, or one group in thirty capped now and
    /// then in a pile at rest, are cheap to mend; quartering every step for them is
    /// not.)
    pub fn hard_since(&self, before: &Self) -> bool {
        // (Saturating: totals a user resets between ticks never count as a hard step.)
        let collisions = self.collisions.saturating_sub(before.collisions);
        let capped = self.capped.saturating_sub(before.capped);
        let solves = self.solves.saturating_sub(before.solves);
        collisions * PARTICLES_PER_MISS > self.particles
            || capped * SOLVES_PER_CAP > solves
            || self.failsafe > before.failsafe
            || self.halved > before.halved
    }
}

/// The level the steps are taken at: each step in `2^level` parts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SplitAhead {
    /// Halvings ahead of the next step.
    pub level: u32,
    /// Easy steps in a row at this level.
    easy: u32,
}

impl SplitAhead {
    /// After a step: down a level (at most `max_level`) if it was hard, up one after
    /// [`EASY_STEPS_TO_GROW`] easy ones in a row.
    pub fn after_step(&mut self, hard: bool, max_level: u32) {
        if hard {
            self.level = (self.level + 1).min(max_level);
            self.easy = 0;
        } else if self.level > 0 {
            self.easy += 1;
            if self.easy >= EASY_STEPS_TO_GROW {
                self.level -= 1;
                self.easy = 0;
            }
        }
        self.level = self.level.min(max_level);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn work(collisions: u64, particles: u64) -> StepWork {
        StepWork {
            collisions,
            particles,
            ..StepWork::default()
        }
    }

    #[test]
    fn a_step_is_hard_when_many_of_its_contact_projections_run_out() {
        let before = StepWork {
            solves: 100,
            capped: 10,
            particles: 3000,
            ..StepWork::default()
        };
        let after = |solves: u64, capped: u64| StepWork {
            solves: 100 + solves,
            capped: 10 + capped,
            ..before
        };
        // One group in thirty capped: easy; one in eight or more: hard.
        assert!(!after(30, 1).hard_since(&before));
        assert!(!after(16, 2).hard_since(&before));
        assert!(after(16, 3).hard_since(&before));
        assert!(after(1, 1).hard_since(&before));
    }

    #[test]
    fn a_step_is_hard_when_it_leaves_many_approaches_to_impulses_or_is_halved() {
        // 2 560 particles: up to ten impulses in a step are cheap to mend.
        let before = work(100, 2560);
        assert!(!work(100, 2560).hard_since(&before));
        assert!(!work(110, 2560).hard_since(&before));
        assert!(work(111, 2560).hard_since(&before));
        // One strand: a single impulse is already one per 256 particles and more.
        assert!(work(1, 60).hard_since(&work(0, 60)));
        let halved = StepWork {
            halved: 1,
            ..before
        };
        assert!(halved.hard_since(&before));
        let failed = StepWork {
            failsafe: 1,
            ..before
        };
        assert!(failed.hard_since(&before));
    }

    #[test]
    fn hard_steps_split_the_next_down_to_the_cap_and_easy_ones_grow_them_back() {
        let mut split = SplitAhead::default();
        for expected in [1, 2, 2, 2] {
            split.after_step(true, 2);
            assert_eq!(split.level, expected);
        }
        for _ in 1..EASY_STEPS_TO_GROW {
            split.after_step(false, 2);
            assert_eq!(split.level, 2);
        }
        split.after_step(false, 2);
        assert_eq!(split.level, 1);
        // A hard step in a run of easy ones starts the count again.
        for _ in 1..EASY_STEPS_TO_GROW {
            split.after_step(false, 2);
        }
        split.after_step(true, 2);
        assert_eq!(split.level, 2);
        for _ in 0..2 * EASY_STEPS_TO_GROW {
            split.after_step(false, 2);
        }
        assert_eq!(split.level, 0);
        // Off (a cap of 0) and a lowered cap.
        split.after_step(true, 0);
        assert_eq!(split.level, 0);
        split.level = 2;
        split.after_step(false, 1);
        assert_eq!(split.level, 1);
    }
}
