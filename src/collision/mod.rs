//! The Collide stage: robust point–edge collision processing (DESIGN §6, §7).
//!
//! On the velocities the constraint solve left, each step:
//!
//! 1. **Proximity** — pairs that would end the step closer than the thickness `h` get
//!    a repulsion impulse, with Coulomb friction.
//! 2. **Continuous detection** — every point against every edge it is not part of,
//!    over the step's linear motion ([`ccd`]); each contact gets an inelastic impulse
//!    with friction ([`response`]); detection repeats with the new velocities until a
//!    full pass finds nothing or the cap is hit.
//! 3. **Re-projection** (§7) — the islands touched by contacts are projected onto their
//!    constraints again with the contacting particles' normal motion held, and 1–2
//!    run again; this alternates a few times, collisions last.
//! 4. **Fail-safe** — collisions still left after the last pass are resolved by rigid
//!    impact zones ([`failsafe`]), which guarantees no crossing.
//!
//! Candidate pairs come from a uniform-grid broad phase ([`broad_phase`]). The walls
//! are ordinary pinned edges. In checked mode, the Measure stage counts edge crossings
//! ([`crossings`]).

pub mod broad_phase;
pub mod ccd;
pub mod crossings;
pub mod failsafe;
pub mod response;

use bevy::math::DVec2;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;

use crate::config::StrandsConfig;
use crate::constraints::projection::{Bodies, ContactRow, ProjectionSettings};
use crate::constraints::{ConstraintConfig, Islands};
use crate::metrics::StrandMetrics;
use crate::schedule::{StepSet, StrandsStep};
use crate::state::ParticleState;
use crate::topology::{Edge, Topology};
use broad_phase::{BroadPhase, BroadPhaseMethod};
use ccd::{closest_on_segment, point_edge_time_of_impact};
use failsafe::ImpactZones;
use response::{PointEdgePair, collision_normal_change, contact_change, repulsion_normal_change};

/// Collision settings.
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_strands::prelude::*;
/// # use bevy_strands::collision::CollisionConfig;
/// let mut app = App::new();
/// app.add_plugins(StrandsPlugin::manual());
/// let mut config = app.world_mut().resource_mut::<CollisionConfig>();
/// config.friction = 0.5;
/// config.thickness = 0.002;
/// ```
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct CollisionConfig {
    /// Whether the Collide stage runs.
    pub enabled: bool,
    /// Thickness `h`: pairs are kept at least this far apart.
    pub thickness: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Restitution of collision impulses (0: inelastic).
    pub restitution: f64,
    /// Detection passes before the fail-safe.
    pub max_iterations: u32,
    /// Alternations of constraint re-projection and collisions (DESIGN §7), at most;
    /// they stop as soon as a pass finds no new collision, so at small steps one or two
    /// run whatever the cap. 0 leaves edges next to contacts as the impulses leave them.
    pub contact_passes: u32,
    /// How candidate pairs are found.
    pub broad_phase: BroadPhaseMethod,
    /// Count edge crossings at the end of every step.
    pub check_crossings: bool,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            thickness: 0.004,
            friction: 0.3,
            restitution: 0.0,
            max_iterations: 10,
            contact_passes: 16,
            broad_phase: BroadPhaseMethod::Grid,
            check_crossings: false,
        }
    }
}

/// Buffers of the Collide stage, reused every step.
#[derive(Resource, Default, Debug)]
pub struct CollisionScratch {
    broad: BroadPhase,
    pairs: Vec<(u32, u32)>,
    displacement: Vec<DVec2>,
    contacts: Vec<Contact>,
    contact_index: HashMap<(u32, u32), u32>,
    contact_rows: Vec<ContactRow>,
    reprojection_inverse_mass: Vec<f64>,
    zones: ImpactZones,
    hits: Vec<(u32, u32, u32)>,
    crossing_pairs: Vec<(u32, u32)>,
    crossing_broad: BroadPhase,
}

