//! The contact loop: the only place where the constraint solve and collision processing
//! meet.
//!
//! Before any impulse, the contact solve (the Speculate sub-stage) turns every pair
//! within reach into a contact row and projects the islands they touch together with
//! them (`constraints::projection::project_with_contacts`): the rows keep pairs a cushion
//! apart, with friction, and every edge stays exact. Continuous detection then
//! verifies the step; what the rows' linearization missed gets collision impulses.
//! After impulses, the islands they touched are projected again together, with every
//! contact as a row that may not approach, and detection runs again; this alternates
//! until a round applies no impulse or [`ContactConfig::passes`] are done. Collisions
//! always come last, so non-penetration is never traded for length: what the last
//! round of impulses left, the islands finish as exact rigid zones.

use bevy::math::DVec2;
use bevy::prelude::*;

use super::active_set::ActiveRows;
use super::driver::GroupDriver;
use super::rows::{ContactRow, RowImpulse};
use super::settings::{ContactOutcome, ContactSettings, Resting};
use super::speculative::{SpeculationScratch, SpeculationSettings, speculative_rows};
use super::warm::{NamedWarmStart, NewIndices, Numbering, keyed, named};
use crate::collision::CollisionScratch;
use crate::collision::impulses::{Collider, Contact};
use crate::collision::plugin::collider;
use crate::constraints::Islands;
use crate::constraints::projection::Bodies;
use crate::halving::HalvingApp;
use crate::metrics::{IterationStats, StrandMetrics};
use crate::model::geometry::closest_on_segment;
use crate::model::{Edge, PointEdgePair};
use crate::schedule::{CollideSet, ConstrainSet, StrandsStep};
use crate::world::config::{CollisionConfig, ConstraintConfig, ContactConfig, StrandsConfig};
use crate::world::state::{ParticleState, copy_buffer};
use crate::world::topology::Topology;

/// The contact loop's settings and buffers.
pub struct ContactLoopPlugin;

impl Plugin for ContactLoopPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ContactConfig>()
            .init_resource::<ContactRows>()
            .register_type::<ContactConfig>()
            // The warm starts are the one thing a step leaves for the next.
            .save_for_halving::<ContactRows, (Vec<(u32, u32, RowImpulse)>, u64, f64)>(
                |rows, (warm, version, warm_dt)| {
                    // The warm starts grow with the keys' buffer: so does their copy.
                    let room = rows.keys.capacity().max(rows.warm.capacity());
                    if warm.capacity() < room {
                        warm.reserve(room);
                    }
                    copy_buffer(warm, &rows.warm);
                    *version = rows.warm_version;
                    *warm_dt = rows.warm_dt;
                },
                |rows, (warm, version, warm_dt)| {
                    copy_buffer(&mut rows.warm, warm);
                    rows.warm_version = *version;
                    rows.warm_dt = *warm_dt;
                },
            )
            .add_systems(
                StrandsStep,
                (
                    speculate.in_set(ConstrainSet::Speculate),
                    contact_loop.in_set(CollideSet::ContactLoop),
                ),
            );
    }
}

/// The longest step whose rows may end `tolerance × thickness × dt` short: a longer
/// step's may end no shorter than this one's. A rope whose contacts were met to the
/// full `dt` at 1/60 s kept a few particles flickering at 0.1–0.3 m/s where its
/// edges lay wedged on each other — each step's shortfall set against its stiff
/// bending's answer to it — and the built-in `rope_coil` was over 1 cm/s at the
/// 95th percentile in a fifth of its ticks for seconds after landing (under 1 % at
/// this bound; docs/step-size.md). At 1/300 s and shorter nothing changes.
const TOLERANCE_STEP: f64 = 1.0 / 300.0;

/// The contact projection's settings: the constraint settings, with the contact loop's
/// correction guard, tolerance and sweeps. Rows give way after `give_way` of the Newton
/// budget: the speculative solve holds its rows longer (9/10: it is the one that keeps
/// strands apart), the contact loop's reprojection sooner (1/2: its rows come after a
/// detected crossing, and the fail-safe is there when they cannot hold). Measured in
/// docs/step-size.md: either share alone leaves more fail-safe steps at 1/120.
fn contact_settings(
    contact: &ContactConfig,
    collisions: &CollisionConfig,
    constraints: &ConstraintConfig,
    dt: f64,
    give_way: (u32, u32),
) -> ContactSettings {
    ContactSettings {
        resting: None,
        projection: constraints.projection(),
        sweeps: contact.sweeps,
        contact_tolerance: contact.tolerance * collisions.thickness * dt.min(TOLERANCE_STEP),
        max_correction: contact.max_correction,
        // At most the budget itself: the product cannot overflow in u64.
        rows_give_way: (u64::from(constraints.max_iterations) * u64::from(give_way.0)
            / u64::from(give_way.1.max(1))) as u32,
        solver: contact.solver,
        newton_first: false,
    }
}

