//! The energy check: a speed no force in the scene can explain freezes its island.
//!
//! Edges stay exact and values finite while a solve pumps energy in — a rope whirling a
//! crate at 10 m/s where its pendulum peaks at 1 m/s is finite and unstretched, and
//! wrong. At each tick's end the scene's mechanical energy (kinetic, gravitational,
//! bending, springs, over the free particles) is compared with what it may be: the
//! lowest it has been since the scene was last driven or changed, plus the work the
//! external forces did since (a constant force over a tick does `F·Δx`, whatever the
//! path). Constraints and contacts do no work, damping and friction only take energy
//! out, so anything above that came from the solve. The check allows for the solve's
//! honest small gains (a contact pushing a point out, the integrator's error) with a
//! wide margin: it acts when the kinetic energy is over four times what the budget
//! leaves for motion (speeds twice what can be explained) plus the whole free mass
//! moving at a quarter second of free fall or a thickness a step — never on a scene
//! that is only imperfect, always on one that whirls or blows up.
//!
//! A tick that something drives — a kinematic particle moving (an anchor, a collider,
//! a body's outline), a tether, a winch changing a length, a position or velocity the
//! game wrote (a particle dragged, thrown or teleported),
//! particles coming, going, sleeping, waking or freezing — starts a new account: its
//! energy is not compared. The energies are taken every [`CHECK_TICKS`] ticks (a pass
//! over every particle and bend costs a large scene 8 % of its tick), the external work
//! and what drove the scene every tick.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::forces::energy::{angle_bending_energy, gravity_energy, kinetic_energy, spring_energy};
use crate::forces::quadratic_bending::quadratic_bending_energy;
use crate::model::{Bend, Edge};
use crate::world::config::BendingModel;
use crate::world::state::ParticleState;

/// How far above the budget's speed the kinetic energy may go: four times the energy,
/// twice the speed.
pub const ENERGY_MARGIN: f64 = 4.0;

/// A scene's mechanical energy, by kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MechanicalEnergy {
    /// `Σ ½ m v²`.
    pub kinetic: f64,
    /// `−Σ m g·x`.
    pub gravity: f64,
    /// The bending model's energy.
    pub bending: f64,
    /// The stretch springs' energy.
    pub springs: f64,
}

impl MechanicalEnergy {
    /// Of the particles `counted` marks (the bends' and springs' energy in full: a bend
    /// between pinned particles stores a constant).
    pub fn of(
        state: &ParticleState,
        (edges, bends): (&[Edge], &[Bend]),
        bending: BendingModel,
        gravity: DVec2,
        counted: &[bool],
    ) -> Self {
        Self {
            kinetic: kinetic_energy(&state.mass, &state.velocity, counted),
            gravity: gravity_energy(&state.mass, &state.position, counted, gravity),
            bending: match bending {
                BendingModel::Quadratic => quadratic_bending_energy(bends, &state.position),
                BendingModel::Angle | BendingModel::AngleExplicit => {
                    angle_bending_energy(bends, &state.position)
                }
            },
            springs: spring_energy(edges, &state.position),
        }
    }

    /// The sum.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.bending + self.springs
    }
}

/// The work the external forces did on the free particles over a tick that began at
/// `start` (forces constant through a tick).
pub fn external_work(state: &ParticleState, start: &[DVec2]) -> f64 {
    (state.external_force.iter().zip(&state.position))
        .zip(start.iter().zip(&state.inverse_mass))
        .filter(|((f, _), (_, w))| **w != 0.0 && **f != DVec2::ZERO)
        .map(|((f, x), (x0, _))| f.dot(*x - *x0))
        .sum()
}

/// A checksum of every particle's position and velocity, bit for bit.
fn checksum(state: &ParticleState) -> u64 {
    let bits = |v: &DVec2| v.x.to_bits().rotate_left(17) ^ v.y.to_bits();
    (state.position.iter().zip(&state.velocity)).fold(state.len() as u64, |h, (x, v)| {
        (h.rotate_left(5) ^ bits(x) ^ bits(v).rotate_left(31)).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    })
}

