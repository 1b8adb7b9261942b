//! Scene files: a scenario's parameters as a human-readable RON file, validated on
//! load, then spawned into a world.
//!
//! Every figure the project quotes comes from a scene under `assets/scenes/`; a scene
//! that cannot be simulated is refused with an error naming the file, the item and the
//! problem, before anything is spawned.

mod spawn;

pub use spawn::{container_builder, spawn_scene};

use std::path::Path;

use bevy::math::DVec2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::constraints::SolverKind;
use crate::export::raster::View;
use crate::strand::{StrandBuilder, StrandKind, StrandMaterial};

/// A problem with a scene file: which file, which item in it, and what is wrong.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{file}: {item}: {problem}")]
pub struct SceneError {
    /// The file (or the built-in scene's name).
    pub file: String,
    /// The item in the file, e.g. `strands[2].spacing`.
    pub item: String,
    /// What is wrong with it.
    pub problem: String,
}

/// A scenario: the step, the forces, the solver and what to spawn.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scenario name.
    pub name: String,
    /// One line on what the scenario shows.
    #[serde(default)]
    pub description: String,
    /// Simulated seconds a run covers.
    pub duration: f64,
    /// Step size in seconds.
    pub dt: f64,
    /// Steps per tick.
    pub substeps: u32,
    /// Gravity acceleration.
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 2],
    /// Mass-proportional damping (1/s).
    #[serde(default)]
    pub damping: f64,
    /// Constraint solver name (see `strands run --help`).
    #[serde(default = "default_solver")]
    pub solver: String,
    /// Default material of the strands.
    #[serde(default)]
    pub material: MaterialSpec,
    /// Constraint solver settings.
    #[serde(default)]
    pub constraints: ConstraintSpec,
    /// Collision settings.
    #[serde(default)]
    pub collisions: CollisionSpec,
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
    /// A furry creature.
    #[serde(default)]
    pub furry_creature: Option<FurryCreatureSpec>,
    /// A throughput test: many strands dropped into a box sized for them (replaces
    /// `container`).
    #[serde(default)]
    pub scale: Option<ScaleSpec>,
}

/// The meatball factory (see [`MeatballFactory`](crate::scenes::meatball_factory::MeatballFactory)).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeatballFactorySpec {
    /// Seconds between drops.
    pub interval: f64,
    /// Simulated time of the first drop.
    #[serde(default)]
    pub start: f64,
    /// Side of the triangles.
    pub side: f64,
    /// Height the triangles' centres are dropped from.
    pub height: f64,
    /// x of the first drop.
    pub first_x: f64,
    /// x step between drops.
    pub step_x: f64,
    /// Drops past this x wrap around by whole steps...
    pub wrap_x: f64,
    /// ...to the lowest drop point at or above this x.
    pub low_x: f64,
    /// Initial falling speed.
    pub speed: f64,
    /// Spin (rad/s), alternating in sign from drop to drop.
    pub spin: f64,
    /// Triangles at most.
    pub max: usize,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
}

/// The furry creature (see [`FurryCreature`](crate::scenes::furry_creature::FurryCreature)).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FurryCreatureSpec {
    /// Centre of the body's circular path.
    pub centre: [f64; 2],
    /// Radius of the path.
    pub path_radius: f64,
    /// Seconds per turn of the path.
    pub period: f64,
    /// Radius of the body.
    pub body_radius: f64,
    /// Hairs, evenly spaced around the rim.
    pub hairs: usize,
    /// Particles per hair.
    pub particles_per_hair: usize,
    /// Rest spacing of the hairs' particles.
    pub spacing: f64,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
}

/// The scale scenario's strands.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ScaleSpec {
    /// Strands.
    pub strands: usize,
    /// Particles per strand.
    pub particles: usize,
    /// Rest spacing.
    pub spacing: f64,
}

/// The spaghetti factory (see [`SpaghettiFactory`](crate::scenes::spaghetti_factory::SpaghettiFactory)).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpaghettiFactorySpec {
    /// Where particles appear.
    pub inlet: [f64; 2],
    /// Their velocity there.
    pub velocity: [f64; 2],
    /// Seconds between particles.
    pub interval: f64,
    /// Particles per strand.
    pub particles_per_strand: usize,
    /// Newest particles held at the inlet velocity.
    #[serde(default = "two")]
    pub held: usize,
    /// Mass of each particle.
    #[serde(default = "one")]
    pub mass: f64,
    /// Stop after this many strands.
    #[serde(default)]
    pub max_strands: Option<usize>,
}

fn two() -> usize {
    2
}

fn default_gravity() -> [f64; 2] {
    [0.0, -9.81]
}

