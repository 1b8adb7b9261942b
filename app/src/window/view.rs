//! The demo's view: a camera that keeps the scenario in the window beside the panel,
//! the bodies drawn under the strands, and the particle under the cursor highlighted.

use bevy::camera::ScalingMode;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy_strands::prelude::StrandsConfig;
use bevy_strands::render::{StrandGizmos, draw_strands, units_per_pixel};

use super::layout::UiLayout;
use super::tools::ToolState;
use super::{ActiveScenario, spawn_active_scenario};
use crate::scenes::Disc;

/// The demo's camera, its fit to the scenario, bodies and the hover mark.
pub struct DemoViewPlugin;

impl Plugin for DemoViewPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<UiLayout>()
            .add_systems(Startup, (spawn_camera, spawn_active_scenario))
            .add_systems(PreUpdate, fixed_rate_follows_the_scene)
            .add_systems(
                Update,
                (
                    fit_camera,
                    draw_bodies.before(draw_strands),
                    draw_hovered.after(draw_strands),
                ),
            );
    }
}

/// The demo owns its clock: its fixed rate is the scene's tick (`dt` × `substeps`), so
/// the step the plugin takes from it is the scene's `dt`, also after the panel edits it.
fn fixed_rate_follows_the_scene(config: Res<StrandsConfig>, mut fixed: ResMut<Time<Fixed>>) {
    let seconds = config.tick_seconds();
    let Ok(timestep) = std::time::Duration::try_from_secs_f64(seconds) else {
        return;
    };
    if config.is_changed() && !timestep.is_zero() && fixed.timestep() != timestep {
        fixed.set_timestep(timestep);
    }
}

fn spawn_camera(mut commands: Commands) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scaling_mode: ScalingMode::WindowSize,
            ..OrthographicProjection::default_2d()
        }),
    ));
}

/// Fit the scenario's view rectangle into the window left of the panel.
fn fit_camera(
    windows: Query<&Window, With<PrimaryWindow>>,
    active: Option<Res<ActiveScenario>>,
    layout: Res<UiLayout>,
    mut cameras: Query<(&mut Transform, &mut Projection), With<Camera2d>>,
) {
    let (Ok(window), Some(active)) = (windows.single(), active) else {
        return;
    };
    let view = active.scenario.view();
    let free = Vec2::new(
        (window.width() - layout.panel_width).max(100.0),
        window.height(),
    );
    let size = (view.max - view.min).as_vec2();
    let pixels_per_unit = (free.x / (1.08 * size.x)).min(free.y / (1.08 * size.y));
    let centre = ((view.min + view.max) / 2.0).as_vec2();
    // Shift so the view's centre sits in the middle of the free area, not the window.
    let shift = (window.width() - free.x) / 2.0 / pixels_per_unit;
    for (mut transform, mut projection) in &mut cameras {
        transform.translation = Vec3::new(centre.x + shift, centre.y, transform.translation.z);
        if let Projection::Orthographic(ortho) = &mut *projection {
            ortho.scale = 1.0 / pixels_per_unit;
        }
    }
}

/// Bodies (a furry creature's) under the strands.
fn draw_bodies(mut gizmos: Gizmos<StrandGizmos>, discs: Query<&Disc>) {
    for disc in &discs {
        gizmos
            .circle_2d(
                disc.centre.as_vec2(),
                disc.radius as f32,
                Color::srgb_u8(120, 105, 160),
            )
            .resolution(64);
    }
}

/// A ring around the particle under the cursor.
fn draw_hovered(
    mut gizmos: Gizmos<StrandGizmos>,
    tools: Option<Res<ToolState>>,
    cameras: Query<&Projection, With<Camera2d>>,
) {
    if let Some(hovered) = tools.and_then(|t| t.hovered_position) {
        let radius = 2.5 * units_per_pixel(&cameras);
        gizmos
            .circle_2d(
                hovered.as_vec2(),
                4.0 * radius,
                Color::srgb_u8(255, 255, 255),
            )
            .resolution(20);
    }
}
