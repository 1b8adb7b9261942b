//! Ribbon meshes for strands: a strand with a [`StrandRibbon`] gets a `Mesh2d` that
//! follows its particles every frame, refilled in place (no allocation after the first
//! frame). Draw it with any 2D material on the same entity — `MeshMaterial2d` of a
//! `ColorMaterial` with a colour and a texture, for example; the texture repeats along
//! the length every [`StrandRibbon::repeat`].

use bevy::asset::RenderAssetUsages;
use bevy::math::DVec2;
use bevy::mesh::{Indices, Mesh, Mesh2d, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::transform::TransformSystems;

use super::geometry::{ribbon_indices, ribbon_positions, ribbon_uvs};
use crate::transforms::TickPositions;
use crate::world::particle::Position;
use crate::world::strand::Strand;

/// Draw this strand as a ribbon mesh.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct StrandRibbon {
    /// Width, in world units.
    pub width: f64,
    /// The length along the strand one copy of the texture covers.
    pub repeat: f64,
    /// Depth of the mesh's vertices (drawing order among 2D meshes).
    pub z: f32,
    /// Place the ribbon between the last two ticks, as [`crate::transforms`] does for
    /// transforms (its particles get [`TickPositions`]).
    pub interpolate: bool,
}

impl Default for StrandRibbon {
    fn default() -> Self {
        Self {
            width: 0.01,
            repeat: 0.05,
            z: 0.0,
            interpolate: true,
        }
    }
}

/// Builds and refreshes the ribbon meshes.
pub struct StrandRibbonPlugin;

impl Plugin for StrandRibbonPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<StrandRibbon>().add_systems(
            PostUpdate,
            (add_ribbon_meshes, update_ribbon_meshes)
                .chain()
                .before(TransformSystems::Propagate),
        );
    }
}

/// A new ribbon gets an empty mesh, and its particles their tick positions.
fn add_ribbon_meshes(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    new: Query<(Entity, &Strand, &StrandRibbon), Without<Mesh2d>>,
    ticks: Query<(), With<TickPositions>>,
) {
    for (entity, strand, ribbon) in &new {
        let mesh = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, Vec::<[f32; 3]>::new())
        .with_inserted_attribute(Mesh::ATTRIBUTE_UV_0, Vec::<[f32; 2]>::new())
        .with_inserted_indices(Indices::U32(Vec::new()));
        commands.entity(entity).insert(Mesh2d(meshes.add(mesh)));
        if ribbon.interpolate {
            for &p in &strand.particles {
                if !ticks.contains(p) {
                    commands.entity(p).try_insert(TickPositions::default());
                }
            }
        }
    }
}

/// Every frame: each ribbon's vertices where its particles are (between ticks if it
/// interpolates).
fn update_ribbon_meshes(
    fixed: Option<Res<Time<Fixed>>>,
    mut meshes: ResMut<Assets<Mesh>>,
    ribbons: Query<(&Strand, &StrandRibbon, &Mesh2d)>,
    particles: Query<(&Position, Option<&TickPositions>)>,
    mut points: Local<Vec<DVec2>>,
) {
    let overstep = fixed.map_or(1.0, |t| t.overstep_fraction_f64());
    for (strand, ribbon, mesh) in &ribbons {
        points.clear();
        points.extend(strand.particles.iter().filter_map(|&p| {
            let (position, ticks) = particles.get(p).ok()?;
            Some(match ticks {
                Some(t) if ribbon.interpolate && t.is_recorded() => t.at(overstep),
                _ => position.0,
            })
        }));
        let Some(mut mesh) = meshes.get_mut(&mesh.0) else {
            continue;
        };
        if let Ok(VertexAttributeValues::Float32x3(out)) =
            mesh.try_attribute_mut(Mesh::ATTRIBUTE_POSITION)
        {
            ribbon_positions(&points, strand.closed, ribbon.width, ribbon.z, out);
        }
        if let Ok(VertexAttributeValues::Float32x2(out)) =
            mesh.try_attribute_mut(Mesh::ATTRIBUTE_UV_0)
        {
            ribbon_uvs(&points, strand.closed, ribbon.repeat, out);
        }
        if let Some(Indices::U32(out)) = mesh.indices_mut() {
            ribbon_indices(points.len(), strand.closed, out);
        }
    }
}
