//! Strands in an avian2d world: crates dropped on a rope bridge land on it, sag it and
//! rest on it; a crane (a kinematic avian body) swings a crate on a rope — the crate's
//! weight hangs on the rope, the rope's pull swings the crate. Avian steps the bodies,
//! the strands step the ropes, each at 60 Hz (the strands in 10 substeps), coupled
//! both ways by `StrandsAvianPlugin`.
//!
//! `cargo run --release --features render,avian --example physics_world`

use avian2d::prelude::*;
use bevy::camera::ScalingMode;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::ribbon::{StrandRibbon, StrandRibbonPlugin};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};

/// The world the camera shows, in metres.
const VIEW: Vec2 = Vec2::new(2.4, 1.35);
/// A crate's side.
const CRATE: f32 = 0.1;
/// Where the crates are dropped over the bridge, one every 1.2 s.
const DROPS: [f32; 5] = [0.62, 0.8, 0.5, 0.95, 0.7];

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("strands in an avian world"))
        .add_plugins((
            PhysicsPlugins::default(),
            StrandsPlugin::default(),
            StrandsAvianPlugin::default(),
            StrandRibbonPlugin,
            ScreenshotPlugin,
        ))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(StrandsConfig {
            substeps: 10,
            ..default()
        })
        .insert_resource(ClearColor(Color::srgb(0.55, 0.7, 0.85)))
        .add_systems(Startup, setup)
        .add_systems(FixedUpdate, (drop_crates, drive_crane))
        .run()
}

/// The crane's beam: driven to and fro.
#[derive(Component)]
struct Crane;

/// Materials the scene reuses.
#[derive(Resource)]
struct Looks {
    crate_colour: Color,
}

fn setup(mut commands: Commands, mut materials: ResMut<Assets<ColorMaterial>>) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scaling_mode: ScalingMode::AutoMin {
                min_width: VIEW.x,
                min_height: VIEW.y,
            },
            ..OrthographicProjection::default_2d()
        }),
        Transform::from_translation((VIEW / 2.0).extend(0.0)),
    ));
    commands.insert_resource(Looks {
        crate_colour: Color::srgb(0.72, 0.5, 0.25),
    });
    // Static bodies: the ground and the bridge's two posts. Strands collide with them
    // as the crates do.
    let wood = Color::srgb(0.4, 0.26, 0.13);
    let solid = |commands: &mut Commands, colour: Color, centre: Vec2, size: Vec2| {
        commands.spawn((
            RigidBody::Static,
            Collider::rectangle(size.x, size.y),
            CollidesWithStrands::default(),
            Sprite::from_color(colour, size),
            Transform::from_translation(centre.extend(-0.5)),
        ));
    };
    solid(
        &mut commands,
        Color::srgb(0.3, 0.45, 0.2),
        Vec2::new(1.2, 0.05),
        Vec2::new(2.4, 0.1),
    );
    for x in [0.27, 1.13] {
        solid(&mut commands, wood, Vec2::new(x, 0.4), Vec2::new(0.04, 0.6));
    }
    let rope = materials.add(Color::srgb(0.62, 0.45, 0.25));
    let ribbon = |width: f64| StrandRibbon {
        width,
        repeat: 2.0 * width,
        z: 0.5,
        ..default()
    };
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.72), DVec2::new(1.1, 0.72), 40, 1.08)
        .mass(0.02)
        .material(StrandMaterial::INERT)
        .spawn(&mut commands)
        .expect("a valid rope");
    commands
        .entity(bridge)
        .insert((ribbon(0.014), MeshMaterial2d(rope.clone())));

    // The crane: a kinematic beam, a rope hung from it, a heavy crate on the rope.
    let beam = commands
        .spawn((
            Crane,
            RigidBody::Kinematic,
            Collider::rectangle(0.3, 0.04),
            Sprite::from_color(wood, Vec2::new(0.3, 0.04)),
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
            Sprite::from_color(Color::srgb(0.55, 0.35, 0.2), Vec2::splat(CRATE)),
            Transform::from_xyz(end.x as f32, end.y as f32 - hook, 0.6),
        ))
        .id();
    let line = StrandBuilder::line(top, -DVec2::Y, links, spacing)
        .mass(0.01)
        .material(StrandMaterial::INERT)
        .spawn(&mut commands)
        .expect("a valid rope");
    commands
        .entity(line)
        .insert((ribbon(0.01), MeshMaterial2d(rope)));
    commands.queue(move |world: &mut World| {
        let particles = world.get::<Strand>(line).unwrap().particles.clone();
        world.entity_mut(particles[0]).insert(BodyAnchor {
            body: beam,
            offset: Vec2::new(0.0, -0.025),
        });
        world.entity_mut(particles[links - 1]).insert(BodyAnchor {
            body: load,
            offset: Vec2::new(0.0, hook),
        });
    });
}

/// A crate every 1.2 s over the bridge, five in all.
fn drop_crates(mut commands: Commands, mut ticks: Local<u32>, looks: Res<Looks>) {
    *ticks += 1;
    let k = (*ticks / 72) as usize;
    if !ticks.is_multiple_of(72) || k > DROPS.len() {
        return;
    }
    commands.spawn((
        RigidBody::Dynamic,
        Collider::rectangle(CRATE, CRATE),
        ColliderDensity(40.0),
        CollidesWithStrands::default(),
        Sprite::from_color(looks.crate_colour, Vec2::splat(CRATE)),
        Transform::from_xyz(DROPS[k - 1], 1.25, 0.6),
    ));
}

/// The crane's beam runs to and fro.
fn drive_crane(time: Res<Time<Fixed>>, mut beam: Query<&mut LinearVelocity, With<Crane>>) {
    for mut velocity in &mut beam {
        velocity.0.x = 0.35 * (0.9 * time.elapsed_secs()).cos();
    }
}