fn default_solver() -> String {
    SolverKind::default().name().to_string()
}

fn one() -> f64 {
    1.0
}

/// Material parameters (see [`StrandMaterial`]).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialSpec {
    /// Stretch stiffness per unit strain.
    pub stretch_stiffness: f64,
    /// Stretch damping along the edge.
    pub stretch_damping: f64,
    /// Bending stiffness.
    pub bending_stiffness: f64,
    /// Bending damping.
    pub bending_damping: f64,
}

impl Default for MaterialSpec {
    fn default() -> Self {
        StrandMaterial::default().into()
    }
}

impl From<StrandMaterial> for MaterialSpec {
    fn from(m: StrandMaterial) -> Self {
        Self {
            stretch_stiffness: m.stretch_stiffness,
            stretch_damping: m.stretch_damping,
            bending_stiffness: m.bending_stiffness,
            bending_damping: m.bending_damping,
        }
    }
}

impl From<MaterialSpec> for StrandMaterial {
    fn from(m: MaterialSpec) -> Self {
        Self {
            stretch_stiffness: m.stretch_stiffness,
            stretch_damping: m.stretch_damping,
            bending_stiffness: m.bending_stiffness,
            bending_damping: m.bending_damping,
        }
    }
}

/// Constraint solver parameters (see [`ConstraintConfig`](crate::constraints::ConstraintConfig)).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ConstraintSpec {
    /// Stop projecting when every `|C| / L²` is at most this.
    pub tolerance: f64,
    /// Linear solves per island per step at most.
    pub max_iterations: u32,
    /// Take the constraint direction at the start of the step instead of the end.
    pub start_of_step: bool,
    /// Keep stretch springs on constrained edges too.
    pub stretch_springs: bool,
}

impl Default for ConstraintSpec {
    fn default() -> Self {
        let c = crate::constraints::ConstraintConfig::default();
        Self {
            tolerance: c.tolerance,
            max_iterations: c.max_iterations,
            start_of_step: c.direction
                == crate::constraints::projection::ConstraintDirection::StartOfStep,
            stretch_springs: c.stretch_springs,
        }
    }
}

/// Collision parameters (see [`CollisionConfig`](crate::collision::CollisionConfig)).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct CollisionSpec {
    /// Whether collisions are processed.
    pub enabled: bool,
    /// Thickness: pairs are kept this far apart.
    pub thickness: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Restitution (0: inelastic).
    pub restitution: f64,
    /// Alternations of constraint re-projection and collisions after contact.
    pub contact_passes: u32,
}

impl Default for CollisionSpec {
    fn default() -> Self {
        let c = crate::collision::CollisionConfig::default();
        Self {
            enabled: c.enabled,
            thickness: c.thickness,
            friction: c.friction,
            restitution: c.restitution,
            contact_passes: c.contact_passes,
        }
    }
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

/// The shape a strand starts in.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum ShapeSpec {
    /// A straight open strand from `start` at `angle_degrees` from the +x axis.
    Line {
        /// First particle.
        start: [f64; 2],
        /// Direction, degrees counter-clockwise from +x.
        angle_degrees: f64,
        /// Particle count.
        particles: usize,
        /// Rest spacing.
        spacing: f64,
    },
    /// An open strand through the points.
    Polyline {
        /// The particles' positions.
        points: Vec<[f64; 2]>,
    },
    /// A closed loop through the points, keeping their shape at rest.
    Polygon {
        /// The particles' positions.
        points: Vec<[f64; 2]>,
    },
}

/// What a strand represents (its colour in pictures).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KindSpec {
    /// A generic rope.
    #[default]
    Rope,
    /// Spaghetti.
    Spaghetti,
    /// A meatball loop.
    Meatball,
    /// A hair.
    Hair,
}

impl From<KindSpec> for StrandKind {
    fn from(k: KindSpec) -> Self {
        match k {
            KindSpec::Rope => StrandKind::Rope,
            KindSpec::Spaghetti => StrandKind::Spaghetti,
            KindSpec::Meatball => StrandKind::Meatball,
            KindSpec::Hair => StrandKind::Hair,
        }
    }
}

/// A strand in a scene file.
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
    pub kind: KindSpec,
    /// Material, when not the scene's default.
    #[serde(default)]
    pub material: Option<MaterialSpec>,
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
    /// Pinned.
    #[serde(default)]
    pub pinned: bool,
}

pub(crate) fn vec2(v: [f64; 2]) -> DVec2 {
    DVec2::new(v[0], v[1])
}