/// A speculative row acts from the start of its solve when it is within this many
/// thicknesses of its target (or carries a warm start): rows farther clear, most of a
/// stiff fur's, are checked after the solve instead of joining its groups. Half the
/// cushion: at zero, the limp fur's resting rows were left out only to be taken in
/// again, a second round in one solve in eight (none in 300 steps at half).
const ACTING_MARGIN: f64 = 0.5;

/// The contact rows of the latest contact projection and the impulses they carried,
/// reused every step.
#[derive(Resource, Default, Debug)]
pub struct ContactRows {
    /// The rows.
    pub rows: Vec<ContactRow>,
    /// Each row's total impulse.
    impulses: Vec<RowImpulse>,
    /// Each speculative row's key (see [`speculative_rows`]).
    keys: Vec<(u32, u32, u32)>,
    speculation: SpeculationScratch,
    /// Each island projected, and whether it met its edges.
    outcomes: Vec<(u32, bool)>,
    /// The last step's speculative impulses, by key, sorted: the warm start of the
    /// same contacts' rows.
    warm: Vec<(u32, u32, RowImpulse)>,
    /// The topology version the warm starts belong to.
    warm_version: u64,
    /// What the packed indices of the numbering's version stand for: warm starts of
    /// that version are renamed through it when the topology is rebuilt.
    numbering: Numbering,
    /// The step the warm starts were taken over: an impulse that held a contact over
    /// it holds it over a step of another size (a halved or split one) scaled by the
    /// ratio of the steps — unscaled, a quarter step began with four times the push.
    warm_dt: f64,
    /// Which rows act, round by round, and the groups they join.
    solve: GroupSolve,
}

/// The active set's rounds and the driver of the groups they project, sized for the
/// islands of one topology version.
#[derive(Default, Debug)]
struct GroupSolve {
    active: ActiveRows,
    driver: GroupDriver,
    version: Option<u64>,
}

impl GroupSolve {
    /// Project every island that `rows` touch, and the loose free particles
    /// they touch, with the rows: both sides of every contact move, each island as a
    /// whole (see [`project_with_contacts`](super::projection::project_with_contacts)), each
    /// independent group on its own and on up to `threads` threads. `island` gives each
    /// particle's island, as [`Topology::island`] does; `impulses[c]` is row c's warm
    /// start on entry and its total impulse on return. `outcomes` tells, for each
    /// island projected, whether it met its edges. With `acting: Some(margin)` only the
    /// rows that act are projected: those warm-started or within `margin` (a distance
    /// over the step) of their target at the start, their neighbours, and any the
    /// projection leaves short (then projected again from the same start) — for islands
    /// the Constrain stage has just met, where most rows within reach never push; a row
    /// left out ends with no impulse. `None`: every row.
    #[allow(clippy::too_many_arguments)]
    fn project(
        &mut self,
        islands: &mut Islands,
        island: &[u32],
        bodies: &mut Bodies,
        rows: &[ContactRow],
        impulses: &mut [RowImpulse],
        dt: f64,
        settings: &ContactSettings,
        stats: &mut IterationStats,
        outcomes: &mut Vec<(u32, bool)>,
        threads: usize,
        acting: Option<f64>,
    ) -> ContactOutcome {
        let version = islands.version;
        let (set, edge_impulse) = islands.contact_parts();
        if self.version != Some(version) {
            self.driver.reserve(set.islands.len(), island.len());
            self.version = Some(version);
        }
        self.active.project(
            &mut self.driver,
            set,
            island,
            bodies,
            rows,
            impulses,
            dt,
            settings,
            threads,
            stats,
            outcomes,
            edge_impulse,
            acting,
        )
    }
}

