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

/// `|sin(θ/2)|` and `|cos(θ/2)|` of the shortest turn `θ` from `start` to
/// `end`, from the quaternion between them.
fn half_turn(start: &Pose, end: &Pose) -> (f64, f64) {
    let dq = end.rotation * start.rotation.inverse();
    (dq.xyz().length() as f64, dq.w.abs() as f64)
}

/// The shortest rotation angle from `start` to `end`, radians.
pub(crate) fn angle_short(start: &Pose, end: &Pose) -> f64 {
    let (s, c) = half_turn(start, end);
    2.0 * s.atan2(c)
}

/// `|sin(θ/2)|` of the turn from `start` to `end` (`θ` its shortest
/// angle), with no atan2: `π` times it bounds `θ`, and twice it is the
/// chord a unit arm sweeps.
pub(crate) fn half_angle_sine(start: &Pose, end: &Pose) -> f64 {
    half_turn(start, end).0
}

/// Bound on the chord a unit arm sweeps on the motion `Motion::from_poses`
/// builds from `start` to `end` with the velocity hint `hint` (the turn it
/// would make over the step, radians): `2·|sin(θ/2)|` of the shortest turn
/// `θ` (the chord grows with the angle up to a half turn) where the hint
/// cannot pick other whole turns ([`angle_bound`]), else 2, a diameter. No
/// atan2 (this runs for every pair a push may spare): `θ` is at most
/// `2·s/c` (`atan x ≤ x`) and at most `π·s`, `s` and `c` the sine and
/// cosine of `θ/2`.
pub(crate) fn chord_bound(start: &Pose, end: &Pose, hint: f64) -> f64 {
    let (s, c) = half_turn(start, end);
    let short = if c > s { 2.0 * s / c } else { PI * s };
    if short + hint < PI {
        (2.0 * s).min(2.0)
    } else {
        2.0
    }
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
/// reach from the centre of mass, rapier's `max_extent`, times
/// [`chord_bound`]), padded for the `f32` poses. Two bodies moving
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
        let chord = chord_bound(&m.start, &m.end, m.angvel.length() as f64 * dt);
        r.mass_properties().max_extent() as f64 * chord
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
    // The chord of the shortest turn, `2·|sin(θ/2)|`, bounds the arm's
    // travel as the angle would (and is no larger).
    travel_bound(shift, extent, 2.0 * half_angle_sine(start, end))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convert::{iso_from_pose, vec_from_glam};
    use crate::motion::{Motion, Trajectory};
    use nalgebra::{Point3, Vector3};
    use proptest::prelude::*;
    use rapier3d::prelude::Rotation;

    /// The largest distance a unit arm of the motion built from `start` to
    /// `end` with spin `angvel` gets from where it started, sampled.
    fn farthest_arm(start: &Pose, end: &Pose, angvel: Vector, arm: Vector3<f64>) -> f64 {
        let motion = Motion::from_poses(
            iso_from_pose(start),
            iso_from_pose(end),
            Point3::origin(),
            1.0 / 60.0,
            vec_from_glam(angvel),
        )
        .expect("finite poses");
        let arm = Point3::from(arm.normalize());
        // The arm's point relative to the centre, which moves apart.
        let at = |tau: f64| {
            let pose = motion.pose_at(tau);
            pose * arm - pose.translation.vector
        };
        let first = at(0.0);
        (1..=128)
            .map(|k| (at(k as f64 / 128.0) - first).norm())
            .fold(0.0, f64::max)
    }

    /// Where a hint against the short turn just picks the whole turn the
    /// other way (the arm then passes the far side), the bound is a
    /// diameter; a hint a little weaker keeps the short turn's chord.
    #[test]
    fn a_hint_against_the_turn_that_picks_the_long_way_round_counts() {
        let dt = 1.0 / 60.0;
        for theta in [0.2f32, 0.8, 1.4, 2.0, 2.8] {
            let start = Pose::IDENTITY;
            let end = Pose::from_parts(Vector::ZERO, Rotation::from_rotation_z(theta));
            for share in [0.25f32, 0.5, 0.75, 0.95, 1.05, 1.3] {
                // Against the turn: `π − θ·share` per step about -z.
                let hint = std::f32::consts::PI - theta * share;
                let angvel = Vector::new(0.0, 0.0, -hint / dt as f32);
                let bound = chord_bound(&start, &end, hint as f64);
                let moved = farthest_arm(&start, &end, angvel, Vector3::x());
                assert!(
                    moved <= bound * (1.0 + 1.0e-4) + 1.0e-5,
                    "θ {theta}, share {share}: moved {moved}, bound {bound}"
                );
            }
        }
    }

    proptest! {
        /// No point a unit arm from the centre of mass gets farther from
        /// where it started, at any sampled time of the motion the stage
        /// builds from two poses and a spin hint (`Motion::from_poses`),
        /// than `chord_bound` says (padded as `relative_travel` pads it):
        /// short turns, turns near a half turn, and hints of up to 100 rad
        /// a step that pick other whole turns.
        #[test]
        fn the_chord_bound_holds_on_the_built_motion(
            axes in prop::array::uniform2(prop::array::uniform3(-1.0f32..1.0)),
            angles in prop::array::uniform2(-3.2f32..3.2),
            hint in prop::array::uniform3(-60.0f32..60.0),
            hint_scale in -2i32..2,
            arm in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let turn = |axis: [f32; 3], angle: f32| {
                Rotation::from_axis_angle(Vector::from(axis).normalize_or(Vector::X), angle)
            };
            let start = Pose::from_parts(Vector::new(0.3, -0.2, 0.1), turn(axes[0], angles[0]));
            let end = Pose::from_parts(Vector::new(1.3, 0.2, -0.4), turn(axes[1], angles[1]));
            let angvel = Vector::from(hint) * 10f32.powi(hint_scale);
            let bound = chord_bound(&start, &end, angvel.length() as f64 / 60.0);
            let arm = Vector3::from(arm);
            prop_assume!(arm.norm() > 1.0e-3);
            let moved = farthest_arm(&start, &end, angvel, arm);
            prop_assert!(
                moved <= bound * (1.0 + 1.0e-4) + 1.0e-5,
                "the arm moved {moved}, bound {bound}"
            );
        }
    }
}
