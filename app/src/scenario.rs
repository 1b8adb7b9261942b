//! Scenario files: a scenario's settings and what it spawns, as a human-readable RON
//! file, validated on load before anything is spawned.
//!
//! The settings are the library's own configuration resources (`step`, `constraints`,
//! `collisions`, `contact`), each field defaulting to the library's default; what to
//! spawn is described by the spec types below. A file that cannot be simulated is
//! refused with an error naming the file, the item and the problem.

use std::path::Path;

use bevy::math::DVec2;
use bevy_strands::model::validate::{
    NumberError, at_least, check_particle, finite, finite_vector, non_negative, positive,
};
use bevy_strands::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::export::raster::View;
use crate::scenes::drain::DrainSpec;
use crate::scenes::furry_creature::FurryCreatureSpec;
use crate::scenes::meatball_factory::MeatballFactorySpec;
use crate::scenes::spaghetti_factory::SpaghettiFactorySpec;
pub use crate::shape::{ShapeSpec, serpentine_points};

/// A problem with a scenario file: which file, which item in it, and what is wrong.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{file}: {item}: {problem}")]
pub struct ScenarioError {
    /// The file (or the built-in scenario's name).
    pub file: String,
    /// The item in the file, e.g. `strands[2].shape.spacing`.
    pub item: String,
    /// What is wrong with it.
    pub problem: String,
}

impl ScenarioError {
    /// A problem with `item` of `file`.
    pub fn new(file: &str, item: impl Into<String>, problem: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            item: item.into(),
            problem: problem.into(),
        }
    }

    fn number(file: &str, prefix: &str, e: NumberError) -> Self {
        let item = if prefix.is_empty() {
            e.field
        } else {
            format!("{prefix}.{}", e.field)
        };
        Self::new(file, item, e.problem)
    }
}

/// A scenario: the settings, how long it runs, and what to spawn.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Scenario name.
    pub name: String,
    /// One line on what the scenario shows.
    #[serde(default)]
    pub description: String,
    /// Simulated seconds a run covers.
    pub duration: f64,
    /// The step, gravity, damping and the default material.
    #[serde(default)]
    pub step: StrandsConfig,
    /// The constraint solver.
    #[serde(default)]
    pub constraints: ConstraintConfig,
    /// Collisions.
    #[serde(default)]
    pub collisions: CollisionConfig,
    /// The contact loop.
    #[serde(default)]
    pub contact: ContactConfig,
    /// An axis-aligned box of pinned walls.
    #[serde(default)]
    pub container: Option<ContainerSpec>,
    /// Strands.
    #[serde(default)]
    pub strands: Vec<StrandSpec>,
    /// Loose particles.
    #[serde(default)]
    pub particles: Vec<ParticleSpec>,
    /// Edges joining particles of the strands above: branches (trees), rungs and
    /// cross-links (graphs).
    #[serde(default)]
    pub links: Vec<LinkSpec>,
    /// A spaghetti factory.
    #[serde(default)]
    pub spaghetti_factory: Option<SpaghettiFactorySpec>,
    /// A meatball factory.
    #[serde(default)]
    pub meatball_factory: Option<MeatballFactorySpec>,
    /// A drain that keeps the pile bounded (for long runs of a factory).
    #[serde(default)]
    pub drain: Option<DrainSpec>,
    /// A furry creature.
    #[serde(default)]
    pub furry_creature: Option<FurryCreatureSpec>,
    /// A throughput test: many strands dropped into a box sized for them (replaces
    /// `container`).
    #[serde(default)]
    pub scale: Option<ScaleSpec>,
    /// The most particles the scene may start with: a larger scene is refused rather
    /// than allocated (a typo of a few zeros would otherwise fill the memory).
    #[serde(default = "default_max_particles")]
    pub max_particles: usize,
    /// Start even though strands cross, overlap within the thickness or leave the
    /// container, for this reason (otherwise such a scene is refused).
    #[serde(default)]
    pub allow_initial_contact: Option<String>,
    /// The file the scene was read from (empty for a built-in one or a snapshot's).
    #[serde(skip)]
    pub source: String,
}