impl ContactRows {
    /// Remember the impulses for the next step's rows of the same pairs, and the
    /// contacts that took one (into `speculated`).
    fn remember(&mut self, speculated: &mut Vec<Contact>, dt: f64) {
        self.warm.clear();
        self.warm_dt = dt;
        // As large as the keys' buffer: they grow when it does, not at a later step.
        let room = self.keys.capacity();
        self.warm.reserve(room.saturating_sub(self.warm.len()));
        speculated.reserve(room.saturating_sub(speculated.len()));
        let rows = self.keys.iter().zip(&self.impulses).zip(&self.rows);
        for ((&(p, key, edge), impulse), row) in rows {
            if impulse.normal > 0.0 {
                self.warm.push((p, key, *impulse));
                speculated.push(Contact {
                    p,
                    edge,
                    alpha: -row.coefficients[2],
                    normal: row.normal,
                });
            }
        }
        self.warm.sort_unstable_by_key(|&(p, k, _)| (p, k));
    }

    /// Carry the warm starts over to `topology`'s numbering (`particles`: its packed
    /// particles' entities), dropping those of contacts it no longer has. Warm starts
    /// restored by a halving from before the last renaming are of a numbering no
    /// longer kept: they are dropped, as every one was before.
    fn renumber(&mut self, particles: &[Entity], topology: &Topology) {
        let (warm, dt) = self.named_warm_starts();
        self.restore_warm_starts(&warm, dt, particles, topology);
    }

    /// Whether the warm starts are numbered as topology `version` is.
    fn numbered_for(&self, version: u64) -> bool {
        self.warm_version == version && self.numbering.version == Some(version)
    }

    /// The warm starts the next step will use, named by entity, and the step they were
    /// taken over (for a snapshot).
    pub fn named_warm_starts(&self) -> (Vec<NamedWarmStart>, f64) {
        if !self.numbered_for(self.warm_version) {
            return (Vec::new(), self.warm_dt);
        }
        (named(&self.warm, &self.numbering), self.warm_dt)
    }

    /// Take `warm` (taken over a step of `dt`) as the warm starts of `topology`, whose
    /// packed particles are `particles` (a restored snapshot's).
    pub fn restore_warm_starts(
        &mut self,
        warm: &[NamedWarmStart],
        dt: f64,
        particles: &[Entity],
        topology: &Topology,
    ) {
        let strands: Vec<Entity> = topology.strands.iter().map(|s| s.entity).collect();
        let new = NewIndices {
            particles: &topology.index,
            strands: &strands,
            edges: &topology.edges,
        };
        self.warm = keyed(warm, &new);
        self.warm_dt = dt;
        (self.numbering).record(topology.version, particles, &strands, &topology.edges);
        self.warm_version = topology.version;
    }

    /// The warm start of the row keyed `(p, key)` in a step of `dt`.
    fn warm_start(&self, p: u32, key: u32, dt: f64) -> RowImpulse {
        let Ok(i) = self
            .warm
            .binary_search_by_key(&(p, key), |&(q, k, _)| (q, k))
        else {
            return RowImpulse::default();
        };
        let impulse = self.warm[i].2;
        if dt == self.warm_dt {
            return impulse;
        }
        let scale = dt / self.warm_dt;
        RowImpulse {
            normal: impulse.normal * scale,
            tangent: impulse.tangent * scale,
        }
    }
}