impl StrandSpec {
    /// The builder this spec describes (not yet validated).
    pub fn builder(&self) -> StrandBuilder {
        let builder = match &self.shape {
            ShapeSpec::Line {
                start,
                angle_degrees,
                particles,
                spacing,
            } => {
                let direction = DVec2::from_angle(angle_degrees.to_radians());
                StrandBuilder::line(vec2(*start), direction, *particles, *spacing)
            }
            ShapeSpec::Polyline { points } => {
                StrandBuilder::polyline(points.iter().map(|&p| vec2(p)))
            }
            ShapeSpec::Polygon { points } => {
                StrandBuilder::closed_loop(points.iter().map(|&p| vec2(p)))
            }
        };
        let mut builder = builder
            .mass(self.mass)
            .velocity(vec2(self.velocity))
            .kind(self.kind.into());
        for &i in &self.pinned {
            builder = builder.pin(i);
        }
        if let Some(lengths) = &self.rest_lengths {
            builder = builder.rest_lengths(lengths.clone());
        }
        if let Some(material) = self.material {
            builder = builder.material(material.into());
        }
        builder
    }
}

impl Scene {
    /// Parse and validate a scene from RON text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
        let scene: Scene = ron::from_str(text).map_err(|e| SceneError {
            file: file.to_string(),
            item: format!("line {}, column {}", e.span.start.line, e.span.start.col),
            problem: e.code.to_string(),
        })?;
        scene.validate(file)?;
        Ok(scene)
    }

    /// Read, parse and validate a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: file.clone(),
            item: "file".to_string(),
            problem: e.to_string(),
        })?;
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

    /// The constraint solver the scene asks for.
    pub fn solver_kind(&self) -> Result<SolverKind, String> {
        self.solver.parse()
    }

    /// Check every number and every item; the first problem found is returned.
    pub fn validate(&self, file: &str) -> Result<(), SceneError> {
        let fail = |item: &str, problem: String| SceneError {
            file: file.to_string(),
            item: item.to_string(),
            problem,
        };
        if self.name.trim().is_empty() {
            return Err(fail("name", "must not be empty".into()));
        }
        positive("duration", self.duration).map_err(|p| fail("duration", p))?;
        positive("dt", self.dt).map_err(|p| fail("dt", p))?;
        if self.substeps == 0 {
            return Err(fail("substeps", "must be at least 1".into()));
        }
        finite2(self.gravity).map_err(|p| fail("gravity", p))?;
        non_negative(self.damping).map_err(|p| fail("damping", p))?;
        self.solver_kind().map_err(|p| fail("solver", p))?;
        self.material
            .validate()
            .map_err(|(field, p)| fail(&format!("material.{field}"), p))?;
        if let Some(container) = &self.container {
            finite2(container.min).map_err(|p| fail("container.min", p))?;
            finite2(container.max).map_err(|p| fail("container.max", p))?;
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
            let at = |field: &str| format!("spaghetti_factory.{field}");
            finite2(f.inlet).map_err(|p| fail(&at("inlet"), p))?;
            finite2(f.velocity).map_err(|p| fail(&at("velocity"), p))?;
            positive("interval", f.interval).map_err(|p| fail(&at("interval"), p))?;
            positive("mass", f.mass).map_err(|p| fail(&at("mass"), p))?;
            if f.velocity[0] == 0.0 && f.velocity[1] == 0.0 {
                return Err(fail(
                    &at("velocity"),
                    "must not be zero: it sets the strands' rest spacing".into(),
                ));
            }
            if f.particles_per_strand < 2 {
                return Err(fail(
                    &at("particles_per_strand"),
                    format!(
                        "a strand needs at least 2 particles, got {}",
                        f.particles_per_strand
                    ),
                ));
            }
        }
        if let Some(m) = &self.meatball_factory {
            let at = |field: &str| format!("meatball_factory.{field}");
            for (field, value) in [
                ("interval", m.interval),
                ("side", m.side),
                ("step_x", m.step_x),
                ("mass", m.mass),
            ] {
                positive(field, value).map_err(|p| fail(&at(field), p))?;
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
                if !value.is_finite() {
                    return Err(fail(&at(field), format!("{value} is not finite")));
                }
            }
        }
        if let Some(f) = &self.furry_creature {
            let at = |field: &str| format!("furry_creature.{field}");
            finite2(f.centre).map_err(|p| fail(&at("centre"), p))?;
            for (field, value) in [
                ("period", f.period),
                ("body_radius", f.body_radius),
                ("spacing", f.spacing),
                ("mass", f.mass),
            ] {
                positive(field, value).map_err(|p| fail(&at(field), p))?;
            }
            non_negative(f.path_radius).map_err(|p| fail(&at("path_radius"), p))?;
            if f.particles_per_hair < 3 {
                return Err(fail(
                    &at("particles_per_hair"),
                    format!(
                        "a hair needs at least 3 particles (two are its root), got {}",
                        f.particles_per_hair
                    ),
                ));
            }
        }
        if let Some(scale) = &self.scale {
            positive("spacing", scale.spacing).map_err(|p| fail("scale.spacing", p))?;
            if scale.strands == 0 {
                return Err(fail("scale.strands", "must be at least 1".into()));
            }
            if scale.particles < 2 {
                return Err(fail(
                    "scale.particles",
                    format!(
                        "a strand needs at least 2 particles, got {}",
                        scale.particles
                    ),
                ));
            }
        }
        for (i, particle) in self.particles.iter().enumerate() {
            let item = format!("particles[{i}]");
            finite2(particle.position).map_err(|p| fail(&format!("{item}.position"), p))?;
            finite2(particle.velocity).map_err(|p| fail(&format!("{item}.velocity"), p))?;
            if !particle.pinned {
                positive("mass", particle.mass).map_err(|p| fail(&format!("{item}.mass"), p))?;
            }
        }
        Ok(())
    }
}

