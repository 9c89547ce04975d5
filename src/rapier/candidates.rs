//! What a fast collider may meet during the step: its swept box against the
//! broad phase, then rapier's own pair rules.
//!
//! The broad phase's leaves hold end-of-step boxes, so a target that moved
//! may have been elsewhere earlier in the step: the query box is enlarged
//! by the largest travel of any moved body, and each moving candidate is
//! then checked against its own swept box.

use super::config::CcdConfig;
use super::convert::{iso_from_pose, point_from_glam};
use super::select::Moved;
use crate::error::CcdError;
use crate::motion::Motion;
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::{
    ActiveEvents, ActiveHooks, BroadPhaseBvh, Collider, ColliderHandle, ColliderSet,
    ImpulseJointSet, PairFilterContext, PhysicsHooks, QueryFilter, RigidBodyHandle, RigidBodySet,
    RigidBodyType, SolverFlags,
};
use std::collections::HashMap;

/// The moved bodies of this step, by handle, and the step length.
pub(crate) struct Motions<'a> {
    pub moved: &'a [Moved],
    pub index: HashMap<RigidBodyHandle, usize>,
    pub dt: f64,
    /// Largest travel of any moved body, metres.
    pub margin: f64,
}

impl<'a> Motions<'a> {
    pub fn new(moved: &'a [Moved], dt: f64) -> Motions<'a> {
        Motions {
            moved,
            index: moved
                .iter()
                .enumerate()
                .map(|(i, m)| (m.handle, i))
                .collect(),
            dt,
            margin: moved.iter().map(|m| m.travel).fold(0.0, f64::max),
        }
    }

    pub fn body(&self, handle: RigidBodyHandle) -> Option<&Moved> {
        self.index.get(&handle).map(|i| &self.moved[*i])
    }

    /// A collider's motion over the step: its body's, or none.
    pub fn collider(&self, co: &Collider, bodies: &RigidBodySet) -> Result<Motion, CcdError> {
        let moved = co.parent().and_then(|h| self.body(h));
        match (
            moved,
            co.position_wrt_parent(),
            co.parent().and_then(|h| bodies.get(h)),
        ) {
            (Some(m), Some(local), Some(rb)) => {
                let motion = Motion::from_poses(
                    iso_from_pose(&(m.start * *local)),
                    iso_from_pose(&(m.end * *local)),
                    point_from_glam(local.inverse_transform_point(rb.local_center_of_mass())),
                    self.dt,
                    super::convert::vec_from_glam(m.angvel),
                )?;
                if m.accel == rapier3d::prelude::Vector::ZERO {
                    Ok(motion)
                } else {
                    motion.with_acceleration(super::convert::vec_from_glam(m.accel))
                }
            }
            _ => Motion::fixed(iso_from_pose(co.position())),
        }
    }
}

/// A box holding `shape` over the whole `motion`:
/// every point stays within the travel bound of both its start and its end.
pub(crate) fn swept_aabb(shape: &dyn Shape, motion: &Motion) -> Aabb {
    use crate::motion::Trajectory;
    // The motion's own end: a motion cut by a clamp (possibly to a
    // standstill) ends before the collider's pose.
    let end_box = shape.compute_aabb(&super::convert::pose_from_iso(&motion.pose_at(1.0)));
    if motion.is_fixed() {
        return end_box;
    }
    let start = super::convert::pose_from_iso(&motion.pose_at(0.0));
    let sphere = shape.compute_local_bounding_sphere();
    let radius = sphere.center.length() as f64 + sphere.radius as f64;
    let travel = motion.travel_bound(radius);
    // f32 boxes: round the margin up, plus rounding of the poses themselves.
    let margin = ((travel * (1.0 + 1.0e-5)) as f32).next_up() + 1.0e-5;
    if !margin.is_finite() {
        return Aabb::new(
            rapier3d::prelude::Vector::splat(f32::MIN),
            rapier3d::prelude::Vector::splat(f32::MAX),
        );
    }
    let a = shape.compute_aabb(&start).loosened(margin);
    let b = end_box.loosened(margin);
    a.intersection(&b).unwrap_or_else(|| a.merged(&b))
}

/// How a pair is handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PairKind {
    /// Contacts would push the shapes apart: a hit clamps.
    Solid,
    /// A sensor is involved: a crossing is reported, never clamped.
    Sensor,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub handle: ColliderHandle,
    pub kind: PairKind,
}

