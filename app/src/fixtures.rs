//! Set-up shared by the repository's tests and benchmarks: a headless app driven by
//! hand, ticks, the unit box, checked crossings, and the Collide stage run on its own.

use bevy::math::DVec2;
use bevy::prelude::*;
use bevy_strands::collision::plugin::{account_collisions, impulses, proximity};
use bevy_strands::contact::plugin::contact_loop;
use bevy_strands::prelude::*;

use crate::scenes::ScenesPlugin;
use crate::spawn::container_builder;

/// A headless app on `MinimalPlugins` with the simulation driven by hand.
pub fn app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, StrandsPlugin::manual(), ScenesPlugin));
    app.finish();
    app.cleanup();
    app
}

/// A headless app with the crossing check on.
pub fn checked_app() -> App {
    let mut app = app();
    check_crossings(&mut app);
    app
}

/// Turn the crossing check on, counting from now.
pub fn check_crossings(app: &mut App) {
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .check_crossings = true;
    app.world_mut()
        .resource_mut::<StrandMetrics>()
        .edge_crossings = Some(0);
}

/// Configure the step.
pub fn set_step(app: &mut App, dt: f64, substeps: u32) {
    let mut config = app.world_mut().resource_mut::<StrandsConfig>();
    config.dt = dt;
    config.substeps = substeps;
}

/// The height of a strand's lowest particle.
pub fn lowest_point(app: &App, strand: Entity) -> f64 {
    strand_particles(app, strand)
        .iter()
        .map(|&p| position(app, p).y)
        .fold(f64::INFINITY, f64::min)
}

/// Run one tick.
pub fn tick(app: &mut App) {
    app.world_mut().run_schedule(StrandsTick);
}

/// Run `n` ticks.
pub fn ticks(app: &mut App, n: usize) {
    for _ in 0..n {
        tick(app);
    }
}

/// The position of a particle entity.
pub fn position(app: &App, entity: Entity) -> DVec2 {
    app.world().get::<Position>(entity).expect("a particle").0
}

/// The velocity of a particle entity.
pub fn velocity(app: &App, entity: Entity) -> DVec2 {
    app.world().get::<Velocity>(entity).expect("a particle").0
}

/// How many times the speed a free fall from height `start` down to `height` allows
/// (under 9.81 m/s²) a body moving at `speed` goes: above one, something gave it
/// energy. The fall counts as at least 1 mm, so a body still at its start reads its
/// speed against that, not a division by zero.
pub fn speed_over_fall(speed: f64, start: f64, height: f64) -> f64 {
    speed / (2.0 * 9.81 * (start - height).max(1e-3)).sqrt()
}

/// The particles of a strand, in order.
pub fn strand_particles(app: &App, strand: Entity) -> Vec<Entity> {
    app.world()
        .get::<Strand>(strand)
        .expect("a strand")
        .particles
        .clone()
}

/// Positions and velocities of a strand's particles.
pub fn strand_state(app: &App, strand: Entity) -> Vec<(DVec2, DVec2)> {
    strand_particles(app, strand)
        .into_iter()
        .map(|p| (position(app, p), velocity(app, p)))
        .collect()
}

/// Step ends at which edges crossed, so far (the crossing check must be on).
pub fn crossings(app: &App) -> u64 {
    app.world()
        .resource::<StrandMetrics>()
        .edge_crossings
        .expect("the crossing check is on")
}

/// The unit box as a pinned closed loop.
pub fn spawn_box(app: &mut App) {
    spawn_container(app.world_mut(), DVec2::ZERO, DVec2::ONE);
}

/// The box from `min` to `max` as a pinned closed loop.
pub fn spawn_container(world: &mut World, min: DVec2, max: DVec2) {
    container_builder(min, max)
        .spawn_in(world)
        .expect("a box with positive sides");
}

/// Run the Collide stage alone, its sub-stages in the order of
/// [`CollideSet`](bevy_strands::schedule::CollideSet), on the packed state as it is.
pub fn run_collide_stage(world: &mut World) {
    world
        .run_system_cached(proximity)
        .expect("the proximity sub-stage runs");
    world
        .run_system_cached(impulses)
        .expect("the impulses sub-stage runs");
    world
        .run_system_cached(contact_loop)
        .expect("the contact loop runs");
    world
        .run_system_cached(account_collisions)
        .expect("the account sub-stage runs");
}

/// How a test reads and pushes the rigid bodies of one engine.
pub struct EngineBodies {
    /// Whether the engine has the body asleep.
    pub asleep: fn(&App, Entity) -> bool,
    /// Its speed.
    pub speed: fn(&App, Entity) -> f64,
    /// The height of its centre.
    pub height: fn(&App, Entity) -> f64,
    /// Set its velocity, as a user would.
    pub shove: fn(&mut App, Entity, Vec2),
    /// Spawn a dynamic square crate of this side (m) and density (kg/m²) at a point,
    /// colliding with strands.
    pub drop_crate: fn(&mut App, f32, f32, Vec2) -> Entity,
}

/// Whether every free particle of `strand` sleeps.
pub fn strand_asleep(app: &App, strand: Entity) -> bool {
    strand_particles(app, strand).iter().all(|&p| {
        let particle = app.world().entity(p);
        particle.contains::<Sleeping>() || particle.contains::<Pinned>()
    })
}

