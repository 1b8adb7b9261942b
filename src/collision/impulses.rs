//! Collision impulses over one step's motion, on slices: the proximity pass that keeps
//! pairs a thickness apart, continuous detection with an inelastic, frictional impulse
//! per collision repeated until a pass is clean, and the fail-safe when the cap is hit.
//!
//! Each pass tests the candidate pairs of the broad phase in a fixed order and applies
//! every impulse as it is found, so later tests see the velocities earlier impulses
//! left. Every contact met is recorded (one per point and edge, the latest), for the
//! contact loop's rows.

use bevy::math::DVec2;
use bevy::platform::collections::HashMap;

use super::broad_phase::{BroadPhase, BroadPhaseMethod};
use super::ccd::point_edge_time_of_impact;
use super::exempt::Exempt;
use super::failsafe::ImpactZones;
use super::response::{collision_normal_change, contact_change, repulsion_normal_change};
use super::still::{StillScratch, merge_by_point};
use crate::model::geometry::closest_on_segment;
use crate::model::motion::{displacement, displacements};
use crate::model::{Edge, NO_ISLAND, PointEdgePair};

/// The collision settings the passes use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpulseSettings {
    /// Thickness `h`: pairs are kept at least this far apart.
    pub thickness: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Restitution of collision impulses.
    pub restitution: f64,
    /// Detection passes before the fail-safe.
    pub max_iterations: u32,
    /// The gap a collision leaves, as a fraction of the thickness.
    pub separation: f64,
    /// How candidate pairs are found.
    pub broad_phase: BroadPhaseMethod,
    /// Threads the candidate search may use (the pairs are the same, in the same
    /// order, whatever the count).
    pub threads: usize,
}

/// A contact met this step: point `p` against edge `edge` at `alpha`, along `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// The point (packed index).
    pub p: u32,
    /// The edge (index into the edge list).
    pub edge: u32,
    /// Where on the edge: `(1 − α) a + α b`.
    pub alpha: f64,
    /// The contact normal, pointing from the edge to the point.
    pub normal: DVec2,
}

/// The passes' buffers, reused every step.
#[derive(Clone, Debug, Default)]
pub struct ImpulseScratch {
    broad: BroadPhase,
    /// Where much of the world stands still: the grid of the moving edges, queried
    /// with the still points (see `still`).
    still: StillScratch,
    /// Candidate (point, edge) pairs of the latest broad phase.
    pub pairs: Vec<(u32, u32)>,
    /// The pairs of a strand's own points and edges within a thickness along it: they
    /// are tested for crossing, not kept a cushion apart.
    exempt: Exempt,
    /// `pairs` less the exempt ones, when some are.
    cushioned: Vec<(u32, u32)>,
    displacement: Vec<DVec2>,
    /// Every contact met this step, one per point and edge.
    pub contacts: Vec<Contact>,
    /// The contacts the contact solve (before any impulse) met this step with an
    /// impulse; they stand for the proximity pass's when `speculated_step` is set.
    pub speculated: Vec<Contact>,
    /// Whether the contact solve ran this step (set by it, taken by the proximity
    /// stage).
    pub speculated_step: bool,
    contact_index: HashMap<(u32, u32), u32>,
    /// The fail-safe's rigid impact zones of this step.
    pub zones: ImpactZones,
    hits: Vec<(u32, u32, u32)>,
    /// The rigid groups (constraint islands) whose velocities impulses changed since
    /// their last projection met every edge or rigid zone moved them: their edges may
    /// be stretched.
    dirty: Vec<bool>,
}

impl ImpulseScratch {
    /// The broad phase's grid as the last pass built it (the crossing check counts on
    /// it when it still covers the step-end edges).
    pub fn grid_mut(&mut self) -> &mut BroadPhase {
        &mut self.broad
    }

    /// Forget the previous step's contacts and zones; `groups` gives each particle's
    /// rigid group (constraint island).
    pub fn begin_step(&mut self, particles: usize) {
        self.contacts.clear();
        self.contact_index.clear();
        self.zones.reset(particles);
        self.dirty.fill(false);
    }

    /// Group `group` was projected again: its edges are met if `met`.
    pub fn projected(&mut self, group: u32, met: bool) {
        if let Some(dirty) = self.dirty.get_mut(group as usize) {
            *dirty = !met;
        }
    }

    /// Whether some group's edges may be stretched by impulses.
    pub fn any_dirty(&self) -> bool {
        self.dirty.iter().any(|&d| d)
    }

    /// Record a contact that changed no velocity outside a projection (one the contact
    /// solve met): it is in the step's contacts, and its groups stay clean.
    pub fn record(&mut self, contact: Contact) {
        let next = self.contacts.len() as u32;
        let slot = *self
            .contact_index
            .entry((contact.p, contact.edge))
            .or_insert(next);
        if slot == next {
            self.contacts.push(contact);
        } else {
            self.contacts[slot as usize] = contact;
        }
    }

