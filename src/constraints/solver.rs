//! Which solver keeps the edges at their length, and the method it uses on each kind of
//! island.

use std::fmt;
use std::str::FromStr;

use bevy::prelude::Reflect;

use super::islands::IslandKind;
use super::relaxation::Relaxation;

/// How edges keep their length.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(into = "String", try_from = "String")
)]
pub enum SolverKind {
    /// No constraints: every edge is a stretch spring.
    Springs,
    /// Exact projection: Thomas on paths and Sherman–Morrison on loops (linear time),
    /// sparse LDLᵀ on trees and graphs.
    #[default]
    Tridiagonal,
    /// Baseline: Gauss–Seidel relaxation, one edge at a time (position-based dynamics;
    /// zero-compliance XPBD), `max_iterations` sweeps.
    GaussSeidel,
    /// Baseline: Jacobi relaxation with per-particle averaging, `max_iterations` sweeps.
    Jacobi,
}

impl SolverKind {
    /// Every solver, in the order `strands run --help` lists them.
    pub const ALL: [SolverKind; 4] = [
        SolverKind::Tridiagonal,
        SolverKind::GaussSeidel,
        SolverKind::Jacobi,
        SolverKind::Springs,
    ];

    /// The name used on the command line and in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Springs => "springs",
            SolverKind::Tridiagonal => "tridiagonal",
            SolverKind::GaussSeidel => "gauss-seidel",
            SolverKind::Jacobi => "jacobi",
        }
    }

    /// One line on what the solver does.
    pub fn description(self) -> &'static str {
        match self {
            SolverKind::Springs => "stretch springs only, no constraints",
            SolverKind::Tridiagonal => {
                "exact fast projection; Thomas solve on paths, Sherman-Morrison on loops, sparse LDLT on trees and graphs (default)"
            }
            SolverKind::GaussSeidel => {
                "baseline: Gauss-Seidel relaxation (PBD, zero-compliance XPBD), --iterations sweeps per step"
            }
            SolverKind::Jacobi => {
                "baseline: Jacobi relaxation with averaging, --iterations sweeps per step"
            }
        }
    }

    /// The method this solver uses on islands of `kind`, if it takes them.
    pub fn method(self, kind: IslandKind) -> Option<&'static str> {
        match (self, kind) {
            (SolverKind::Tridiagonal, IslandKind::Path) => Some("Thomas"),
            (SolverKind::Tridiagonal, IslandKind::Cycle) => Some("cyclic (Sherman-Morrison)"),
            (SolverKind::Tridiagonal, IslandKind::Tree | IslandKind::Graph) => {
                Some("sparse LDLT (minimum degree)")
            }
            (SolverKind::GaussSeidel, _) => Some("Gauss-Seidel relaxation"),
            (SolverKind::Jacobi, _) => Some("Jacobi relaxation"),
            (SolverKind::Springs, _) => None,
        }
    }

    /// The relaxation this baseline solver sweeps with, if it is one.
    pub fn relaxation(self) -> Option<Relaxation> {
        match self {
            SolverKind::GaussSeidel => Some(Relaxation::GaussSeidel),
            SolverKind::Jacobi => Some(Relaxation::Jacobi),
            SolverKind::Springs | SolverKind::Tridiagonal => None,
        }
    }

    /// Whether contacts are fed back into the constraint solve as inequality rows. The
    /// baselines leave contacts to the collision impulses alone, as the
    /// engines they stand for do.
    pub fn projects_contacts(self) -> bool {
        self == SolverKind::Tridiagonal
    }

    /// Whether the solver can solve islands of `kind`.
    pub fn solves(self, kind: IslandKind) -> bool {
        self.method(kind).is_some()
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

impl From<SolverKind> for String {
    fn from(kind: SolverKind) -> String {
        kind.name().to_string()
    }
}

impl TryFrom<String> for SolverKind {
    type Error = String;

    fn try_from(name: String) -> Result<Self, Self::Error> {
        name.parse()
    }
}
