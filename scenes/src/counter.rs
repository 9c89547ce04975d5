//! The generic oracle, run on every scene: contacts the step jumped over.
//!
//! For each step and each pair of colliders that may collide (collision and
//! solver groups respected, sensors and disabled colliders skipped, rapier's
//! active-collision-type rules applied), the motion between the two poses
//! ([`StepPath`]) is sampled at [`SAMPLES`] instants and the penetration
//! depth is measured with parry's `contact` query. With `limit` =
//! max(half the thinner shape's thickness, [`DEPTH_FLOOR`]):
//!
//! - a **missed contact**: some sample is deeper than `limit` while neither
//!   end pose is;
//! - a **deep end**: the step starts no deeper than `limit` and ends deeper.
//!
//! A pair already more than half `limit` deep at the start counts only when
//! the step takes it another half `limit` deeper: a contact driven in, not
//! a resting one wobbling across the line (thin slabs resting on terrain
//! wobble between 8 and 11 mm deep under rapier's own contacts, step after
//! step, whatever the CCD).
//!
//! Cost is kept down three ways: swept boxes first (O(n²) box tests, fine for
//! the few hundred colliders of a scene); then the two end poses, whose
//! signed gaps plus a bound on how far any point moves prove most pairs
//! cannot get deep in between; the same bound skips individual samples.
//!
//! Sampling is not proof: a shape thinner than the distance it moves between
//! two samples (1/31 of the step) can slip between them. The per-scene
//! guards ([`super::guard`]) catch those.

use super::snapshot::Snapshot;
use super::step_path::StepPath;
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::parry::query;
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{Collider, ColliderHandle, PhysicsWorld, RigidBodyType};

/// Instants sampled per step, both ends included.
pub const SAMPLES: usize = 32;

/// Smallest penetration (metres) that counts as deep. Rapier's resting
/// contacts sink a few millimetres at most; 1 cm is well above that and well
/// below the size of the thinnest shapes in the scenes.
pub const DEPTH_FLOOR: Real = 0.01;

/// What kind of contact failure an event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactKind {
    /// Deeper than the limit between the poses, not at them.
    Missed,
    /// Shallow at the start of the step, deep at its end.
    DeepEnd,
}

/// One missed contact or deep end.
#[derive(Clone, Copy, Debug)]
pub struct ContactEvent {
    pub kind: ContactKind,
    /// Step the event belongs to (0-based).
    pub step: usize,
    pub a: ColliderHandle,
    pub b: ColliderHandle,
    /// Deepest penetration seen (metres).
    pub depth: Real,
    /// Limit it was compared with (metres).
    pub limit: Real,
    /// Step fraction of the deepest sample.
    pub t: Real,
    /// Midpoint of the contact points there (world, metres).
    pub at: Vector,
}

/// A collider as the counter sees it over one step.
struct Tracked<'a> {
    handle: ColliderHandle,
    collider: &'a Collider,
    body_type: RigidBodyType,
    /// `None` for a collider that does not move (fixed or parentless).
    motion: Option<StepPath>,
    /// Collider pose relative to its body (or its world pose if it does not move).
    relative: Pose,
    /// Box covering every pose the collider takes over the step.
    swept: Aabb,
    /// Bound on how far any of its points moves over the step (metres).
    travel: Real,
    /// Thickness (metres) used for the depth limit.
    thickness: Real,
}

impl Tracked<'_> {
    fn pose_at(&self, t: Real) -> Pose {
        match &self.motion {
            Some(m) => m.pose_at(t) * self.relative,
            None => self.relative,
        }
    }
}

/// Counts the missed contacts and deep ends of the step that just ran.
/// `before` is the snapshot taken before it; `step` only labels the events.
pub fn check_step(world: &PhysicsWorld, before: &Snapshot, step: usize) -> Vec<ContactEvent> {
    let tracked: Vec<Tracked> = world
        .colliders
        .iter()
        .filter_map(|(handle, collider)| track(world, before, handle, collider))
        .collect();
    let mut events = Vec::new();
    for i in 0..tracked.len() {
        for j in (i + 1)..tracked.len() {
            let (a, b) = (&tracked[i], &tracked[j]);
            if a.motion.is_none() && b.motion.is_none() {
                continue;
            }
            if !a.swept.intersects(&b.swept) || !may_collide(a, b) {
                continue;
            }
            if let Some(event) = check_pair(a, b, step) {
                events.push(event);
            }
        }
    }
    events
}

