//! The motion the oracle assumes a body made over one step.
//!
//! Rapier only keeps the two poses. Between them we assume what its
//! integrator does on a step without contacts: the centre of mass moves on a
//! straight line at constant speed, and the body turns about its centre of
//! mass at constant angular speed about a fixed axis (a slerp). The shortest
//! arc between the two orientations is wrong for a body that turned more than
//! half a turn in the step; then the angular velocity decides how many whole
//! turns to add.

use affine_ccd::rapier::turns::{self, free_flight};
use rapier3d::math::{Pose, Real, Rotation, Vector};
use std::f32::consts::{PI, TAU};

/// How close (radians) the end orientation must be to the one a free spin
/// at the body's angular velocity gives before whole turns are added: the
/// stage's own convention.
const SPIN_MATCH: Real = turns::SPIN_MATCH as Real;

/// Below this angle (radians) the rotation axis is numerical noise.
const TINY_ANGLE: Real = turns::TINY_ANGLE as Real;

/// One body's motion over a step, as a function of the step fraction t ∈ [0, 1].
#[derive(Clone, Copy, Debug)]
pub struct StepPath {
    /// Centre of mass at t = 0 (world frame, metres).
    com0: Vector,
    /// Centre-of-mass displacement over the step (metres).
    delta: Vector,
    /// Orientation at t = 0.
    rot0: Rotation,
    /// Unit axis of the turn (world frame).
    axis: Vector,
    /// Signed angle turned over the step about `axis` (radians, may exceed π).
    angle: Real,
    /// Centre of mass in the body frame.
    local_com: Vector,
}

impl StepPath {
    /// A body that does not move.
    pub fn still(pose: &Pose, local_com: Vector) -> Self {
        Self::between(pose, pose, local_com, Vector::ZERO, 0.0)
    }

    /// The motion from `start` to `end` for a body whose centre of mass sits
    /// at `local_com` in its own frame. `angvel` (radians per second, world
    /// frame) and `dt`
    /// (seconds) are only used to count whole turns; rapier integrates the
    /// pose with the velocity at the end of the step, so pass that one.
    pub fn between(start: &Pose, end: &Pose, local_com: Vector, angvel: Vector, dt: Real) -> Self {
        Self::between_free(start, end, local_com, None, angvel, dt)
    }

    /// [`StepPath::between`], and with `linvel` (m/s, the velocity at the
    /// end of the step) the whole turns are only added when the step also
    /// moved the centre of mass as a free flight at `linvel` does
    /// (`affine_ccd::rapier::turns::free_flight`): a step cut short by a CCD clamp whose orientation
    /// happens to match a free spin again is not taken for one.
    pub fn between_free(
        start: &Pose,
        end: &Pose,
        local_com: Vector,
        linvel: Option<Vector>,
        angvel: Vector,
        dt: Real,
    ) -> Self {
        let com0 = start.transform_point(local_com);
        let com1 = end.transform_point(local_com);
        let free = linvel.is_none_or(|v| free_flight(com1 - com0, v, dt));
        let spin = if free { angvel } else { Vector::ZERO };
        let (axis, angle) = unwrapped_turn(start.rotation, end.rotation, spin, dt);
        Self {
            com0,
            delta: com1 - com0,
            rot0: start.rotation,
            axis,
            angle,
            local_com,
        }
    }

    /// The body pose at step fraction `t`.
    pub fn pose_at(&self, t: Real) -> Pose {
        let rotation = if self.angle.abs() < TINY_ANGLE {
            self.rot0
        } else {
            (Rotation::from_axis_angle(self.axis, self.angle * t) * self.rot0).normalize()
        };
        let com = self.com0 + self.delta * t;
        Pose::from_parts(com - rotation * self.local_com, rotation)
    }

    /// Centre of mass at step fraction `t`.
    pub fn com_at(&self, t: Real) -> Vector {
        self.com0 + self.delta * t
    }

    /// Length of the centre-of-mass path over the step (metres).
    pub fn travel(&self) -> Real {
        self.delta.length()
    }