/// Ticks between checks: the energies cost a pass over every particle and bend, which a
/// large scene feels every tick; a blow-up is caught within this many.
pub const CHECK_TICKS: u32 = 4;

/// Whether `kinetic` energy is more than the motion can explain: the energy `allowed`
/// less the `potential` the particles have now is what may move them; `slack` the
/// allowance for honest gains.
pub fn unexplained(kinetic: f64, potential: f64, allowed: f64, slack: f64) -> bool {
    kinetic > ENERGY_MARGIN * (allowed - potential).max(0.0) + slack
}

/// The kinetic energy allowed on top of the budget, for a scene at rest (whose budget
/// is nil): the free mass `mass` at the speed of a twentieth of a second's fall under
/// `gravity` and a tenth of a `thickness` a step `dt`.
pub fn slack(mass: f64, gravity: DVec2, thickness: f64, dt: f64) -> f64 {
    let speed = 0.05 * gravity.length() + 0.1 * thickness / dt;
    0.5 * mass * speed * speed
}

/// What drives the scene this tick besides its forces: a kinematic particle with a
/// velocity, or a tether (`tethered`).
pub fn driven(state: &ParticleState, tethered: bool) -> bool {
    let moving = (state.inverse_mass.iter().zip(&state.velocity))
        .any(|(w, v)| *w == 0.0 && *v != DVec2::ZERO);
    moving || tethered
}

/// The account between ticks.
#[derive(Default, Debug)]
pub struct EnergyAccount {
    /// The energy the scene may have; `None` until an undriven tick starts an account.
    allowed: Option<f64>,
    /// What the account was opened on: which particles are free, the edges' rest
    /// lengths and the bends. A change opens a new one.
    signature: (usize, usize, u64, usize, u64),
    /// Positions at the tick's start.
    pub(super) tick_start: Vec<DVec2>,
    /// Per packed particle, whether it is free (counted).
    pub(super) counted: Vec<bool>,
    /// A checksum of the positions and velocities written back at the last tick's end:
    /// the next tick's gather finding others means the game wrote some (a particle
    /// dragged, thrown, teleported), which drove the scene.
    written_back: Option<u64>,
    /// Since the last check: the ticks, the external forces' work, and whether
    /// something drove the scene.
    pending: (u32, f64, bool),
}

/// What the account says of a tick.
#[derive(Debug, PartialEq)]
pub enum Verdict {
    /// Driven, changed, or the first: a new account is opened.
    Opened,
    /// Within the budget.
    Explained,
    /// More kinetic energy than anything explains.
    Unexplained,
}

impl EnergyAccount {
    /// Mark the free particles, and note what the account depends on.
    /// A tick's start, once gathered: note its positions, and whether the game wrote
    /// any position or velocity since the last tick's end.
    pub fn begin_tick(&mut self, state: &ParticleState) {
        self.tick_start.clear();
        self.tick_start.extend_from_slice(&state.position);
        let written = self.written_back.take() != Some(checksum(state));
        self.pending.2 |= written;
    }

    /// The state the tick's end writes back.
    pub fn end_tick(&mut self, state: &ParticleState) {
        self.written_back = Some(checksum(state));
    }

    /// A tick's end: add its external work and whether it was `driven`. Whether the
    /// account is due a check.
    pub fn accrue(&mut self, state: &ParticleState, driven: bool) -> bool {
        let (ticks, work, was_driven) = &mut self.pending;
        *ticks += 1;
        *work += external_work(state, &self.tick_start);
        *was_driven |= driven;
        *ticks >= CHECK_TICKS
    }

    /// The work and drive since the last check, which this one consumes.
    pub fn take_pending(&mut self) -> (f64, bool) {
        let (_, work, driven) = std::mem::take(&mut self.pending);
        (work, driven)
    }

