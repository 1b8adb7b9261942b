//! The shapes a strand of a scenario file starts in, and the particles each lays out.

use bevy::math::DVec2;
use bevy_strands::model::validate::{NumberError, at_least, finite, finite_vector, positive};
use bevy_strands::prelude::*;
use serde::{Deserialize, Serialize};

use crate::scenario::vec2;

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
    /// An open strand folded in rows: from `start` (its first particle) rightwards
    /// `width` long, then back `row_gap` lower, and so on, each row joined to the next
    /// by a half turn; a rope laid out or dropped in coils.
    Serpentine {
        /// First particle: the top row's left end.
        start: [f64; 2],
        /// Length of a row.
        width: f64,
        /// Distance from one row to the next.
        row_gap: f64,
        /// Particle count.
        particles: usize,
        /// Rest spacing along the rows (the turns' is the same, to within a rounding).
        spacing: f64,
    },
}

/// The particles of a [`ShapeSpec::Serpentine`].
pub fn serpentine_points(
    start: DVec2,
    width: f64,
    row_gap: f64,
    particles: usize,
    spacing: f64,
) -> Vec<DVec2> {
    let per_row = (width / spacing).floor() as usize + 1;
    let radius = 0.5 * row_gap;
    let turn = ((std::f64::consts::PI * radius / spacing).round() as usize).max(2);
    let mut points = Vec::with_capacity(particles);
    let mut y = start.y;
    let mut rightwards = true;
    while points.len() < particles {
        for i in 0..per_row {
            let along = if rightwards { i } else { per_row - 1 - i };
            points.push(DVec2::new(start.x + along as f64 * spacing, y));
            if points.len() == particles {
                return points;
            }
        }
        let (end, side) = if rightwards {
            (start.x + (per_row - 1) as f64 * spacing, 1.0)
        } else {
            (start.x, -1.0)
        };
        for k in 1..turn {
            let angle = std::f64::consts::PI * k as f64 / turn as f64;
            points.push(DVec2::new(
                end + side * radius * angle.sin(),
                y - radius + radius * angle.cos(),
            ));
            if points.len() == particles {
                return points;
            }
        }
        y -= row_gap;
        rightwards = !rightwards;
    }
    points
}

impl ShapeSpec {
    /// The builder of a strand in this shape (its mass, pins and material are the
    /// strand spec's to add).
    pub fn builder(&self) -> StrandBuilder {
        match self {
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
            &ShapeSpec::Serpentine {
                start,
                width,
                row_gap,
                particles,
                spacing,
            } => StrandBuilder::polyline(serpentine_points(
                vec2(start),
                width,
                row_gap,
                particles,
                spacing,
            )),
        }
    }

    /// Validate the shape's own numbers: on failure, the field (with a leading `.`)
    /// and the problem.
    pub(crate) fn validate(&self) -> Result<(), (String, String)> {
        let at = |e: NumberError| (format!(".{}", e.field), e.problem);
        match self {
            ShapeSpec::Line {
                start,
                angle_degrees,
                particles,
                spacing,
            } => {
                finite_vector("shape.start", vec2(*start)).map_err(at)?;
                finite("shape.angle_degrees", *angle_degrees).map_err(at)?;
                at_least("shape.particles", *particles, 2, "a strand").map_err(at)?;
                if !(spacing.is_finite() && *spacing > 0.0) {
                    return Err((
                        ".shape.spacing".into(),
                        format!(
                            "{spacing} would make a zero or negative rest length; it must be positive"
                        ),
                    ));
                }
            }
            ShapeSpec::Polyline { points } | ShapeSpec::Polygon { points } => {
                for (j, &p) in points.iter().enumerate() {
                    finite_vector(&format!("shape.points[{j}]"), vec2(p)).map_err(at)?;
                }
            }
            ShapeSpec::Serpentine {
                start,
                width,
                row_gap,
                particles,
                spacing,
            } => {
                finite_vector("shape.start", vec2(*start)).map_err(at)?;
                at_least("shape.particles", *particles, 2, "a strand").map_err(at)?;
                positive("shape.spacing", *spacing).map_err(at)?;
                positive("shape.row_gap", *row_gap).map_err(at)?;
                if !(width.is_finite() && *width >= *spacing) {
                    return Err((
                        ".shape.width".into(),
                        format!(
                            "{width} is shorter than one spacing ({spacing}); a row needs two particles"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
