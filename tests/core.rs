//! The core: data model, step pipeline, forces and integration, headless on
//! `MinimalPlugins`.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::prelude::*;
use bevy_strands::snapshot::StrandsSnapshot;
use bevy_strands_app::fixtures::*;

fn spawn_particle(app: &mut App, x: DVec2, v: DVec2) -> Entity {
    app.world_mut()
        .spawn((Particle, Position(x), Velocity(v)))
        .id()
}

#[test]
fn free_fall_follows_symplectic_euler() {
    let mut app = app();
    let dt = 1.0 / 3000.0;
    set_step(&mut app, dt, 1);
    let (x0, v0) = (DVec2::new(0.2, 0.9), DVec2::new(0.3, 1.0));
    let p = spawn_particle(&mut app, x0, v0);
    let g = app.world().resource::<StrandsConfig>().gravity;
    for n in 1..=600u32 {
        tick(&mut app);
        let n = n as f64;
        // v_n = v0 + n g dt; x_n = x0 + dt Σ v_k = x0 + n dt v0 + n(n+1)/2 g dt².
        let v = v0 + n * dt * g;
        let x = x0 + n * dt * v0 + 0.5 * n * (n + 1.0) * dt * dt * g;
        assert!(velocity(&app, p).distance(v) < 1e-12, "step {n}");
        assert!(position(&app, p).distance(x) < 1e-12, "step {n}");
    }
}

#[test]
fn pinned_particle_stays_put_and_driven_one_moves_kinematically() {
    let mut app = app();
    let rope = StrandBuilder::line(DVec2::new(0.5, 0.9), DVec2::X, 10, 0.02)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap();
    let driven = app
        .world_mut()
        .spawn((
            Particle,
            Kinematic,
            Position(DVec2::ZERO),
            Velocity(DVec2::X),
        ))
        .id();
    // Pinned means fixed: a velocity given to a pinned particle moves nothing.
    let fixed = app
        .world_mut()
        .spawn((Particle, Pinned, Position(DVec2::Y), Velocity(DVec2::X)))
        .id();
    let anchor = strand_particles(&app, rope)[0];
    ticks(&mut app, 50);
    assert_eq!(position(&app, anchor), DVec2::new(0.5, 0.9));
    assert_eq!(velocity(&app, anchor), DVec2::ZERO);
    assert_eq!(position(&app, fixed), DVec2::Y);
    assert_eq!(velocity(&app, fixed), DVec2::ZERO);
    // 50 ticks of 1/100 s at unit speed, untouched by gravity.
    assert!((position(&app, driven) - DVec2::new(0.5, 0.0)).length() < 1e-12);
    // The free end swings.
    let tip = *strand_particles(&app, rope).last().unwrap();
    assert!(position(&app, tip).distance(DVec2::new(0.68, 0.9)) > 0.05);
}

#[test]
fn spring_pair_oscillates_with_the_expected_period() {
    let mut app = app();
    let dt = 1e-4;
    set_step(&mut app, dt, 1);
    app.world_mut().resource_mut::<StrandsConfig>().gravity = DVec2::ZERO;
    // A millimetre's swing, two seconds long: it would rest, and sleep.
    app.world_mut()
        .resource_mut::<StrandsConfig>()
        .sleep
        .enabled = false;
    app.world_mut().resource_mut::<ConstraintConfig>().solver = SolverKind::Springs;
    let (k, rest, m) = (50.0, 0.1, 0.5);
    let material = StrandMaterial {
        stretch_stiffness: k,
        stretch_damping: 0.0,
        bending_stiffness: 0.0,
        bending_damping: 0.0,
    };
    // Start stretched by 10 %.
    let pair = StrandBuilder::polyline([DVec2::ZERO, DVec2::new(1.1 * rest, 0.0)])
        .rest_lengths(vec![rest])
        .mass(m)
        .material(material)
        .spawn_in(app.world_mut())
        .unwrap();
    let [a, b] = strand_particles(&app, pair)[..] else {
        unreachable!()
    };
    // Linear stiffness k/L on the reduced mass m/2; symplectic Euler turns the phase
    // by θ per step with cos θ = 1 − (ω dt)²/2.
    let omega = ((k / rest) / (m / 2.0)).sqrt();
    let theta = (1.0 - (omega * dt).powi(2) / 2.0).acos();
    let expected = std::f64::consts::TAU / theta * dt;

    let mut crossings = Vec::new();
    let mut previous = 0.1 * rest;
    for step in 1..=20_000 {
        tick(&mut app);
        let stretch = position(&app, a).distance(position(&app, b)) - rest;
        if previous > 0.0 && stretch <= 0.0 {
            // Interpolate the downward zero crossing.
            crossings.push((step as f64 - stretch / (stretch - previous)) * dt);
        }
        previous = stretch;
    }
    assert!(crossings.len() >= 5, "too few periods: {crossings:?}");
    let periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    for period in periods {
        assert!(
            (period - expected).abs() < 2.0 * dt,
            "period {period} vs {expected}"
        );
    }
    // The momentum of the pair stays zero.
    let state = app.world().resource::<ParticleState>();
    assert!(state.linear_momentum().length() < 1e-12);
}