impl MaterialSpec {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        let fields = [
            ("stretch_stiffness", self.stretch_stiffness),
            ("stretch_damping", self.stretch_damping),
            ("bending_stiffness", self.bending_stiffness),
            ("bending_damping", self.bending_damping),
        ];
        for (name, value) in fields {
            non_negative(value).map_err(|p| (name, p))?;
        }
        Ok(())
    }
}

impl Scene {
    /// Every link names two different, existing, separate particles, once.
    fn validate_links(&self) -> Result<(), (String, String)> {
        if self.links.is_empty() {
            return Ok(());
        }
        let points: Vec<Vec<DVec2>> = self
            .strands
            .iter()
            .map(|s| s.builder().points().to_vec())
            .collect();
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

impl StrandSpec {
    /// Validate; on failure, the field (with a leading `.`) and the problem.
    fn validate(&self) -> Result<(), (String, String)> {
        let at = |field: &str, problem: String| (format!(".{field}"), problem);
        match &self.shape {
            ShapeSpec::Line {
                start,
                angle_degrees,
                particles,
                spacing,
            } => {
                finite2(*start).map_err(|p| at("shape.start", p))?;
                if !angle_degrees.is_finite() {
                    return Err(at(
                        "shape.angle_degrees",
                        format!("{angle_degrees} is not finite"),
                    ));
                }
                if *particles < 2 {
                    return Err(at(
                        "shape.particles",
                        format!("a strand needs at least 2 particles, got {particles}"),
                    ));
                }
                if !(spacing.is_finite() && *spacing > 0.0) {
                    return Err(at(
                        "shape.spacing",
                        format!(
                            "{spacing} would make a zero or negative rest length; it must be positive"
                        ),
                    ));
                }
            }
            ShapeSpec::Polyline { points } | ShapeSpec::Polygon { points } => {
                for (j, &p) in points.iter().enumerate() {
                    finite2(p).map_err(|problem| at(&format!("shape.points[{j}]"), problem))?;
                }
            }
        }
        if let Some(material) = &self.material {
            material
                .validate()
                .map_err(|(f, p)| at(&format!("material.{f}"), p))?;
        }
        finite2(self.velocity).map_err(|p| at("velocity", p))?;
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(at(
                "mass",
                format!("{} must be positive and finite", self.mass),
            ));
        }
        self.builder()
            .validate()
            .map(|_| ())
            .map_err(|e| (String::new(), e.to_string()))
    }
}

impl ScaleSpec {
    /// Strands per row of the initial arrangement.
    pub fn columns(&self) -> usize {
        ((self.strands as f64 / 8.0).sqrt().ceil() as usize).max(1)
    }

    /// Length of one strand.
    pub fn strand_length(&self) -> f64 {
        (self.particles - 1) as f64 * self.spacing
    }

    /// Horizontal and vertical pitch of the arrangement.
    pub fn pitch(&self) -> DVec2 {
        DVec2::new(
            self.strand_length() + 5.0 * self.spacing,
            4.0 * self.spacing,
        )
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

fn finite2(v: [f64; 2]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("({}, {}) is not finite", v[0], v[1]))
    }
}

fn positive(name: &str, x: f64) -> Result<(), String> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} {x} must be positive and finite"))
    }
}

fn non_negative(x: f64) -> Result<(), String> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(format!("{x} must be zero or positive and finite"))
    }
}
