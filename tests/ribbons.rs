//! Ribbon meshes (the `ribbons` feature): one mesh per strand, following its particles,
//! refilled in place.
#![cfg(feature = "ribbons")]

use bevy::asset::AssetPlugin;
use bevy::math::DVec2;
use bevy::mesh::{Mesh, Mesh2d, VertexAttributeValues};
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::ribbon::{StrandRibbon, StrandRibbonPlugin};

fn positions(app: &App, strand: Entity) -> (Vec<[f32; 3]>, *const [f32; 3]) {
    let handle = &app.world().get::<Mesh2d>(strand).expect("a ribbon mesh").0;
    let mesh = app.world().resource::<Assets<Mesh>>().get(handle).unwrap();
    match mesh.attribute(Mesh::ATTRIBUTE_POSITION) {
        Some(VertexAttributeValues::Float32x3(v)) => (v.clone(), v.as_ptr()),
        other => panic!("positions: {other:?}"),
    }
}

#[test]
fn a_ribbon_follows_its_strand_without_reallocating() {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin::default(),
        StrandsPlugin::manual(),
        StrandRibbonPlugin,
    ));
    app.init_asset::<Mesh>();
    let strand = StrandBuilder::line(DVec2::new(0.2, 0.8), DVec2::X, 10, 0.03)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap();
    app.world_mut().entity_mut(strand).insert(StrandRibbon {
        width: 0.01,
        interpolate: false,
        ..default()
    });
    app.update();
    let (first, buffer) = positions(&app, strand);
    assert_eq!(first.len(), 20);
    // Either side of the first particle, half the width off.
    assert!((first[0][1] - 0.805).abs() < 1e-6 && (first[1][1] - 0.795).abs() < 1e-6);
    for _ in 0..5 {
        app.world_mut().run_schedule(StrandsTick);
        app.update();
    }
    let (later, later_buffer) = positions(&app, strand);
    assert_eq!(later_buffer, buffer, "the vertex buffer was reallocated");
    // The free end fell; the pinned one did not (the ribbon turns about it).
    let mid = |v: &[[f32; 3]], k: usize| {
        DVec2::new(
            0.5 * (v[2 * k][0] + v[2 * k + 1][0]) as f64,
            0.5 * (v[2 * k][1] + v[2 * k + 1][1]) as f64,
        )
    };
    assert!(mid(&later, 0).distance(DVec2::new(0.2, 0.8)) < 1e-6);
    assert!(later[19][1] < first[19][1] - 1e-3);
    let tip = app
        .world()
        .get::<Position>(
            *app.world()
                .get::<Strand>(strand)
                .unwrap()
                .particles
                .last()
                .unwrap(),
        )
        .unwrap()
        .0;
    assert!(mid(&later, 9).distance(tip) < 1e-6);
}