/// [`Scenario::max_particles`] unless a scene says otherwise: the library's default cap.
pub use bevy_strands::world::config::DEFAULT_MAX_PARTICLES;

fn default_max_particles() -> usize {
    DEFAULT_MAX_PARTICLES
}

/// Many straight strands in rows, dropped into a box sized to hold them (the scale and
/// pile scenarios).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ScaleSpec {
    /// Strands.
    pub strands: usize,
    /// Particles per strand.
    pub particles: usize,
    /// Rest spacing.
    pub spacing: f64,
    /// Strands per row (default: about √(strands / 8)).
    #[serde(default)]
    pub columns: Option<usize>,
    /// Horizontal and vertical distance between the rows' strands (default: the
    /// strand's length plus five spacings, and four spacings).
    #[serde(default)]
    pub pitch: Option<(f64, f64)>,
}

fn one() -> f64 {
    1.0
}

/// Walls: a closed loop of four pinned particles at the corners of a box.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ContainerSpec {
    /// Lower-left corner.
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

/// A strand in a scenario file.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StrandSpec {
    /// Initial shape.
    pub shape: ShapeSpec,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
    /// Initial velocity of each particle.
    #[serde(default)]
    pub velocity: [f64; 2],
    /// Indices of pinned particles.
    #[serde(default)]
    pub pinned: Vec<usize>,
    /// Rest lengths, when not the initial distances.
    #[serde(default)]
    pub rest_lengths: Option<Vec<f64>>,
    /// What it represents.
    #[serde(default)]
    pub kind: StrandKind,
    /// Material, when not the scenario's default.
    #[serde(default)]
    pub material: Option<StrandMaterial>,
}

/// An edge between two particles of `strands`, each named `(strand, particle)` by
/// index; its rest length is their initial distance.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// One end: (strand index, particle index).
    pub from: (usize, usize),
    /// The other end.
    pub to: (usize, usize),
}

/// A particle on its own.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ParticleSpec {
    /// Position.
    pub position: [f64; 2],
    /// Velocity.
    #[serde(default)]
    pub velocity: [f64; 2],
    /// Mass.
    #[serde(default = "one")]
    pub mass: f64,
    /// Pinned: fixed where it is (its velocity is ignored).
    #[serde(default)]
    pub pinned: bool,
    /// Kinematic: infinite mass, moving with its velocity (ignored if pinned).
    #[serde(default)]
    pub kinematic: bool,
}

pub(crate) fn vec2(v: [f64; 2]) -> DVec2 {
    DVec2::new(v[0], v[1])
}

impl StrandSpec {
    /// The builder this spec describes (not yet validated).
    pub fn builder(&self) -> StrandBuilder {
        let builder = self.shape.builder();
        let mut builder = builder
            .mass(self.mass)
            .velocity(vec2(self.velocity))
            .kind(self.kind);
        for &i in &self.pinned {
            builder = builder.pin(i);
        }
        if let Some(lengths) = &self.rest_lengths {
            builder = builder.rest_lengths(lengths.clone());
        }
        if let Some(material) = self.material {
            builder = builder.material(material);
        }
        builder
    }

    /// Validate: the spec's own numbers, then the builder's rules. On failure, the
    /// field (with a leading `.`, or empty for the strand as a whole) and the problem.
    fn validate(&self) -> Result<(), (String, String)> {
        let at = |e: NumberError| (format!(".{}", e.field), e.problem);
        self.shape.validate()?;
        if let Some(material) = &self.material {
            material.validate().map_err(|e| at(e.within("material")))?;
        }
        finite_vector("velocity", vec2(self.velocity)).map_err(at)?;
        positive("mass", self.mass).map_err(at)?;
        self.builder()
            .validate()
            .map(|_| ())
            .map_err(|e| (String::new(), e.to_string()))
    }
}

