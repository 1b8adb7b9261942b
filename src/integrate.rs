//! Symplectic Euler: the predictor (`v* = v + dt f / m`) and the position update
//! (`x += dt v`) from the velocities the constraint and collision stages filtered.
//!
//! Pinned and kinematic particles have inverse mass 0, so the predictor leaves their
//! velocity alone: zero for a pinned one, the prescribed one for a kinematic one.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::model::motion::end_of_step;
use crate::schedule::{StepSet, StrandsStep};
use crate::world::clock::SimulationClock;
use crate::world::config::StrandsConfig;
use crate::world::state::ParticleState;

/// `v += dt w f` for every particle.
pub fn predict_velocities(velocity: &mut [DVec2], force: &[DVec2], inverse_mass: &[f64], dt: f64) {
    for ((v, &f), &w) in velocity.iter_mut().zip(force).zip(inverse_mass) {
        *v += dt * w * f;
    }
}

/// Every particle to the end of its step's motion, `x += dt v`.
pub fn advance_positions(position: &mut [DVec2], velocity: &[DVec2], dt: f64) {
    for (x, &v) in position.iter_mut().zip(velocity) {
        *x = end_of_step(*x, v, dt);
    }
}

/// The Predict and Integrate stages.
pub struct IntegratorPlugin;

impl Plugin for IntegratorPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            StrandsStep,
            (
                predict.in_set(StepSet::Predict),
                integrate.in_set(StepSet::Integrate),
            ),
        );
    }
}

/// The Predict stage.
pub fn predict(config: Res<StrandsConfig>, mut state: ResMut<ParticleState>) {
    let ParticleState {
        velocity,
        force,
        inverse_mass,
        ..
    } = &mut *state;
    predict_velocities(velocity, force, inverse_mass, config.dt);
}

/// The Integrate stage; also advances the simulation clock.
pub fn integrate(
    config: Res<StrandsConfig>,
    mut state: ResMut<ParticleState>,
    mut clock: ResMut<SimulationClock>,
) {
    let ParticleState {
        position, velocity, ..
    } = &mut *state;
    advance_positions(position, velocity, config.dt);
    clock.advance(config.dt);
}
