//! One engine's run of the chains: wall time of its steps alone, and what the step
//! ends showed.

use crate::chain::{Chains, Grid, Segment, StepMeasure, measure};

pub struct EngineRun {
    pub engine: &'static str,
    pub model: &'static str,
    /// The engine's length unit: the scale of its contact tolerances.
    pub length_unit: f32,
    pub threads: usize,
    pub steps: u64,
    pub wall: f64,
    /// The largest joint gap over the link length at any step end.
    pub stretch: f32,
    /// Step ends at which two links crossed, and the most pairs crossed at one.
    pub crossed_steps: u64,
    pub most_crossed_pairs: usize,
    /// Links outside the container at the last step end.
    pub escaped: usize,
}

impl EngineRun {
    pub fn new(
        engine: &'static str,
        model: &'static str,
        length_unit: f32,
        threads: usize,
    ) -> Self {
        EngineRun {
            engine,
            model,
            length_unit,
            threads,
            steps: 0,
            wall: 0.0,
            stretch: 0.0,
            crossed_steps: 0,
            most_crossed_pairs: 0,
            escaped: 0,
        }
    }

    /// Run an engine for `steps` steps: `step` steps it once, writes each chain's links
    /// as it left them (link lengths `lengths`, in chain order) and returns the
    /// seconds its own step took.
    pub fn drive(
        &mut self,
        chains: &Chains,
        lengths: &[Vec<f32>],
        steps: u64,
        mut step: impl FnMut(&mut Vec<Vec<Segment>>) -> f64,
    ) {
        // A joint's gap is measured against the shorter of the two links it joins.
        let rest: Vec<Vec<f32>> = (lengths.iter())
            .map(|chain| chain.windows(2).map(|p| p[0].min(p[1])).collect())
            .collect();
        let mut grid = Grid::new(0.03);
        let mut segments: Vec<Vec<Segment>> = Vec::new();
        for _ in 0..steps {
            segments.clear();
            self.wall += step(&mut segments);
            self.record(
                measure(&segments, &rest, &mut grid),
                &segments,
                chains.container,
            );
        }
        self.steps = steps;
    }

    fn record(
        &mut self,
        step: StepMeasure,
        links: &[Vec<Segment>],
        container: ([f32; 2], [f32; 2]),
    ) {
        self.stretch = self.stretch.max(step.stretch);
        self.crossed_steps += u64::from(step.crossed_pairs > 0);
        self.most_crossed_pairs = self.most_crossed_pairs.max(step.crossed_pairs);
        let ([x0, y0], [x1, y1]) = container;
        let outside = |p: [f32; 2]| p[0] < x0 || p[0] > x1 || p[1] < y0 || p[1] > y1;
        self.escaped = links
            .iter()
            .flatten()
            .filter(|s| outside(s[0]) || outside(s[1]))
            .count();
    }

    pub fn real_time_factor(&self, dt: f64) -> f64 {
        self.steps as f64 * dt / self.wall
    }
}