    /// Absolute angle turned over the step (radians).
    pub fn turn(&self) -> Real {
        self.angle.abs()
    }

    /// Whether the body neither moves nor turns.
    pub fn is_still(&self) -> bool {
        self.delta == Vector::ZERO && self.angle.abs() < TINY_ANGLE
    }

    /// Upper bound on how far any point within `radius` of the centre of mass
    /// moves over the step (metres): path length plus arc length.
    pub fn max_point_travel(&self, radius: Real) -> Real {
        self.travel() + self.turn() * radius
    }
}

/// Axis and signed angle of the turn from `q0` to `q1`, unwrapped by whole
/// turns when `angvel · dt` says the body turned more than half a turn.
fn unwrapped_turn(q0: Rotation, q1: Rotation, angvel: Vector, dt: Real) -> (Vector, Real) {
    let dq = (q1 * q0.inverse()).normalize();
    let (mut axis, mut angle) = dq.to_axis_angle();
    // glam returns an angle in [0, 2π]; take the shortest arc in (-π, π].
    if angle > PI {
        angle -= TAU;
    }
    if !angle.is_finite() || !axis.is_finite() {
        return (Vector::X, 0.0);
    }
    let spin = angvel.length();
    let predicted = spin * dt;
    if !predicted.is_finite() || predicted <= PI {
        return (axis, angle);
    }
    // A fast spin: orient the axis along the angular velocity, then add the
    // whole turns that bring the angle closest to the predicted one.
    let spin_axis = angvel / spin;
    if angle.abs() < TINY_ANGLE {
        axis = spin_axis;
        angle = 0.0;
    } else if axis.dot(spin_axis) < 0.0 {
        axis = -axis;
        angle = -angle;
    }
    let along = angvel.dot(axis) * dt;
    let turns = ((along - angle) / TAU).round();
    let unwrapped = angle + turns * TAU;
    if (unwrapped - along).abs() <= SPIN_MATCH {
        (axis, unwrapped)
    } else {
        // The end orientation does not match a free spin at this angular
        // velocity: the step was cut short (a CCD clamp) or a contact changed
        // the spin. The shortest arc is then the least-assuming guess.
        (axis, angle)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fast_spin_keeps_its_whole_turns() {
        // 1.25 turns about z in one step: the poses alone say a quarter turn.
        let dt = 0.1;
        let angvel = Vector::new(0.0, 0.0, 1.25 * TAU / dt);
        let start = Pose::IDENTITY;
        let end = Pose::from_rotation(Rotation::from_axis_angle(Vector::Z, 1.25 * TAU));
        let m = StepPath::between(&start, &end, Vector::ZERO, angvel, dt);
        assert!(
            (m.turn() - 1.25 * TAU).abs() < 1e-3,
            "turn {} instead of {}",
            m.turn(),
            1.25 * TAU
        );
        // Half way it has turned 0.625 turns: the x axis points to angle 225°.
        let x = m.pose_at(0.5).rotation * Vector::X;
        let expected = Vector::new((1.25 * PI).cos(), (1.25 * PI).sin(), 0.0);
        assert!(
            (x - expected).length() < 1e-3,
            "x axis {x:?} instead of {expected:?}"
        );
    }

    #[test]
    fn the_centre_of_mass_moves_straight() {
        let start = Pose::from_translation(Vector::new(0.0, 0.0, 0.0));
        let end = Pose::from_parts(
            Vector::new(2.0, 0.0, 0.0),
            Rotation::from_axis_angle(Vector::Y, 1.0),
        );
        let com = Vector::new(0.5, 0.0, 0.0);
        let m = StepPath::between(&start, &end, com, Vector::ZERO, 1.0 / 60.0);
        for t in [0.0, 0.25, 0.5, 1.0] {
            let p = m.pose_at(t).transform_point(com);
            let expected = Vector::new(0.5 + 2.0 * t, 0.0, 0.0)
                + (end.transform_point(com) - Vector::new(2.5, 0.0, 0.0)) * t;
            assert!(
                (p - expected).length() < 1e-4,
                "t = {t}: {p:?} vs {expected:?}"
            );
        }
    }
}
