//! A body's motion over the step as the stage sees it: its two poses, the
//! angular velocity that chooses its whole turns, and bounds on how far its
//! points travel. Every phase of the stage passes these along.

use rapier3d::prelude::{Pose, RigidBody, RigidBodyHandle, Vector};
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

/// Bound on the rotation angle (radians) of the motion
/// `Motion::from_poses` builds: the short angle between the poses unless the
/// velocity hint may pick other whole turns, then at most `hint + π`.
pub(crate) fn angle_bound(short: f64, hint: f64) -> f64 {
    if short + hint < PI { short } else { hint + PI }
}

/// The shortest rotation angle from `start` to `end`, radians.
pub(crate) fn angle_short(start: &Pose, end: &Pose) -> f64 {
    let dq = end.rotation * start.rotation.inverse();
    2.0 * (dq.xyz().length() as f64).atan2(dq.w.abs() as f64)
}

/// `|sin(θ/2)|` of the turn from `start` to `end` (`θ` its shortest
/// angle), with no atan2: `π` times it bounds `θ`, and twice it is the
/// chord a unit arm sweeps.
pub(crate) fn half_angle_sine(start: &Pose, end: &Pose) -> f64 {
    let dq = end.rotation * start.rotation.inverse();
    dq.xyz().length() as f64
}

/// Bound on how far any point of a body moves, metres: its centre of
/// mass's `shift` plus the chord of its farthest point (`extent` from the
/// centre) turned by `angle` radians (at most two extents), padded for
/// rounding.
pub(crate) fn travel_bound(shift: f64, extent: f64, angle: f64) -> f64 {
    (shift + extent * angle.min(2.0)) * (1.0 + 1.0e-4) + 1.0e-6
}

/// Bound on how far any point of body `a` moves relative to any point of
/// body `b` during the step (`ra`, `rb` their rigid bodies), metres, each
/// on the motion the stage builds from its record (`Motion::from_poses`
/// with its acceleration): the centres of mass's relative shift and the
/// acceleration terms' difference, plus each body's turning chord (its
/// reach from the centre of mass, rapier's `max_extent`, times its angle,
/// at most two reaches), padded for the `f32` poses. Two bodies moving
/// together (a paddle and the boxes it carries) get a small bound however
/// fast they go.
pub(crate) fn relative_travel(
    a: &Moved,
    ra: &RigidBody,
    b: &Moved,
    rb: &RigidBody,
    dt: f64,
) -> f64 {
    let shift = |m: &Moved, r: &RigidBody| {
        let com = r.local_center_of_mass();
        (m.end * com - m.start * com).as_dvec3()
    };
    let linear = (shift(a, ra) - shift(b, rb)).length()
        + 0.5 * (a.accel - b.accel).as_dvec3().length() * dt * dt;
    let turn = |m: &Moved, r: &RigidBody| {
        let angle = angle_bound(angle_short(&m.start, &m.end), m.angvel.length() as f64 * dt);
        r.mass_properties().max_extent() as f64 * angle.min(2.0)
    };
    // `f32` products and differences of coordinates this large.
    let scale = [a.start, a.end, b.start, b.end]
        .iter()
        .map(|p| p.translation.abs().max_element())
        .fold(0.0f32, f32::max) as f64;
    (linear + turn(a, ra) + turn(b, rb)) * (1.0 + 1.0e-4) + 1.0e-5 + 1.0e-6 * scale
}

/// Bound on how far any point of `rb` moves on the shortest motion from
/// `start` to `end`, metres (the `travel` of a motion rebuilt by the stage).
pub(crate) fn travel_between(rb: &RigidBody, start: &Pose, end: &Pose) -> f64 {
    let com = rb.local_center_of_mass();
    let shift = (*end * com - *start * com).length() as f64;
    let extent = rb.mass_properties().max_extent() as f64;
    travel_bound(shift, extent, angle_short(start, end))
}
