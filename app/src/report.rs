//! The run report: one JSON object, or a readable table.

use bevy_strands::metrics::CrossingEvent;
use bevy_strands::world::topology::Topology;
use serde::Serialize;

use crate::profile::StageShare;

/// The first step end with crossed edges, told in terms a reader can find again.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct CrossingReport {
    /// The step that ended with the crossing.
    pub step: u64,
    /// Simulated time at its end.
    pub time: f64,
    /// Edge pairs crossed at that step end.
    pub pairs: usize,
    /// The two edges of the first pair: the strand (by creation order, and entity), the
    /// edge along it, and its particles with their positions.
    pub edges: Vec<String>,
}

impl CrossingReport {
    /// Describe `event`, numbering strands by their creation order in `topology`.
    pub fn describe(event: &CrossingEvent, topology: &Topology) -> Self {
        let mut order: Vec<u32> = topology
            .strands
            .iter()
            .map(|s| s.entity.index_u32())
            .collect();
        order.sort_unstable();
        let edges = event
            .edges
            .iter()
            .map(|e| {
                let rank = order
                    .binary_search(&e.strand.index_u32())
                    .map_or("?".to_string(), |r| r.to_string());
                let [p, q] = e.positions;
                format!(
                    "strand {rank} ({}) edge {}: particle {} at ({:.6}, {:.6}) to particle {} at ({:.6}, {:.6})",
                    e.strand, e.edge, e.particles[0], p.x, p.y, e.particles[1], q.x, q.y
                )
            })
            .collect();
        Self {
            step: event.step,
            time: event.time,
            pairs: event.pairs,
            edges,
        }
    }
}

/// Constraint islands by kind and by the solver that took them.
#[derive(Serialize, Clone, Debug, Default, PartialEq)]
pub struct IslandReport {
    /// Chains (open strands, or pieces between pins): Thomas.
    pub path: usize,
    /// Loops: Sherman–Morrison on top of Thomas.
    pub cycle: usize,
    /// Branching islands.
    pub tree: usize,
    /// Islands with several loops or redundant edges.
    pub graph: usize,
    /// Islands the configured solver could not take; their edges are stretch springs.
    pub unsolved: usize,
    /// The solver of each kind, e.g. `path: thomas`.
    pub solvers: Vec<String>,
}

