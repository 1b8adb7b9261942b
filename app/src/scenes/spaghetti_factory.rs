//! The spaghetti factory: an inlet that extrudes strands into the box.
//!
//! Every `interval` seconds a particle appears at the inlet moving at `velocity`; the
//! newest `held` particles are kinematic, driven at that velocity, as the inlet's
//! rollers would; every `particles_per_strand` particles finish a strand and the next
//! particle starts a new one. A strand is spawned — and constrained — as soon as it
//! has two particles.
//!
//! A factory whose inlet is blocked — an edge of another strand within two thicknesses
//! of where the held particles are about to move — stops its rollers (the held particles
//! stand still) and postpones its emissions by the time it stands, rather than pushing
//! kinematic particles, which nothing can stop, through the pile.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::model::geometry::segment_distance;
use bevy_strands::prelude::*;
use bevy_strands::sleeping::SleepState;
use serde::{Deserialize, Serialize};

/// What a spaghetti factory makes: the scenario file's `spaghetti_factory` section.
#[derive(Serialize, Deserialize, Reflect, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpaghettiFactorySpec {
    /// Where particles appear.
    pub inlet: DVec2,
    /// Their velocity at the inlet.
    pub velocity: DVec2,
    /// Seconds between particles (their spacing is `|velocity| × interval`).
    pub interval: f64,
    /// Particles per strand.
    pub particles_per_strand: usize,
    /// Newest particles held at the inlet velocity.
    #[serde(default = "two")]
    pub held: usize,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
    /// Stop after this many strands (`None`: never).
    #[serde(default)]
    pub max_strands: Option<usize>,
}

fn two() -> usize {
    2
}

fn one() -> f64 {
    1.0
}

impl SpaghettiFactorySpec {
    /// Rest spacing of the strands.
    pub fn spacing(&self) -> f64 {
        self.velocity.length() * self.interval
    }
}

/// How far a factory has got.
#[derive(Reflect, Clone, Debug, Default, PartialEq)]
pub struct SpaghettiProgress {
    /// Simulated time of the next emission.
    pub next_emission: f64,
    /// Strands finished or in progress.
    pub strands_started: usize,
    /// Particles of the strand being extruded, oldest first.
    pub current: Vec<Entity>,
    /// Its strand entity, once it has two particles.
    pub current_strand: Option<Entity>,
    /// Whether the inlet is blocked (the rollers stand still).
    pub blocked: bool,
    /// Ticks the inlet has been blocked, in all.
    pub blocked_ticks: u64,
    /// Lone particles withdrawn from a blocked inlet (see [`run_spaghetti_factories`]).
    pub withdrawn: u64,
}

/// An inlet emitting strands. Add it to an entity; the factory system does the rest.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct SpaghettiFactory {
    /// What it makes.
    pub spec: SpaghettiFactorySpec,
    /// Material of the strands (the global default if `None`).
    pub material: Option<StrandMaterial>,
    /// How far it has got.
    pub progress: SpaghettiProgress,
}

impl SpaghettiFactory {
    /// A factory that has emitted nothing yet.
    pub fn new(spec: SpaghettiFactorySpec) -> Self {
        Self {
            spec,
            material: None,
            progress: SpaghettiProgress::default(),
        }
    }

    /// The particles the rollers hold: the newest ones of the strand being extruded.
    pub fn held_particles(&self) -> &[Entity] {
        let current = &self.progress.current;
        &current[current.len().saturating_sub(self.spec.held)..]
    }

    fn finished(&self) -> bool {
        self.spec
            .max_strands
            .is_some_and(|max| self.progress.strands_started >= max)
            && self.progress.current.is_empty()
    }
}

/// Emit the particles due by the current simulated time; hold the rollers while the
/// inlet is blocked.
#[allow(clippy::too_many_arguments)]
pub fn run_spaghetti_factories(
    mut commands: Commands,
    clock: Res<SimulationClock>,
    config: Res<StrandsConfig>,
    collisions: Option<Res<CollisionConfig>>,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    sleep: Option<Res<SleepState>>,
    mut factories: Query<&mut SpaghettiFactory>,
    mut strands: Query<&mut Strand>,
    mut velocities: Query<&mut Velocity>,
) {
    let reach = 2.0 * collisions.map_or(0.0, |c| c.thickness);
    let tick = config.tick_seconds();
    for mut factory in &mut factories {
        let asleep = |i: u32| sleep.as_ref().is_some_and(|s| s.is_asleep(i as usize));
        let blocked = inlet_blocked(&factory, tick, reach, &state, &topology, asleep);
        if blocked != factory.progress.blocked {
            let velocity = if blocked {
                DVec2::ZERO
            } else {
                factory.spec.velocity
            };
            for &p in factory.held_particles() {
                if let Ok(mut v) = velocities.get_mut(p) {
                    v.0 = velocity;
                }
            }
            factory.progress.blocked = blocked;
        }
        if blocked {
            // The extrusion stands still: so does its schedule.
            factory.progress.next_emission += tick;
            factory.progress.blocked_ticks += 1;
            // A strand's first particle, alone and held at the inlet, can be what
            // holds up the tail that blocks it (a strand hooked on it hangs there for
            // ever while the rollers wait): it is withdrawn, and emitted again once
            // the inlet is clear. Taking a particle away crosses nothing.
            let progress = &mut factory.progress;
            if progress.current_strand.is_none() && progress.current.len() == 1 {
                commands.entity(progress.current[0]).despawn();
                progress.current.clear();
                progress.strands_started -= 1;
                progress.withdrawn += 1;
            }
            continue;
        }
        let interval = factory.spec.interval;
        // A little slack so that emission times on tick boundaries are not missed by
        // rounding of the clock.
        while !factory.finished() && factory.progress.next_emission <= clock.time + 1e-9 * interval
        {
            let emitted_at = factory.progress.next_emission;
            emit(
                &mut commands,
                &mut factory,
                &mut strands,
                clock.time - emitted_at,
            );
            factory.progress.next_emission += interval;
        }
    }
}

