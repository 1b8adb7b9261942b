//! The worlds of the game-style examples without their looks: what the simulation
//! steps (strands, walls, the engines' bodies and the systems that drive them), so
//! that the windowed examples dress them in sprites and ribbons and the frame
//! benchmark runs them headless, the same world either way.

#[cfg(any(feature = "avian", feature = "rapier"))]
pub mod bodies_world;
pub mod game;
#[cfg(feature = "avian")]
pub mod physics_world;
#[cfg(feature = "rapier")]
pub mod rapier_world;
