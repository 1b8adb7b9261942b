//! Drawing with gizmos: edges as lines in the assignment's colours (or coloured by
//! their relative length error), particles as dots, pinned particles red, the particle
//! under the cursor highlighted; and a camera that keeps the scene in view beside the
//! panel.

use bevy::camera::ScalingMode;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

use super::tools::ToolState;
use super::ui::UiLayout;
use super::{ActiveScene, spawn_active_scene};
use crate::export::Disc;
use crate::export::raster::kind_color;
use crate::metrics::StrandMetrics;
use crate::state::ParticleState;
use crate::strand::StrandKind;
use crate::topology::Topology;

/// What the drawing shows.
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct DrawSettings {
    /// Colour edges by their relative length error instead of their kind.
    pub color_by_error: bool,
    /// Draw a dot for every particle (pinned ones are always drawn)...
    pub particles: bool,
    /// ...unless there are more than this many, when the dots would hide the strands.
    pub max_particle_dots: usize,
}

impl Default for DrawSettings {
    fn default() -> Self {
        Self {
            color_by_error: false,
            particles: true,
            max_particle_dots: 1500,
        }
    }
}

/// The camera, the gizmo drawing and its settings.
pub struct StrandsRenderPlugin;

impl Plugin for StrandsRenderPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<DrawSettings>()
            .init_resource::<UiLayout>()
            .register_type::<DrawSettings>()
            .add_systems(
                Startup,
                (spawn_camera, configure_gizmos, spawn_active_scene),
            )
            .add_systems(Update, (fit_camera, draw_strands));
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

fn configure_gizmos(mut store: ResMut<GizmoConfigStore>) {
    let (config, _) = store.config_mut::<DefaultGizmoConfigGroup>();
    config.line.width = 2.0;
}

/// Fit the scene's view rectangle into the window left of the panel.
fn fit_camera(
    windows: Query<&Window, With<PrimaryWindow>>,
    active: Option<Res<ActiveScene>>,
    layout: Res<UiLayout>,
    mut cameras: Query<(&mut Transform, &mut Projection), With<Camera2d>>,
) {
    let (Ok(window), Some(active)) = (windows.single(), active) else {
        return;
    };
    let view = active.scene.view();
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

/// A colour from blue (1e-16) through green and yellow to red (1e-2) for a relative
/// length error.
pub fn error_color(error: f64) -> Color {
    let t = ((error.max(1e-16).log10() + 16.0) / 14.0).clamp(0.0, 1.0) as f32;
    Color::hsl(240.0 * (1.0 - t), 0.9, 0.55)
}

fn to_vec2(p: DVec2) -> Vec2 {
    p.as_vec2()
}

#[allow(clippy::too_many_arguments)]
fn draw_strands(
    mut gizmos: Gizmos,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    metrics: Res<StrandMetrics>,
    settings: Res<DrawSettings>,
    tools: Option<Res<ToolState>>,
    discs: Query<&Disc>,
    cameras: Query<&Projection, With<Camera2d>>,
) {
    if state.len() != topology.pinned.len() {
        return; // the packed state is being rebuilt
    }
    for disc in &discs {
        gizmos
            .circle_2d(
                to_vec2(disc.centre),
                disc.radius as f32,
                Color::srgb_u8(120, 105, 160),
            )
            .resolution(64);
    }
    for (k, edge) in topology.edges.iter().enumerate() {
        let (a, b) = (
            to_vec2(state.position[edge.a as usize]),
            to_vec2(state.position[edge.b as usize]),
        );
        let kind = topology.strands[edge.strand as usize].kind;
        let color = if settings.color_by_error && kind != StrandKind::Wall {
            error_color(metrics.relative_length_error.get(k).copied().unwrap_or(0.0))
        } else {
            let [r, g, b] = kind_color(kind);
            Color::srgb_u8(r, g, b)
        };
        gizmos.line_2d(a, b, color);
    }
    // Dots a few pixels across whatever the zoom.
    let units_per_pixel = match cameras.single() {
        Ok(Projection::Orthographic(ortho)) => ortho.scale,
        _ => 1.0 / 600.0,
    };
    let radius = 2.5 * units_per_pixel;
    let dots = settings.particles && state.len() <= settings.max_particle_dots;
    // Many pins (hair roots) are drawn small, so that they mark rather than cover.
    let pinned = topology.pinned.iter().filter(|&&p| p).count();
    let pin_radius = if pinned > 100 {
        0.6 * radius
    } else {
        1.6 * radius
    };
    for (i, &p) in state.position.iter().enumerate() {
        if topology.pinned[i] {
            gizmos
                .circle_2d(to_vec2(p), pin_radius, Color::srgb_u8(230, 60, 50))
                .resolution(10);
        } else if dots {
            gizmos
                .circle_2d(to_vec2(p), radius, Color::srgb_u8(230, 230, 230))
                .resolution(6);
        }
    }
    if let Some(hovered) = tools.and_then(|t| t.hovered_position) {
        gizmos
            .circle_2d(
                to_vec2(hovered),
                4.0 * radius,
                Color::srgb_u8(255, 255, 255),
            )
            .resolution(20);
    }
}
