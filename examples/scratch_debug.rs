use bevy_strands::prelude::*;
use bevy_strands::runner::*;
fn main() {
    let scene = load_scene(&RunOptions {
        scenario: "spaghetti_factory".into(),
        ..Default::default()
    })
    .unwrap();
    let mut app = headless_app(&scene).unwrap();
    app.world_mut().resource_mut::<StrandsConfig>().substeps = 1;
    let mut prev = (0u64, 0u64, 0u64, 0u64);
    for step in 0..90000u64 {
        if step == 4794 {
            unsafe { std::env::set_var("DBG", "28") }
        } else {
            unsafe { std::env::remove_var("DBG") }
        }
        let before: Vec<bevy::math::DVec2> =
            app.world().resource::<ParticleState>().velocity.clone();
        app.world_mut().run_schedule(StrandsTick);
        let s = app.world().resource::<ParticleState>();
        let m = app.world().resource::<StrandMetrics>();
        let (i, vmax) = s
            .velocity
            .iter()
            .enumerate()
            .filter(|(i, _)| s.inverse_mass[*i] > 0.0)
            .map(|(i, v)| (i, v.length()))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let now = (
            m.contact_projection.rejected,
            m.contact_unsettled_steps,
            m.failsafe_steps,
            m.collisions_last_step,
        );
        if vmax > 6.0 {
            let b = if i < before.len() {
                before[i].length()
            } else {
                0.0
            };
            println!(
                "step {step}: particle {i} speed {vmax:.3} (before {b:.3}) at {:?} contact {} rejected {} unsettled {} failsafe {} impulses {} err {:.2e}",
                s.position[i],
                s.in_contact[i],
                now.0 - prev.0,
                now.1 - prev.1,
                now.2 - prev.2,
                now.3,
                m.max_rel_length_error_now
            );
            break;
        }
        prev = now;
    }
}
