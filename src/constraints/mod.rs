//! Inextensibility constraints: which solver keeps edges at their rest length.

use std::fmt;
use std::str::FromStr;

use bevy::prelude::*;

/// How edges keep their length.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SolverKind {
    /// No constraints: every edge is a stretch spring.
    #[default]
    Springs,
}

impl SolverKind {
    /// Every solver, in the order `strands run --help` lists them.
    pub const ALL: [SolverKind; 1] = [SolverKind::Springs];

    /// The name used on the command line and in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Springs => "springs",
        }
    }

    /// One line on what the solver does.
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Springs => "stretch springs only, no constraints",
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SolverKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|k| k.name()).collect();
                format!("unknown solver '{s}'; valid solvers: {}", names.join(", "))
            })
    }
}

/// Constraint solver settings.
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct ConstraintConfig {
    /// The solver.
    pub solver: SolverKind,
}

impl Default for ConstraintConfig {
    fn default() -> Self {
        Self {
            solver: SolverKind::Springs,
        }
    }
}
