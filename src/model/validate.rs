//! The validation rules, in one place: what makes a particle, a strand and a number in
//! a configuration simulable. The strand builder, the topology rebuild (which checks
//! components edited at run time), the packed-state gather and scene files all apply
//! these functions, so a value refused by one is refused by all, with the same words.

use std::ops::RangeInclusive;

use bevy::math::DVec2;
use thiserror::Error;

use super::edge::{bend_count, edge_count};

/// Why a particle's data cannot be simulated.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParticleError {
    /// The position is NaN or infinite.
    #[error("position {0:?} is not finite")]
    Position(DVec2),
    /// The velocity is NaN or infinite.
    #[error("velocity {0:?} is not finite")]
    Velocity(DVec2),
    /// A free particle's mass is zero, negative or not finite.
    #[error("mass {0} must be positive and finite")]
    Mass(f64),
}

impl ParticleError {
    /// The quantity at fault: `position`, `velocity` or `mass`.
    pub fn field(&self) -> &'static str {
        match self {
            ParticleError::Position(_) => "position",
            ParticleError::Velocity(_) => "velocity",
            ParticleError::Mass(_) => "mass",
        }
    }
}

/// Check one particle: finite position and velocity, and a positive finite mass unless
/// it is pinned (a pinned particle's mass is never used).
pub fn check_particle(
    position: DVec2,
    velocity: DVec2,
    mass: f64,
    pinned: bool,
) -> Result<(), ParticleError> {
    if !position.is_finite() {
        Err(ParticleError::Position(position))
    } else if !velocity.is_finite() {
        Err(ParticleError::Velocity(velocity))
    } else if !(pinned || mass.is_finite() && mass > 0.0) {
        Err(ParticleError::Mass(mass))
    } else {
        Ok(())
    }
}

/// Why a strand cannot be built or simulated.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StrandError {
    /// Too few particles for the strand's kind.
    #[error("{kind} strand needs at least {min} particles, got {got}")]
    TooFewParticles {
        /// "an open" or "a closed".
        kind: &'static str,
        /// The minimum.
        min: usize,
        /// What was given.
        got: usize,
    },
    /// A particle of the strand cannot be simulated.
    #[error("particle {index}: {problem}")]
    Particle {
        /// Particle index along the strand.
        index: usize,
        /// What is wrong with it.
        problem: ParticleError,
    },
    /// Two consecutive particles coincide, which would make a zero-length edge.
    #[error("particles {a} and {b} coincide at {at:?}: an edge needs a positive length")]
    CoincidentParticles {
        /// First particle index.
        a: usize,
        /// Second particle index.
        b: usize,
        /// Where.
        at: DVec2,
    },
    /// A rest length is zero, negative or not finite.
    #[error("rest length of edge {edge} must be positive and finite, got {value}")]
    BadRestLength {
        /// Edge index.
        edge: usize,
        /// The bad value.
        value: f64,
    },
    /// A rest angle is not finite.
    #[error("rest angle {value} at bending vertex {vertex} is not finite")]
    BadRestAngle {
        /// Bending vertex index.
        vertex: usize,
        /// The bad value.
        value: f64,
    },
    /// A list has the wrong length.
    #[error("{what} has {got} entries, expected {expected}")]
    WrongLength {
        /// Which list.
        what: &'static str,
        /// What was given.
        got: usize,
        /// What the particle count implies.
        expected: usize,
    },
    /// A pinned index is out of range.
    #[error("pinned particle index {index} is out of range for {count} particles")]
    PinOutOfRange {
        /// The bad index.
        index: usize,
        /// Particle count.
        count: usize,
    },
    /// An edge joins a particle to itself.
    #[error("edge {edge} joins a particle to itself")]
    SelfEdge {
        /// Edge index.
        edge: usize,
    },
    /// More particles than one strand may have.
    #[error("a strand may have at most {max} particles, got more")]
    TooManyParticles {
        /// The cap, [`MAX_STRAND_PARTICLES`].
        max: usize,
    },
    /// A vertex is not a particle that can be simulated (despawned, or refused).
    #[error("vertex {index} is not a particle that can be simulated")]
    NotSimulated {
        /// Vertex index along the strand.
        index: usize,
    },
}

/// The most particles one strand may have (2²⁴, 256 MiB of positions): a builder
/// asked for more stops collecting there instead of allocating without bound.
pub const MAX_STRAND_PARTICLES: usize = 1 << 24;

/// At least two particles for an open strand, three for a closed one.
pub fn check_particle_count(particles: usize, closed: bool) -> Result<(), StrandError> {
    let (kind, min) = if closed {
        ("a closed", 3)
    } else {
        ("an open", 2)
    };
    if particles < min {
        return Err(StrandError::TooFewParticles {
            kind,
            min,
            got: particles,
        });
    }
    Ok(())
}

