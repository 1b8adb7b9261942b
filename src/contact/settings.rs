//! How a contact projection is asked to stop, and how it ended; which solver finds its
//! rows' impulses.

use bevy::prelude::Reflect;

use crate::constraints::projection::ProjectionSettings;

/// How a contact projection finds its contact rows' impulses.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ContactSolver {
    /// Each contact projection by whichever of the two below costs less for it (an
    /// estimate from the rows' response lengths and the factor's fill): Newton for
    /// long strands, the sweeps for short ones in a dense pile.
    #[default]
    Auto,
    /// Newton's method on the rows and edges together, one sparse factorization a
    /// Newton step: a row costs its own particles whatever the strands' lengths.
    Newton,
    /// Projected Gauss–Seidel over each row's response on the whole strands it
    /// touches, inside the edges' Newton steps (the earlier design, kept as a
    /// baseline).
    GaussSeidel,
}

impl ContactSolver {
    /// Every solver, in the order they are listed.
    pub const ALL: [ContactSolver; 3] = [
        ContactSolver::Auto,
        ContactSolver::Newton,
        ContactSolver::GaussSeidel,
    ];

    /// The solver's name on the command line: `auto`, `newton`, `gauss-seidel`.
    pub fn name(self) -> &'static str {
        match self {
            ContactSolver::Auto => "auto",
            ContactSolver::Newton => "newton",
            ContactSolver::GaussSeidel => "gauss-seidel",
        }
    }
}

impl std::fmt::Display for ContactSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ContactSolver {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown contact solver '{s}'; valid solvers: auto, newton, gauss-seidel")
            })
    }
}

/// A group of strands at rest: its free particles' mean speed, apart from the step's
/// fall under gravity, below `speed`. Its rows are met to `tolerance` with up to
/// `sweeps` sweeps: the sweeps stop at the usual tolerance a thickness per second
/// short of their rows, and in a pile held by friction that residue never dies down
/// (docs/contact.md); a resting group's warm start is nearly exact, so meeting it
/// closely costs little.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resting {
    /// The mean speed below which a group rests.
    pub speed: f64,
    /// The velocity gravity adds in a step (`g dt`).
    pub fall: bevy::math::DVec2,
    /// Sweeps per Newton step, at most.
    pub sweeps: u32,
    /// How far (a distance per step) a normal row may fall short of its target.
    pub tolerance: f64,
}

/// How a contact projection is asked to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// The edges' tolerance and the cap on Newton steps (the direction is always the
    /// end-of-step one).
    pub projection: ProjectionSettings,
    /// Gauss–Seidel sweeps over the rows per Newton step, at most.
    pub sweeps: u32,
    /// How far (a distance per step) a normal row may fall short of its target.
    pub contact_tolerance: f64,
    /// A part whose corrections would move a particle by more than this many of its
    /// shortest rest lengths keeps its velocities (infinite: no guard): nearly
    /// dependent rows can ask for absurd corrections.
    pub max_correction: f64,
    /// Rows that keep the edges from settling for this many Newton steps give way
    /// (frozen, the edges polished alone in the steps left); the cap holds them
    /// otherwise.
    pub rows_give_way: u32,
    /// How a group at rest is met, if differently.
    pub resting: Option<Resting>,
    /// How the rows' impulses are found.
    pub solver: ContactSolver,
    /// Under `Auto`, go to the contact Newton without trying the sweeps first (the
    /// group's sweeps recently left a squeezed pair short).
    pub newton_first: bool,
}

/// How a contact projection ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactOutcome {
    /// Newton steps.
    pub iterations: u32,
    /// Gauss–Seidel sweeps over the rows, summed over the Newton steps.
    pub sweeps: u32,
    /// Whether every island met its edges.
    pub converged: bool,
    /// Final `max |C_k| / L_k²` over every island.
    pub residual: f64,
    /// How far (a distance per step) the most violated normal row falls short.
    pub contact_violation: f64,
    /// Sparse factorizations of the contact Newton.
    pub factorizations: u32,
    /// Whether `Auto` solved a group again by the contact Newton because its sweeps
    /// left a squeezed pair's row short.
    pub escalated: bool,
    /// Whether `Auto` went to the contact Newton first ([`ContactSettings::newton_first`]).
    pub newton_first: bool,
}