    /// The candidate pairs kept a thickness apart: the latest pairs less the exempt ones
    /// (all of them when none is).
    pub fn cushioned_pairs(&mut self, edges: &[Edge]) -> &[(u32, u32)] {
        if self.exempt.is_empty() {
            return &self.pairs;
        }
        let exempt = &self.exempt;
        self.cushioned.clear();
        self.cushioned
            .extend((self.pairs.iter()).filter(|&&(p, k)| !exempt.exempt(p, &edges[k as usize])));
        &self.cushioned
    }

    /// Whether point `p` met edge `edge` this step.
    pub fn met(&self, p: u32, edge: u32) -> bool {
        self.contact_index.contains_key(&(p, edge))
    }
}

/// A pair to push apart: the point against the edge at the contact coordinate, along
/// the normal towards the point's side.
#[derive(Clone, Copy, Debug)]
struct Collision {
    pair: PointEdgePair,
    normal: DVec2,
    /// Relative normal velocity now (negative: approaching).
    normal_velocity: f64,
    /// Gap along the normal at the start of the step.
    start_gap: f64,
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
    /// The first of them: the point and the edge's two particles (packed indices), and
    /// the moving pinned particle that drove their zone into it, if one did.
    pub first_unresolved: Option<([u32; 3], Option<u32>)>,
}

impl CollisionOutcome {
    /// Add another round's figures.
    pub fn add(&mut self, other: CollisionOutcome) {
        self.impulses += other.impulses;
        self.failsafe |= other.failsafe;
        self.unresolved += other.unresolved;
        self.first_unresolved = self.first_unresolved.or(other.first_unresolved);
    }
}

/// The slices and settings of one step's collision processing.
pub struct Collider<'a> {
    /// Every edge (walls included).
    pub edges: &'a [Edge],
    /// The topology version the edges are of (what is derived from them is kept
    /// while it holds).
    pub version: u64,
    /// Positions at the start of the step.
    pub position: &'a [DVec2],
    /// Velocities: the step's motion, changed by the impulses.
    pub velocity: &'a mut [DVec2],
    /// Masses.
    pub mass: &'a [f64],
    /// Inverse masses (0: pinned).
    pub inverse_mass: &'a [f64],
    /// The rigid group (constraint island) of each particle: a fail-safe zone takes in
    /// whole groups.
    pub groups: &'a [u32],
    /// Whether each particle is a wall's or a body's (see [`Edge::solid`]).
    pub solid: &'a [bool],
    /// Set for every free particle that takes part in a contact.
    pub in_contact: &'a mut [bool],
    /// The settings.
    pub settings: &'a ImpulseSettings,
    /// The step.
    pub dt: f64,
    /// The buffers.
    pub scratch: &'a mut ImpulseScratch,
}

