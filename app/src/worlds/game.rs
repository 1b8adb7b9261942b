//! The `game` example's world: a rope bridge between two posts, a rope swinging a
//! heavy lantern from a beam, and a head of 28 hairs, over a floor; a 60 Hz fixed step
//! in 10 substeps.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;

/// The world the camera shows, in metres.
pub const VIEW: Vec2 = Vec2::new(2.4, 1.35);
/// The head the hairs grow from: its centre and radius.
pub const HEAD: (DVec2, f64) = (DVec2::new(1.95, 0.42), 0.12);
/// The lantern's mass (the swinging rope's last particle).
pub const LANTERN_MASS: f64 = 3.0;

/// The strands of the world, for the looks.
#[derive(Clone, Debug)]
pub struct GameWorld {
    /// The rope bridge.
    pub bridge: Entity,
    /// The rope the lantern swings on (the lantern is its last particle).
    pub swing: Entity,
    /// The hairs.
    pub hair: Vec<Entity>,
}

/// The step the example runs: a 60 Hz tick in 10 substeps.
pub fn game_config() -> StrandsConfig {
    StrandsConfig {
        substeps: 10,
        ..default()
    }
}

/// Spawn the world's strands.
pub fn spawn_game_world(commands: &mut Commands) -> GameWorld {
    // The floor the strands land on (a static two-particle strand).
    StrandBuilder::polyline([DVec2::new(0.0, 0.1), DVec2::new(2.4, 0.1)])
        .pin(0)
        .pin(1)
        .kind(StrandKind::Wall)
        .material(StrandMaterial::INERT)
        .spawn(commands)
        .expect("a valid wall");
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.7), DVec2::new(1.1, 0.7), 40, 1.08)
        .spawn(commands)
        .expect("a valid rope");

    // A rope from a beam, released sideways, with a heavy lantern on its end.
    let swing = StrandBuilder::line(DVec2::new(1.55, 1.25), DVec2::new(1.0, -0.25), 26, 0.02)
        .pin_first()
        .spawn(commands)
        .expect("a valid rope");
    commands.queue(move |world: &mut World| {
        let last = *world
            .get::<Strand>(swing)
            .expect("the rope")
            .particles
            .last()
            .expect("a particle");
        world.entity_mut(last).insert(Mass(LANTERN_MASS));
    });

    // A head with hair: roots pinned on the upper half of a disc, each hair's first two
    // particles pinned so it keeps its root's direction.
    let (centre, radius) = HEAD;
    let material = StrandMaterial {
        bending_stiffness: 2.0e-4,
        bending_damping: 2.0e-6,
        ..default()
    };
    let hair = (0..28)
        .map(|k| {
            let angle = std::f64::consts::PI * (0.05 + 0.9 * k as f64 / 27.0);
            let out = DVec2::from_angle(angle);
            StrandBuilder::line(centre + radius * out, out, 9, 0.018)
                .pin(0)
                .pin(1)
                .mass(0.05)
                .kind(StrandKind::Hair)
                .material(material)
                .spawn(commands)
                .expect("a valid hair")
        })
        .collect();
    GameWorld {
        bridge,
        swing,
        hair,
    }
}