/// Whether the inlet must stand still this tick: an edge lies within half of `reach`
/// (the thickness) of the stretch from the inlet to the oldest held particle, where the
/// next edge will appear; or an edge of another strand lies within `reach` of the
/// stretch the held particles sweep in the coming tick (from the inlet to a tick past
/// the oldest held particle) and is not moving on ahead of them: the tail of the strand
/// just finished, leaving at the inlet's speed, is no obstacle; a pile grown up to the
/// inlet is.
fn inlet_blocked(
    factory: &SpaghettiFactory,
    tick: f64,
    reach: f64,
    state: &ParticleState,
    topology: &Topology,
    asleep: impl Fn(u32) -> bool,
) -> bool {
    if reach <= 0.0 || factory.finished() {
        return false;
    }
    let spec = &factory.spec;
    let index = |p: &Entity| topology.index.get(p).copied();
    let held = factory.held_particles();
    let is_held = |i: u32| held.iter().any(|p| index(p) == Some(i));
    // The held particles lie on the line from the inlet; the oldest leads.
    let lead = held
        .first()
        .and_then(index)
        .map_or(spec.inlet, |i| state.position[i as usize]);
    let (from, to) = (spec.inlet, lead + spec.velocity * tick);
    let own = factory
        .progress
        .current_strand
        .and_then(|s| topology.strands.iter().position(|r| r.entity == s));
    let speed = spec.velocity.length();
    let ahead = spec.velocity / speed;
    let keeps_ahead = |i: usize| state.velocity[i].dot(ahead) >= 0.5 * speed;
    let clearance = 0.5 * reach;
    topology.edges.iter().any(|e| {
        let (a, b) = (e.a as usize, e.b as usize);
        if a >= state.position.len() || b >= state.position.len() || is_held(e.a) || is_held(e.b) {
            return false;
        }
        let (p, q) = (state.position[a], state.position[b]);
        // A new edge is born between the newest held particle and the inlet: nothing may
        // lie across that stretch or within the thickness of it, moving or not, or the
        // strand is made crossing.
        if segment_distance(spec.inlet, lead, p, q) < clearance {
            return true;
        }
        // What the pile brings up into the coming tick's stretch blocks it; walls cannot
        // move into it, and the tail of the strand just finished moves on ahead. A
        // sleeping strand is held like a wall but is not one: it lies where it lies.
        !(e.is_static && !asleep(e.a) && !asleep(e.b))
            && Some(e.strand as usize) != own
            && !(keeps_ahead(a) && keeps_ahead(b))
            && segment_distance(from, to, p, q) < reach
    })
}

fn emit(
    commands: &mut Commands,
    factory: &mut SpaghettiFactory,
    strands: &mut Query<&mut Strand>,
    age: f64,
) {
    let spec = factory.spec;
    let material = factory.material;
    let progress = &mut factory.progress;
    if progress.current.is_empty() {
        progress.strands_started += 1;
    }
    // Where the particle would be had it appeared exactly on time.
    let position = spec.inlet + spec.velocity * age.max(0.0);
    let mut particle = commands.spawn((
        Particle,
        Position(position),
        Velocity(spec.velocity),
        Mass(spec.mass),
        Kinematic,
    ));
    if let Some(strand) = progress.current_strand {
        particle.insert(StrandOf(strand));
    }
    let particle = particle.id();
    progress.current.push(particle);
    let spacing = spec.spacing();

    match progress.current_strand {
        None if progress.current.len() == 2 => {
            let mut strand = commands.spawn((
                Strand {
                    particles: progress.current.clone(),
                    rest_lengths: vec![spacing],
                    rest_angles: Vec::new(),
                    closed: false,
                },
                StrandKind::Spaghetti,
            ));
            if let Some(material) = material {
                strand.insert(material);
            }
            let strand = strand.id();
            for &p in &progress.current {
                commands.entity(p).insert(StrandOf(strand));
            }
            progress.current_strand = Some(strand);
        }
        Some(entity) => {
            if let Ok(mut strand) = strands.get_mut(entity) {
                strand.particles.push(particle);
                strand.rest_lengths.push(spacing);
            }
        }
        None => {}
    }

    // Release what the rollers no longer hold; a finished strand is let go entirely.
    let done = progress.current.len() >= spec.particles_per_strand;
    let keep = if done { 0 } else { spec.held };
    let release = progress.current.len().saturating_sub(keep);
    for &p in &progress.current[..release] {
        commands.entity(p).remove::<Kinematic>();
    }
    if done {
        progress.current.clear();
        progress.current_strand = None;
    }
}
