//! Mouse tools: the cursor's world position and the particle under it, and each tool's
//! gesture turned into the library's editing operations
//! ([`bevy_strands::world::edit`]).

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

use bevy_strands::prelude::*;
use bevy_strands::world::edit::{
    ToolError, create_edge_near, create_particle, delete_particle, draw_strand, toggle_pin,
};

use super::layout::UiLayout;

/// The mouse tools.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tool {
    /// Drag a particle: a spring to the cursor while running, moved directly while paused.
    #[default]
    Drag,
    /// Click to create a particle.
    Particle,
    /// Click between two particles to join them with an edge.
    Edge,
    /// Draw a hair: a strand along the stroke, rooted where it starts.
    Hair,
    /// Click a particle to pin or unpin it.
    Pin,
    /// Click a particle to delete it (its strand is split).
    Delete,
}

impl Tool {
    /// Every tool, in the panel's order.
    pub const ALL: [Tool; 6] = [
        Tool::Drag,
        Tool::Particle,
        Tool::Edge,
        Tool::Hair,
        Tool::Pin,
        Tool::Delete,
    ];

    /// Name in the panel.
    pub fn label(self) -> &'static str {
        match self {
            Tool::Drag => "drag",
            Tool::Particle => "particle",
            Tool::Edge => "edge",
            Tool::Hair => "hair",
            Tool::Pin => "pin",
            Tool::Delete => "delete",
        }
    }
}

/// The tools' state.
#[derive(Resource, Debug)]
pub struct ToolState {
    /// The selected tool.
    pub tool: Tool,
    /// The particle under the cursor, if any.
    pub hovered: Option<Entity>,
    /// Its position.
    pub hovered_position: Option<DVec2>,
    /// The cursor's world position, when it is over the window.
    pub cursor: Option<DVec2>,
    /// Spacing of drawn hairs.
    pub hair_spacing: f64,
    /// The last tool error, shown in the panel.
    pub message: Option<String>,
    dragging: Option<Entity>,
    stroke: Vec<DVec2>,
}

impl Default for ToolState {
    fn default() -> Self {
        Self {
            tool: Tool::Drag,
            hovered: None,
            hovered_position: None,
            cursor: None,
            hair_spacing: 0.015,
            message: None,
            dragging: None,
            stroke: Vec::new(),
        }
    }
}

impl ToolState {
    /// The particle a drag holds, if one is in progress.
    pub fn dragging(&self) -> Option<Entity> {
        self.dragging
    }
}

/// The cursor: in logical window pixels, in world coordinates, and the world length of
/// one pixel.
pub fn cursor_in_world(
    windows: &Query<&Window, With<PrimaryWindow>>,
    cameras: &Query<(&Camera, &GlobalTransform, &Projection), With<Camera2d>>,
) -> Option<(Vec2, DVec2, f64)> {
    let cursor = windows.single().ok()?.cursor_position()?;
    let (camera, transform, projection) = cameras.single().ok()?;
    let point = camera.viewport_to_world_2d(transform, cursor).ok()?;
    let units_per_pixel = match projection {
        Projection::Orthographic(ortho) => ortho.scale as f64,
        _ => 1e-3,
    };
    Some((cursor, point.as_dvec2(), units_per_pixel))
}

/// Report a tool's failure in the panel.
fn report(world: &mut World, result: Result<impl Sized, ToolError>) {
    if let Err(e) = result {
        world.resource_mut::<ToolState>().message = Some(e.to_string());
    }
}

/// Turn the mouse into editing operations.
#[allow(clippy::too_many_arguments)]
pub fn use_tools(
    mut commands: Commands,
    mut tools: ResMut<ToolState>,
    mouse: Res<ButtonInput<MouseButton>>,
    layout: Res<UiLayout>,
    config: Res<StrandsConfig>,
    state: Res<ParticleState>,
    windows: Query<&Window, With<PrimaryWindow>>,
    cameras: Query<(&Camera, &GlobalTransform, &Projection), With<Camera2d>>,
) {
    let Some((screen, cursor, pixel)) = cursor_in_world(&windows, &cameras) else {
        tools.hovered = None;
        tools.hovered_position = None;
        tools.cursor = None;
        return;
    };
    tools.cursor = Some(cursor);
    let pick = 12.0 * pixel;
    let nearest = state
        .position
        .iter()
        .enumerate()
        .map(|(i, p)| (p.distance(cursor), i))
        .filter(|(d, _)| *d <= pick)
        .min_by(|a, b| a.0.total_cmp(&b.0));
    tools.hovered = nearest.map(|(_, i)| state.entity[i]);
    tools.hovered_position = nearest.map(|(_, i)| state.position[i]);

    // A drag in progress follows the cursor even over the panel, and ends on release.
    if let Some(particle) = tools.dragging {
        if mouse.pressed(MouseButton::Left) {
            if config.paused {
                commands
                    .entity(particle)
                    .insert((Position(cursor), Velocity(DVec2::ZERO)));
            } else {
                commands.entity(particle).insert(drag_spring(cursor));
            }
        } else {
            commands.entity(particle).remove::<Tether>();
            tools.dragging = None;
        }
        return;
    }
    if layout.owns_pointer(screen) {
        return;
    }
    let pressed = mouse.just_pressed(MouseButton::Left);
    match tools.tool {
        Tool::Drag => {
            if pressed && let Some(particle) = tools.hovered {
                tools.dragging = Some(particle);
                commands.entity(particle).insert(drag_spring(cursor));
            }
        }
        Tool::Particle if pressed => {
            commands.queue(move |world: &mut World| {
                create_particle(world, cursor);
            });
        }
        Tool::Edge if pressed => {
            commands.queue(move |world: &mut World| {
                let result = create_edge_near(world, cursor, 10.0 * pick);
                report(world, result);
            });
        }
        Tool::Hair => {
            if pressed {
                tools.stroke.clear();
                tools.stroke.push(cursor);
            } else if mouse.pressed(MouseButton::Left) && !tools.stroke.is_empty() {
                let last = *tools.stroke.last().expect("not empty");
                if last.distance(cursor) > 0.25 * tools.hair_spacing {
                    tools.stroke.push(cursor);
                }
            } else if mouse.just_released(MouseButton::Left) && !tools.stroke.is_empty() {
                let stroke = std::mem::take(&mut tools.stroke);
                let spacing = tools.hair_spacing;
                commands.queue(move |world: &mut World| {
                    let result = draw_strand(world, &stroke, spacing, true, StrandKind::Hair);
                    report(world, result);
                });
            }
        }
        Tool::Pin if pressed => {
            if let Some(particle) = tools.hovered {
                commands.queue(move |world: &mut World| {
                    let result = toggle_pin(world, particle);
                    report(world, result);
                });
            }
        }
        Tool::Delete if pressed => {
            if let Some(particle) = tools.hovered {
                commands.queue(move |world: &mut World| {
                    let result = delete_particle(world, particle);
                    report(world, result);
                });
            }
        }
        _ => {}
    }
}

/// The spring of a mouse drag: stiff enough to lift a few dozen unit-mass particles
/// against gravity, damped near critically for the particle it holds, and still well
/// inside explicit stability at the canonical step (ω dt ≈ 0.02).
fn drag_spring(target: DVec2) -> Tether {
    Tether {
        target,
        stiffness: 5000.0,
        damping: 100.0,
    }
}
