//! The mouse tools' logic, driven headless: what each tool does to the world, and that
//! the simulation takes it up cleanly on the next tick.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::world::edit::*;
use bevy_strands_app::fixtures::*;

#[test]
fn creating_a_particle_puts_a_simulated_particle_at_the_point() {
    let mut app = app();
    let p = create_particle(app.world_mut(), DVec2::new(0.3, 0.6));
    assert_eq!(position(&app, p), DVec2::new(0.3, 0.6));
    tick(&mut app);
    assert!(position(&app, p).y < 0.6, "it falls");
    assert_eq!(app.world().resource::<StrandMetrics>().particles, 1);
}

#[test]
fn an_edge_joins_the_two_particles_nearest_the_cursor() {
    let mut app = app();
    let a = create_particle(app.world_mut(), DVec2::new(0.40, 0.5));
    let b = create_particle(app.world_mut(), DVec2::new(0.45, 0.5));
    let far = create_particle(app.world_mut(), DVec2::new(0.9, 0.9));
    let strand = create_edge_near(app.world_mut(), DVec2::new(0.42, 0.51), 0.1).unwrap();
    let s = app.world().get::<Strand>(strand).unwrap();
    assert_eq!(s.particles.len(), 2);
    assert!(s.particles.contains(&a) && s.particles.contains(&b) && !s.particles.contains(&far));
    assert!((s.rest_lengths[0] - 0.05).abs() < 1e-12);
    // Joining them again is refused (a is nearer the cursor than b).
    assert_eq!(
        create_edge_near(app.world_mut(), DVec2::new(0.42, 0.51), 0.1),
        Err(ToolError::AlreadyJoined(a, b))
    );
    // Too few particles near the cursor.
    assert!(matches!(
        create_edge_near(app.world_mut(), DVec2::new(0.9, 0.9), 0.01),
        Err(ToolError::TooFewParticles {
            needed: 2,
            found: 1
        })
    ));
    ticks(&mut app, 20);
    let metrics = app.world().resource::<StrandMetrics>();
    assert_eq!(metrics.constrained_edges, 1);
    assert!(metrics.max_rel_length_error < 1e-12);
}

#[test]
fn a_drawn_hair_is_resampled_and_rooted() {
    let mut app = app();
    let stroke: Vec<DVec2> = (0..200)
        .map(|i| {
            let t = i as f64 / 199.0;
            DVec2::new(0.2 + 0.4 * t, 0.7 + 0.1 * (3.0 * t).sin())
        })
        .collect();
    let hair = draw_strand(app.world_mut(), &stroke, 0.02, true, StrandKind::Hair).unwrap();
    let particles = strand_particles(&app, hair);
    assert!(particles.len() > 15);
    for w in particles.windows(2) {
        let d = position(&app, w[0]).distance(position(&app, w[1]));
        assert!((d - 0.02).abs() < 1e-12);
    }
    assert!(app.world().get::<Pinned>(particles[0]).is_some());
    assert!(app.world().get::<Pinned>(particles[1]).is_none());
    ticks(&mut app, 30);
    assert_eq!(position(&app, particles[0]), stroke[0]);
    assert!(app.world().resource::<StrandMetrics>().max_rel_length_error < 1e-12);
    // A stroke shorter than the spacing makes nothing.
    assert!(draw_strand(app.world_mut(), &stroke[..2], 0.02, true, StrandKind::Hair).is_err());
}

#[test]
fn pins_toggle() {
    let mut app = app();
    let p = create_particle(app.world_mut(), DVec2::new(0.5, 0.5));
    assert_eq!(toggle_pin(app.world_mut(), p), Ok(true));
    ticks(&mut app, 5);
    assert_eq!(position(&app, p), DVec2::new(0.5, 0.5));
    assert_eq!(toggle_pin(app.world_mut(), p), Ok(false));
    ticks(&mut app, 5);
    assert!(position(&app, p).y < 0.5);
    let not_a_particle = app.world_mut().spawn_empty().id();
    assert_eq!(
        toggle_pin(app.world_mut(), not_a_particle),
        Err(ToolError::NotAParticle(not_a_particle))
    );
}

#[test]
fn deleting_a_particle_splits_its_strand_cleanly() {
    let mut app = app();
    let rope = StrandBuilder::line(DVec2::new(0.2, 0.6), DVec2::X, 9, 0.05)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap();
    let particles = strand_particles(&app, rope);
    ticks(&mut app, 3);
    delete_particle(app.world_mut(), particles[4]).unwrap();
    assert!(app.world().get_entity(particles[4]).is_err());
    let mut strands = app.world_mut().query::<&Strand>();
    let pieces: Vec<Vec<Entity>> = strands
        .iter(app.world())
        .map(|s| s.particles.clone())
        .collect();
    assert_eq!(pieces.len(), 2);
    assert!(pieces.contains(&particles[..4].to_vec()) && pieces.contains(&particles[5..].to_vec()));
    ticks(&mut app, 10);
    // Handled by the tool, not found broken by the simulation: no input problem.
    assert!(app.world().resource::<InputProblems>().entries.is_empty());
    let metrics = app.world().resource::<StrandMetrics>();
    assert_eq!(
        (metrics.particles, metrics.strands, metrics.edges),
        (8, 2, 6)
    );
    assert!(metrics.max_rel_length_error < 1e-12);

    // Deleting from a two-particle strand leaves the other particle free.
    let pair = StrandBuilder::line(DVec2::new(0.5, 0.3), DVec2::X, 2, 0.05)
        .spawn_in(app.world_mut())
        .unwrap();
    let [a, b] = strand_particles(&app, pair)[..] else {
        unreachable!()
    };
    delete_particle(app.world_mut(), a).unwrap();
    assert!(app.world().get_entity(pair).is_err(), "the strand went");
    assert!(
        app.world().get_entity(b).is_ok(),
        "its other particle stays"
    );
    tick(&mut app);
    assert!(app.world().resource::<InputProblems>().entries.is_empty());
}

