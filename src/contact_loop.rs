//! The contact loop: the only place where the constraint solve and collision processing
//! meet.
//!
//! Collision impulses come after the constraint solve, so the edges next to contacts
//! end a step stretched by them. After the first round of impulses, the islands that
//! contacts touched are projected onto their constraints again with every contact as
//! an inequality row (the pair may not approach beyond a cushion), and detection with
//! impulses runs again on the result; this alternates until a round applies no impulse
//! or [`ContactConfig::passes`] are done. Collisions always come last, so
//! non-penetration is never traded for length: what the last round of impulses changes,
//! edges keep (the report counts such steps as unsettled).

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::collision::CollisionScratch;
use crate::collision::impulses::Collider;
use crate::collision::plugin::collider;
use crate::constraints::Islands;
use crate::constraints::projection::{Bodies, ContactRow, ProjectionSettings};
use crate::metrics::StrandMetrics;
use crate::model::geometry::closest_on_segment;
use crate::model::{Edge, PointEdgePair};
use crate::schedule::{CollideSet, ConstrainSet, StrandsStep};
use crate::world::config::{CollisionConfig, ConstraintConfig, ContactConfig, StrandsConfig};
use crate::world::state::ParticleState;
use crate::world::topology::Topology;

/// The contact loop's settings and buffers.
pub struct ContactLoopPlugin;

impl Plugin for ContactLoopPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ContactConfig>()
            .init_resource::<ContactRows>()
            .register_type::<ContactConfig>()
            .add_systems(
                StrandsStep,
                (
                    speculate.in_set(ConstrainSet::Speculate),
                    contact_loop.in_set(CollideSet::ContactLoop),
                ),
            );
    }
}

/// The projection's settings with contact rows: the constraint settings, with the
/// contact loop's correction guard and tolerance.
fn contact_projection(
    contact: &ContactConfig,
    collisions: &CollisionConfig,
    constraints: &ConstraintConfig,
) -> ProjectionSettings {
    ProjectionSettings {
        max_correction: contact.max_correction,
        contact_tolerance: contact.tolerance * collisions.thickness,
        ..constraints.projection()
    }
}

/// The contact rows of the latest re-projection, reused every step.
#[derive(Resource, Default, Debug)]
pub struct ContactRows {
    /// The rows.
    pub rows: Vec<ContactRow>,
    /// Each island projected, and whether it met its edges.
    outcomes: Vec<(u32, bool)>,
}

/// The Speculate sub-stage: the points the projected motion would bring within `keep`
/// of the thickness of an edge become rows, and their islands are projected again with
/// them, before any impulse: against obstacles (walls, pinned edges) and between paths,
/// which are projected together as one unit. An island whose projection with rows
/// fails is projected alone again, so that the stage always leaves every edge met.
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
    if !(collisions.enabled && constraints.solver.projects_contacts() && contact.speculative) {
        return;
    }
    let settings = contact_projection(&contact, &collisions, &constraints);
    let impulse_settings = collisions.impulse_settings(step.worker_threads());
    let keep = contact.keep * collisions.thickness;
    let buffers = &mut *buffers;
    let mut collider = collider(
        &mut state,
        &topology,
        &impulse_settings,
        step.dt,
        &mut scratch.impulses,
    );
    collider.find_pairs();
    let (position, velocity, dt) = (collider.position, &*collider.velocity, collider.dt);
    buffers.rows.clear();
    let groups = collider.groups;
    for &(p, k) in &collider.scratch.pairs {
        let e = &collider.edges[k as usize];
        // A row between two free islands is met by both at once only when both are
        // paths (one unit); with a loop, tree or graph the island sweep would push the
        // first one solved, so those pairs stay with the momentum-conserving impulses.
        if !islands.one_unit([p, e.a, e.b].map(|i| groups[i as usize])) {
            continue;
        }
        let (q, r) = (position[e.a as usize], position[e.b as usize]);
        let x = position[p as usize];
        let (alpha, gap) = closest_on_segment(x, q, r);
        if gap <= 0.0 {
            continue; // on the edge: the collision stage decides its side
        }
        let normal = (x - q.lerp(r, alpha)) / gap;
        let pair = PointEdgePair {
            p: p as usize,
            q: e.a as usize,
            r: e.b as usize,
            alpha,
        };
        let mut row = ContactRow::point_edge(pair, normal, velocity);
        if gap + dt * row.target >= keep {
            continue; // ends the step farther than `keep` along the normal
        }
        // Approach allowed down to `keep`; from closer, no further.
        row.target = if gap >= keep { (keep - gap) / dt } else { 0.0 };
        buffers.rows.push(row);
    }
    if buffers.rows.is_empty() {
        return;
    }
    let mut bodies = Bodies::new(collider.position, collider.velocity, collider.inverse_mass);
    islands.project_with_contacts(
        collider.groups,
        &mut bodies,
        &buffers.rows,
        dt,
        &settings,
        contact.sweeps,
        false,
        &mut metrics.contact_projection,
        &mut buffers.outcomes,
    );
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
    let settings = contact_projection(&contact, &collisions, &constraints);
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
fn reproject(
    collider: &mut Collider,
    contact: &ContactConfig,
    islands: &mut Islands,
    settings: &ProjectionSettings,
    buffers: &mut ContactRows,
    metrics: &mut StrandMetrics,
) {
    let rows = &mut buffers.rows;
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
    let mut bodies = Bodies::new(collider.position, collider.velocity, collider.inverse_mass);
    islands.project_with_contacts(
        collider.groups,
        &mut bodies,
        rows,
        dt,
        settings,
        contact.sweeps,
        true,
        &mut metrics.contact_projection,
        &mut buffers.outcomes,
    );
    for &(island, met) in &buffers.outcomes {
        collider.scratch.projected(island, met);
    }
}
