//! Which bodies moved, and which of them can tunnel.
//!
//! Before the step we record the pose of every enabled, non-fixed body,
//! asleep or not (targets that move need their start pose too, and a
//! sleeping body may be woken and thrown during the step). After it we keep the
//! dynamic ones whose fastest point went farther than `fast_factor` times
//! their thinnest extent: rapier's post-solve test, with the rotation
//! counted as an arc (whole turns included, through the velocity term)
//! instead of a chord. Everything here reads bodies, never writes them,
//! so a step with no fast body leaves rapier's state untouched.

use super::config::CcdConfig;
use super::moved::{Moved, Start, angle_bound, angle_short, travel_bound};
use super::report::{CcdReport, SkipReason};
use super::turns::turn_hint;
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{ColliderSet, RigidBody, RigidBodySet, Vector};

fn finite_vels(rb: &RigidBody) -> bool {
    rb.linvel().is_finite() && rb.angvel().is_finite()
}

/// The poses of the bodies that may move during the next step, sleeping
/// ones included: a body asleep at the start can be woken by a hit during
/// the step and leave it fast (the long soak lost a resting compound
/// through the floor that way). Awake dynamic bodies with a non-finite
/// state are reported and left out; a sleeping one is recorded as it is and
/// checked after the step if it moved (`moved`).
pub(crate) fn record(
    bodies: &RigidBodySet,
    config: &CcdConfig,
    report: &mut CcdReport,
    out: &mut Vec<Start>,
) {
    out.clear();
    for (handle, rb) in bodies.iter() {
        if rb.is_fixed() || !rb.is_enabled() {
            continue;
        }
        // A sleeping body is checked after the step, if it moved at all
        // (`moved`): most never do, and checking them costs as much as
        // rapier's own step spends on them.
        if !rb.is_sleeping() && (!rb.position().is_finite() || !finite_vels(rb)) {
            if rb.is_dynamic() && !config.opted_out(rb.user_data) {
                report.skip(handle, SkipReason::NonFinite);
            }
            continue;
        }
        out.push(Start {
            handle,
            pose: *rb.position(),
        });
    }
}

/// The thinnest extent rapier's test compares the motion with, metres.
/// Meshes, polylines and heightfields have no thickness in parry (0); they
/// get their local box's smallest half extent instead, so that a slowly
/// moving mesh body is not swept every step.
pub(crate) fn thickness(shape: &dyn Shape) -> f64 {
    match shape.as_typed_shape() {
        TypedShape::TriMesh(_)
        | TypedShape::Polyline(_)
        | TypedShape::HeightField(_)
        | TypedShape::Voxels(_) => shape.compute_local_aabb().half_extents().min_element() as f64,
        _ => shape.ccd_thickness() as f64,
    }
}

/// How far the body's colliders reach from its centre of mass, for how
/// far they move when it turns, metres: rapier's `max_extent`, except that
/// a body of balls counts only their centres (a ball turns into itself: a
/// rolling ball moves no farther than its centre does).
pub(crate) fn turning_extent(rb: &RigidBody, colliders: &ColliderSet) -> f64 {
    let com = rb.local_center_of_mass();
    let mut extent = 0.0f64;
    for co in rb.colliders().iter().filter_map(|h| colliders.get(*h)) {
        if !co.is_enabled() {
            continue;
        }
        match (co.shape().as_ball(), co.position_wrt_parent()) {
            (Some(_), Some(local)) => {
                extent = extent.max((local.translation - com).length() as f64);
            }
            _ => return rb.mass_properties().max_extent() as f64,
        }
    }
    extent
}

pub(crate) fn body_thickness(rb: &RigidBody, colliders: &ColliderSet) -> f64 {
    rb.colliders()
        .iter()
        .filter_map(|h| colliders.get(*h))
        .filter(|co| co.is_enabled())
        .map(|co| thickness(co.shape()))
        .fold(f64::INFINITY, f64::min)
}

/// The bodies of `starts` that moved during `dt` seconds, each marked fast
/// or not. A body counts as fast when its velocity would take it across
/// its thickness within `horizon` seconds (`dt`, or the whole step when
/// `dt` is a piece of it: a body that tunnels over the step is swept in
/// every piece, however short). A body whose end state is not finite is
/// reported and left out.
#[allow(clippy::too_many_arguments)]
pub(crate) fn moved(
    starts: &[Start],
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    dt: f64,
    horizon: f64,
    config: &CcdConfig,
    report: &mut CcdReport,
    out: &mut Vec<Moved>,
) {
    out.clear();
    for start in starts {
        let Some(rb) = bodies.get(start.handle) else {
            continue;
        };
        if !rb.is_enabled() {
            continue;
        }
        let end = *rb.position();
        // Unmoved (a sleeping body, a resting one): nothing to check (a
        // non-finite pose is never equal to itself).
        if end == start.pose {
            continue;
        }
        if !end.is_finite() || !finite_vels(rb) {
            report.skip(start.handle, SkipReason::NonFinite);
            continue;
        }
        let com = rb.local_center_of_mass();
        let shift = (end * com - start.pose * com).length() as f64;
        let extent = turning_extent(rb, colliders);
        let spin = rb.angvel().length() as f64 * dt;
        let short = angle_short(&start.pose, &end);
        let travel = travel_bound(shift, extent, angle_bound(short, spin));
        // Arc length of the farthest point; the velocity term is rapier's.
        let arc = shift + extent * short.max(spin);
        let by_velocity =
            (rb.linvel().length() as f64 + rb.angvel().length() as f64 * extent) * horizon.max(dt);
        let tunnels = arc.max(by_velocity) > config.fast_factor * body_thickness(rb, colliders);
        let fast = rb.is_dynamic() && !config.opted_out(rb.user_data) && tunnels;
        let pusher = rb.is_kinematic() && config.targets.kinematic && tunnels;
        out.push(Moved {
            handle: start.handle,
            start: start.pose,
            end,
            angvel: turn_hint(rb, &start.pose, &end, dt),
            accel: Vector::ZERO,
            fast,
            pusher,
            travel,
        });
    }
}