    /// Whether any of that changed since the last check.
    pub fn count(&mut self, state: &ParticleState, edges: &[Edge], bends: &[Bend]) -> bool {
        self.counted.clear();
        self.counted
            .extend((0..state.len()).map(|i| !state.is_pinned(i)));
        let (mut free, mut index_sum) = (0usize, 0u64);
        for (i, _) in self.counted.iter().enumerate().filter(|(_, c)| **c) {
            free += 1;
            index_sum = index_sum.wrapping_add(i as u64 + 1);
        }
        let lengths: f64 = edges.iter().map(|e| e.rest_length).sum();
        let signature = (state.len(), free, index_sum, bends.len(), lengths.to_bits());
        std::mem::replace(&mut self.signature, signature) != signature
    }

    /// Take the tick's end: `open` (changed, from [`count`](Self::count), or driven)
    /// opens a new account; otherwise the `energy` is checked against the budget plus
    /// the external forces' `work`, with `slack`.
    pub fn settle(
        &mut self,
        energy: MechanicalEnergy,
        work: f64,
        slack: f64,
        open: bool,
    ) -> Verdict {
        let (kinetic, energy) = (energy.kinetic, energy.total());
        let potential = energy - kinetic;
        if !(energy.is_finite() && work.is_finite()) {
            // The finiteness checks freeze what made it; nothing to compare with.
            self.allowed = None;
            return Verdict::Opened;
        }
        let Some(allowed) = self.allowed.filter(|_| !open) else {
            self.allowed = Some(energy);
            return Verdict::Opened;
        };
        let allowed = allowed + work;
        if unexplained(kinetic, potential, allowed, slack) {
            self.allowed = None;
            return Verdict::Unexplained;
        }
        // What the scene loses it does not get back.
        self.allowed = Some(allowed.min(energy));
        Verdict::Explained
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn energy(kinetic: f64, gravity: f64) -> MechanicalEnergy {
        MechanicalEnergy {
            kinetic,
            gravity,
            bending: 0.0,
            springs: 0.0,
        }
    }

    #[test]
    fn the_account_allows_what_falls_and_what_is_pushed_and_no_more() {
        let mut account = EnergyAccount::default();
        let slack = 0.01;
        assert_eq!(
            account.settle(energy(0.0, 10.0), 0.0, slack, false),
            Verdict::Opened
        );
        // A fall turns height into speed: explained, up to four times over.
        assert_eq!(
            account.settle(energy(5.0, 5.0), 0.0, slack, false),
            Verdict::Explained
        );
        assert_eq!(
            account.settle(energy(40.0, 0.0), 0.0, slack, false),
            Verdict::Explained
        );
        assert_eq!(
            account.settle(energy(40.1, 0.0), 0.0, slack, false),
            Verdict::Unexplained
        );
        // A push's work is allowed on top.
        let mut account = EnergyAccount::default();
        account.settle(energy(1.0, 0.0), 0.0, slack, false);
        assert_eq!(
            account.settle(energy(30.0, 0.0), 9.0, slack, false),
            Verdict::Explained
        );
        // What is lost is not given back: after damping took it to 0.5, 2.1 is too much.
        let mut account = EnergyAccount::default();
        account.settle(energy(1.0, 0.0), 0.0, slack, false);
        account.settle(energy(0.5, 0.0), 0.0, slack, false);
        assert_eq!(
            account.settle(energy(2.1, 0.0), 0.0, slack, false),
            Verdict::Unexplained
        );
        // A driven tick opens a new account from where it ends.
        let mut account = EnergyAccount::default();
        account.settle(energy(1.0, 0.0), 0.0, slack, false);
        assert_eq!(
            account.settle(energy(100.0, 0.0), 0.0, slack, true),
            Verdict::Opened
        );
        assert_eq!(
            account.settle(energy(100.0, 0.0), 0.0, slack, false),
            Verdict::Explained
        );
        // At rest the slack is all there is; non-finite energy opens nothing to compare.
        let mut account = EnergyAccount::default();
        account.settle(energy(0.0, 0.0), 0.0, slack, false);
        assert_eq!(
            account.settle(energy(0.009, 0.0), 0.0, slack, false),
            Verdict::Explained
        );
        assert_eq!(
            account.settle(energy(0.011, 0.0), 0.0, slack, false),
            Verdict::Unexplained
        );
        assert_eq!(
            account.settle(energy(f64::NAN, 0.0), 0.0, slack, false),
            Verdict::Opened
        );
    }
}
