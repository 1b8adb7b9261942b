//! Problems found in the input at run time, each naming the entity it concerns.

use std::collections::HashSet;

use bevy::prelude::*;

/// A problem found in the input, naming the entity it concerns.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputProblem {
    /// The particle or strand.
    pub entity: Entity,
    /// What is wrong and what was done about it.
    pub problem: String,
}

/// Problems found in the input since start-up. Each distinct problem is logged once.
#[derive(Resource, Default, Debug)]
pub struct InputProblems {
    /// Every problem, in the order found.
    pub entries: Vec<InputProblem>,
    seen: HashSet<(Entity, String)>,
}

impl InputProblems {
    /// Record (and log, the first time) a problem with `entity`.
    pub fn report(&mut self, entity: Entity, problem: impl Into<String>) {
        let problem = problem.into();
        if self.seen.insert((entity, problem.clone())) {
            warn!("bevy_strands: {entity}: {problem}");
            self.entries.push(InputProblem { entity, problem });
        }
    }

    /// Whether any problem mentions `entity`.
    pub fn concerns(&self, entity: Entity) -> bool {
        self.entries.iter().any(|p| p.entity == entity)
    }

    /// Forget every problem (a scene restarted).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.seen.clear();
    }
}