/// What the crates on a sleeping bridge did when woken, one way: ticks (of 60 a
/// second) until all slept again, the fastest crate after the wake, and whether the
/// other side woke.
#[derive(Clone, Copy, Debug)]
pub struct Woken {
    /// Ticks until the crates and the bridge all slept again.
    pub ticks: usize,
    /// The fastest crate at any tick after the wake (m/s).
    pub fastest: f64,
    /// The side not woken directly (the bridge after a shove, the crates after a
    /// strand's landing) woke.
    pub other_woke: bool,
}

/// Crates at rest on a rope bridge, all asleep (the crates in their engine, the
/// bridge in the strands), woken both ways in turn: a shove to the first crate
/// (0.3 m/s, the engine wakes it), then a short strand dropped on the bridge's end
/// (the strands wake). Asserts that everything sleeps at the start, that nothing
/// crosses and no crate falls under the bridge at any tick, that no crate goes faster
/// than the shove after it or than 5 cm/s after the landing (a woken crate must be
/// held up as it slept, not fall a tick of gravity), and that all sleep again within
/// 15 s of each wake; returns what each wake did.
pub fn wake_a_sleeping_bridge(
    app: &mut App,
    bridge: Entity,
    crates: &[Entity],
    engine: &EngineBodies,
) -> [Woken; 2] {
    let asleep =
        |app: &App| crates.iter().all(|&c| (engine.asleep)(app, c)) && strand_asleep(app, bridge);
    assert!(
        asleep(app),
        "asleep at the start: crates {:?}, bridge {}",
        crates
            .iter()
            .map(|&c| (engine.asleep)(app, c))
            .collect::<Vec<_>>(),
        strand_asleep(app, bridge)
    );
    let mut woken = [Woken {
        ticks: 0,
        fastest: 0.0,
        other_woke: false,
    }; 2];
    for (way, woken) in woken.iter_mut().enumerate() {
        let shove = 0.3;
        if way == 0 {
            (engine.shove)(app, crates[0], Vec2::new(shove as f32, 0.0));
        } else {
            StrandBuilder::line(DVec2::new(0.34, 0.9), DVec2::X, 6, 0.01)
                .mass(0.002)
                .spawn_in(app.world_mut())
                .expect("a strand");
        }
        let mut slept = false;
        for k in 1..=900 {
            app.update();
            assert_eq!(crossings(app), 0, "way {way}, tick {k}");
            let lowest = lowest_point(app, bridge);
            for &c in crates {
                let speed = (engine.speed)(app, c);
                assert!(speed.is_finite(), "way {way}, tick {k}: a crate at {speed}");
                woken.fastest = woken.fastest.max(speed);
                let height = (engine.height)(app, c);
                assert!(
                    height > lowest,
                    "way {way}, tick {k}: a crate under the bridge"
                );
            }
            woken.other_woke |= if way == 0 {
                !strand_asleep(app, bridge)
            } else {
                crates.iter().all(|&c| !(engine.asleep)(app, c))
            };
            if woken.other_woke && asleep(app) {
                woken.ticks = k;
                slept = true;
                break;
            }
        }
        assert!(
            slept,
            "way {way}: not asleep again 15 s after the wake: {woken:?}"
        );
        let fastest = if way == 0 { shove * 1.01 } else { 0.05 };
        assert!(
            woken.fastest <= fastest,
            "way {way}: a crate went faster than {fastest} m/s: {woken:?}"
        );
    }
    woken
}

/// A rope bridge left to sleep, then a crate dropped 30 cm onto it: its outline's fall
/// wakes the bridge before they meet (a sleeping strand is a wall to what drives into
/// it), so the crate lands on the bridge and never goes through it or crosses it, goes
/// no faster than its fall allows, every edge stays exact, and then the crate and the
/// bridge sleep together. Returns the seconds from the drop until both sleep.
pub fn crate_onto_a_sleeping_bridge(app: &mut App, engine: &EngineBodies) -> f64 {
    let bridge = StrandBuilder::hanging(DVec2::new(0.3, 0.72), DVec2::new(1.1, 0.72), 40, 1.08)
        .mass(0.02)
        .material(StrandMaterial::INERT)
        .spawn_in(app.world_mut())
        .expect("a bridge");
    let mut ticks = 0;
    while !strand_asleep(app, bridge) {
        app.update();
        ticks += 1;
        assert!(ticks < 600, "the bridge alone did not sleep in 10 s");
    }
    let start = lowest_point(app, bridge) + 0.35;
    let crate_ = (engine.drop_crate)(app, 0.1, 40.0, Vec2::new(0.7, start as f32));
    for k in 1..=900 {
        app.update();
        assert_eq!(crossings(app), 0, "tick {k} after the drop");
        let height = (engine.height)(app, crate_);
        assert!(
            height > lowest_point(app, bridge),
            "tick {k} after the drop: the crate at {height} is under the bridge"
        );
        let speed = (engine.speed)(app, crate_);
        let ratio = speed_over_fall(speed, start, height);
        assert!(
            ratio <= 1.01,
            "tick {k} after the drop: the crate went {ratio} times as fast as its fall allows"
        );
        if (engine.asleep)(app, crate_) && strand_asleep(app, bridge) {
            let error = app.world().resource::<StrandMetrics>().max_rel_length_error;
            assert!(error < 1e-9, "the bridge stretched by {error:e}");
            return k as f64 / 60.0;
        }
    }
    panic!("the crate and the bridge not asleep 15 s after the drop");
}
