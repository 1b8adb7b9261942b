//! Edges and bending elements between packed particles (indices into the packed state).

use bevy::math::DVec2;

/// An edge between two packed particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// First particle (packed index).
    pub a: u32,
    /// Second particle (packed index).
    pub b: u32,
    /// Rest length.
    pub rest_length: f64,
    /// Index of the owning strand in the topology's strand list.
    pub strand: u32,
    /// Both ends pinned: the edge never changes and is only an obstacle.
    pub is_static: bool,
    /// Kept at its rest length by the constraint solver.
    pub constrained: bool,
    /// Carries a stretch spring.
    pub spring: bool,
    /// Stretch spring stiffness per unit strain.
    pub stiffness: f64,
    /// Stretch spring damping along the edge.
    pub damping: f64,
    /// An edge of a wall or a collider's body: it meets strands, never another wall's
    /// particles (bodies meet each other in their own physics, walls never move).
    pub solid: bool,
}

impl Edge {
    /// A dynamic edge from `a` to `b` with no spring, not yet constrained.
    pub fn new(a: u32, b: u32, rest_length: f64) -> Self {
        Self {
            a,
            b,
            rest_length,
            strand: 0,
            is_static: false,
            constrained: false,
            spring: false,
            stiffness: 0.0,
            damping: 0.0,
            solid: false,
        }
    }

    /// Whether the two edges share a particle.
    pub fn shares_particle(&self, other: &Edge) -> bool {
        self.a == other.a || self.a == other.b || self.b == other.a || self.b == other.b
    }

    /// `|ℓ − L| / L` at `position`.
    pub fn relative_length_error(&self, position: &[DVec2]) -> f64 {
        let length = position[self.a as usize].distance(position[self.b as usize]);
        (length - self.rest_length).abs() / self.rest_length
    }
}

/// A bending element at particle `s` between edges (a, s) and (s, b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bend {
    /// Previous particle.
    pub a: u32,
    /// The vertex.
    pub s: u32,
    /// Next particle.
    pub b: u32,
    /// Rest turning angle.
    pub rest_angle: f64,
    /// `k_b / ℓ̄`: stiffness over the vertex's Voronoi length.
    pub stiffness: f64,
    /// Damping of the turning-angle rate.
    pub damping: f64,
    /// Rest lengths of the edges (a, s) and (s, b): the quadratic bending model's
    /// unit tangents are the edges over them.
    pub rest_lengths: [f64; 2],
}

/// Edges of a strand of `particles` particles: one fewer when open, as many when closed.
pub fn edge_count(particles: usize, closed: bool) -> usize {
    match (particles, closed) {
        (0, _) => 0,
        (n, false) => n - 1,
        (n, true) => n,
    }
}

/// Bending vertices of a strand of `particles` particles: every interior particle when
/// open, every particle when closed.
pub fn bend_count(particles: usize, closed: bool) -> usize {
    if closed {
        particles
    } else {
        particles.saturating_sub(2)
    }
}

/// Relative length error of every edge into `errors` (0 for static edges); returns the
/// maxima over all edges and over those with no particle in contact.
pub fn measure_length_errors(
    edges: &[Edge],
    position: &[DVec2],
    in_contact: &[bool],
    errors: &mut [f64],
) -> (f64, f64) {
    let (mut all, mut free) = (0.0f64, 0.0f64);
    for (edge, error) in edges.iter().zip(errors.iter_mut()) {
        *error = if edge.is_static {
            0.0
        } else {
            edge.relative_length_error(position)
        };
        all = all.max(*error);
        if !(in_contact[edge.a as usize] || in_contact[edge.b as usize]) {
            free = free.max(*error);
        }
    }
    (all, free)
}
