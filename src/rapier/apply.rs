//! Applying what the sweeps found: the hit bodies go to their cut poses
//! (velocities kept, or a pusher's), each clamp is reported, and the
//! sensors crossed before each body's stop get their events.

use super::clamp;
use super::report::{CcdHitEvent, CcdReport, SkipReason};
use super::rounds::Plan;
use super::sweep::{self, SensorPair};
use crate::convert::{glam_from_vec, pose_from_iso};
use crate::hashing::FastMap;
use crate::motion::Trajectory;
use crate::query::QueryOptions;
use rapier3d::parry::query::{DefaultQueryDispatcher, QueryDispatcher};
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::{
    ColliderSet, CollisionEvent, CollisionEventFlags, EventHandler, RigidBodySet, Vector,
};

/// A clamp that keeps at most this share of the body's motion holds it
/// where it started.
const HELD: f64 = 1.0e-3;

/// Clamps the hit bodies, then reports the sensors crossed before each
/// body's stop.
pub(crate) fn apply(
    plan: &Plan,
    bodies: &mut RigidBodySet,
    colliders: &mut ColliderSet,
    dt: f64,
    opts: &QueryOptions,
    events: &dyn EventHandler,
    report: &mut CcdReport,
) {
    let mut stops = FastMap::default();
    for (i, hit) in &plan.hits {
        let body = &plan.moved[*i];
        clamp::clamp(bodies, body);
        if let (Some(v), Some(rb)) = (plan.velocity[*i], bodies.get_mut(body.handle)) {
            rb.set_linvel(v, true);
        } else if plan.held[*i]
            && plan.scale[*i] <= HELD
            && let Some(rb) = bodies.get_mut(body.handle)
        {
            // Held where it started by a pair touching at the start: its
            // velocity would only drive it into the same hold next step
            // while gravity and the solver pile more on. It stops; the next
            // step's contacts go on from rest.
            rb.set_linvel(Vector::ZERO, true);
            rb.set_angvel(Vector::ZERO, true);
        }
        let fraction = plan.scale[*i];
        stops.insert(body.handle, fraction);
        report.hits.push(CcdHitEvent {
            body: body.handle,
            collider1: hit.collider1,
            collider2: hit.collider2,
            fraction,
            time: fraction * dt,
            point: glam_from_vec(&hit.toi.witness1.coords),
            normal: glam_from_vec(&hit.toi.normal1),
        });
    }
    if !plan.hits.is_empty() {
        clamp::sync_colliders(bodies, colliders);
    }
    for pair in &plan.sensors {
        let Some(body) = colliders[pair.collider1].parent() else {
            continue;
        };
        let until = stops.get(&body).copied().unwrap_or(1.0);
        let (s1, s2) = (
            colliders[pair.collider1].shape(),
            colliders[pair.collider2].shape(),
        );
        match sweep::first_crossing(s1, pair, s2, until, opts, report) {
            Ok(Some(_)) if !touches_at(s1, pair, s2, until) => {
                report.sensor_crossings += 1;
                for event in [CollisionEvent::Started, CollisionEvent::Stopped] {
                    let e = event(pair.collider1, pair.collider2, CollisionEventFlags::SENSOR);
                    events.handle_collision_event(bodies, colliders, e, None);
                }
            }
            Ok(_) => {}
            Err(e) => report.skip(body, SkipReason::Query(e.to_string())),
        }
    }
}

/// True when the pair overlaps with the body at `until` and the target at
/// its end: rapier's narrow phase then reports it itself.
fn touches_at(s1: &dyn Shape, pair: &SensorPair, s2: &dyn Shape, until: f64) -> bool {
    let p1 = pose_from_iso(&pair.motion1.pose_at(until));
    let p2 = pose_from_iso(&pair.motion2.pose_at(1.0));
    DefaultQueryDispatcher
        .intersection_test(&p1.inv_mul(&p2), s1, s2)
        .is_ok_and(|i| i.intersecting)
}