/// Everything the pair rules read.
pub(crate) struct Scene<'a> {
    pub bodies: &'a RigidBodySet,
    pub colliders: &'a ColliderSet,
    pub joints: &'a ImpulseJointSet,
    pub hooks: &'a dyn PhysicsHooks,
    pub config: &'a CcdConfig,
}

fn body_type(scene: &Scene, co: &Collider) -> RigidBodyType {
    co.parent()
        .and_then(|h| scene.bodies.get(h))
        .map_or(RigidBodyType::Fixed, |rb| rb.body_type())
}

/// Rapier's rules for whether the fast collider `(h1, co1)` and `(h2, co2)`
/// interact, and how; `None` when they do not.
pub(crate) fn pair_kind(
    scene: &Scene,
    h1: ColliderHandle,
    co1: &Collider,
    h2: ColliderHandle,
    co2: &Collider,
) -> Option<PairKind> {
    if h1 == h2 || !co2.is_enabled() || (co2.parent().is_some() && co2.parent() == co1.parent()) {
        return None;
    }
    let (t1, t2) = (body_type(scene, co1), body_type(scene, co2));
    let targets = &scene.config.targets;
    let wanted = match t2 {
        RigidBodyType::Fixed => targets.fixed,
        RigidBodyType::Dynamic => targets.dynamic,
        _ => targets.kinematic,
    };
    if !wanted
        || !co1.collision_groups().test(co2.collision_groups())
        || !(co1.active_collision_types() | co2.active_collision_types()).test(t1, t2)
    {
        return None;
    }
    if let (Some(b1), Some(b2)) = (co1.parent(), co2.parent()) {
        if scene
            .joints
            .joints_between(b1, b2)
            .any(|(_, j)| !j.data.contacts_enabled)
        {
            return None;
        }
    }
    let context = || PairFilterContext {
        bodies: scene.bodies,
        colliders: scene.colliders,
        collider1: h1,
        collider2: h2,
        rigid_body1: co1.parent(),
        rigid_body2: co2.parent(),
    };
    let hooks = co1.active_hooks() | co2.active_hooks();
    if co1.is_sensor() || co2.is_sensor() {
        let reported =
            (co1.active_events() | co2.active_events()).contains(ActiveEvents::COLLISION_EVENTS);
        let allowed = !hooks.contains(ActiveHooks::FILTER_INTERSECTION_PAIR)
            || scene.hooks.filter_intersection_pair(&context());
        return (reported && allowed).then_some(PairKind::Sensor);
    }
    if !co1.solver_groups().test(co2.solver_groups()) {
        return None;
    }
    if hooks.contains(ActiveHooks::FILTER_CONTACT_PAIRS) {
        let flags = scene.hooks.filter_contact_pair(&context())?;
        if !flags.contains(SolverFlags::COMPUTE_RIGID_IMPULSES) {
            return None;
        }
    }
    Some(PairKind::Solid)
}

/// The colliders the fast collider `(h1, co1)` with swept box `swept` may
/// meet, with how each pair is handled. Moving candidates must also pass
/// their own swept box, `own_box`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather(
    scene: &Scene,
    broad_phase: &BroadPhaseBvh,
    dispatcher: &dyn rapier3d::parry::query::QueryDispatcher,
    motions: &Motions,
    h1: ColliderHandle,
    co1: &Collider,
    swept: &Aabb,
    mut own_box: impl FnMut(ColliderHandle, &Collider) -> Option<Aabb>,
    out: &mut Vec<Candidate>,
) {
    out.clear();
    let query = broad_phase.as_query_pipeline(
        dispatcher,
        scene.bodies,
        scene.colliders,
        QueryFilter::default(),
    );
    let margin = ((motions.margin * (1.0 + 1.0e-5)) as f32).next_up();
    let wide = swept.loosened(margin);
    for (h2, co2) in query.intersect_aabb_conservative(wide) {
        let Some(kind) = pair_kind(scene, h1, co1, h2, co2) else {
            continue;
        };
        let moving = co2.parent().is_some_and(|b| motions.body(b).is_some());
        if moving {
            match own_box(h2, co2) {
                Some(b) if b.intersects(swept) => {}
                _ => continue,
            }
        } else if !co2.compute_aabb().intersects(swept) {
            continue;
        }
        out.push(Candidate { handle: h2, kind });
    }
}