/// Figures of one headless run.
#[derive(Serialize, Clone, Debug, PartialEq)]
pub struct Report {
    /// Scenario name.
    pub scenario: String,
    /// The scene parameters actually used (dt, substeps and solver included).
    pub config: serde_json::Value,
    /// The constraint solver used.
    pub solver: String,
    /// Steps taken.
    pub steps: u64,
    /// Simulated seconds.
    pub sim_time: f64,
    /// Particles at the end.
    pub particles: usize,
    /// Strands at the end (walls included).
    pub strands: usize,
    /// Edges kept at rest length by the constraint solver at the end.
    pub constrained_edges: usize,
    /// The constraint islands at the end, by kind, and which solver took them.
    pub islands: IslandReport,
    /// Largest `|ℓ − L| / L` over every non-static edge and every step end.
    pub max_rel_length_error: f64,
    /// The same over edges with no particle in contact that step.
    pub max_rel_length_error_free: f64,
    /// The largest particle speed at the end of the run: a bounded motion stays near
    /// the scene's own speeds, a step past its stability limit grows without bound.
    pub max_speed_at_end: f64,
    /// The median speed of the free particles at the end (pinned, driven and sleeping
    /// ones aside): a pile at rest ends below a millimetre per second.
    pub median_speed_at_end: f64,
    /// The 95th percentile of the same speeds.
    pub p95_speed_at_end: f64,
    /// The scene's mechanical energy (kinetic, gravitational, bending, springs) at the
    /// end of the first tick, in joules.
    pub energy_start: f64,
    /// The same at the end of the last tick.
    pub energy_end: f64,
    /// The largest rise of that energy above an earlier low while nothing drove the
    /// scene (no kinematic particle moving, no external force or tether, no particle
    /// added or removed): energy no force put in. A scene left alone keeps it near 0.
    pub energy_gained: f64,
    /// Ticks in which something drove the scene (their energy starts a new low).
    pub driven_ticks: u64,
    /// Step ends at which two edges sharing no particle intersected; null if unchecked.
    pub edge_crossings: Option<u64>,
    /// The first of those, with its edges; null if none (or unchecked).
    pub first_crossing: Option<CrossingReport>,
    /// Point–edge contacts met, summed over steps (held by the contact solve or pushed
    /// apart by a collision impulse).
    pub contacts: u64,
    /// Collision impulses applied (what the contact solve left to continuous detection).
    pub collisions: u64,
    /// Steps that needed the collision fail-safe.
    pub failsafe_steps: u64,
    /// Steps that would have ended in the fail-safe, taken again as two halves.
    pub halved_steps: u64,
    /// Steps taken in parts from the start after a hard one.
    pub split_steps: u64,
    /// Particles asleep at the end of the run.
    pub asleep_particles: usize,
    /// Strands (units of strands joined by shared particles) put to sleep, in all.
    pub sleeps: u64,
    /// Strands woken, in all.
    pub wakes: u64,
    /// Mean constraint-solve iterations per island per step.
    pub projection_iterations_mean: f64,
    /// Most constraint-solve iterations of any island in any step.
    pub projection_iterations_max: u32,
    /// Island solves that stopped at the iteration cap.
    pub projection_capped_solves: u64,
    /// Island solves that one projection could not meet, stepped again in substeps.
    pub projection_restepped_solves: u64,
    /// The substeps those re-stepped solves took, in all.
    pub projection_substeps: u64,
    /// Re-projections of islands in contact (the contact loop): solves, mean and most
    /// iterations, and solves that stopped at the cap.
    pub contact_projection_solves: u64,
    /// Mean iterations of a re-projection in contact.
    pub contact_projection_iterations_mean: f64,
    /// Most iterations of a re-projection in contact.
    pub contact_projection_iterations_max: u32,
    /// Re-projections in contact that stopped at the cap.
    pub contact_projection_capped_solves: u64,
    /// Re-projections in contact dropped because they asked for absurd corrections.
    pub contact_projection_rejected_solves: u64,
    /// Projections in contact whose rows the contact Newton solved (the others were
    /// swept).
    pub contact_projection_newton_solves: u64,
    /// The contact Newton's sparse factorizations.
    pub contact_projection_factorizations: u64,
    /// Of the Newton's projections, those solved again after the sweeps left a
    /// squeezed pair short.
    pub contact_projection_escalated: u64,
    /// Steps whose collisions still needed impulses after the last re-projection:
    /// edges next to those contacts end the step as the impulses left them.
    pub contact_unsettled_steps: u64,
    /// Threads a stage could use; the wall-clock figures depend on it, nothing else does.
    pub threads: usize,
    /// Wall-clock seconds of the run's ticks.
    pub wall_seconds: f64,
    /// Particles × steps per wall-clock second.
    pub particle_steps_per_second: f64,
    /// Simulated seconds per wall-clock second (above 1: faster than real time).
    pub real_time_factor: f64,
    /// What a reader must know to interpret the figures.
    pub notes: Vec<String>,
    /// Problems found in the input, and what was done about them.
    pub input_problems: Vec<String>,
    /// Pictures written (GIF, PNG frames, plot).
    pub pictures: Vec<String>,
    /// Each stage's share of the wall time (with `--profile`; empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stage_profile: Vec<StageShare>,
}

impl Report {
    /// The fields measured by the wall clock: they differ between identical runs.
    pub const WALL_CLOCK_FIELDS: [&'static str; 5] = [
        "threads",
        "stage_profile",
        "wall_seconds",
        "particle_steps_per_second",
        "real_time_factor",
    ];