/// Builds the per-step view of a collider, or `None` when it takes no part.
fn track<'a>(
    world: &PhysicsWorld,
    before: &Snapshot,
    handle: ColliderHandle,
    collider: &'a Collider,
) -> Option<Tracked<'a>> {
    if collider.is_sensor() || !collider.is_enabled() {
        return None;
    }
    let shape = collider.shape();
    let thickness = thickness(shape);
    let parent = collider
        .parent()
        .and_then(|h| Some((h, world.bodies.get(h)?)));
    let (body_type, moving) = match parent {
        Some((_, body)) if !body.is_enabled() => return None,
        Some((h, body)) if !body.is_fixed() => (body.body_type(), Some((h, body))),
        Some((_, body)) => (body.body_type(), None),
        None => (RigidBodyType::Fixed, None),
    };
    let Some((body_handle, body)) = moving else {
        let pose = *collider.position();
        return Some(Tracked {
            handle,
            collider,
            body_type,
            motion: None,
            relative: pose,
            swept: shape.compute_aabb(&pose),
            travel: 0.0,
            thickness,
        });
    };
    let relative = collider
        .position_wrt_parent()
        .copied()
        .unwrap_or(Pose::IDENTITY);
    let local_com = body.local_center_of_mass();
    let start = before
        .bodies
        .get(&body_handle)
        .map(|s| s.pose)
        .unwrap_or(*body.position());
    let motion = StepPath::between_free(
        &start,
        body.position(),
        local_com,
        Some(body.linvel()),
        body.angvel(),
        world.integration_parameters.dt,
    );
    // Reach: how far the collider extends from the body's centre of mass.
    let sphere = shape.compute_local_bounding_sphere();
    let reach = (relative.transform_point(sphere.center) - local_com).length() + sphere.radius;
    if !reach.is_finite() {
        // An unbounded shape on a moving body: nothing sensible to sample.
        return None;
    }
    let travel = motion.max_point_travel(reach);
    let swept = if motion.turn() == 0.0 {
        // Pure translation: the two end boxes span the sweep.
        shape
            .compute_aabb(&(motion.pose_at(0.0) * relative))
            .merged(&shape.compute_aabb(&(motion.pose_at(1.0) * relative)))
    } else {
        let c0 = motion.com_at(0.0);
        let c1 = motion.com_at(1.0);
        Aabb::new(c0.min(c1), c0.max(c1)).loosened(reach)
    };
    Some(Tracked {
        handle,
        collider,
        body_type,
        motion: Some(motion),
        relative,
        swept,
        travel,
        thickness,
    })
}

/// Rapier's own filters: different bodies, groups, active collision types.
fn may_collide(a: &Tracked, b: &Tracked) -> bool {
    let (ca, cb) = (a.collider, b.collider);
    if ca.parent().is_some() && ca.parent() == cb.parent() {
        return false;
    }
    if !ca.collision_groups().test(cb.collision_groups())
        || !ca.solver_groups().test(cb.solver_groups())
    {
        return false;
    }
    ca.active_collision_types().test(a.body_type, b.body_type)
        || cb.active_collision_types().test(a.body_type, b.body_type)
}

/// Signed gap between the two colliders at step fraction `t` (metres,
/// negative = penetration depth), with where it is measured. A gap larger
/// than `prediction` is reported as `prediction` (a lower bound). `None`
/// when parry has no contact query for this shape pair.
fn gap_at(a: &Tracked, b: &Tracked, t: Real, prediction: Real) -> Option<(Real, Vector)> {
    let (pa, pb) = (a.pose_at(t), b.pose_at(t));
    let (sa, sb) = (a.collider.shape(), b.collider.shape());
    let (gap, at) = contact_gap(&pa, sa, &pb, sb, prediction)?;
    if gap >= -DEPTH_FLOOR {
        return Some((gap, at));
    }
    // parry 0.31.1's contact is not stable everywhere: a capsule resting
    // 1e-4 m deep across the inner edge of a two-triangle floor came back
    // 2-4 cm deep, with a contact point 0.6 m from it, at a rotation 1 ulp
    // from one it answered right (seen in `settle_flat`). A real
    // penetration does not change under a 1e-5 rad turn of one shape; so a
    // deep answer counts only as deep as the shallowest of it and two such
    // turns of `b` about its own origin.
    let mut gap = gap;
    for axis in [Vector::X, Vector::Z] {
        let turned = pb * Pose::from_rotation(Rotation::from_axis_angle(axis, 1.0e-5));
        if let Some((g, _)) = contact_gap(&pa, sa, &turned, sb, prediction) {
            gap = gap.max(g);
        }
    }
    Some((gap, at))
}