impl Scenario {
    /// Parse and validate a scenario from RON text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
        let scenario: Scenario = ron::from_str(text).map_err(|e| {
            ScenarioError::new(
                file,
                format!("line {}, column {}", e.span.start.line, e.span.start.col),
                e.code.to_string(),
            )
        })?;
        let mut scenario = scenario;
        scenario.validate(file)?;
        scenario.source = file.to_string();
        Ok(scenario)
    }

    /// What messages about the scene name: its file, or its name if it has none.
    pub fn origin(&self) -> &str {
        if self.source.is_empty() {
            &self.name
        } else {
            &self.source
        }
    }

    /// Read, parse and validate a scenario file.
    pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| ScenarioError::new(&file, "file", e.to_string()))?;
        Self::parse(&text, &file)
    }

    /// The rectangle pictures show: the container (the scale scenario's included), or
    /// the unit box.
    pub fn view(&self) -> View {
        let container = self.scale.map(|s| s.container()).or(self.container);
        match container {
            Some(c) => View {
                min: vec2(c.min),
                max: vec2(c.max),
            },
            None => View {
                min: DVec2::ZERO,
                max: DVec2::ONE,
            },
        }
    }

    /// Particles spawned at the start (factories add theirs later), counted without
    /// overflow.
    pub fn initial_particles(&self) -> usize {
        let strands = self.strands.iter().map(|s| match &s.shape {
            ShapeSpec::Line { particles, .. } => *particles,
            ShapeSpec::Polyline { points } | ShapeSpec::Polygon { points } => points.len(),
            ShapeSpec::Serpentine { particles, .. } => *particles,
        });
        let scale = self.scale.map(|s| s.strands.saturating_mul(s.particles));
        let fur =
            (self.furry_creature.as_ref()).map(|f| f.hairs.saturating_mul(f.particles_per_hair));
        (strands.chain(scale).chain(fur)).fold(self.particles.len(), usize::saturating_add)
    }

    /// Check every number and every item; the first problem found is returned.
    pub fn validate(&self, file: &str) -> Result<(), ScenarioError> {
        let fail = |item: &str, problem: String| ScenarioError::new(file, item, problem);
        let number = |prefix: &'static str| move |e| ScenarioError::number(file, prefix, e);
        if self.name.trim().is_empty() {
            return Err(fail("name", "must not be empty".into()));
        }
        positive("duration", self.duration).map_err(number(""))?;
        let particles = self.initial_particles();
        if particles > self.max_particles {
            return Err(fail(
                "max_particles",
                format!(
                    "the scene starts with {particles} particles, more than {} (raise \
                     max_particles to allow it)",
                    self.max_particles
                ),
            ));
        }
        if self
            .allow_initial_contact
            .as_deref()
            .is_some_and(|r| r.trim().is_empty())
        {
            return Err(fail(
                "allow_initial_contact",
                "give the reason the scene starts in contact, not an empty string".into(),
            ));
        }
        self.step.validate().map_err(number("step"))?;
        if self.step.dt > self.duration {
            return Err(fail(
                "step.dt",
                format!(
                    "{:e} s is longer than the run ({:e} s): not one whole step fits",
                    self.step.dt, self.duration
                ),
            ));
        }
        self.constraints.validate().map_err(number("constraints"))?;
        self.collisions.validate().map_err(number("collisions"))?;
        self.contact.validate().map_err(number("contact"))?;
        if let Some(container) = &self.container {
            finite_vector("min", vec2(container.min)).map_err(number("container"))?;
            finite_vector("max", vec2(container.max)).map_err(number("container"))?;
            if !(container.min[0] < container.max[0] && container.min[1] < container.max[1]) {
                return Err(fail(
                    "container",
                    format!(
                        "min {:?} must be below and left of max {:?}",
                        container.min, container.max
                    ),
                ));
            }
        }
        for (i, strand) in self.strands.iter().enumerate() {
            let item = format!("strands[{i}]");
            strand
                .validate()
                .map_err(|(field, p)| fail(&format!("{item}{field}"), p))?;
        }
        self.validate_links().map_err(|(item, p)| fail(&item, p))?;
        if let Some(f) = &self.spaghetti_factory {
            let at = number("spaghetti_factory");
            finite_vector("inlet", f.inlet).map_err(at)?;
            finite_vector("velocity", f.velocity).map_err(at)?;
            positive("interval", f.interval).map_err(at)?;
            positive("mass", f.mass).map_err(at)?;
            if f.velocity == DVec2::ZERO {
                return Err(fail(
                    "spaghetti_factory.velocity",
                    "must not be zero: it sets the strands' rest spacing".into(),
                ));
            }
            at_least(
                "particles_per_strand",
                f.particles_per_strand,
                2,
                "a strand",
            )
            .map_err(at)?;
        }
        if let Some(m) = &self.meatball_factory {
            let at = number("meatball_factory");
            for (field, value) in [
                ("interval", m.interval),
                ("side", m.side),
                ("step_x", m.step_x),
                ("mass", m.mass),
            ] {
                positive(field, value).map_err(at)?;
            }
            for (field, value) in [
                ("start", m.start),
                ("height", m.height),
                ("first_x", m.first_x),
                ("wrap_x", m.wrap_x),
                ("low_x", m.low_x),
                ("speed", m.speed),
                ("spin", m.spin),
            ] {
                finite(field, value).map_err(at)?;
            }
        }
        if let Some(d) = &self.drain {
            // A drain keeps at least one strand of the factory's: below that it would
            // empty the box as fast as it fills.
            at_least("max_particles", d.max_particles, 2, "a strand").map_err(number("drain"))?;
        }
        if let Some(f) = &self.furry_creature {
            let at = number("furry_creature");
            finite_vector("centre", f.centre).map_err(at)?;
            for (field, value) in [
                ("period", f.period),
                ("body_radius", f.body_radius),
                ("spacing", f.spacing),
                ("mass", f.mass),
            ] {
                positive(field, value).map_err(at)?;
            }
            non_negative("path_radius", f.path_radius).map_err(at)?;
            if let Some(inset) = f.body_inset {
                positive("body_inset", inset).map_err(at)?;
                if inset >= f.body_radius {
                    return Err(ScenarioError::new(
                        file,
                        "furry_creature.body_inset",
                        format!(
                            "{inset} leaves no body inside the rim (body_radius {})",
                            f.body_radius
                        ),
                    ));
                }
            }
            at_least(
                "particles_per_hair",
                f.particles_per_hair,
                3,
                "a hair (two are its root)",
            )
            .map_err(at)?;
        }
        if let Some(scale) = &self.scale {
            let at = number("scale");
            positive("spacing", scale.spacing).map_err(at)?;
            if let Some((x, y)) = scale.pitch {
                positive("pitch.0", x).map_err(at)?;
                positive("pitch.1", y).map_err(at)?;
                if x <= scale.strand_length() {
                    return Err(fail(
                        "scale.pitch",
                        format!(
                            "{x} must exceed the strands' length {}: they would overlap",
                            scale.strand_length()
                        ),
                    ));
                }
            }
            at_least("strands", scale.strands, 1, "a scale run").map_err(at)?;
            at_least("particles", scale.particles, 2, "a strand").map_err(at)?;
        }
        for (i, particle) in self.particles.iter().enumerate() {
            let item = format!("particles[{i}]");
            let (position, velocity) = (vec2(particle.position), vec2(particle.velocity));
            check_particle(position, velocity, particle.mass, particle.pinned)
                .map_err(|e| fail(&format!("{item}.{}", e.field()), e.to_string()))?;
        }
        Ok(())
    }
}