    /// The report as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serializes")
    }

    /// The report as an aligned two-column table.
    pub fn to_table(&self) -> String {
        let crossings = self
            .edge_crossings
            .map_or("not checked".to_string(), |c| c.to_string());
        let rows: Vec<(&str, String)> = vec![
            ("scenario", self.scenario.clone()),
            ("solver", self.solver.clone()),
            ("steps", self.steps.to_string()),
            ("sim_time", format!("{:.4} s", self.sim_time)),
            ("particles", self.particles.to_string()),
            ("strands", self.strands.to_string()),
            ("constrained_edges", self.constrained_edges.to_string()),
            (
                "islands",
                format!(
                    "{} path, {} cycle, {} tree, {} graph; {} unsolved",
                    self.islands.path,
                    self.islands.cycle,
                    self.islands.tree,
                    self.islands.graph,
                    self.islands.unsolved
                ),
            ),
            (
                "max_rel_length_error",
                format!("{:.3e}", self.max_rel_length_error),
            ),
            (
                "max_rel_length_error_free",
                format!("{:.3e}", self.max_rel_length_error_free),
            ),
            ("max_speed_at_end", format!("{:.3e}", self.max_speed_at_end)),
            (
                "speed_at_end",
                format!(
                    "median {:.3e}, 95th percentile {:.3e} (free particles)",
                    self.median_speed_at_end, self.p95_speed_at_end
                ),
            ),
            (
                "energy",
                format!(
                    "{:.4e} J at the start, {:.4e} J at the end; gained {:.3e} J at most \
                     above an earlier low with nothing driving ({} driven ticks)",
                    self.energy_start, self.energy_end, self.energy_gained, self.driven_ticks
                ),
            ),
            ("edge_crossings", crossings),
            ("contacts", self.contacts.to_string()),
            ("collisions", self.collisions.to_string()),
            ("failsafe_steps", self.failsafe_steps.to_string()),
            ("halved_steps", self.halved_steps.to_string()),
            ("split_steps", self.split_steps.to_string()),
            (
                "asleep",
                format!(
                    "{} of {} particles at the end; {} strands put to sleep, {} woken",
                    self.asleep_particles, self.particles, self.sleeps, self.wakes
                ),
            ),
            (
                "projection_iterations",
                format!(
                    "mean {:.2}, max {}, capped {}, re-stepped {} ({} substeps)",
                    self.projection_iterations_mean,
                    self.projection_iterations_max,
                    self.projection_capped_solves,
                    self.projection_restepped_solves,
                    self.projection_substeps
                ),
            ),
            (
                "contact_projection",
                format!(
                    "{} solves ({} by Newton, {} of them after the sweeps, {} factorizations), mean {:.2}, max {}, capped {}, rejected {}; unsettled steps {}",
                    self.contact_projection_solves,
                    self.contact_projection_newton_solves,
                    self.contact_projection_escalated,
                    self.contact_projection_factorizations,
                    self.contact_projection_iterations_mean,
                    self.contact_projection_iterations_max,
                    self.contact_projection_capped_solves,
                    self.contact_projection_rejected_solves,
                    self.contact_unsettled_steps
                ),
            ),
            ("threads", self.threads.to_string()),
            ("wall_seconds", format!("{:.3}", self.wall_seconds)),
            (
                "particle_steps_per_second",
                format!("{:.3e}", self.particle_steps_per_second),
            ),
            ("real_time_factor", format!("{:.3}", self.real_time_factor)),
        ];
        let width = rows.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
        let mut out = String::new();
        for (key, value) in rows {
            out.push_str(&format!("{key:<width$}  {value}\n"));
        }
        if let Some(crossing) = &self.first_crossing {
            out.push_str(&format!(
                "first crossing: step {}, t = {:.6} s, {} pair(s)\n",
                crossing.step, crossing.time, crossing.pairs
            ));
            for edge in &crossing.edges {
                out.push_str(&format!("  {edge}\n"));
            }
        }
        for note in &self.notes {
            out.push_str(&format!("note: {note}\n"));
        }
        for problem in &self.input_problems {
            out.push_str(&format!("input problem: {problem}\n"));
        }
        for picture in &self.pictures {
            out.push_str(&format!("wrote {picture}\n"));
        }
        if !self.stage_profile.is_empty() {
            out.push_str("where the wall time went (share of the ticks' wall time):\n");
            for row in &self.stage_profile {
                out.push_str(&format!(
                    "  {:<46} {:>6.2} %  {:.4} s\n",
                    row.stage,
                    100.0 * row.share,
                    row.seconds
                ));
            }
        }
        out
    }
}
