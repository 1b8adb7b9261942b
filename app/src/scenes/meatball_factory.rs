//! The meatball factory: spinning triangles (3-particle loops) dropped into the box.
//!
//! Every `interval` seconds a triangle of side `side` appears at height `height`, at
//! the next of a row of drop points (`first_x`, `first_x + step_x`, …, wrapping past
//! `wrap_x` back to the lowest point above `low_x`), falling at `speed` and spinning at
//! `spin` rad/s with alternating sign, until `max` have been dropped. A drop point with
//! an edge nearby is skipped rather than spawning a triangle through it.

use std::f64::consts::TAU;

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::model::geometry::closest_on_segment;
use bevy_strands::prelude::*;
use serde::{Deserialize, Serialize};

/// What a meatball factory drops: the scenario file's `meatball_factory` section.
#[derive(Serialize, Deserialize, Reflect, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeatballFactorySpec {
    /// Seconds between drops.
    pub interval: f64,
    /// Simulated time of the first drop.
    #[serde(default)]
    pub start: f64,
    /// Side of the triangles.
    pub side: f64,
    /// Height the triangles' centres are dropped from.
    pub height: f64,
    /// x of the first drop.
    pub first_x: f64,
    /// x step between drops.
    pub step_x: f64,
    /// Drops past this x wrap around by whole steps...
    pub wrap_x: f64,
    /// ...to the lowest drop point at or above this x.
    pub low_x: f64,
    /// Initial falling speed.
    pub speed: f64,
    /// Spin magnitude (rad/s); the sign alternates from drop to drop.
    pub spin: f64,
    /// Triangles at most.
    pub max: usize,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
}

fn one() -> f64 {
    1.0
}

impl MeatballFactorySpec {
    /// The drop point after `x`: one step on, or, past `wrap_x`, back by whole steps to
    /// the lowest point at or above `low_x`.
    pub fn next_x(&self, x: f64) -> f64 {
        let next = x + self.step_x;
        if next > self.wrap_x {
            next - self.step_x * ((next - self.low_x) / self.step_x).floor()
        } else {
            next
        }
    }
}

/// How far a meatball factory has got.
#[derive(Serialize, Deserialize, Reflect, Clone, Copy, Debug, PartialEq)]
pub struct MeatballProgress {
    /// Simulated time of the next drop.
    pub next_drop: f64,
    /// x of the next drop point.
    pub drop_x: f64,
    /// Triangles dropped so far.
    pub dropped: usize,
    /// Drops skipped because an edge was in the way.
    pub skipped: usize,
}

/// A source of spinning triangles. Add it to an entity; the factory system does the rest.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct MeatballFactory {
    /// What it drops.
    pub spec: MeatballFactorySpec,
    /// How far it has got.
    pub progress: MeatballProgress,
}

impl MeatballFactory {
    /// A factory that has dropped nothing yet.
    pub fn new(spec: MeatballFactorySpec) -> Self {
        Self {
            spec,
            progress: MeatballProgress {
                next_drop: spec.start,
                drop_x: spec.first_x,
                dropped: 0,
                skipped: 0,
            },
        }
    }
}

/// Drop the triangles due by the current simulated time.
pub fn run_meatball_factories(
    mut commands: Commands,
    clock: Res<SimulationClock>,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    collisions: Option<Res<CollisionConfig>>,
    mut factories: Query<&mut MeatballFactory>,
) {
    let thickness = collisions.map_or(0.0, |c| c.thickness);
    for mut factory in &mut factories {
        let spec = factory.spec;
        let progress = &mut factory.progress;
        while progress.dropped < spec.max && progress.next_drop <= clock.time + 1e-9 * spec.interval
        {
            let age = (clock.time - progress.next_drop).max(0.0);
            progress.next_drop += spec.interval;
            let x = progress.drop_x;
            progress.drop_x = spec.next_x(x);
            let centre = DVec2::new(x, spec.height - spec.speed * age);
            let radius = spec.side / 3f64.sqrt();
            if edge_near(centre, radius + 2.0 * thickness, &state, &topology) {
                progress.skipped += 1;
                continue;
            }
            let spin = if progress.dropped % 2 == 0 {
                spec.spin
            } else {
                -spec.spin
            };
            let turn = 0.37 * progress.dropped as f64; // vary the orientation a little
            let corners: Vec<DVec2> = (0..3)
                .map(|i| centre + radius * DVec2::from_angle(turn + TAU * i as f64 / 3.0))
                .collect();
            let velocities = corners
                .iter()
                .map(|&c| DVec2::new(0.0, -spec.speed) + spin * (c - centre).perp())
                .collect();
            let spawned = StrandBuilder::closed_loop(corners)
                .velocities(velocities)
                .mass(spec.mass)
                .kind(StrandKind::Meatball)
                .spawn(&mut commands);
            match spawned {
                Ok(_) => progress.dropped += 1,
                Err(e) => {
                    // A validated spec makes valid triangles; say so if one is not.
                    error!("meatball factory: a triangle was refused: {e}");
                    progress.skipped += 1;
                }
            }
        }
    }
}

/// Whether any edge passes within `reach` of `centre`.
fn edge_near(centre: DVec2, reach: f64, state: &ParticleState, topology: &Topology) -> bool {
    topology.edges.iter().any(|e| {
        let (a, b) = (e.a as usize, e.b as usize);
        if a >= state.position.len() || b >= state.position.len() {
            return false;
        }
        closest_on_segment(centre, state.position[a], state.position[b]).1 < reach
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drop_points_follow_the_scenario() {
        let spec = MeatballFactorySpec {
            interval: 1.0,
            start: 0.0,
            side: 0.08,
            height: 0.9,
            first_x: 0.5,
            step_x: 0.16,
            wrap_x: 0.9,
            low_x: 0.1,
            speed: 0.07,
            spin: 15.0,
            max: 16,
            mass: 1.0,
        };
        let mut x = spec.first_x;
        let mut seen = vec![x];
        for _ in 0..6 {
            x = spec.next_x(x);
            seen.push(x);
        }
        let expected = [0.5, 0.66, 0.82, 0.18, 0.34, 0.5, 0.66];
        for (a, b) in seen.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{seen:?}");
        }
    }
}
