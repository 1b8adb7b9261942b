//! The Collide stage: robust point–edge collision processing.
//!
//! On the velocities the constraint solve left, each step:
//!
//! 1. **Proximity** — when the contact solve ran (the crate's `contact` module), its
//!    contacts are the step's and no impulse is needed; otherwise pairs that would end
//!    the step closer than the thickness `h` get a repulsion impulse, with Coulomb
//!    friction.
//! 2. **Continuous detection** — every point against every edge it is not part of,
//!    over the step's linear motion ([`ccd`]); each contact gets an inelastic impulse
//!    with friction ([`response`]); detection repeats with the new velocities until a
//!    full pass finds nothing or the cap is hit ([`impulses`]).
//! 3. **Fail-safe** — collisions still left after the last pass are resolved by rigid
//!    impact zones ([`failsafe`]), which guarantees no crossing.
//!
//! The contact loop (the crate's `contact` module) then alternates constraint
//! re-projection with 2–3. Candidate pairs come from a uniform-grid broad phase ([`broad_phase`]).
//! The walls are ordinary pinned edges. In checked mode, the Measure stage counts edge
//! crossings ([`crossings`]). [`plugin`] holds the thin systems.
//!
//! Imports: [`crate::model`], [`crate::parallel`], [`crate::metrics`]; its plugin,
//! [`crate::world`] and [`crate::schedule`].

pub mod broad_phase;
pub mod ccd;
pub mod clearance;
pub mod crossings;
pub mod exempt;
pub mod failsafe;
pub mod impulses;
pub mod plugin;
pub mod response;
pub mod still;

pub use plugin::{CollisionPlugin, CollisionScratch};
