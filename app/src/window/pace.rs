//! The real-time factor: simulated seconds per wall-clock second over the last moments,
//! what a person watching sees (slow motion below 1).

use std::collections::VecDeque;

use bevy::prelude::*;
use bevy_strands::prelude::SimulationClock;

/// Wall-clock seconds the factor is measured over.
const WINDOW_SECONDS: f64 = 2.0;
/// Fewer wall-clock seconds than this give no figure yet.
const MIN_SECONDS: f64 = 0.5;

/// Simulated time over wall-clock time across the last [`WINDOW_SECONDS`].
#[derive(Resource, Debug, Default, Clone)]
pub struct RealTimeFactor {
    /// The factor, once enough time has passed to measure it.
    pub value: Option<f64>,
    /// (wall-clock seconds, simulated seconds) per frame, oldest first.
    samples: VecDeque<(f64, f64)>,
}

impl RealTimeFactor {
    /// Account a frame at wall-clock `real` seconds with the simulation at `simulated`.
    pub fn record(&mut self, real: f64, simulated: f64) {
        // A reset moves simulated time back: measure afresh.
        if self.samples.back().is_some_and(|&(_, s)| simulated < s) {
            self.samples.clear();
        }
        self.samples.push_back((real, simulated));
        while self
            .samples
            .get(1)
            .is_some_and(|&(r, _)| real - r >= WINDOW_SECONDS)
        {
            self.samples.pop_front();
        }
        let (first, last) = (self.samples.front(), self.samples.back());
        self.value = match (first, last) {
            (Some(&(r0, s0)), Some(&(r1, s1))) if r1 - r0 >= MIN_SECONDS => {
                Some((s1 - s0) / (r1 - r0))
            }
            _ => None,
        };
    }
}

/// Keeps [`RealTimeFactor`] up to date.
pub struct PacePlugin;

impl Plugin for PacePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<RealTimeFactor>()
            .add_systems(Last, measure);
    }
}

fn measure(real: Res<Time<Real>>, clock: Res<SimulationClock>, mut rate: ResMut<RealTimeFactor>) {
    rate.record(real.elapsed_secs_f64(), clock.time);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factor_is_simulated_over_wall_time_in_the_window() {
        let mut rate = RealTimeFactor::default();
        rate.record(0.0, 0.0);
        rate.record(0.25, 0.05);
        assert_eq!(rate.value, None, "a quarter second is too short to tell");
        // Half speed for 3 s: only the last 2 s count.
        for i in 2..=12 {
            rate.record(0.25 * i as f64, 0.125 * i as f64);
        }
        assert!((rate.value.unwrap() - 0.5).abs() < 1e-12);
        // Then twice real time.
        for i in 13..=24 {
            rate.record(0.25 * i as f64, 1.5 + 0.5 * (i - 12) as f64);
        }
        assert!((rate.value.unwrap() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_reset_starts_the_measurement_over() {
        let mut rate = RealTimeFactor::default();
        for i in 0..=8 {
            rate.record(0.25 * i as f64, 0.25 * i as f64);
        }
        assert!((rate.value.unwrap() - 1.0).abs() < 1e-12);
        rate.record(2.25, 0.0);
        assert_eq!(rate.value, None);
    }
}
