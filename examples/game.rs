//! The plugin in a game's own setting: sprites, a camera of the game's choosing, a
//! 60 Hz fixed step with 10 substeps (a step of 1/600 s), and strands drawn as ribbon
//! meshes — a textured rope bridge, a rope swinging a lantern sprite, and a head of
//! hair. No demo panel: only what a game would add.
//!
//! `cargo run --release --features render --example game`

use bevy::asset::RenderAssetUsages;
use bevy::camera::ScalingMode;
use bevy::image::{ImageAddressMode, ImageSampler, ImageSamplerDescriptor};
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy_strands::prelude::*;
use bevy_strands::ribbon::{StrandRibbon, StrandRibbonPlugin};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};

/// The world the camera shows, in metres.
const VIEW: Vec2 = Vec2::new(2.4, 1.35);

fn main() -> AppExit {
    App::new()
        .add_plugins(window_plugins("a game"))
        .add_plugins((
            StrandsPlugin::default(),
            StrandRibbonPlugin,
            ScreenshotPlugin,
        ))
        // The game's clock: 60 Hz. The plugin takes its step from it (1/60 s in 10
        // substeps) and never changes it.
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(StrandsConfig {
            substeps: 10,
            ..default()
        })
        .insert_resource(ClearColor(Color::srgb(0.55, 0.7, 0.85)))
        .add_systems(Startup, setup)
        .run()
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<ColorMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
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
    let rect = |commands: &mut Commands, color: Color, centre: Vec2, size: Vec2, z: f32| {
        commands.spawn((
            Sprite::from_color(color, size),
            Transform::from_translation(centre.extend(z)),
        ));
    };
    // Ground, and the floor the strands land on (a static two-particle strand).
    rect(
        &mut commands,
        Color::srgb(0.3, 0.45, 0.2),
        Vec2::new(1.2, 0.05),
        Vec2::new(2.4, 0.1),
        -1.0,
    );
    wall(&mut commands, DVec2::new(0.0, 0.1), DVec2::new(2.4, 0.1));
    // Two posts and the bridge between them.
    let post = Color::srgb(0.4, 0.26, 0.13);
    for x in [0.3, 1.1] {
        rect(
            &mut commands,
            post,
            Vec2::new(x, 0.4),
            Vec2::new(0.05, 0.6),
            -0.5,
        );
    }
    let rope_texture = images.add(rope_texture());
    let rope = materials.add(ColorMaterial {
        color: Color::WHITE,
        texture: Some(rope_texture),
        ..default()
    });
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.7), DVec2::new(1.1, 0.7), 40, 1.08);
    let bridge = bridge.spawn(&mut commands).expect("a valid rope");
    commands.entity(bridge).insert((
        StrandRibbon {
            width: 0.022,
            repeat: 0.044,
            z: 0.5,
            ..default()
        },
        MeshMaterial2d(rope.clone()),
    ));

    // A rope from a beam, released sideways, with a lantern on its end.
    rect(
        &mut commands,
        post,
        Vec2::new(1.55, 1.27),
        Vec2::new(0.4, 0.04),
        -0.5,
    );
    let swing = StrandBuilder::line(DVec2::new(1.55, 1.25), DVec2::new(1.0, -0.25), 26, 0.02)
        .pin_first()
        .spawn(&mut commands)
        .expect("a valid rope");
    commands.entity(swing).insert((
        StrandRibbon {
            width: 0.016,
            repeat: 0.032,
            z: 0.5,
            ..default()
        },
        MeshMaterial2d(rope),
    ));
    commands.queue(move |world: &mut World| {
        let last = *world
            .get::<Strand>(swing)
            .unwrap()
            .particles
            .last()
            .unwrap();
        world.entity_mut(last).insert((
            Mass(3.0),
            SyncTransform::default(),
            Sprite::from_color(Color::srgb(1.0, 0.85, 0.3), Vec2::splat(0.06)),
        ));
    });

    // A head with hair: roots pinned on the upper half of a disc, each hair's first two
    // particles pinned so it keeps its root's direction.
    let centre = DVec2::new(1.95, 0.42);
    let radius = 0.12;
    commands.spawn((
        Mesh2d(meshes.add(Circle::new(radius as f32))),
        MeshMaterial2d(materials.add(Color::srgb(0.93, 0.75, 0.6))),
        Transform::from_translation(centre.as_vec2().extend(0.2)),
    ));
    let hair = materials.add(Color::srgb(0.35, 0.2, 0.1));
    let material = StrandMaterial {
        bending_stiffness: 2.0e-4,
        bending_damping: 2.0e-6,
        ..default()
    };
    for k in 0..28 {
        let angle = std::f64::consts::PI * (0.05 + 0.9 * k as f64 / 27.0);
        let out = DVec2::from_angle(angle);
        let strand = StrandBuilder::line(centre + radius * out, out, 9, 0.018)
            .pin(0)
            .pin(1)
            .mass(0.05)
            .kind(StrandKind::Hair)
            .material(material)
            .spawn(&mut commands)
            .expect("a valid hair");
        commands.entity(strand).insert((
            StrandRibbon {
                width: 0.007,
                repeat: 1.0,
                z: 0.3,
                ..default()
            },
            MeshMaterial2d(hair.clone()),
        ));
    }
}

/// A static wall edge.
fn wall(commands: &mut Commands, a: DVec2, b: DVec2) {
    StrandBuilder::polyline([a, b])
        .pin(0)
        .pin(1)
        .kind(StrandKind::Wall)
        .material(StrandMaterial::INERT)
        .spawn(commands)
        .expect("a valid wall");
}

/// A twisted-rope texture: diagonal bands of two browns, repeating in both directions.
fn rope_texture() -> Image {
    let (w, h) = (32u32, 16u32);
    let mut data = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let band = (x + 2 * y) % 16 < 8;
            let edge = y == 0 || y == h - 1;
            let [r, g, b] = match (edge, band) {
                (true, _) => [70, 45, 20],
                (false, true) => [196, 150, 90],
                (false, false) => [150, 105, 55],
            };
            data.extend([r, g, b, 255]);
        }
    }
    let mut image = Image::new(
        Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::default(),
    );
    image.sampler = ImageSampler::Descriptor(ImageSamplerDescriptor {
        address_mode_u: ImageAddressMode::Repeat,
        address_mode_v: ImageAddressMode::Repeat,
        ..ImageSamplerDescriptor::linear()
    });
    image
}