/// parry's signed gap and the midpoint of its contact points.
fn contact_gap(
    pa: &Pose,
    sa: &dyn Shape,
    pb: &Pose,
    sb: &dyn Shape,
    prediction: Real,
) -> Option<(Real, Vector)> {
    // parry 0.31.1 answers a convex shape against a half-space wrongly (the
    // depth grows with the distance from the plane's origin); the
    // half-space first is right.
    let found = if sb.as_halfspace().is_some() && sa.as_halfspace().is_none() {
        query::contact(pb, sb, pa, sa, prediction).map(|c| c.map(|c| c.flipped()))
    } else {
        query::contact(pa, sa, pb, sb, prediction)
    };
    match found {
        Ok(Some(c)) => Some((c.dist, (c.point1 + c.point2) * 0.5)),
        Ok(None) => Some((prediction, (pa.translation + pb.translation) * 0.5)),
        Err(_) => None,
    }
}

/// The depth a pair starting `depth0` deep must pass to count: `limit`,
/// or half a limit deeper than it started if that is more (module docs).
/// `None` for a pair already deeper than `limit` at the start: not this
/// step's doing.
fn counted_depth(limit: Real, depth0: Real) -> Option<Real> {
    (depth0 <= limit).then(|| limit.max(depth0 + 0.5 * limit))
}

/// Samples one pair over the step.
fn check_pair(a: &Tracked, b: &Tracked, step: usize) -> Option<ContactEvent> {
    let limit = (0.5 * a.thickness.min(b.thickness)).max(DEPTH_FLOOR);
    // Any point moves at most `travel` over the step, so the signed gap
    // changes by at most `reach` per unit of step fraction.
    let reach = a.travel + b.travel;
    let prediction = reach + 2.0 * limit;
    let (gap0, _) = gap_at(a, b, 0.0, prediction)?;
    let (gap1, at1) = gap_at(a, b, 1.0, prediction)?;
    let (depth0, depth1) = (-gap0, -gap1);
    let limit = counted_depth(limit, depth0)?;
    let event = |kind, depth, t, at| ContactEvent {
        kind,
        step,
        a: a.handle,
        b: b.handle,
        depth,
        limit,
        t,
        at,
    };
    if depth1 > limit {
        return Some(event(ContactKind::DeepEnd, depth1, 1.0, at1));
    }
    // Lowest gap the bound allows anywhere in the step.
    if 0.5 * (gap0 + gap1 - reach) >= -limit {
        return None;
    }
    let mut deepest: Option<(Real, Real, Vector)> = None;
    for i in 1..SAMPLES - 1 {
        let t = i as Real / (SAMPLES - 1) as Real;
        let bound = (gap0 - reach * t).max(gap1 - reach * (1.0 - t));
        if bound >= -limit {
            continue;
        }
        let Some((gap, at)) = gap_at(a, b, t, 0.0) else {
            continue;
        };
        if -gap > limit && deepest.is_none_or(|(d, _, _)| -gap > d) {
            deepest = Some((-gap, t, at));
        }
    }
    deepest.map(|(depth, t, at)| event(ContactKind::Missed, depth, t, at))
}

/// The thickness of a shape for the depth limit (metres): the smallest
/// extent of a solid, zero for surfaces (meshes, triangles, segments),
/// infinite for a half-space, the thinnest child for a compound.
pub fn thickness(shape: &dyn Shape) -> Real {
    match shape.as_typed_shape() {
        TypedShape::HalfSpace(_) => Real::INFINITY,
        TypedShape::TriMesh(_)
        | TypedShape::Polyline(_)
        | TypedShape::HeightField(_)
        | TypedShape::Triangle(_)
        | TypedShape::Segment(_) => 0.0,
        TypedShape::RoundTriangle(t) => 2.0 * t.border_radius,
        TypedShape::Compound(c) => c
            .shapes()
            .iter()
            .map(|(_, child)| thickness(child.as_ref()))
            .fold(Real::INFINITY, Real::min),
        _ => {
            let aabb = shape.compute_local_aabb();
            let e = aabb.maxs - aabb.mins;
            e.min_element().max(0.0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::counted_depth;

    #[test]
    fn a_resting_pair_counts_only_when_driven_half_a_limit_deeper() {
        let limit = 0.01;
        // Apart or shallow at the start: the limit itself.
        assert_eq!(counted_depth(limit, -0.5), Some(limit));
        assert_eq!(counted_depth(limit, 0.004), Some(limit));
        // Resting 9 mm deep: a wobble to 11 mm is not counted, 14.5 mm is.
        let nine = counted_depth(limit, 0.009).expect("counted");
        assert!(0.011 < nine && nine < 0.0145, "{nine}");
        // Already deeper than the limit: never this step's event.
        assert_eq!(counted_depth(limit, 0.011), None);
    }
}