#[test]
fn damping_decays_kinetic_energy_geometrically() {
    let mut app = app();
    let dt = 1e-3;
    set_step(&mut app, dt, 1);
    let c = 2.0;
    {
        let mut config = app.world_mut().resource_mut::<StrandsConfig>();
        config.gravity = DVec2::ZERO;
        config.damping = c;
    }
    for i in 0..5 {
        let v = DVec2::new(i as f64 - 2.0, 1.0 + i as f64);
        spawn_particle(&mut app, DVec2::new(0.1 * i as f64, 0.5), v);
    }
    tick(&mut app);
    let mut energy = app.world().resource::<ParticleState>().kinetic_energy();
    for _ in 0..200 {
        tick(&mut app);
        let next = app.world().resource::<ParticleState>().kinetic_energy();
        // v ← (1 − c dt) v, so the energy shrinks by (1 − c dt)² each step.
        let expected = energy * (1.0 - c * dt).powi(2);
        assert!((next - expected).abs() <= 1e-12 * energy);
        energy = next;
    }
}

fn spawn_rope_scene(app: &mut App) -> Entity {
    StrandBuilder::line(DVec2::new(0.2, 0.8), DVec2::new(1.0, 0.3), 25, 0.02)
        .pin_first()
        .spawn_in(app.world_mut())
        .unwrap()
}

#[test]
fn substeps_equal_the_same_count_of_single_steps() {
    let mut grouped = app();
    let mut single = app();
    set_step(&mut grouped, 1.0 / 3000.0, 30);
    set_step(&mut single, 1.0 / 3000.0, 1);
    let a = spawn_rope_scene(&mut grouped);
    let b = spawn_rope_scene(&mut single);
    for _ in 0..10 {
        tick(&mut grouped);
        ticks(&mut single, 30);
    }
    assert_eq!(strand_state(&grouped, a), strand_state(&single, b));
    assert_eq!(
        grouped.world().resource::<SimulationClock>().steps,
        single.world().resource::<SimulationClock>().steps
    );
}

#[test]
fn spawning_and_despawning_strands_mid_run_keeps_other_state() {
    let mut changed = app();
    let mut reference = app();
    let kept = spawn_rope_scene(&mut changed);
    let kept_reference = spawn_rope_scene(&mut reference);
    let doomed = StrandBuilder::line(DVec2::new(0.6, 0.2), DVec2::X, 8, 0.03)
        .spawn_in(changed.world_mut())
        .unwrap();
    let doomed_particles = strand_particles(&changed, doomed);
    ticks(&mut changed, 5);
    ticks(&mut reference, 5);

    changed.world_mut().despawn(doomed);
    StrandBuilder::line(DVec2::new(0.1, 0.3), DVec2::Y, 12, 0.01)
        .spawn_in(changed.world_mut())
        .unwrap();
    for _ in 0..5 {
        tick(&mut changed);
        tick(&mut reference);
        assert_eq!(
            strand_state(&changed, kept),
            strand_state(&reference, kept_reference)
        );
    }
    // The despawned strand took its particles with it.
    for p in doomed_particles {
        assert!(changed.world().get_entity(p).is_err());
    }
    let metrics = changed.world().resource::<StrandMetrics>();
    assert_eq!(metrics.strands, 2);
    assert_eq!(metrics.particles, 25 + 12);
}

