//! The meatball factory: spinning triangles (3-particle loops) dropped into the box.
//!
//! Every `interval` seconds a triangle of side `side` appears at height `height`, at
//! the next of a row of drop points (`drop_x`, `drop_x + step_x`, …, wrapping past
//! `wrap_x` back to the lowest point above `low_x`), falling at `speed` and spinning at `spin` rad/s with alternating sign,
//! until `max` have been dropped. A drop point with an edge nearby is skipped rather
//! than spawning a triangle through it.

use std::f64::consts::TAU;

use bevy::math::DVec2;
use bevy::prelude::*;

use bevy_strands::model::geometry::closest_on_segment;
use bevy_strands::prelude::*;

/// A source of spinning triangles. Add it to an entity; the factory system does the rest.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct MeatballFactory {
    /// Seconds between drops.
    pub interval: f64,
    /// Side of the triangles.
    pub side: f64,
    /// Height of the triangles' centres when dropped.
    pub height: f64,
    /// x of the next drop point.
    pub drop_x: f64,
    /// Step between drop points.
    pub step_x: f64,
    /// Drop points past this x wrap around by whole steps...
    pub wrap_x: f64,
    /// ...to the lowest point at or above this x.
    pub low_x: f64,
    /// Initial falling speed.
    pub speed: f64,
    /// Spin magnitude (rad/s); the sign alternates.
    pub spin: f64,
    /// Triangles at most.
    pub max: usize,
    /// Mass of each particle.
    pub mass: f64,
    /// Simulated time of the next drop.
    pub next_drop: f64,
    /// Triangles dropped so far.
    pub dropped: usize,
    /// Drops skipped because an edge was in the way.
    pub skipped: usize,
}

impl MeatballFactory {
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
        while factory.dropped < factory.max
            && factory.next_drop <= clock.time + 1e-9 * factory.interval
        {
            let age = (clock.time - factory.next_drop).max(0.0);
            factory.next_drop += factory.interval;
            let x = factory.drop_x;
            factory.drop_x = factory.next_x(x);
            let centre = DVec2::new(x, factory.height - factory.speed * age);
            let radius = factory.side / 3f64.sqrt();
            if edge_near(centre, radius + 2.0 * thickness, &state, &topology) {
                factory.skipped += 1;
                continue;
            }
            let spin = if factory.dropped % 2 == 0 {
                factory.spin
            } else {
                -factory.spin
            };
            let turn = 0.37 * factory.dropped as f64; // vary the orientation a little
            let corners: Vec<DVec2> = (0..3)
                .map(|i| centre + radius * DVec2::from_angle(turn + TAU * i as f64 / 3.0))
                .collect();
            let velocities = corners
                .iter()
                .map(|&c| DVec2::new(0.0, -factory.speed) + spin * (c - centre).perp())
                .collect();
            StrandBuilder::closed_loop(corners)
                .velocities(velocities)
                .mass(factory.mass)
                .kind(StrandKind::Meatball)
                .spawn(&mut commands)
                .expect("a triangle of positive side is a valid loop");
            factory.dropped += 1;
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
        let factory = MeatballFactory {
            interval: 1.0,
            side: 0.08,
            height: 0.9,
            drop_x: 0.5,
            step_x: 0.16,
            wrap_x: 0.9,
            low_x: 0.1,
            speed: 0.07,
            spin: 15.0,
            max: 16,
            mass: 1.0,
            next_drop: 0.0,
            dropped: 0,
            skipped: 0,
        };
        let mut x = factory.drop_x;
        let mut seen = vec![x];
        for _ in 0..6 {
            x = factory.next_x(x);
            seen.push(x);
        }
        let expected = [0.5, 0.66, 0.82, 0.18, 0.34, 0.5, 0.66];
        for (a, b) in seen.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{seen:?}");
        }
    }
}
