//! What the `physics_world` (avian) and `rapier_world` (Rapier) examples share: the
//! world's layout and its strands — a rope bridge between two posts and a crane's rope
//! with a crate on its hook — so that each engine's world only adds its own bodies.

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
/// The ground's centre and size.
pub const GROUND: (Vec2, Vec2) = (Vec2::new(1.2, 0.05), Vec2::new(2.4, 0.1));
/// The posts' centres (x) and their common centre height and size.
pub const POSTS: ([f32; 2], f32, Vec2) = ([0.27, 1.13], 0.4, Vec2::new(0.04, 0.6));
/// The crane's beam: where it starts and its size.
pub const BEAM: (Vec2, Vec2) = (Vec2::new(1.8, 1.2), Vec2::new(0.3, 0.04));
/// The dropped crates' density and the crane's load's (kg/m²).
pub const DENSITIES: (f32, f32) = (40.0, 200.0);
/// The crane's rope: particles and spacing.
const LINE: (usize, f64) = (21, 0.025);
/// The hook's height above the load's centre.
pub const HOOK: f32 = 0.5 * CRATE + 0.006;

/// The crane's beam: driven to and fro.
#[derive(Component)]
pub struct Crane;

/// A crate dropped on the bridge.
#[derive(Component)]
pub struct DroppedCrate;

/// The bodies and strands of the world, for the looks.
#[derive(Clone, Debug)]
pub struct BodiesWorld {
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

/// The step both examples run: a 60 Hz tick in 10 substeps.
pub fn bodies_world_config() -> StrandsConfig {
    StrandsConfig {
        substeps: 10,
        ..default()
    }
}

/// Where the load hangs at the start: under the rope's last particle.
pub fn load_centre() -> Vec2 {
    let end = line_top() - DVec2::Y * LINE.1 * (LINE.0 - 1) as f64;
    Vec2::new(end.x as f32, end.y as f32 - HOOK)
}

fn line_top() -> DVec2 {
    DVec2::new(BEAM.0.x as f64, (BEAM.0.y - 0.025) as f64)
}

/// The bridge and the crane's rope, hung on the beam and the load (bodies of either
/// engine): returns (bridge, line).
pub fn spawn_ropes(commands: &mut Commands, beam: Entity, load: Entity) -> (Entity, Entity) {
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.72), DVec2::new(1.1, 0.72), 40, 1.08)
        .mass(0.02)
        .material(StrandMaterial::INERT)
        .spawn(commands)
        .expect("a valid rope");
    let (links, spacing) = LINE;
    let line = StrandBuilder::line(line_top(), -DVec2::Y, links, spacing)
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
            offset: Vec2::new(0.0, HOOK),
        });
    });
    (bridge, line)
}

/// Whether this tick drops a crate, and where: one every 1.2 s, five in all.
pub fn drop_at(ticks: &mut u32) -> Option<f32> {
    *ticks += 1;
    let k = (*ticks / DROP_TICKS) as usize;
    if !ticks.is_multiple_of(DROP_TICKS) || k > DROPS.len() {
        return None;
    }
    Some(DROPS[k - 1])
}

/// The crane beam's speed at `seconds`: to and fro.
pub fn crane_speed(seconds: f32) -> f32 {
    0.35 * (0.9 * seconds).cos()
}