#[test]
fn a_particle_with_bad_mass_is_left_out_with_a_message() {
    let mut app = app();
    let bad = app
        .world_mut()
        .spawn((Particle, Position(DVec2::new(0.5, 0.5)), Mass(-1.0)))
        .id();
    let good = spawn_particle(&mut app, DVec2::new(0.3, 0.5), DVec2::ZERO);
    ticks(&mut app, 3);
    assert_eq!(position(&app, bad), DVec2::new(0.5, 0.5));
    assert!(position(&app, good).y < 0.5);
    let problems = app.world().resource::<InputProblems>();
    assert!(problems.concerns(bad));
    assert!(
        problems.entries[0].problem.contains("mass -1"),
        "{:?}",
        problems.entries
    );
}

#[test]
fn a_nan_written_between_ticks_is_refused_and_the_last_state_kept() {
    let mut app = app();
    let p = spawn_particle(&mut app, DVec2::new(0.5, 0.5), DVec2::ZERO);
    let twin = spawn_particle(&mut app, DVec2::new(0.7, 0.5), DVec2::ZERO);
    ticks(&mut app, 2);
    app.world_mut().get_mut::<Position>(p).unwrap().0.x = f64::NAN;
    ticks(&mut app, 2);
    // The packed state kept the last good position and stepped on from it, exactly as
    // its untouched twin did...
    assert_eq!(
        position(&app, p) + DVec2::new(0.2, 0.0),
        position(&app, twin)
    );
    assert_eq!(velocity(&app, p), velocity(&app, twin));
    // ...and the problem was reported; the next rebuild leaves the particle alone.
    let problems = app.world().resource::<InputProblems>();
    assert!(
        problems
            .entries
            .iter()
            .any(|e| e.entity == p && e.problem.contains("NaN"))
    );
}

#[test]
fn a_strand_referencing_a_despawned_particle_is_split_with_a_message() {
    let mut app = app();
    let rope = StrandBuilder::line(DVec2::new(0.1, 0.5), DVec2::X, 7, 0.05)
        .spawn_in(app.world_mut())
        .unwrap();
    let particles = strand_particles(&app, rope);
    tick(&mut app);
    app.world_mut().despawn(particles[3]);
    tick(&mut app);

    let mut strands = app.world_mut().query::<&Strand>();
    let pieces: Vec<Vec<Entity>> = strands
        .iter(app.world())
        .map(|s| s.particles.clone())
        .collect();
    assert_eq!(pieces.len(), 2);
    assert!(pieces.contains(&particles[0..3].to_vec()));
    assert!(pieces.contains(&particles[4..7].to_vec()));
    for strand in strands.iter(app.world()) {
        assert!(
            strand
                .particles
                .iter()
                .all(|&p| app.world().get_entity(p).is_ok())
        );
        assert_eq!(strand.rest_lengths.len(), 2);
    }
    let problems = app.world().resource::<InputProblems>();
    assert!(problems.entries.iter().any(|e| e.entity == rope
        && e.problem.contains("despawned")
        && e.problem.contains("split into 2")));
    assert_eq!(app.world().resource::<StrandMetrics>().edges, 4);
}

#[test]
fn an_invalid_strand_component_is_left_out_with_a_message() {
    let mut app = app();
    let a = spawn_particle(&mut app, DVec2::new(0.1, 0.5), DVec2::ZERO);
    let b = spawn_particle(&mut app, DVec2::new(0.2, 0.5), DVec2::ZERO);
    let one = app
        .world_mut()
        .spawn(Strand {
            particles: vec![a],
            rest_lengths: vec![],
            rest_angles: vec![],
            closed: false,
        })
        .id();
    let negative = app
        .world_mut()
        .spawn(Strand {
            particles: vec![a, b],
            rest_lengths: vec![-0.1],
            rest_angles: vec![],
            closed: false,
        })
        .id();
    tick(&mut app);
    let problems = app.world().resource::<InputProblems>();
    let message = |e: Entity| {
        problems
            .entries
            .iter()
            .find(|p| p.entity == e)
            .map(|p| p.problem.clone())
            .unwrap_or_default()
    };
    assert!(
        message(one).contains("needs at least 2"),
        "{}",
        message(one)
    );
    assert!(
        message(negative).contains("rest length of edge 0 must be positive and finite, got -0.1")
    );
    assert_eq!(app.world().resource::<StrandMetrics>().strands, 0);
}