/// The Speculate sub-stage: the contact solve. The pairs the broad phase finds for the
/// projected motion become rows ([`speculative_rows`]: keep the cushion, no sliding
/// beyond Coulomb's cone), and every island the rows touch is projected again together
/// with them, both sides of each contact moving and every edge exact, warm-started
/// from the previous step's impulses of the same contacts. An island whose contact
/// projection fails is projected alone again, so that the stage always leaves every
/// edge met.
#[allow(clippy::too_many_arguments)]
pub fn speculate(
    collisions: Res<CollisionConfig>,
    contact: Res<ContactConfig>,
    constraints: Res<ConstraintConfig>,
    step: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut islands: ResMut<Islands>,
    mut state: ResMut<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
    mut buffers: ResMut<ContactRows>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if !speculating(&collisions, &contact, &constraints) {
        return;
    }
    let settings = ContactSettings {
        // Groups at rest are met closely (the sweeps' residue keeps a pile trembling).
        resting: Some(Resting {
            speed: step.sleep.speed,
            fall: step.gravity * step.dt,
            sweeps: contact.rest_sweeps,
            tolerance: contact.rest_tolerance * collisions.thickness * step.dt,
        }),
        ..contact_settings(&contact, &collisions, &constraints, step.dt, (9, 10))
    };
    let impulse_settings = collisions.impulse_settings(step.worker_threads());
    let thickness = collisions.thickness;
    let reach = contact.reach.max(1.0) * thickness;
    let buffers = &mut *buffers;
    if !buffers.numbered_for(topology.version) {
        buffers.renumber(&state.entity, &topology);
    }
    let mut collider = collider(
        &mut state,
        &topology,
        &impulse_settings,
        step.dt,
        &mut scratch.impulses,
    );
    collider.find_pairs();
    collider.scratch.speculated.clear();
    collider.scratch.speculated_step = true;
    let dt = collider.dt;
    speculative_rows(
        collider.scratch.cushioned_pairs(collider.edges),
        collider.edges,
        collider.position,
        collider.velocity,
        dt,
        &SpeculationSettings {
            thickness,
            keep: contact.keep * thickness,
            reach,
            friction: collisions.friction,
            down: step.gravity.normalize_or_zero(),
        },
        collider.settings.threads,
        &mut buffers.speculation,
        &mut buffers.rows,
        &mut buffers.keys,
    );
    buffers.impulses.clear();
    for &(p, key, _) in &buffers.keys {
        let warm = buffers.warm_start(p, key, dt);
        buffers.impulses.push(warm);
    }
    if buffers.rows.is_empty() {
        buffers.warm.clear();
        return;
    }
    let mut bodies = Bodies::new(collider.position, collider.velocity, collider.inverse_mass);
    buffers.solve.project(
        &mut islands,
        collider.groups,
        &mut bodies,
        &buffers.rows,
        &mut buffers.impulses,
        dt,
        &settings,
        &mut metrics.contact_projection,
        &mut buffers.outcomes,
        collider.settings.threads,
        Some(ACTING_MARGIN * thickness),
    );
    buffers.remember(&mut collider.scratch.speculated, dt);
    for &(island, met) in &buffers.outcomes {
        if !met {
            islands.project_alone(
                island as usize,
                &mut bodies,
                dt,
                &constraints.projection(),
                &mut metrics.projection,
            );
        }
    }
}

/// Whether the Speculate sub-stage runs its contact solve (and so takes the place of
/// the proximity impulses).
fn speculating(
    collisions: &CollisionConfig,
    contact: &ContactConfig,
    constraints: &ConstraintConfig,
) -> bool {
    collisions.enabled && constraints.solver.projects_contacts() && contact.speculative
}

/// The ContactLoop sub-stage: alternate re-projection with contact rows and collision
/// impulses until a round applies no impulse.
#[allow(clippy::too_many_arguments)]
pub fn contact_loop(
    collisions: Res<CollisionConfig>,
    contact: Res<ContactConfig>,
    constraints: Res<ConstraintConfig>,
    step: Res<StrandsConfig>,
    topology: Res<Topology>,
    mut islands: ResMut<Islands>,
    mut state: ResMut<ParticleState>,
    mut scratch: ResMut<CollisionScratch>,
    mut rows: ResMut<ContactRows>,
    mut metrics: ResMut<StrandMetrics>,
) {
    if !(collisions.enabled && constraints.solver.projects_contacts() && contact.passes > 0) {
        return;
    }
    let settings = contact_settings(&contact, &collisions, &constraints, step.dt, (1, 2));
    let impulse_settings = collisions.impulse_settings(step.worker_threads());
    let scratch = &mut *scratch;
    let mut changed = scratch.outcome.impulses > 0;
    let mut collider = collider(
        &mut state,
        &topology,
        &impulse_settings,
        step.dt,
        &mut scratch.impulses,
    );
    for _ in 0..contact.passes {
        if !changed {
            break;
        }
        reproject(
            &mut collider,
            &contact,
            &mut islands,
            &settings,
            &mut rows,
            &mut metrics,
        );
        let round = collider.resolve_crossings(true);
        changed = round.impulses > 0;
        scratch.outcome.add(round);
    }
    let unsettled = collider.scratch.any_dirty();
    if unsettled {
        // Impulses after an island's last good projection (the last round's, or before a
        // projection that failed): rather than leave those edges stretched, end the step
        // with the islands rigid.
        scratch.outcome.add(collider.finish_rigidly());
    }
    metrics.contact_unsettled_steps += u64::from(unsettled);
}