#[test]
fn a_tether_drags_a_particle_towards_the_cursor() {
    let mut app = app();
    app.world_mut().resource_mut::<StrandsConfig>().gravity = DVec2::ZERO;
    let rope = StrandBuilder::line(DVec2::new(0.3, 0.5), DVec2::X, 10, 0.02)
        .spawn_in(app.world_mut())
        .unwrap();
    let end = *strand_particles(&app, rope).last().unwrap();
    let target = DVec2::new(0.6, 0.8);
    app.world_mut().entity_mut(end).insert(Tether {
        target,
        // About critically damped for the 10-particle rope it drags: 2 √(k M) ≈ 89.
        stiffness: 200.0,
        damping: 90.0,
    });
    ticks(&mut app, 400);
    // From 0.42 away to near the target (the undamped rope behind still swings).
    assert!(
        position(&app, end).distance(target) < 0.02,
        "{}",
        position(&app, end)
    );
    assert!(app.world().resource::<StrandMetrics>().max_rel_length_error < 1e-12);
}

#[test]
fn cutting_an_edge_splits_an_open_strand_and_opens_a_loop() {
    let mut app = app();
    let rope = StrandBuilder::line(DVec2::new(0.2, 0.8), DVec2::X, 10, 0.03)
        .spawn_in(app.world_mut())
        .unwrap();
    let ring = StrandBuilder::closed_loop((0..8).map(|k| {
        DVec2::new(0.5, 0.4) + 0.1 * DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_4)
    }))
    .spawn_in(app.world_mut())
    .unwrap();
    tick(&mut app);
    let before = strand_particles(&app, rope);
    assert_eq!(cut_edge(app.world_mut(), rope, 3), Ok(2));
    assert_eq!(strand_particles(&app, rope), before[..4].to_vec());
    assert_eq!(cut_edge(app.world_mut(), ring, 5), Ok(1));
    let ring_strand = app.world().get::<Strand>(ring).unwrap().clone();
    assert!(!ring_strand.closed && ring_strand.particles.len() == 8);
    assert_eq!(
        cut_edge(app.world_mut(), rope, 7),
        Err(bevy_strands::world::edit::ToolError::NoSuchEdge(rope, 7))
    );
    // The last edge of the first piece leaves a lone particle: it goes loose.
    assert_eq!(cut_edge(app.world_mut(), rope, 2), Ok(1));
    assert!(app.world().get::<StrandOf>(before[3]).is_none());
    ticks(&mut app, 20);
    let topology = app.world().resource::<Topology>();
    assert_eq!(topology.strands.len(), 3);
    let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
    assert!(error < 1e-9, "{error:e}");
}

#[test]
fn a_ray_meets_the_first_strand_in_its_way() {
    let mut app = app();
    let near = StrandBuilder::line(DVec2::new(0.4, 0.2), DVec2::Y, 10, 0.05)
        .spawn_in(app.world_mut())
        .unwrap();
    StrandBuilder::line(DVec2::new(0.7, 0.2), DVec2::Y, 10, 0.05)
        .spawn_in(app.world_mut())
        .unwrap();
    tick(&mut app);
    let hit = ray_cast_strands(app.world(), DVec2::new(0.1, 0.33), DVec2::X, 2.0).unwrap();
    assert_eq!(hit.strand, near);
    assert_eq!(hit.edge, 2);
    let x = position(&app, hit.particles[0]).x;
    assert!((hit.hit.point.x - x).abs() < 1e-12 && (hit.hit.distance - (x - 0.1)).abs() < 1e-12);
    assert!(ray_cast_strands(app.world(), DVec2::new(0.1, 0.33), -DVec2::X, 2.0).is_none());
    let nearest = nearest_strand_edge(app.world(), DVec2::new(0.45, 0.5), 0.1).unwrap();
    assert_eq!(nearest.strand, near);
    assert!(nearest_strand_edge(app.world(), DVec2::new(0.55, 0.5), 0.1).is_none());
}

#[test]
fn a_winch_reels_a_hanging_rope_in_and_pays_it_out_keeping_it_exact() {
    for speed in [-0.1, 0.1] {
        let mut app = app();
        let rope = StrandBuilder::line(DVec2::new(0.5, 0.9), -DVec2::Y, 21, 0.02)
            .pin_first()
            .spawn_in(app.world_mut())
            .unwrap();
        app.world_mut().entity_mut(rope).insert(Winch {
            speed,
            spacing: 0.02,
            min_length: 0.1,
            max_length: 0.8,
        });
        tick(&mut app);
        let length =
            |app: &App| bevy_strands::winch::rope_length(app.world().get::<Strand>(rope).unwrap());
        let start = length(&app);
        ticks(&mut app, 200);
        // 200 ticks of 6 × 1/600 s: 0.2 m in or out.
        assert!(
            (length(&app) - start - 2.0 * speed).abs() < 1e-9,
            "{} from {start}",
            length(&app)
        );
        let particles = strand_particles(&app, rope).len();
        // One particle per 0.02 m: ten more or ten fewer.
        assert_eq!(particles as i64, 21 + (speed / 0.01).round() as i64);
        let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
        assert!(error < 1e-9, "{speed}: {error:e}");
        // The rope hangs from its pin: its lowest particle is about a length below.
        let tip = position(&app, *strand_particles(&app, rope).last().unwrap());
        assert!(
            (0.9 - tip.y - length(&app)).abs() < 0.05,
            "{tip} for {}",
            length(&app)
        );
    }
}