/// A contact met this step: point `p` against edge `edge` at `alpha`, along `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Contact {
    p: u32,
    edge: u32,
    alpha: f64,
    normal: DVec2,
}

/// The Collide stage, its settings and the crossing check.
pub struct CollisionPlugin;

impl Plugin for CollisionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<CollisionConfig>()
            .init_resource::<CollisionScratch>()
            .register_type::<CollisionConfig>()
            .add_systems(
                StrandsStep,
                (
                    collide.in_set(StepSet::Collide),
                    check_crossings
                        .in_set(StepSet::Measure)
                        .after(crate::metrics::measure),
                ),
            );
    }
}

/// How one step's collision processing went.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CollisionOutcome {
    /// Impulses applied (proximity and collision).
    pub impulses: u64,
    /// Whether the fail-safe had to run.
    pub failsafe: bool,
    /// Collisions the fail-safe could not resolve (kinematic particles driven into
    /// each other); 0 in every sound scene.
    pub unresolved: usize,
}

/// The slices and settings of one step's collision processing.
struct Contacts<'a> {
    edges: &'a [Edge],
    position: &'a [DVec2],
    velocity: &'a mut [DVec2],
    mass: &'a [f64],
    inverse_mass: &'a [f64],
    in_contact: &'a mut [bool],
    config: &'a CollisionConfig,
    dt: f64,
    scratch: &'a mut CollisionScratch,
}

