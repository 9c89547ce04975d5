//! Scripted kinematic bodies: a pose as a function of time.
//!
//! The runner calls [`Script::apply`] before every step with the time the
//! step ends at; rapier then moves the (position-based) kinematic body there
//! over the step and gives it the matching velocity.

use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::prelude::{PhysicsWorld, RigidBodyHandle};

/// How a scripted body moves.
#[derive(Clone, Copy, Debug)]
pub enum Motion {
    /// Turns about `axis` (world, unit) through the pivot of `base` between
    /// `low` and `high` radians: a quick flick up over `flick` seconds, a slow
    /// return over the rest of `period` seconds (a pinball flipper).
    Flick {
        /// Pose at angle 0; the body turns about its translation.
        base: Pose,
        axis: Vector,
        low: Real,
        high: Real,
        flick: Real,
        period: Real,
    },
    /// Goes from `from` to `to` and back at constant speed, one round trip
    /// every `period` seconds, keeping `rotation`.
    Slide {
        from: Vector,
        to: Vector,
        rotation: Rotation,
        period: Real,
    },
}

/// A kinematic body and its motion.
#[derive(Clone, Copy, Debug)]
pub struct Script {
    pub body: RigidBodyHandle,
    pub motion: Motion,
}

impl Motion {
    /// The pose at time `time` (seconds since the start of the run).
    pub fn pose_at(&self, time: Real) -> Pose {
        match *self {
            Motion::Flick {
                base,
                axis,
                low,
                high,
                flick,
                period,
            } => {
                let period = period.max(Real::EPSILON);
                let flick = flick.clamp(Real::EPSILON, period);
                let phase = time.rem_euclid(period);
                let angle = if phase < flick {
                    low + (high - low) * phase / flick
                } else if period > flick {
                    high - (high - low) * (phase - flick) / (period - flick)
                } else {
                    high
                };
                let turn = Rotation::from_axis_angle(axis, angle);
                Pose::from_parts(base.translation, turn * base.rotation)
            }
            Motion::Slide {
                from,
                to,
                rotation,
                period,
            } => {
                let period = period.max(Real::EPSILON);
                let phase = time.rem_euclid(period) / period;
                // Triangle wave: 0 → 1 over the first half, back to 0.
                let s = if phase < 0.5 {
                    2.0 * phase
                } else {
                    2.0 - 2.0 * phase
                };
                Pose::from_parts(from + (to - from) * s, rotation)
            }
        }
    }
}

impl Script {
    /// Sets the kinematic target for the step ending at `time` (seconds).
    /// Does nothing if the body is gone.
    pub fn apply(&self, world: &mut PhysicsWorld, time: Real) {
        if let Some(body) = world.bodies.get_mut(self.body) {
            body.set_next_kinematic_position(self.motion.pose_at(time));
        }
    }
}