#[test]
fn a_paused_app_keeps_its_state_and_shows_edits() {
    // Driven by FixedUpdate, as in a game.
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::default()));
    app.world_mut().resource_mut::<StrandsConfig>().paused = true;
    let p = spawn_particle(&mut app, DVec2::new(0.5, 0.5), DVec2::ZERO);
    // Run the fixed loop for a while of wall-clock time.
    let start = std::time::Instant::now();
    while start.elapsed() < std::time::Duration::from_millis(150) {
        app.update();
    }
    assert_eq!(position(&app, p), DVec2::new(0.5, 0.5));
    assert_eq!(app.world().resource::<SimulationClock>().steps, 0);
    // The paused ticks still synchronised: the new particle is in the packed state.
    let state = app.world().resource::<ParticleState>();
    assert_eq!(state.position, vec![DVec2::new(0.5, 0.5)]);
}

/// What a Prepare-phase system sees at the start of the next tick: how many edges the
/// topology has and where the first packed particle is.
#[derive(Resource, Default)]
struct SeenAtPrepare(Vec<(usize, Option<DVec2>)>);

fn record_prepare(
    topology: Res<Topology>,
    state: Res<ParticleState>,
    mut seen: ResMut<SeenAtPrepare>,
) {
    let first = state.position.first().copied();
    seen.0.push((topology.edges.len(), first));
}

fn recording_app() -> App {
    let mut app = app();
    app.init_resource::<SeenAtPrepare>()
        .add_systems(StrandsTick, record_prepare.in_set(TickSet::Prepare));
    app
}

#[test]
fn a_restored_world_is_synchronised_before_its_first_tick() {
    // Scene logic (an inlet checking whether it is blocked) runs before the topology
    // rebuild of its tick and reads what the last tick left: a restored world must
    // offer the same, or the restored run takes another course from its first tick.
    let mut app = recording_app();
    spawn_box(&mut app);
    StrandBuilder::line(DVec2::new(0.3, 0.6), DVec2::X, 12, 0.03)
        .spawn_in(app.world_mut())
        .unwrap();
    ticks(&mut app, 20);
    let (snapshot, _) = StrandsSnapshot::capture(app.world_mut());

    let mut restored = recording_app();
    snapshot.restore(restored.world_mut()).unwrap();
    for other in [&mut app, &mut restored] {
        ticks(other, 10);
    }
    let seen = |app: &App| app.world().resource::<SeenAtPrepare>().0.clone();
    assert_eq!(seen(&restored), seen(&app)[20..]);
    let positions = |app: &App| app.world().resource::<ParticleState>().position.clone();
    assert_eq!(positions(&restored), positions(&app));
}

#[test]
fn a_restored_world_keeps_its_contacts_warm() {
    // Strands lying on the floor and on each other: the next step starts every
    // contact from the impulse it held. A snapshot carries those impulses, by entity,
    // so the restored run goes on bit for bit (before, it started its contacts cold
    // and parted from the first step). Sleeping off: asleep, they would hold no rows.
    let awake = || {
        let mut app = app();
        app.world_mut()
            .resource_mut::<StrandsConfig>()
            .sleep
            .enabled = false;
        app
    };
    let mut app = awake();
    spawn_box(&mut app);
    for (k, y) in [0.006, 0.012].into_iter().enumerate() {
        StrandBuilder::line(DVec2::new(0.2 + 0.01 * k as f64, y), DVec2::X, 12, 0.03)
            .spawn_in(app.world_mut())
            .unwrap();
    }
    ticks(&mut app, 150);
    let (snapshot, _) = StrandsSnapshot::capture(app.world_mut());
    assert!(snapshot.contacts.len() >= 12, "{}", snapshot.contacts.len());

    let mut restored = awake();
    snapshot.restore(restored.world_mut()).unwrap();
    for other in [&mut app, &mut restored] {
        ticks(other, 60);
    }
    let state = |app: &App| {
        let state = app.world().resource::<ParticleState>();
        (state.position.clone(), state.velocity.clone())
    };
    assert!(state(&restored) == state(&app), "the restored run parted");

    // A warm start naming a particle the snapshot lacks is refused, nothing spawned.
    let mut broken = snapshot.clone();
    broken.contacts[0].point = broken.particles.len() as u32;
    let mut world = awake();
    assert!(broken.restore(world.world_mut()).is_err());
    let particles = world
        .world_mut()
        .query_filtered::<(), With<Particle>>()
        .iter(world.world())
        .count();
    assert_eq!(particles, 0);
    let mut broken = snapshot.clone();
    broken.contacts[0].normal = f64::NAN;
    assert!(broken.restore(awake().world_mut()).is_err());
}