/// Project the islands the contacts touched onto their constraints again, with the
/// contacts as rows that must not approach, and record which met their edges.
///
/// Its rows are built here, not by [`speculative_rows`], on purpose: they come after
/// the collision stage's impulses, which already took friction and the approach
/// speed, so each only asks its pair not to come closer than it now is (or than
/// `keep`) — no friction, no cushion target — for every contact the impulses met and
/// every pair already within `reach`, where the speculative rows are one per point and
/// strand for the motion the step predicts.
fn reproject(
    collider: &mut Collider,
    contact: &ContactConfig,
    islands: &mut Islands,
    settings: &ContactSettings,
    buffers: &mut ContactRows,
    metrics: &mut StrandMetrics,
) {
    let (rows, impulses, solve) = (&mut buffers.rows, &mut buffers.impulses, &mut buffers.solve);
    // Rows: every contact met this step, and every pair already closer than `reach`
    // thicknesses. Each may approach while it ends the step at least `keep` of the
    // thickness apart.
    let thickness = collider.settings.thickness;
    let keep = contact.keep * thickness;
    let (position, velocity, dt) = (collider.position, &*collider.velocity, collider.dt);
    let row = |p: u32, e: &Edge, alpha: f64, normal: DVec2| {
        let pair = PointEdgePair {
            p: p as usize,
            q: e.a as usize,
            r: e.b as usize,
            alpha,
        };
        let mut row = ContactRow::point_edge(pair, normal, velocity);
        let contact_point = position[e.a as usize].lerp(position[e.b as usize], alpha);
        let gap = normal.dot(position[p as usize] - contact_point);
        row.target = row.target.min((keep - gap) / dt);
        row
    };
    let scratch = &*collider.scratch;
    rows.clear();
    for c in &scratch.contacts {
        let e = &collider.edges[c.edge as usize];
        rows.push(row(c.p, e, c.alpha, c.normal));
    }
    for &(p, k) in &scratch.pairs {
        let e = &collider.edges[k as usize];
        if scratch.met(p, k) {
            continue;
        }
        let x = position[p as usize];
        let (alpha, distance) =
            closest_on_segment(x, position[e.a as usize], position[e.b as usize]);
        if distance > 0.0 && distance < contact.reach * thickness {
            let contact_point = position[e.a as usize].lerp(position[e.b as usize], alpha);
            rows.push(row(p, e, alpha, (x - contact_point) / distance));
        }
    }
    impulses.clear();
    impulses.resize(rows.len(), RowImpulse::default());
    let mut bodies = Bodies::new(collider.position, collider.velocity, collider.inverse_mass);
    solve.project(
        islands,
        collider.groups,
        &mut bodies,
        rows,
        impulses,
        dt,
        settings,
        &mut metrics.contact_projection,
        &mut buffers.outcomes,
        collider.settings.threads,
        // Every row: impulses left these islands stretched, so all must be projected.
        None,
    );
    for &(island, met) in &buffers.outcomes {
        collider.scratch.projected(island, met);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_warm_start_is_scaled_to_the_step_it_starts() {
        // An impulse that held a contact over a step of 1/60 s holds it over a quarter
        // step at a quarter of its size (unscaled, the built-in pile boiled at 1/60 split
        // ahead), over the same step unchanged bit for bit.
        let impulse = RowImpulse {
            normal: 0.3,
            tangent: -0.1,
        };
        let dt = 1.0 / 60.0;
        let rows = ContactRows {
            warm: vec![(4, 7, impulse)],
            warm_dt: dt,
            ..Default::default()
        };
        assert_eq!(rows.warm_start(4, 7, dt), impulse);
        let quarter = rows.warm_start(4, 7, dt / 4.0);
        assert!((quarter.normal - 0.075).abs() < 1e-15, "{quarter:?}");
        assert!((quarter.tangent + 0.025).abs() < 1e-15, "{quarter:?}");
        let whole = ContactRows {
            warm_dt: dt / 4.0,
            ..rows
        };
        let back = whole.warm_start(4, 7, dt);
        assert!((back.normal - 1.2).abs() < 1e-15, "{back:?}");
        // A pair with no impulse last step starts from none.
        assert_eq!(whole.warm_start(4, 8, dt), RowImpulse::default());
    }
}
