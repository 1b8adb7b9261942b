//! Bodies and strands sleeping together.
//!
//! A crate resting on a rope bridge pushes on it every tick, and a push wakes a body
//! in either engine, so neither could sleep: the crate's outline moved, which kept
//! the bridge awake, and the bridge's push kept the crate awake. At a tick's end each
//! dynamic body is told how the strands it touches or holds stand:
//!
//! - all settled (each has rested the sleep time, or sleeps): its push is
//!   [`BodyPush::settled`], handed over without waking it, so its engine may put it
//!   to sleep by its own rule. Asleep, it holds still where its frame is, a wall to the
//!   strands (`coupling::follow_bodies`), and the bridge under it then sleeps too;
//! - one not settled, while its engine has it asleep: [`BodyPush::wake`], and its
//!   adapter wakes it. The other way round is the strands' own waking: a body its
//!   engine woke moves its outline, which wakes the strands within reach.
//!
//! With the strands' sleeping off nothing has settled, and no body sleeps on them.

use bevy::prelude::*;

use super::coupling::BodyCoupling;
use super::truss::BodyTruss;
use super::view::{BodyPush, BodyView};
use crate::contact_events::TouchingPairs;
use crate::sleeping::SleepState;
use crate::world::config::StrandsConfig;
use crate::world::particle::SolverIndex;
use crate::world::strand::{Strand, StrandKind};

/// Each dynamic body's [`BodyPush::settled`] and [`BodyPush::wake`] for this tick.
#[allow(clippy::too_many_arguments)]
pub(super) fn settle_bodies(
    config: Res<StrandsConfig>,
    coupling: Res<BodyCoupling>,
    touching: Res<TouchingPairs>,
    sleep: Option<Res<SleepState>>,
    strands: Query<(&Strand, Option<&StrandKind>)>,
    indices: Query<&SolverIndex>,
    trusses: Query<&BodyTruss>,
    mut bodies: Query<(Entity, &BodyView, &mut BodyPush)>,
) {
    let time = config.sleep.time;
    let sleep = sleep.filter(|_| config.sleep.enabled);
    // A particle's settledness; with sleeping off, none has.
    let particle = |entity: Entity| {
        let Some(sleep) = &sleep else {
            return false;
        };
        indices
            .get(entity)
            .ok()
            .and_then(|index| index.get())
            .is_none_or(|i| sleep.settled(i, time))
    };
    // Whether a strand (or a loose particle) that touches or holds a body has settled;
    // `None` for a wall: an outline (the body's own, or another collider's, which a
    // pair names by its collider) or a container.
    let other = |entity: Entity| match strands.get(entity) {
        Ok((_, Some(StrandKind::Wall))) => None,
        Ok((strand, _)) => Some(strand.particles.iter().all(|&p| particle(p))),
        Err(_) => indices.get(entity).is_ok().then(|| particle(entity)),
    };
    let own = coupling.own_strands();
    for (entity, view, mut push) in &mut bodies {
        if !view.is_dynamic() {
            continue;
        }
        let mut touches = false;
        let mut unsettled = false;
        // The ropes tied to it.
        let start = own.partition_point(|&(body, _)| body < entity);
        let tied = own[start..].iter().take_while(|(body, _)| *body == entity);
        for settled in tied.filter_map(|&(_, strand)| other(strand)) {
            touches = true;
            unsettled |= !settled;
        }
        // What touched its outline in this tick's steps.
        let mut radius = 0.0f32;
        if let Ok(truss) = trusses.get(entity) {
            radius = truss
                .offsets
                .iter()
                .map(|&o| (o - view.centre_of_mass).length())
                .fold(0.0, f32::max);
            let c = truss.collider;
            for &(a, b) in &touching.current {
                let found = if a == c {
                    b
                } else if b == c {
                    a
                } else {
                    continue;
                };
                // Another body's outline: their engine settles that between them.
                touches = true;
                unsettled |= !other(found).unwrap_or(true);
            }
        }
        // On strands, it settles slower than the body speed; touching nothing, what
        // it is pushed with is round-off, and its engine alone decides.
        let speed = view.linear.length() + view.angular.abs() * radius;
        let slow = (speed as f64) < config.sleep.body_speed;
        let settled = !unsettled && (slow || !touches);
        let wake = view.sleeping && unsettled;
        if push.settled != settled || push.wake != wake {
            push.settled = settled;
            push.wake = wake;
        }
    }
}
