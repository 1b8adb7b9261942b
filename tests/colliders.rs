//! Colliders that are not strands: strands land on them, are pushed by them when they
//! move, and never pass through them.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands_app::fixtures::*;

/// A headless app with transform propagation (colliders follow `GlobalTransform`) and
/// the crossing check at every step.
fn app_with_transforms() -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        bevy::transform::TransformPlugin,
        StrandsPlugin::manual(),
    ));
    check_crossings(&mut app);
    set_step(&mut app, 1.0 / 600.0, 10);
    app
}

fn particles(app: &App, strand: Entity) -> Vec<DVec2> {
    strand_particles(app, strand)
        .iter()
        .map(|&p| position(app, p))
        .collect()
}

#[test]
fn a_rope_drapes_over_a_circle_and_never_enters_it() {
    let mut app = app_with_transforms();
    let centre = DVec2::new(0.5, 0.4);
    let radius = 0.1;
    app.world_mut().spawn((
        Transform::from_translation(centre.as_vec2().extend(0.0)),
        StrandCollider::new(ColliderShape::Circle {
            radius: radius as f32,
        }),
    ));
    let rope = StrandBuilder::line(DVec2::new(0.25, 0.6), DVec2::X, 26, 0.02)
        .spawn_in(app.world_mut())
        .unwrap();
    let mut closest = f64::MAX;
    for _ in 0..60 {
        app.update();
        tick(&mut app);
        for p in particles(&app, rope) {
            closest = closest.min(p.distance(centre));
        }
    }
    // Landed on it (within a few thicknesses), never inside.
    assert!(
        closest > radius,
        "{closest} inside the circle of radius {radius}"
    );
    assert!(
        closest < radius + 0.02,
        "never reached the circle: {closest}"
    );
    // Draped: the ends hang below the top of the circle.
    let ends = particles(&app, rope);
    assert!(ends[0].y < centre.y && ends[25].y < centre.y, "{ends:?}");
    assert_eq!(crossings(&app), 0);
    let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error < 1e-9, "{error:e}");
}

#[test]
fn a_moving_box_pushes_a_hanging_rope_aside_without_passing_through_it() {
    let mut app = app_with_transforms();
    let rope = StrandBuilder::line(DVec2::new(0.5, 0.9), -DVec2::Y, 21, 0.02)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap();
    let paddle = app
        .world_mut()
        .spawn((
            Transform::from_xyz(0.3, 0.65, 0.0),
            StrandCollider::new(ColliderShape::Box {
                half_size: Vec2::new(0.03, 0.1),
            }),
        ))
        .id();
    for k in 0..60 {
        // The paddle sweeps right at 0.6 m/s, through where the rope hangs.
        let x = 0.3 + 0.6 * k as f32 / 100.0;
        app.world_mut()
            .get_mut::<Transform>(paddle)
            .unwrap()
            .translation
            .x = x;
        app.update();
        tick(&mut app);
    }
    let paddle_x = app.world().get::<Transform>(paddle).unwrap().translation.x as f64;
    assert!(paddle_x > 0.6);
    // The rope's middle is ahead of the paddle's leading face: pushed, not passed.
    let rope_at = particles(&app, rope);
    let middle = rope_at[12];
    assert!(
        middle.x > paddle_x + 0.03,
        "{middle} behind the paddle at {paddle_x}"
    );
    assert_eq!(crossings(&app), 0);
    let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error < 1e-9, "{error:e}");

    // Removing the collider removes its outline.
    app.world_mut()
        .entity_mut(paddle)
        .remove::<StrandCollider>();
    tick(&mut app);
    let walls = app
        .world_mut()
        .query::<&StrandKind>()
        .iter(app.world())
        .filter(|k| **k == StrandKind::Wall)
        .count();
    assert_eq!(walls, 0);
}

#[test]
fn contact_messages_say_when_a_rope_lands_on_a_collider_and_leaves_it() {
    let mut app = app_with_transforms();
    let slab = app
        .world_mut()
        .spawn((
            Transform::from_xyz(0.5, 0.3, 0.0),
            StrandCollider::new(ColliderShape::Box {
                half_size: Vec2::new(0.3, 0.02),
            }),
        ))
        .id();
    let rope = StrandBuilder::line(DVec2::new(0.35, 0.4), DVec2::X, 11, 0.03)
        .spawn_in(app.world_mut())
        .unwrap();
    let mut seen = Vec::new();
    let read = |app: &mut App, seen: &mut Vec<StrandContact>| {
        let messages = app.world().resource::<Messages<StrandContact>>();
        seen.extend(messages.iter_current_update_messages().copied());
        app.world_mut()
            .resource_mut::<Messages<StrandContact>>()
            .update();
    };
    for _ in 0..40 {
        app.update();
        tick(&mut app);
        read(&mut app, &mut seen);
    }
    let pair = (rope.min(slab), rope.max(slab));
    eprintln!("SEEN {seen:?}");
    assert_eq!(
        seen.first(),
        Some(&StrandContact::Started(pair.0, pair.1)),
        "{seen:?}"
    );
    // Lifted well clear: the contact ends.
    for p in strand_particles(&app, rope) {
        let x = position(&app, p);
        app.world_mut()
            .entity_mut(p)
            .insert((Position(x + DVec2::new(0.0, 0.5)), Velocity(DVec2::ZERO)));
    }
    for _ in 0..3 {
        app.update();
        tick(&mut app);
        read(&mut app, &mut seen);
    }
    assert_eq!(
        seen.last(),
        Some(&StrandContact::Ended(pair.0, pair.1)),
        "{seen:?}"
    );
}

/// Colliders that overlap each other (a box half inside a circle) are not crossed
/// edges, and a rope dropped across both still lands on their outer outline.
#[test]
fn overlapping_colliders_are_not_crossings_and_still_hold_a_rope() {
    let mut app = app_with_transforms();
    let centre = DVec2::new(0.5, 0.4);
    app.world_mut().spawn((
        Transform::from_translation(centre.as_vec2().extend(0.0)),
        StrandCollider::new(ColliderShape::Circle { radius: 0.1 }),
    ));
    app.world_mut().spawn((
        Transform::from_xyz(0.6, 0.45, 0.0),
        StrandCollider::new(ColliderShape::Box {
            half_size: Vec2::new(0.08, 0.05),
        }),
    ));
    let rope = StrandBuilder::line(DVec2::new(0.3, 0.65), DVec2::X, 26, 0.02)
        .spawn_in(app.world_mut())
        .unwrap();
    for _ in 0..60 {
        app.update();
        tick(&mut app);
    }
    assert_eq!(crossings(&app), 0);
    // Resting on top: above the circle and the box.
    let lowest_over_both = particles(&app, rope)
        .into_iter()
        .filter(|p| (0.45..0.65).contains(&p.x))
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest_over_both > 0.49, "{lowest_over_both}");
    let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error < 1e-9, "{error:e}");
}
