//! The spaghetti factory: an inlet that extrudes strands into the box.
//!
//! Every `interval` seconds a particle appears at the inlet moving at `velocity`; the
//! newest `held` particles are pinned and driven at that velocity, as the inlet's
//! rollers would; every `particles_per_strand` particles finish a strand and the next
//! particle starts a new one. A strand is spawned — and constrained — as soon as it
//! has two particles.

use bevy::math::DVec2;
use bevy::prelude::*;

use bevy_strands::prelude::*;

/// An inlet emitting strands. Add it to an entity; the factory system does the rest.
#[derive(Component, Reflect, Clone, Debug, PartialEq)]
#[reflect(Component)]
pub struct SpaghettiFactory {
    /// Where particles appear.
    pub inlet: DVec2,
    /// Their velocity at the inlet.
    pub velocity: DVec2,
    /// Seconds between particles (their spacing is `|velocity| × interval`).
    pub interval: f64,
    /// Particles per strand.
    pub particles_per_strand: usize,
    /// Newest particles held at the inlet velocity.
    pub held: usize,
    /// Mass of each particle.
    pub mass: f64,
    /// Material of the strands (the global default if `None`).
    pub material: Option<StrandMaterial>,
    /// Stop after this many strands (`None`: never).
    pub max_strands: Option<usize>,
    /// Simulated time of the next emission.
    pub next_emission: f64,
    /// Strands finished or in progress.
    pub strands_started: usize,
    /// Particles of the strand being extruded, oldest first.
    current: Vec<Entity>,
    /// Its strand entity, once it has two particles.
    current_strand: Option<Entity>,
}

impl SpaghettiFactory {
    /// A factory emitting from `inlet` at `velocity`, a particle every `interval`.
    pub fn new(inlet: DVec2, velocity: DVec2, interval: f64, particles_per_strand: usize) -> Self {
        Self {
            inlet,
            velocity,
            interval,
            particles_per_strand,
            held: 2,
            mass: 1.0,
            material: None,
            max_strands: None,
            next_emission: 0.0,
            strands_started: 0,
            current: Vec::new(),
            current_strand: None,
        }
    }

    /// Rest spacing of the strands.
    pub fn spacing(&self) -> f64 {
        self.velocity.length() * self.interval
    }

    fn finished(&self) -> bool {
        self.max_strands
            .is_some_and(|max| self.strands_started >= max)
            && self.current.is_empty()
    }
}

/// Emit the particles due by the current simulated time.
pub fn run_spaghetti_factories(
    mut commands: Commands,
    clock: Res<SimulationClock>,
    mut factories: Query<&mut SpaghettiFactory>,
    mut strands: Query<&mut Strand>,
) {
    for mut factory in &mut factories {
        // A little slack so that emission times on tick boundaries are not missed by
        // rounding of the clock.
        while !factory.finished() && factory.next_emission <= clock.time + 1e-9 * factory.interval {
            let emitted_at = factory.next_emission;
            emit(
                &mut commands,
                &mut factory,
                &mut strands,
                clock.time - emitted_at,
            );
            factory.next_emission += factory.interval;
        }
    }
}

fn emit(
    commands: &mut Commands,
    factory: &mut SpaghettiFactory,
    strands: &mut Query<&mut Strand>,
    age: f64,
) {
    if factory.current.is_empty() {
        factory.strands_started += 1;
    }
    // Where the particle would be had it appeared exactly on time.
    let position = factory.inlet + factory.velocity * age.max(0.0);
    let mut particle = commands.spawn((
        Particle,
        Position(position),
        Velocity(factory.velocity),
        Mass(factory.mass),
        Pinned,
    ));
    if let Some(strand) = factory.current_strand {
        particle.insert(StrandOf(strand));
    }
    let particle = particle.id();
    factory.current.push(particle);
    let spacing = factory.spacing();

    match factory.current_strand {
        None if factory.current.len() == 2 => {
            let mut strand = commands.spawn((
                Strand {
                    particles: factory.current.clone(),
                    rest_lengths: vec![spacing],
                    rest_angles: Vec::new(),
                    closed: false,
                },
                StrandKind::Spaghetti,
            ));
            if let Some(material) = factory.material {
                strand.insert(material);
            }
            let strand = strand.id();
            for &p in &factory.current {
                commands.entity(p).insert(StrandOf(strand));
            }
            factory.current_strand = Some(strand);
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
    let done = factory.current.len() >= factory.particles_per_strand;
    let keep = if done { 0 } else { factory.held };
    let release = factory.current.len().saturating_sub(keep);
    for &p in &factory.current[..release] {
        commands.entity(p).remove::<Pinned>();
    }
    if done {
        factory.current.clear();
        factory.current_strand = None;
    }
}