impl Contacts<'_> {
    /// Candidate (point, edge) pairs for the current velocities.
    fn find_pairs(&mut self) {
        let scratch = &mut *self.scratch;
        scratch.displacement.clear();
        scratch
            .displacement
            .extend(self.velocity.iter().map(|v| self.dt * *v));
        scratch.broad.build(
            self.edges,
            self.position,
            Some(&scratch.displacement),
            self.config.thickness,
        );
        scratch.pairs.clear();
        let (edges, w) = (self.edges, self.inverse_mass);
        let keep = |p: u32, k: u32| {
            let e = &edges[k as usize];
            e.a != p
                && e.b != p
                && (w[p as usize] > 0.0 || w[e.a as usize] > 0.0 || w[e.b as usize] > 0.0)
        };
        scratch.broad.point_edge_pairs(
            self.config.broad_phase,
            self.position,
            &scratch.displacement,
            keep,
            &mut scratch.pairs,
        );
    }

    fn pair(&self, p: u32, k: u32, alpha: f64) -> PointEdgePair {
        let e = &self.edges[k as usize];
        PointEdgePair {
            p: p as usize,
            q: e.a as usize,
            r: e.b as usize,
            alpha,
        }
    }

    /// A relative speed that moves a pair by a billionth of the thickness per step:
    /// below it, an approach is round-off, not a collision.
    fn negligible_speed(&self) -> f64 {
        1e-9 * self.config.thickness.max(1e-9) / self.dt
    }

    /// Apply a relative-velocity change and record the contact.
    fn respond(&mut self, pair: PointEdgePair, edge: u32, delta: DVec2, normal: DVec2) -> bool {
        if !pair.apply(delta, self.velocity, self.inverse_mass) {
            return false;
        }
        for i in [pair.p, pair.q, pair.r] {
            self.in_contact[i] |= self.inverse_mass[i] > 0.0;
        }
        let contact = Contact {
            p: pair.p as u32,
            edge,
            alpha: pair.alpha,
            normal,
        };
        // One record per point and edge: the latest contact between them.
        let scratch = &mut *self.scratch;
        let next = scratch.contacts.len() as u32;
        let slot = *scratch
            .contact_index
            .entry((contact.p, edge))
            .or_insert(next);
        if slot == next {
            scratch.contacts.push(contact);
        } else {
            scratch.contacts[slot as usize] = contact;
        }
        true
    }

    /// Repulsion for pairs that would end the step closer than the thickness.
    fn proximity_pass(&mut self) -> u64 {
        let mut impulses = 0;
        for slot in 0..self.scratch.pairs.len() {
            let (p, k) = self.scratch.pairs[slot];
            let e = &self.edges[k as usize];
            let (x, q, r) = (
                self.position[p as usize],
                self.position[e.a as usize],
                self.position[e.b as usize],
            );
            let (alpha, distance) = closest_on_segment(x, q, r);
            let pair = self.pair(p, k, alpha);
            let relative = pair.relative_velocity(self.velocity);
            let closest = q.lerp(r, alpha);
            let normal = if distance > 0.0 {
                (x - closest) / distance
            } else {
                // On the edge: push against the approach, or off the edge's side.
                let side = (r - q).perp().normalize_or(DVec2::Y);
                if side.dot(relative) > 0.0 {
                    -side
                } else {
                    side
                }
            };
            let change = repulsion_normal_change(
                distance,
                normal.dot(relative),
                self.config.thickness,
                self.dt,
            );
            // A few ulps short of the thickness is at the thickness.
            if change <= 1e-9 * self.config.thickness / self.dt {
                continue;
            }
            let delta = contact_change(relative, normal, change, self.config.friction);
            impulses += u64::from(self.respond(pair, k, delta, normal));
        }
        impulses
    }

    /// One detection pass over the current pairs; impulses are applied as found, each
    /// test using the velocities the earlier impulses left.
    fn collision_pass(&mut self) -> u64 {
        let mut impulses = 0;
        for slot in 0..self.scratch.pairs.len() {
            let (p, k) = self.scratch.pairs[slot];
            let Some((pair, normal, normal_velocity)) = self.approaching_hit(p, k) else {
                continue;
            };
            let change = collision_normal_change(normal_velocity, self.config.restitution);
            let relative = pair.relative_velocity(self.velocity);
            let delta = contact_change(relative, normal, change, self.config.friction);
            impulses += u64::from(self.respond(pair, k, delta, normal));
        }
        impulses
    }

    /// The contact of point `p` with edge `k` over the step, if they meet approaching.
    fn approaching_hit(&self, p: u32, k: u32) -> Option<(PointEdgePair, DVec2, f64)> {
        let e = &self.edges[k as usize];
        let (a, b, i) = (e.a as usize, e.b as usize, p as usize);
        let dt = self.dt;
        let hit = point_edge_time_of_impact(
            self.position[i],
            dt * self.velocity[i],
            self.position[a],
            dt * self.velocity[a],
            self.position[b],
            dt * self.velocity[b],
        )?;
        let pair = self.pair(p, k, hit.alpha);
        let normal_velocity = hit.normal.dot(pair.relative_velocity(self.velocity));
        // Touching while moving apart (or not at all) is no collision; creeping through
        // the edge, however slowly, is one.
        let approaching = normal_velocity < -self.negligible_speed();
        let creeping = !approaching && normal_velocity < 0.0 && {
            let end = |x: usize| self.position[x] + dt * self.velocity[x];
            hit.normal.dot(end(i) - end(a).lerp(end(b), hit.alpha)) < 0.0
        };
        (approaching || creeping).then_some((pair, hit.normal, normal_velocity))
    }

    /// Proximity, then crossings ([`Contacts::resolve_crossings`]).
    fn resolve(&mut self) -> CollisionOutcome {
        self.find_pairs();
        let proximity = self.proximity_pass();
        let mut outcome = self.resolve_crossings(proximity > 0);
        outcome.impulses += proximity;
        outcome
    }

    /// Detection and impulses until a full pass finds no collision or the cap is hit;
    /// then the fail-safe. Leaves the velocities collision-free. `stale`: the current
    /// pairs predate a velocity change.
    fn resolve_crossings(&mut self, mut stale: bool) -> CollisionOutcome {
        let mut outcome = CollisionOutcome::default();
        for _ in 0..self.config.max_iterations {
            if stale {
                self.find_pairs();
            }
            let impulses = self.collision_pass();
            outcome.impulses += impulses;
            if impulses == 0 {
                return outcome;
            }
            stale = true;
        }
        outcome.failsafe = true;
        outcome.unresolved = self.fail_safe();
        outcome
    }

    /// Project the islands the contacts touched onto their constraints again, with the
    /// contacts as rows that must not approach (DESIGN §7). Particles in rigid impact
    /// zones keep their velocities.
    fn reproject(
        &mut self,
        islands: &mut Islands,
        settings: &ProjectionSettings,
        metrics: &mut StrandMetrics,
    ) {
        // Rows: every contact met this step, and every pair already closer than twice
        // the thickness. Each may approach while it ends the step at least half the
        // thickness apart (the next proximity pass restores the rest); asking for no
        // approach at all over-constrains a jammed pile.
        let keep = 0.5 * self.config.thickness;
        let (position, velocity, dt) = (self.position, &*self.velocity, self.dt);
        let row = |p: u32, e: &Edge, alpha: f64, normal: DVec2| {
            let mut row = ContactRow::point_edge(p, e.a, e.b, alpha, normal, velocity);
            let contact_point = position[e.a as usize].lerp(position[e.b as usize], alpha);
            let gap = normal.dot(position[p as usize] - contact_point);
            row.target = row.target.min((keep - gap) / dt);
            row
        };
        let scratch = &mut *self.scratch;
        scratch.contact_rows.clear();
        for c in &scratch.contacts {
            let e = &self.edges[c.edge as usize];
            scratch.contact_rows.push(row(c.p, e, c.alpha, c.normal));
        }
        for &(p, k) in &scratch.pairs {
            let e = &self.edges[k as usize];
            if scratch.contact_index.contains_key(&(p, k)) {
                continue;
            }
            let x = position[p as usize];
            let (alpha, distance) =
                closest_on_segment(x, position[e.a as usize], position[e.b as usize]);
            if distance > 0.0 && distance < 2.0 * self.config.thickness {
                let contact_point = position[e.a as usize].lerp(position[e.b as usize], alpha);
                scratch
                    .contact_rows
                    .push(row(p, e, alpha, (x - contact_point) / distance));
            }
        }
        scratch.reprojection_inverse_mass.clear();
        scratch
            .reprojection_inverse_mass
            .extend_from_slice(self.inverse_mass);
        for &i in scratch.zones.members() {
            scratch.reprojection_inverse_mass[i as usize] = 0.0;
        }
        let mut bodies = Bodies {
            position: self.position,
            velocity: &mut *self.velocity,
            inverse_mass: &scratch.reprojection_inverse_mass,
        };
        islands.project_with_contacts(
            &mut bodies,
            &scratch.contact_rows,
            self.dt,
            settings,
            &mut metrics.contact_projection,
        );
    }

    /// Rigid impact zones until no approaching contact is left; returns the number
    /// left unresolved.
    fn fail_safe(&mut self) -> usize {
        let n = self.position.len();
        self.scratch.zones.reset(n);
        for _round in 0..(4 * n + 16) {
            self.find_pairs();
            self.scratch.hits.clear();
            for slot in 0..self.scratch.pairs.len() {
                let (p, k) = self.scratch.pairs[slot];
                if let Some((pair, ..)) = self.approaching_hit(p, k) {
                    self.scratch
                        .hits
                        .push((pair.p as u32, pair.q as u32, pair.r as u32));
                }
            }
            if self.scratch.hits.is_empty() {
                break;
            }
            let zones = &mut self.scratch.zones;
            let mut merged = false;
            for &(p, q, r) in &self.scratch.hits {
                merged |= zones.join(p as usize, q as usize);
                merged |= zones.join(p as usize, r as usize);
            }
            if !merged {
                // Collisions inside zones: their rotation is the culprit.
                let mut stopped = false;
                for &(p, ..) in &self.scratch.hits {
                    stopped |= zones.stop_rotation(p as usize);
                }
                if !stopped {
                    return self.scratch.hits.len();
                }
            }
            zones.rigidify(self.position, self.velocity, self.mass, self.inverse_mass);
        }
        for &i in self.scratch.zones.members() {
            self.in_contact[i as usize] |= self.inverse_mass[i as usize] > 0.0;
        }
        0
    }
}

