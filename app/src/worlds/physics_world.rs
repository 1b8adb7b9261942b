//! The `physics_world` example's world: avian bodies and strands coupled both ways. A
//! ground and two posts (static bodies), a rope bridge between the posts, five crates
//! dropped on it one every 1.2 s, and a crane (a kinematic beam driven to and fro)
//! swinging a heavy crate on a rope. Avian and the strands each at 60 Hz, the strands
//! in 10 substeps.

use avian2d::prelude::*;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;

/// The world the camera shows, in metres.
pub const VIEW: Vec2 = Vec2::new(2.4, 1.35);
/// A crate's side.
pub const CRATE: f32 = 0.1;
/// Where the crates are dropped over the bridge, one every 1.2 s (72 ticks).
pub const DROPS: [f32; 5] = [0.62, 0.8, 0.5, 0.95, 0.7];
/// Ticks between drops.
pub const DROP_TICKS: u32 = 72;

/// The crane's beam: driven to and fro.
#[derive(Component)]
pub struct Crane;

/// A crate dropped on the bridge.
#[derive(Component)]
pub struct DroppedCrate;

/// The bodies and strands of the world, for the looks.
#[derive(Clone, Debug)]
pub struct PhysicsWorld {
    /// The ground.
    pub ground: Entity,
    /// The bridge's posts.
    pub posts: [Entity; 2],
    /// The rope bridge.
    pub bridge: Entity,
    /// The crane's beam.
    pub beam: Entity,
    /// The crate on the crane's rope.
    pub load: Entity,
    /// The crane's rope.
    pub line: Entity,
}

/// The step the example runs: a 60 Hz tick in 10 substeps.
pub fn physics_world_config() -> StrandsConfig {
    StrandsConfig {
        substeps: 10,
        ..default()
    }
}

/// Drops the crates and drives the crane, in `FixedUpdate`.
pub struct PhysicsWorldPlugin;

impl Plugin for PhysicsWorldPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(FixedUpdate, (drop_crates, drive_crane));
    }
}

/// Spawn the world's bodies and strands.
pub fn spawn_physics_world(commands: &mut Commands) -> PhysicsWorld {
    // Static bodies: the ground and the bridge's two posts. Strands collide with them
    // as the crates do.
    let mut solid = |centre: Vec2, size: Vec2| {
        commands
            .spawn((
                RigidBody::Static,
                Collider::rectangle(size.x, size.y),
                CollidesWithStrands::default(),
                Transform::from_translation(centre.extend(-0.5)),
            ))
            .id()
    };
    let ground = solid(Vec2::new(1.2, 0.05), Vec2::new(2.4, 0.1));
    let posts = [0.27, 1.13].map(|x| solid(Vec2::new(x, 0.4), Vec2::new(0.04, 0.6)));
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.72), DVec2::new(1.1, 0.72), 40, 1.08)
        .mass(0.02)
        .material(StrandMaterial::INERT)
        .spawn(commands)
        .expect("a valid rope");

    // The crane: a kinematic beam, a rope hung from it, a heavy crate on the rope.
    let beam = commands
        .spawn((
            Crane,
            RigidBody::Kinematic,
            Collider::rectangle(0.3, 0.04),
            Transform::from_xyz(1.8, 1.2, -0.5),
        ))
        .id();
    let (links, spacing) = (21, 0.025);
    let top = DVec2::new(1.8, 1.175);
    let end = top - DVec2::Y * spacing * (links - 1) as f64;
    let hook = 0.5 * CRATE + 0.006;
    let load = commands
        .spawn((
            RigidBody::Dynamic,
            Collider::rectangle(CRATE, CRATE),
            ColliderDensity(200.0),
            CollidesWithStrands::default(),
            Transform::from_xyz(end.x as f32, end.y as f32 - hook, 0.6),
        ))
        .id();
    let line = StrandBuilder::line(top, -DVec2::Y, links, spacing)
        .mass(0.01)
        .material(StrandMaterial::INERT)
        .spawn(commands)
        .expect("a valid rope");
    commands.queue(move |world: &mut World| {
        let particles = world
            .get::<Strand>(line)
            .expect("the rope")
            .particles
            .clone();
        world.entity_mut(particles[0]).insert(BodyAnchor {
            body: beam,
            offset: Vec2::new(0.0, -0.025),
        });
        world.entity_mut(particles[links - 1]).insert(BodyAnchor {
            body: load,
            offset: Vec2::new(0.0, hook),
        });
    });
    PhysicsWorld {
        ground,
        posts,
        bridge,
        beam,
        load,
        line,
    }
}

/// A crate every 1.2 s over the bridge, five in all.
pub fn drop_crates(mut commands: Commands, mut ticks: Local<u32>) {
    *ticks += 1;
    let k = (*ticks / DROP_TICKS) as usize;
    if !ticks.is_multiple_of(DROP_TICKS) || k > DROPS.len() {
        return;
    }
    commands.spawn((
        DroppedCrate,
        RigidBody::Dynamic,
        Collider::rectangle(CRATE, CRATE),
        ColliderDensity(40.0),
        CollidesWithStrands::default(),
        Transform::from_xyz(DROPS[k - 1], 1.25, 0.6),
    ));
}

/// The crane's beam runs to and fro.
pub fn drive_crane(time: Res<Time<Fixed>>, mut beam: Query<&mut LinearVelocity, With<Crane>>) {
    for mut velocity in &mut beam {
        velocity.0.x = 0.35 * (0.9 * time.elapsed_secs()).cos();
    }
}
