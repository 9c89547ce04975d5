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
use super::report::{CcdReport, SkipReason};
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{ColliderSet, Pose, RigidBody, RigidBodyHandle, RigidBodySet, Vector};
use std::f64::consts::PI;

/// A body's state before the step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Start {
    pub handle: RigidBodyHandle,
    pub pose: Pose,
}

/// A body that moved during the step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Moved {
    pub handle: RigidBodyHandle,
    pub start: Pose,
    pub end: Pose,
    /// Angular velocity after the solve, rad/s: chooses the whole turns.
    pub angvel: Vector,
    /// Constant acceleration of the centre of mass, m/s². Zero for a
    /// recorded step (the body runs straight from `start` to `end`); gravity
    /// and forces for a predicted one (`substep`), whose `end` is then where
    /// the body would be without them.
    pub accel: Vector,
    /// A dynamic body, not opted out, fast enough to tunnel.
    pub fast: bool,
    /// A kinematic body fast enough to pass through dynamic bodies (by the
    /// same test): they are swept against it and pushed.
    pub pusher: bool,
    /// Bound on how far any point of the body travels during the step,
    /// metres (for enlarging broad-phase queries).
    pub travel: f64,
}

fn finite_vels(rb: &RigidBody) -> bool {
    rb.linvel().is_finite() && rb.angvel().is_finite()
}

/// The poses of the bodies that may move during the next step, sleeping
/// ones included: a body asleep at the start can be woken by a hit during
/// the step and leave it fast (the long soak lost a resting compound
/// through the floor that way). Dynamic bodies with a non-finite state are
/// reported and left out.
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
        if !rb.position().is_finite() || !finite_vels(rb) {
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

pub(crate) fn body_thickness(rb: &RigidBody, colliders: &ColliderSet) -> f64 {
    rb.colliders()
        .iter()
        .filter_map(|h| colliders.get(*h))
        .filter(|co| co.is_enabled())
        .map(|co| thickness(co.shape()))
        .fold(f64::INFINITY, f64::min)
}

/// Bound on the rotation angle (radians) of the motion
/// `Motion::from_poses` builds: the short angle between the poses unless the
/// velocity hint may pick other whole turns, then at most `hint + π`.
fn angle_bound(short: f64, hint: f64) -> f64 {
    if short + hint < PI { short } else { hint + PI }
}

/// The shortest rotation angle from `start` to `end`, radians.
pub(crate) fn angle_short(start: &Pose, end: &Pose) -> f64 {
    let dq = end.rotation * start.rotation.inverse();
    2.0 * (dq.xyz().length() as f64).atan2(dq.w.abs() as f64)
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
        if !end.is_finite() || !finite_vels(rb) {
            report.skip(start.handle, SkipReason::NonFinite);
            continue;
        }
        if end == start.pose {
            continue;
        }
        let com = rb.local_center_of_mass();
        let shift = (end * com - start.pose * com).length() as f64;
        let extent = rb.mass_properties().max_extent() as f64;
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

/// Bound on how far any point of a body moves, metres: its centre of
/// mass's `shift` plus the chord of its farthest point (`extent` from the
/// centre) turned by `angle` radians (at most two extents), padded for
/// rounding.
pub(crate) fn travel_bound(shift: f64, extent: f64, angle: f64) -> f64 {
    (shift + extent * angle.min(2.0)) * (1.0 + 1.0e-4) + 1.0e-6
}

/// Bound on how far any point of `rb` moves on the shortest motion from
/// `start` to `end`, metres (the `travel` of a motion rebuilt by the stage).
pub(crate) fn travel_between(rb: &RigidBody, start: &Pose, end: &Pose) -> f64 {
    let com = rb.local_center_of_mass();
    let shift = (*end * com - *start * com).length() as f64;
    let extent = rb.mass_properties().max_extent() as f64;
    travel_bound(shift, extent, angle_short(start, end))
}

/// How far from a free spin (radians) the end orientation may be for the
/// angular velocity to choose the whole turns of the motion.
const SPIN_MATCH: f64 = std::f64::consts::FRAC_PI_4;

/// The angular velocity that chooses the whole turns of the motion from
/// `start` to `end` (see `Motion::from_poses`): the body's own when the end
/// orientation is within [`SPIN_MATCH`] of a free spin at it, else zero
/// (the shortest rotation). A contact that changed the spin during the step
/// (a bounce) leaves an angular velocity that says nothing of the turns
/// made, and adding a whole turn the body never made would sweep a path
/// it never took (and miss the one it did). Likewise when the centre of
/// mass did not move as a free flight at the body's velocity (a clamp that
/// happens to leave the orientation one free spin on). The same convention
/// as the scene oracle's (`scenes::motion::BodyMotion::between_free`).
pub(crate) fn turn_hint(rb: &RigidBody, start: &Pose, end: &Pose, dt: f64) -> Vector {
    let angvel = rb.angvel();
    let spin = angvel.length() as f64 * dt;
    // At most half a turn (or NaN): the shortest rotation is the one.
    if spin.partial_cmp(&PI) != Some(std::cmp::Ordering::Greater) {
        return angvel;
    }
    let com = rb.local_center_of_mass();
    let delta = *end * com - *start * com;
    if !crate::scenes::motion::free_flight(delta, rb.linvel(), dt as f32) {
        return Vector::ZERO;
    }
    let dq = end.rotation * start.rotation.inverse();
    let (axis, angle) = dq.to_axis_angle();
    let (axis, angle) = (
        nalgebra::Vector3::new(axis.x as f64, axis.y as f64, axis.z as f64),
        angle as f64,
    );
    let w = nalgebra::Vector3::new(angvel.x as f64, angvel.y as f64, angvel.z as f64) * dt;
    // The turn about the axis oriented along the spin, whole turns added
    // to come nearest the spin's component along it.
    let (axis, signed) = if axis.dot(&w) < 0.0 {
        (-axis, -angle)
    } else {
        (axis, angle)
    };
    let along = w.dot(&axis);
    let turns = ((along - signed) / std::f64::consts::TAU).round();
    let unwrapped = signed + turns * std::f64::consts::TAU;
    if (unwrapped - along).abs() <= SPIN_MATCH {
        angvel
    } else {
        Vector::ZERO
    }
}
