//! The plugin in a game's own setting: sprites, a camera of the game's choosing, a
//! 60 Hz fixed step with 10 substeps (a step of 1/600 s), and strands drawn as ribbon
//! meshes — a textured rope bridge, a rope swinging a lantern sprite, and a head of
//! hair. No demo panel: only what a game would add.
//!
//! `cargo run --release --features render --example game`

use bevy::asset::RenderAssetUsages;
use bevy::camera::ScalingMode;
use bevy::image::{ImageAddressMode, ImageSampler, ImageSamplerDescriptor};
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy_strands::prelude::*;
use bevy_strands::ribbon::{StrandRibbon, StrandRibbonPlugin};
use bevy_strands_app::window::{ScreenshotPlugin, window_plugins};
use bevy_strands_app::worlds::game::{HEAD, VIEW, game_config, spawn_game_world};

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
        .insert_resource(game_config())
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
    let world = spawn_game_world(&mut commands);
    // Ground, two posts, the beam the lantern hangs from.
    rect(
        &mut commands,
        Color::srgb(0.3, 0.45, 0.2),
        Vec2::new(1.2, 0.05),
        Vec2::new(2.4, 0.1),
        -1.0,
    );
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
    rect(
        &mut commands,
        post,
        Vec2::new(1.55, 1.27),
        Vec2::new(0.4, 0.04),
        -0.5,
    );
    let rope_texture = images.add(rope_texture());
    let rope = materials.add(ColorMaterial {
        color: Color::WHITE,
        texture: Some(rope_texture),
        ..default()
    });
    for (strand, width) in [(world.bridge, 0.022), (world.swing, 0.016)] {
        commands.entity(strand).insert((
            StrandRibbon {
                width,
                repeat: 2.0 * width,
                z: 0.5,
                ..default()
            },
            MeshMaterial2d(rope.clone()),
        ));
    }
    // The lantern: the swinging rope's last particle, drawn as a sprite.
    let swing = world.swing;
    commands.queue(move |world: &mut World| {
        let last = *world
            .get::<Strand>(swing)
            .unwrap()
            .particles
            .last()
            .unwrap();
        world.entity_mut(last).insert((
            SyncTransform::default(),
            Sprite::from_color(Color::srgb(1.0, 0.85, 0.3), Vec2::splat(0.06)),
        ));
    });
    // The head and its hair.
    let (centre, radius) = HEAD;
    commands.spawn((
        Mesh2d(meshes.add(Circle::new(radius as f32))),
        MeshMaterial2d(materials.add(Color::srgb(0.93, 0.75, 0.6))),
        Transform::from_translation(centre.as_vec2().extend(0.2)),
    ));
    let hair = materials.add(Color::srgb(0.35, 0.2, 0.1));
    for strand in world.hair {
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