/// Check a strand's shape: enough particles for an open or closed strand, one positive
/// finite rest length per edge, and either no rest angles (straight) or one finite
/// angle per bending vertex.
pub fn check_strand_shape(
    particles: usize,
    closed: bool,
    rest_lengths: &[f64],
    rest_angles: &[f64],
) -> Result<(), StrandError> {
    check_particle_count(particles, closed)?;
    let edges = edge_count(particles, closed);
    if rest_lengths.len() != edges {
        return Err(StrandError::WrongLength {
            what: "rest lengths",
            got: rest_lengths.len(),
            expected: edges,
        });
    }
    if let Some((edge, &value)) = rest_lengths
        .iter()
        .enumerate()
        .find(|(_, l)| !(l.is_finite() && **l > 0.0))
    {
        return Err(StrandError::BadRestLength { edge, value });
    }
    let bends = bend_count(particles, closed);
    if !rest_angles.is_empty() && rest_angles.len() != bends {
        return Err(StrandError::WrongLength {
            what: "rest angles",
            got: rest_angles.len(),
            expected: bends,
        });
    }
    if let Some((vertex, &value)) = rest_angles.iter().enumerate().find(|(_, a)| !a.is_finite()) {
        return Err(StrandError::BadRestAngle { vertex, value });
    }
    Ok(())
}

/// Rest lengths of the edges through `points` (their current distances), refusing
/// coincident neighbours.
pub fn rest_lengths_of(points: &[DVec2], closed: bool) -> Result<Vec<f64>, StrandError> {
    let n = points.len();
    (0..edge_count(n, closed))
        .map(|k| {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let length = a.distance(b);
            if length > 0.0 && length.is_finite() {
                Ok(length)
            } else {
                Err(StrandError::CoincidentParticles {
                    a: k,
                    b: (k + 1) % n,
                    at: a,
                })
            }
        })
        .collect()
}

/// A number in a configuration outside its meaning.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{field}: {problem}")]
pub struct NumberError {
    /// The field, e.g. `dt` or `collisions.thickness`.
    pub field: String,
    /// What is wrong with it.
    pub problem: String,
}

impl NumberError {
    /// The same problem, its field inside `parent` (`parent.field`).
    pub fn within(self, parent: &str) -> Self {
        Self {
            field: format!("{parent}.{}", self.field),
            problem: self.problem,
        }
    }
}

fn number_error(field: &str, problem: String) -> NumberError {
    NumberError {
        field: field.to_string(),
        problem,
    }
}

/// `value` must be finite and above zero.
pub fn positive(field: &str, value: f64) -> Result<(), NumberError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(number_error(
            field,
            format!("{value} must be positive and finite"),
        ))
    }
}

/// `value` must be finite and at least zero.
pub fn non_negative(field: &str, value: f64) -> Result<(), NumberError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(number_error(
            field,
            format!("{value} must be zero or positive and finite"),
        ))
    }
}

/// `value` must be finite.
pub fn finite(field: &str, value: f64) -> Result<(), NumberError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(number_error(field, format!("{value} is not finite")))
    }
}

/// Both coordinates must be finite.
pub fn finite_vector(field: &str, value: DVec2) -> Result<(), NumberError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(number_error(
            field,
            format!("({}, {}) is not finite", value.x, value.y),
        ))
    }
}

/// `value` must lie in `range` (which implies finite).
pub fn within(field: &str, value: f64, range: RangeInclusive<f64>) -> Result<(), NumberError> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(number_error(
            field,
            format!(
                "{value} must be between {} and {}",
                range.start(),
                range.end()
            ),
        ))
    }
}

/// A count that must be at least `min`.
pub fn at_least(field: &str, value: usize, min: usize, what: &str) -> Result<(), NumberError> {
    if value >= min {
        Ok(())
    } else {
        Err(number_error(
            field,
            format!("{what} needs at least {min}, got {value}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn particles_and_strands_are_checked_with_one_set_of_rules() {
        assert!(check_particle(DVec2::ZERO, DVec2::ZERO, 1.0, false).is_ok());
        assert!(check_particle(DVec2::ZERO, DVec2::ZERO, 0.0, true).is_ok());
        assert_eq!(
            check_particle(DVec2::ZERO, DVec2::ZERO, -1.0, false),
            Err(ParticleError::Mass(-1.0))
        );
        assert!(matches!(
            check_particle(DVec2::new(f64::NAN, 0.0), DVec2::ZERO, 1.0, false),
            Err(ParticleError::Position(_))
        ));
        assert!(check_strand_shape(3, false, &[1.0, 1.0], &[]).is_ok());
        assert!(matches!(
            check_strand_shape(2, true, &[1.0, 1.0], &[]),
            Err(StrandError::TooFewParticles { min: 3, .. })
        ));
        assert!(matches!(
            check_strand_shape(3, false, &[1.0, 0.0], &[]),
            Err(StrandError::BadRestLength { edge: 1, .. })
        ));
        assert!(matches!(
            check_strand_shape(3, false, &[1.0, 1.0], &[0.1, 0.2]),
            Err(StrandError::WrongLength { expected: 1, .. })
        ));
        assert!(matches!(
            check_strand_shape(3, false, &[1.0, 1.0], &[f64::INFINITY]),
            Err(StrandError::BadRestAngle { vertex: 0, .. })
        ));
    }

    #[test]
    fn numbers_are_checked_against_their_meaning() {
        assert!(positive("dt", 1e-3).is_ok());
        assert_eq!(
            positive("dt", 0.0).unwrap_err().to_string(),
            "dt: 0 must be positive and finite"
        );
        assert!(non_negative("damping", 0.0).is_ok());
        assert!(non_negative("damping", f64::NAN).is_err());
        assert!(within("restitution", 1.0, 0.0..=1.0).is_ok());
        assert!(within("restitution", 2.0, 0.0..=1.0).is_err());
        assert_eq!(
            positive("thickness", -1.0)
                .unwrap_err()
                .within("collisions")
                .field,
            "collisions.thickness"
        );
    }
}