impl Collider<'_> {
    /// Candidate (point, edge) pairs for the current velocities.
    pub fn find_pairs(&mut self) {
        let scratch = &mut *self.scratch;
        displacements(self.velocity, self.dt, &mut scratch.displacement);
        scratch.broad.build(
            self.edges,
            self.position,
            Some(&scratch.displacement),
            self.settings.thickness,
            self.settings.threads,
        );
        scratch.pairs.clear();
        scratch.exempt.update(
            self.version,
            self.edges,
            self.position.len(),
            self.settings.thickness,
        );
        let (edges, w, solid) = (self.edges, self.inverse_mass, self.solid);
        let keep = |p: u32, k: u32| {
            let e = &edges[k as usize];
            e.a != p
                && e.b != p
                && (w[p as usize] > 0.0 || w[e.a as usize] > 0.0 || w[e.b as usize] > 0.0)
                && !(e.solid && solid.get(p as usize).copied().unwrap_or(false))
        };
        let still = &mut scratch.still;
        let grid = self.settings.broad_phase == BroadPhaseMethod::Grid;
        if !(grid && still.split(edges, w, &scratch.displacement)) {
            scratch.broad.point_edge_pairs(
                self.settings.broad_phase,
                self.settings.threads,
                self.position,
                &scratch.displacement,
                keep,
                &mut scratch.pairs,
            );
            return;
        }
        // Moving points against every edge, still points against the moving edges;
        // merged in point order.
        scratch.broad.listed_point_edge_pairs(
            self.settings.threads,
            &still.moving_points,
            self.position,
            &scratch.displacement,
            keep,
            &mut scratch.pairs,
        );
        still.pairs.clear();
        still.broad.build(
            &still.edges,
            self.position,
            Some(&scratch.displacement),
            self.settings.thickness,
            self.settings.threads,
        );
        let index = &still.edge_index;
        still.broad.listed_point_edge_pairs(
            self.settings.threads,
            &still.still_points,
            self.position,
            &scratch.displacement,
            |p, k| keep(p, index[k as usize]),
            &mut still.pairs,
        );
        for pair in &mut still.pairs {
            pair.1 = index[pair.1 as usize];
        }
        merge_by_point(&mut scratch.pairs, &still.pairs, &mut still.merged);
    }

    /// The candidate pairs for the current velocities: those of the last search while
    /// no particle's motion over the step has moved from the one it was searched with
    /// by more than half the thickness (the edges' boxes were inflated by the
    /// thickness, so every pair that can now touch was found), else a new search.
    pub fn refresh_pairs(&mut self) {
        let half = 0.5 * self.settings.thickness;
        let searched = &self.scratch.displacement;
        let moved = searched.len() != self.velocity.len()
            || (self.velocity.iter().zip(searched))
                .any(|(v, d)| (displacement(*v, self.dt) - *d).length_squared() > half * half);
        if moved {
            self.find_pairs();
        }
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
        for i in [pair.p, pair.q, pair.r] {
            let g = self.groups[i];
            if g != NO_ISLAND {
                if scratch.dirty.len() <= g as usize {
                    scratch.dirty.resize(g as usize + 1, false);
                }
                scratch.dirty[g as usize] = true;
            }
        }
        scratch.record(contact);
        true
    }

    /// Take the contact solve's contacts as this step's: recorded, their free
    /// particles marked in contact.
    pub fn adopt_speculated(&mut self) {
        let scratch = &mut *self.scratch;
        // As large as the speculated buffer: they grow when it does, not a step later.
        let room = scratch.speculated.capacity();
        scratch
            .contacts
            .reserve(room.saturating_sub(scratch.contacts.len()));
        let len = scratch.contact_index.len();
        scratch.contact_index.reserve(room.saturating_sub(len));
        for slot in 0..scratch.speculated.len() {
            let contact = scratch.speculated[slot];
            scratch.record(contact);
            let e = &self.edges[contact.edge as usize];
            for i in [contact.p, e.a, e.b] {
                let i = i as usize;
                self.in_contact[i] |= self.inverse_mass[i] > 0.0;
            }
        }
    }

    /// Repulsion for pairs that would end the step closer than the thickness.
    pub fn proximity_pass(&mut self) -> u64 {
        let mut impulses = 0;
        for slot in 0..self.scratch.pairs.len() {
            let (p, k) = self.scratch.pairs[slot];
            let e = &self.edges[k as usize];
            if self.scratch.exempt.exempt(p, e) {
                continue;
            }
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
                self.settings.thickness,
                self.dt,
            );
            // A few ulps short of the thickness is at the thickness.
            if change <= 1e-9 * self.settings.thickness / self.dt {
                continue;
            }
            let delta = contact_change(relative, normal, change, self.settings.friction);
            impulses += u64::from(self.respond(pair, k, delta, normal));
        }
        impulses
    }

    /// One detection pass over the current pairs; impulses are applied as found, each
    /// test using the velocities the earlier impulses left. A collision leaves the
    /// pair ending the step at least the separation apart (or bouncing with the
    /// restitution, if that is more).
    fn collision_pass(&mut self) -> u64 {
        let mut impulses = 0;
        let separation = self.settings.separation * self.settings.thickness;
        for slot in 0..self.scratch.pairs.len() {
            let (p, k) = self.scratch.pairs[slot];
            let Some(c) = self.collision(p, k) else {
                continue;
            };
            let change = collision_normal_change(
                c.normal_velocity,
                c.start_gap,
                separation,
                self.settings.restitution,
                self.dt,
            );
            let relative = c.pair.relative_velocity(self.velocity);
            let delta = contact_change(relative, c.normal, change, self.settings.friction);
            impulses += u64::from(self.respond(c.pair, k, delta, c.normal));
        }
        impulses
    }

    /// Whether point `p` and edge `k` must be pushed apart this pass: they meet during
    /// the step approaching, or the point ends across the edge's line (however slowly
    /// it got there).
    fn collision(&self, p: u32, k: u32) -> Option<Collision> {
        let e = &self.edges[k as usize];
        let (a, b, i) = (e.a as usize, e.b as usize, p as usize);
        let (x, v, dt) = (self.position, &*self.velocity, self.dt);
        let hit = point_edge_time_of_impact(
            x[i],
            displacement(v[i], dt),
            x[a],
            displacement(v[a], dt),
            x[b],
            displacement(v[b], dt),
        )?;
        let collision = self.collision_at(p, k, hit.alpha, hit.normal);
        (collision.normal_velocity < 0.0 || hit.crosses).then_some(collision)
    }

    /// Point `p` against edge `k` at `alpha` along `normal`: the pair, its relative
    /// normal velocity and its gap along the normal at the start of the step.
    fn collision_at(&self, p: u32, k: u32, alpha: f64, normal: DVec2) -> Collision {
        let e = &self.edges[k as usize];
        let x = self.position;
        let pair = self.pair(p, k, alpha);
        // Differences from the edge's first end, which lies close to the point, keep
        // the gap exact to far below the coordinates' own rounding.
        let (q, r) = (x[e.a as usize], x[e.b as usize]);
        let start_gap = normal.dot((x[p as usize] - q) - alpha * (r - q));
        Collision {
            pair,
            normal,
            normal_velocity: normal.dot(pair.relative_velocity(self.velocity)),
            start_gap,
        }
    }

    /// Detection and impulses until a full pass finds no collision or the cap is hit;
    /// then the fail-safe. Leaves the velocities collision-free. `stale`: the current
    /// pairs predate a velocity change.
    pub fn resolve_crossings(&mut self, mut stale: bool) -> CollisionOutcome {
        let mut outcome = CollisionOutcome::default();
        for _ in 0..self.settings.max_iterations {
            if stale {
                self.refresh_pairs();
            }
            let impulses = self.collision_pass();
            outcome.impulses += impulses;
            if impulses == 0 {
                return outcome;
            }
            stale = true;
        }
        let mut failsafe = self.fail_safe(false);
        failsafe.impulses = outcome.impulses;
        failsafe
    }

    /// End the step rigidly: every group that impulses left stretched (see
    /// [`ImpulseScratch::any_dirty`]) moves as an exact rigid zone, merged with whatever
    /// it still meets. For a step whose contacts did not settle.
    pub fn finish_rigidly(&mut self) -> CollisionOutcome {
        self.fail_safe(true)
    }

    /// Rigid impact zones until no collision is left, seeded with the dirty groups when
    /// `seeded`.
    fn fail_safe(&mut self, seeded: bool) -> CollisionOutcome {
        let unresolved = self.zones_until_clean(seeded);
        let first = (unresolved > 0)
            .then(|| self.scratch.hits.first().copied())
            .flatten();
        let first_unresolved = first.map(|(p, q, r)| {
            // What no impulse and no rigid motion could stop: a pinned particle that
            // moves, in the zone of the point.
            let zone = self.scratch.zones.zone(p as usize);
            let members = self.scratch.zones.members().to_vec();
            let driven = members.into_iter().find(|&i| {
                let i = i as usize;
                self.inverse_mass[i] == 0.0
                    && self.velocity[i] != DVec2::ZERO
                    && self.scratch.zones.zone(i) == zone
            });
            ([p, q, r], driven)
        });
        CollisionOutcome {
            failsafe: true,
            unresolved,
            first_unresolved,
            ..CollisionOutcome::default()
        }
    }

    /// Move every zone rigidly; a zone's groups are then exact, no longer dirty.
    fn rigidify_zones(&mut self) {
        let scratch = &mut *self.scratch;
        scratch.zones.rigidify(
            self.position,
            self.velocity,
            self.mass,
            self.inverse_mass,
            self.dt,
        );
        for &i in scratch.zones.members() {
            if let Some(dirty) = scratch.dirty.get_mut(self.groups[i as usize] as usize) {
                *dirty = false;
            }
        }
    }

    /// Rigid impact zones until no collision is left; returns the number left
    /// unresolved.
    fn zones_until_clean(&mut self, seeded: bool) -> usize {
        let n = self.position.len();
        self.scratch.zones.reset(n);
        self.scratch
            .zones
            .prepare_groups(self.groups, self.edges, self.inverse_mass);
        if seeded {
            let scratch = &mut *self.scratch;
            for g in 0..scratch.dirty.len() {
                if scratch.dirty[g] {
                    scratch.zones.join_group(g as u32);
                }
            }
            self.rigidify_zones();
        }
        for _round in 0..(4 * n + 16) {
            self.find_pairs();
            self.scratch.hits.clear();
            for slot in 0..self.scratch.pairs.len() {
                let (p, k) = self.scratch.pairs[slot];
                if let Some(Collision { pair, .. }) = self.collision(p, k) {
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
                merged |= zones.join(p as usize, q as usize, self.groups);
                merged |= zones.join(p as usize, r as usize, self.groups);
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
            self.rigidify_zones();
        }
        for &i in self.scratch.zones.members() {
            self.in_contact[i as usize] |= self.inverse_mass[i as usize] > 0.0;
        }
        0
    }
}
