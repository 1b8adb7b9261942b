//! Simulated time, and the wall-clock time spent stepping.

use bevy::prelude::*;

/// Simulated time and steps taken.
#[derive(Resource, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[reflect(Resource)]
pub struct SimulationClock {
    /// Simulated seconds since start.
    pub time: f64,
    /// Steps taken since start.
    pub steps: u64,
}

impl SimulationClock {
    /// Account for one step of `dt`.
    pub fn advance(&mut self, dt: f64) {
        self.steps += 1;
        // Multiply rather than accumulate so long runs do not drift.
        self.time = self.steps as f64 * dt;
    }
}

/// Wall-clock seconds spent in the steps (not in the tick's gather and write-back).
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTiming {
    /// Seconds spent stepping since start.
    pub wall_seconds: f64,
    /// Seconds of the latest tick's steps.
    pub last_tick_seconds: f64,
}
