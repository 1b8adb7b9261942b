//! Symplectic Euler: the predictor (`v* = v + dt f / m`) and the position update
//! (`x += dt v`) from the velocities the constraint and collision stages filtered.
//!
//! Pinned and kinematic particles have inverse mass 0, so the predictor leaves their
//! velocity alone: zero for a pinned one, the prescribed one for a kinematic one.

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::forces::implicit_angle::ImplicitAngle;
use crate::forces::implicit_bending::ImplicitBending;
use crate::forces::quadratic_bending::add_quadratic_bending;
use crate::model::Bend;
use crate::model::motion::end_of_step;
use crate::schedule::{StepSet, StrandsStep};
use crate::world::clock::SimulationClock;
use crate::world::config::{BendingModel, StrandsConfig};
use crate::world::state::ParticleState;
use crate::world::topology::Topology;

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
        app.init_resource::<ImplicitBendingState>().add_systems(
            StrandsStep,
            (
                predict.in_set(StepSet::Predict),
                integrate.in_set(StepSet::Integrate),
            ),
        );
    }
}

/// The quadratic bending model's factored implicit system, and the topology it was
/// built for.
#[derive(Resource, Default)]
pub struct ImplicitBendingState {
    solver: ImplicitBending,
    topology_version: Option<u64>,
    /// Set when the system could not be factored (non-finite masses or stiffness);
    /// bending is then explicit until the topology changes.
    failed: bool,
    /// The implicit angle model's bend system, and the topology it was planned for.
    angle: ImplicitAngle,
    angle_topology: Option<u64>,
    /// Set as `failed`, for the angle model.
    angle_failed: bool,
}

/// The Predict stage: explicit, or with implicit quadratic bending.
pub fn predict(
    config: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut implicit: ResMut<ImplicitBendingState>,
    mut state: ResMut<ParticleState>,
) {
    let ParticleState {
        position,
        velocity,
        force,
        mass,
        inverse_mass,
        ..
    } = &mut *state;
    if config.bending != BendingModel::Quadratic || topology.bends.is_empty() {
        let stiff = config.bending == BendingModel::Angle
            && !topology.bends.is_empty()
            && stiff_strands(&topology, mass, &mut implicit, config.dt);
        if !stiff {
            predict_velocities(velocity, force, inverse_mass, config.dt);
            return;
        }
        let bends = &topology.bends;
        implicit
            .angle
            .remove_damping(bends, position, velocity, force);
        predict_velocities(velocity, force, inverse_mass, config.dt);
        correct_angle(
            bends,
            position,
            velocity,
            inverse_mass,
            &mut implicit,
            config.dt,
        );
        return;
    }
    let implicit = &mut *implicit;
    let stale = implicit.topology_version != Some(topology.version)
        || !implicit.solver.is_current(mass, config.dt);
    if stale {
        implicit.topology_version = Some(topology.version);
        implicit.failed = false;
        if let Err(pivot) = implicit
            .solver
            .build(&topology.bends, mass, inverse_mass, config.dt)
        {
            error!(
                "bevy_strands: the implicit bending system is singular at row {} (a \
                 non-finite mass or stiffness?); bending is explicit until the topology \
                 changes",
                pivot.row
            );
            implicit.failed = true;
        }
    }
    if implicit.failed {
        add_quadratic_bending(&topology.bends, position, velocity, force);
        predict_velocities(velocity, force, inverse_mass, config.dt);
    } else {
        implicit
            .solver
            .predict(&topology.bends, position, velocity, force, inverse_mass);
    }
}

/// Whether the angle model has strands too stiff for the explicit predictor at `dt`
/// (found again on every topology change).
fn stiff_strands(
    topology: &Topology,
    mass: &[f64],
    implicit: &mut ImplicitBendingState,
    dt: f64,
) -> bool {
    if implicit.angle_topology != Some(topology.version) {
        implicit.angle_topology = Some(topology.version);
        implicit.angle_failed = false;
        implicit.angle.reset(&topology.bends, mass);
    }
    !implicit.angle_failed && implicit.angle.update(&topology.bends, dt)
}

/// The implicit angle model's end-of-step stiffness and damping on the stiff strands'
/// predicted velocities. A singular system (a non-finite mass or stiffness) leaves
/// them as predicted, undamped, with an error; bending stays explicit until the
/// topology changes.
fn correct_angle(
    bends: &[Bend],
    position: &[DVec2],
    velocity: &mut [DVec2],
    inverse_mass: &[f64],
    implicit: &mut ImplicitBendingState,
    dt: f64,
) {
    // `correct` writes the velocities only once the system is factored: on an error
    // they are still the predictor's.
    if let Err(pivot) = implicit
        .angle
        .correct(bends, position, velocity, inverse_mass, dt)
    {
        error!(
            "bevy_strands: the implicit angle bending system is singular at row {} (a \
             non-finite mass or stiffness?); bending is explicit until the topology \
             changes",
            pivot.row
        );
        implicit.angle_failed = true;
    }
}

/// The Integrate stage; also advances the simulation clock.
pub fn integrate(
    config: Res<StrandsConfig>,
    mut state: ResMut<ParticleState>,
    mut clock: ResMut<SimulationClock>,
) {
    let ParticleState {
        position,
        velocity,
        end_velocity_change,
        ..
    } = &mut *state;
    advance_positions(position, velocity, config.dt);
    // Re-stepped islands moved along their chord; they leave at their last substep's
    // velocity, which the chord's average would turn and slow.
    for (v, change) in velocity.iter_mut().zip(end_velocity_change.iter_mut()) {
        *v += std::mem::take(change);
    }
    clock.advance(config.dt);
}