impl Scenario {
    /// Every link names two different, existing, separate particles, once.
    fn validate_links(&self) -> Result<(), (String, String)> {
        if self.links.is_empty() {
            return Ok(());
        }
        let builders: Vec<_> = self.strands.iter().map(|s| s.builder()).collect();
        let points: Vec<&[DVec2]> = builders.iter().map(|b| b.points()).collect();
        let mut seen = std::collections::HashSet::new();
        for (i, link) in self.links.iter().enumerate() {
            let item = format!("links[{i}]");
            let mut ends = [DVec2::ZERO; 2];
            for (end, (field, (strand, particle))) in
                ends.iter_mut().zip([("from", link.from), ("to", link.to)])
            {
                let Some(strand_points) = points.get(strand) else {
                    return Err((
                        format!("{item}.{field}"),
                        format!(
                            "strand {strand} does not exist; the scene has {} strands",
                            points.len()
                        ),
                    ));
                };
                *end = *strand_points.get(particle).ok_or_else(|| {
                    (
                        format!("{item}.{field}"),
                        format!(
                            "strand {strand} has no particle {particle}; it has {}",
                            strand_points.len()
                        ),
                    )
                })?;
            }
            if link.from == link.to {
                return Err((item, "an edge needs two different particles".into()));
            }
            if ends[0].distance(ends[1]) <= 0.0 {
                return Err((
                    item,
                    format!(
                        "its particles coincide at {:?}: a zero rest length",
                        ends[0]
                    ),
                ));
            }
            let key = (link.from.min(link.to), link.from.max(link.to));
            let ((s, a), (t, b)) = key;
            let n = points[s].len();
            if s == t && (b - a == 1 || builders[s].is_closed() && (a, b) == (0, n - 1)) {
                return Err((
                    item,
                    format!(
                        "joins particles {a} and {b} of strand {s}, which an edge of that \
                         strand already joins"
                    ),
                ));
            }
            if !seen.insert(key) {
                return Err((
                    item,
                    "joins the same two particles as an earlier link".into(),
                ));
            }
        }
        Ok(())
    }
}

