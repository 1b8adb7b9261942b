//! Debug drawing with gizmos (feature `render`): edges as lines in their kind's colour
//! (or coloured by their relative length error), particles as dots, pinned particles
//! red, sleeping strands dimmed. It draws into its own gizmo group, [`StrandGizmos`], so the app's global gizmo
//! settings stay as they were, and it spawns no camera: the app's 2D camera shows it.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_strands::prelude::*;
//! use bevy_strands::render::StrandsDebugDrawPlugin;
//!
//! App::new()
//!     .add_plugins(DefaultPlugins)
//!     .add_plugins((StrandsPlugin::default(), StrandsDebugDrawPlugin))
//!     .add_systems(Startup, |mut commands: Commands| {
//!         commands.spawn(Camera2d);
//!     })
//!     .run();
//! ```

use bevy::math::DVec2;
use bevy::prelude::*;

use crate::metrics::StrandMetrics;
use crate::sleeping::SleepState;
use crate::world::state::ParticleState;
use crate::world::strand::StrandKind;
use crate::world::topology::Topology;

/// What the debug drawing shows.
#[derive(Resource, Reflect, Clone, Debug, PartialEq)]
#[reflect(Resource)]
pub struct DrawSettings {
    /// Colour edges by their relative length error instead of their kind.
    pub color_by_error: bool,
    /// Draw a dot for every particle (pinned ones are always drawn)...
    pub particles: bool,
    /// ...unless there are more than this many, when the dots would hide the strands.
    pub max_particle_dots: usize,
    /// Draw sleeping strands dimmed, in a colour of their own.
    pub show_sleep: bool,
}

impl Default for DrawSettings {
    fn default() -> Self {
        Self {
            color_by_error: false,
            particles: true,
            max_particle_dots: 1500,
            show_sleep: true,
        }
    }
}

/// The gizmo group the strands are drawn in (lines 2 pixels wide by default).
#[derive(Default, Reflect, GizmoConfigGroup)]
pub struct StrandGizmos;

/// Gizmo drawing of every strand and particle, in [`Update`].
pub struct StrandsDebugDrawPlugin;

impl Plugin for StrandsDebugDrawPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<DrawSettings>()
            .register_type::<DrawSettings>()
            .insert_gizmo_config(
                StrandGizmos,
                GizmoConfig {
                    line: GizmoLineConfig {
                        width: 2.0,
                        ..default()
                    },
                    ..default()
                },
            )
            .add_systems(Update, draw_strands);
    }
}

/// Sleeping strands: a dim slate blue, whatever their kind.
pub const SLEEP_COLOR: Color = Color::srgb(0.32, 0.38, 0.52);

/// A colour from blue (1e-16) through green and yellow to red (1e-2) for a relative
/// length error.
pub fn error_color(error: f64) -> Color {
    let t = ((error.max(1e-16).log10() + 16.0) / 14.0).clamp(0.0, 1.0) as f32;
    Color::hsl(240.0 * (1.0 - t), 0.9, 0.55)
}

/// The on-screen length of a pixel in world units, from the 2D camera's projection.
pub fn units_per_pixel(cameras: &Query<&Projection, With<Camera2d>>) -> f32 {
    match cameras.single() {
        Ok(Projection::Orthographic(ortho)) => ortho.scale,
        _ => 1.0 / 600.0,
    }
}

fn to_vec2(p: DVec2) -> Vec2 {
    p.as_vec2()
}

/// Draw every edge and particle of the packed state.
pub fn draw_strands(
    mut gizmos: Gizmos<StrandGizmos>,
    state: Res<ParticleState>,
    topology: Res<Topology>,
    metrics: Res<StrandMetrics>,
    settings: Res<DrawSettings>,
    sleep: Option<Res<SleepState>>,
    cameras: Query<&Projection, With<Camera2d>>,
) {
    let asleep =
        |i: u32| settings.show_sleep && sleep.as_ref().is_some_and(|s| s.is_asleep(i as usize));
    if state.len() != topology.pinned.len() {
        return; // the packed state is being rebuilt
    }
    for (k, edge) in topology.edges.iter().enumerate() {
        let (a, b) = (
            to_vec2(state.position[edge.a as usize]),
            to_vec2(state.position[edge.b as usize]),
        );
        let kind = topology.strands[edge.strand as usize].kind;
        let color = if asleep(edge.a) {
            SLEEP_COLOR
        } else if settings.color_by_error && kind != StrandKind::Wall {
            error_color(metrics.relative_length_error.get(k).copied().unwrap_or(0.0))
        } else {
            let [r, g, b] = kind.color();
            Color::srgb_u8(r, g, b)
        };
        gizmos.line_2d(a, b, color);
    }
    // Dots a few pixels across whatever the zoom.
    let radius = 2.5 * units_per_pixel(&cameras);
    let dots = settings.particles && state.len() <= settings.max_particle_dots;
    // Many pins (hair roots) are drawn small, so that they mark rather than cover.
    let pinned = topology.pinned.iter().filter(|&&p| p).count();
    let pin_radius = if pinned > 100 {
        0.6 * radius
    } else {
        1.6 * radius
    };
    for (i, &p) in state.position.iter().enumerate() {
        if asleep(i as u32) {
            if dots {
                gizmos
                    .circle_2d(to_vec2(p), 0.6 * radius, SLEEP_COLOR)
                    .resolution(6);
            }
        } else if topology.pinned[i] {
            gizmos
                .circle_2d(to_vec2(p), pin_radius, Color::srgb_u8(230, 60, 50))
                .resolution(10);
        } else if dots {
            gizmos
                .circle_2d(to_vec2(p), radius, Color::srgb_u8(230, 230, 230))
                .resolution(6);
        }
    }
}
