//! The report's energy account: the scene's mechanical energy (kinetic, gravitational,
//! bending, springs) at the end of every tick, and the largest rise above an earlier
//! low while nothing drove the motion — energy no force in the scene put in, which the
//! contact solve or the integration must have.

use bevy::prelude::*;
use bevy_strands::guard::energy::MechanicalEnergy;
use bevy_strands::prelude::*;
use bevy_strands::world::topology::Topology;

use crate::free::FreeParticles;

/// What drives a tick: its energy is then not compared with the ticks before.
/// `tethers` keeps the query of tethered particles from tick to tick.
fn driven(
    world: &World,
    state: &ParticleState,
    tethers: &mut Option<QueryState<(), With<Tether>>>,
) -> bool {
    let pushed = state
        .external_force
        .iter()
        .any(|f| *f != bevy::math::DVec2::ZERO);
    if tethers.is_none() {
        *tethers = world.try_query_filtered::<(), With<Tether>>();
    }
    let tethered = tethers
        .as_mut()
        .is_some_and(|q| q.iter(world).next().is_some());
    pushed || bevy_strands::guard::energy::driven(state, tethered)
}

/// The account, updated after every tick.
#[derive(Default)]
pub struct EnergyLedger {
    /// Energy at the end of the first tick.
    pub start: Option<f64>,
    /// Energy at the end of the latest tick.
    pub end: f64,
    /// The lowest energy since the scene was last driven or changed.
    low: Option<f64>,
    /// The largest rise above such a low.
    pub largest_rise: f64,
    /// Ticks in which something drove the scene or particles came or went.
    pub driven_ticks: u64,
    particles: usize,
    counted: Vec<bool>,
    free: FreeParticles,
    tethers: Option<QueryState<(), With<Tether>>>,
}

impl EnergyLedger {
    /// Take the energy at the end of a tick.
    pub fn observe(&mut self, world: &World) {
        let state = world.resource::<ParticleState>();
        let topology = world.resource::<Topology>();
        let config = world.resource::<StrandsConfig>();
        self.free.mark(world, &mut self.counted);
        let energy = MechanicalEnergy::of(
            state,
            (&topology.edges, &topology.bends),
            config.bending,
            config.gravity,
            &self.counted,
        )
        .total();
        if !energy.is_finite() {
            return; // the guard reports a non-finite state
        }
        let changed = self.start.is_some() && state.len() != self.particles;
        self.particles = state.len();
        self.start.get_or_insert(energy);
        self.end = energy;
        if changed || driven(world, state, &mut self.tethers) {
            self.driven_ticks += 1;
            self.low = Some(energy);
            return;
        }
        let low = self.low.get_or_insert(energy);
        *low = low.min(energy);
        self.largest_rise = self.largest_rise.max(energy - *low);
    }
}