impl ScaleSpec {
    /// Strands per row of the initial arrangement.
    pub fn columns(&self) -> usize {
        self.columns
            .unwrap_or_else(|| (self.strands as f64 / 8.0).sqrt().ceil() as usize)
            .max(1)
    }

    /// Length of one strand.
    pub fn strand_length(&self) -> f64 {
        (self.particles - 1) as f64 * self.spacing
    }

    /// Horizontal and vertical pitch of the arrangement.
    pub fn pitch(&self) -> DVec2 {
        self.pitch.map_or(
            DVec2::new(
                self.strand_length() + 5.0 * self.spacing,
                4.0 * self.spacing,
            ),
            |(x, y)| DVec2::new(x, y),
        )
    }

    /// Height of the gentle wave along each strand, so that strands do not land
    /// perfectly flat on each other: half a spacing, or a quarter of the rows' pitch
    /// when they are packed closer.
    pub fn wave(&self) -> f64 {
        (0.5 * self.spacing).min(0.25 * self.pitch().y)
    }

    /// The box the strands start in and fall into.
    pub fn container(&self) -> ContainerSpec {
        let rows = self.strands.div_ceil(self.columns());
        let pitch = self.pitch();
        ContainerSpec {
            min: [0.0, 0.0],
            max: [
                self.columns() as f64 * pitch.x + 2.0 * self.spacing,
                (rows as f64 + 2.0) * pitch.y,
            ],
        }
    }

    /// First particle of strand `s`; strands run along +x.
    pub fn start(&self, s: usize) -> DVec2 {
        let (row, column) = (s / self.columns(), s % self.columns());
        let pitch = self.pitch();
        DVec2::new(
            3.5 * self.spacing + column as f64 * pitch.x,
            (row as f64 + 1.5) * pitch.y,
        )
    }
}
