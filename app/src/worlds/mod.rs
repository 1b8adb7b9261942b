//! The worlds of the game-style examples without their looks: what the simulation
//! steps (strands, walls, avian bodies and the systems that drive them), so that the
//! windowed examples dress them in sprites and ribbons and the frame benchmark runs
//! them headless, the same world either way.

pub mod game;
#[cfg(feature = "avian")]
pub mod physics_world;