/// The Collide stage.
#[allow(clippy::too_many_arguments)]
pub fn collide(
    config: Res<CollisionConfig>,
    step: Res<StrandsConfig>,
    constraint: Option<Res<ConstraintConfig>>,
    islands: Option<ResMut<Islands>>,
    topology: Res<Topology>,
    mut state: ResMut<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
    mut metrics: ResMut<StrandMetrics>,
) {
    let ParticleState {
        position,
        velocity,
        mass,
        inverse_mass,
        in_contact,
        ..
    } = &mut *state;
    in_contact.fill(false);
    if !config.enabled {
        return;
    }
    let scratch = &mut *scratch;
    scratch.contacts.clear();
    scratch.contact_index.clear();
    scratch.zones.reset(position.len());
    let mut contacts = Contacts {
        edges: &topology.edges,
        position,
        velocity,
        mass,
        inverse_mass,
        in_contact,
        config: &config,
        dt: step.dt,
        scratch,
    };
    let reprojection = match (constraint, islands) {
        (Some(c), Some(i)) if c.solver.projects_contacts() && config.contact_passes > 0 => {
            Some((c, i))
        }
        _ => None,
    };
    let mut total = contacts.resolve();
    if let Some((constraint, mut islands)) = reprojection {
        // Re-project the islands the contacts touched, with the contacts as rows that
        // must not approach; accept the result unless it makes something cross, in which
        // case resolve that and try again. Ending inside the cushion is accepted: the
        // next step's proximity pass deals with it. Whatever happens, collisions come
        // last, so non-penetration is never traded for length.
        let settings = ProjectionSettings {
            // Two shortest edges per step: room for the corrections of a strand that
            // lands moving a good part of an edge per step (dt = 1/300 on long_strand
            // stays exact; half an edge rejected a sixth of those), while a nearly
            // dependent set of rows asking for more is still refused.
            max_correction: 2.0,
            // Contacts met to a thousandth of the thickness per step, well inside the
            // cushion (the edges are met exactly whatever the contacts do).
            contact_tolerance: 1e-3 * config.thickness,
            ..constraint.projection()
        };
        let mut changed = total.impulses > 0;
        for _ in 0..config.contact_passes {
            if !changed {
                break;
            }
            contacts.reproject(&mut islands, &settings, &mut metrics);
            let crossings = contacts.resolve_crossings(true);
            changed = crossings.impulses > 0;
            total.impulses += crossings.impulses;
            total.failsafe |= crossings.failsafe;
            total.unresolved += crossings.unresolved;
        }
        metrics.contact_unsettled_steps += u64::from(changed);
    }
    metrics.collisions += total.impulses;
    metrics.collisions_last_step = total.impulses;
    metrics.failsafe_steps += u64::from(total.failsafe);
    metrics.unresolved_collisions += total.unresolved as u64;
}

/// The Measure stage's crossing check (checked mode only).
pub fn check_crossings(
    config: Res<CollisionConfig>,
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if !config.check_crossings {
        return;
    }
    let CollisionScratch {
        crossing_pairs,
        crossing_broad,
        ..
    } = &mut *scratch;
    let crossings = crossings::count_crossings(
        &topology.edges,
        &state.position,
        crossing_broad,
        config.broad_phase,
        crossing_pairs,
    );
    metrics.crossing_pairs_last_step = crossings;
    *metrics.edge_crossings.get_or_insert(0) += u64::from(crossings > 0);
}
