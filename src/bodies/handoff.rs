//! A body's state handed between the strands and its engine: the rigid fit of a
//! body's frame at the tick's end (pure: slices in, state out).
//!
//! A dynamic body with a frame is integrated by the strands through each tick — its
//! gravity, the strands' pull and contacts, all inside the exact projection — and its
//! pose and velocity at the tick's end are written to the engine, which steps it from
//! there. What the engine's own step did to it besides gravity (its contacts with other
//! bodies, joints, the game's forces and damping) comes back the next tick as an
//! acceleration on the frame. The body is integrated once, by one integrator; nothing
//! is exchanged a tick late, so the coupling adds no energy.

use bevy::math::{DVec2, Rot2, Vec2};
use bevy::prelude::Reflect;

/// A body's pose and velocity, as the strands hand it to the engine.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
pub struct BodyState {
    /// The body's origin in the world.
    pub position: Vec2,
    /// Its orientation.
    pub rotation: Rot2,
    /// The velocity of its centre of mass.
    pub linear: Vec2,
    /// Its angular velocity.
    pub angular: f32,
}

/// The rigid state of a frame: its particles' positions `x`, velocities `v` and masses
/// `m`; `hub` the index of the particle at the body's centre of mass (`centre` in the
/// body's frame); `reference` another particle and its point in the body's frame, which
/// fixes the rotation. `None` for a frame with no mass or a non-finite state.
pub fn frame_state(
    (x, v, m): (&[DVec2], &[DVec2], &[f64]),
    hub: usize,
    reference: (usize, Vec2),
    centre: Vec2,
) -> Option<BodyState> {
    let total: f64 = m.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let weighted = |values: &[DVec2]| -> DVec2 {
        values.iter().zip(m).map(|(&p, &w)| w * p).sum::<DVec2>() / total
    };
    let (x_cm, v_cm) = (weighted(x), weighted(v));
    let (mut momentum, mut inertia) = (0.0, 0.0);
    for ((&p, &u), &w) in x.iter().zip(v).zip(m) {
        let r = p - x_cm;
        momentum += w * r.perp_dot(u - v_cm);
        inertia += w * r.length_squared();
    }
    let angular = if inertia > 0.0 {
        momentum / inertia
    } else {
        0.0
    };
    let (k, offset) = reference;
    let now = x[k] - x[hub];
    let rest = (offset - centre).as_dvec2();
    let angle = now.y.atan2(now.x) - rest.y.atan2(rest.x);
    let rotation = Rot2::radians(angle as f32);
    let position = x[hub].as_vec2() - rotation * centre;
    let linear = v_cm + angular * (x[hub] - x_cm).perp();
    let state = BodyState {
        position,
        rotation,
        linear: linear.as_vec2(),
        angular: angular as f32,
    };
    (state.position.is_finite() && state.linear.is_finite() && state.angular.is_finite())
        .then_some(state)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turning_frame_gives_its_bodys_pose_and_velocity() {
        // A body at (1, 2) turned by 30°, centre of mass at (0.1, 0) in its frame,
        // moving at (0.5, −1) with ω = 2; its frame a hub and three vertices.
        let (origin, turn, centre) = (
            Vec2::new(1.0, 2.0),
            Rot2::degrees(30.0),
            Vec2::new(0.1, 0.0),
        );
        let (linear, omega) = (DVec2::new(0.5, -1.0), 2.0);
        let offsets = [
            centre,
            Vec2::new(0.5, 0.3),
            Vec2::new(-0.4, 0.2),
            Vec2::new(0.0, -0.6),
        ];
        let masses = [3.0, 0.5, 0.7, 0.9];
        let com = (origin + turn * centre).as_dvec2();
        let x: Vec<DVec2> = offsets
            .iter()
            .map(|&o| (origin + turn * o).as_dvec2())
            .collect();
        let v: Vec<DVec2> = x
            .iter()
            .map(|&p| linear + omega * (p - com).perp())
            .collect();
        let state = frame_state((&x, &v, &masses), 0, (2, offsets[2]), centre).unwrap();
        assert!((state.position - origin).length() < 1e-5, "{state:?}");
        assert!(
            (state.rotation.as_degrees() - 30.0).abs() < 1e-4,
            "{state:?}"
        );
        assert!(
            (state.linear.as_dvec2() - linear).length() < 1e-5,
            "{state:?}"
        );
        assert!((state.angular as f64 - omega).abs() < 1e-5, "{state:?}");
        assert!(frame_state((&x, &v, &[0.0; 4]), 0, (2, offsets[2]), centre).is_none());
    }
}
