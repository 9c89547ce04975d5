//! The state of every body and collider at one instant, kept between steps.
//!
//! Rapier overwrites poses in place; the oracle needs the pose before a step
//! and the pose after it, so the runner takes a [`Snapshot`] before each step.

use rapier3d::math::{Pose, Vector};
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle, RigidBodyType};
use std::collections::HashMap;

/// One body's state.
#[derive(Clone, Copy, Debug)]
pub struct BodyState {
    /// Pose of the body frame (world).
    pub pose: Pose,
    /// Centre of mass in the body frame (metres).
    pub local_com: Vector,
    /// Linear velocity of the centre of mass (m/s, world).
    pub linvel: Vector,
    /// Angular velocity (rad/s, world).
    pub angvel: Vector,
    pub body_type: RigidBodyType,
}

impl BodyState {
    /// Centre of mass in the world frame.
    pub fn com(&self) -> Vector {
        self.pose.transform_point(self.local_com)
    }
}

/// Poses of all bodies and colliders of a world.
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    pub bodies: HashMap<RigidBodyHandle, BodyState>,
    pub colliders: HashMap<ColliderHandle, Pose>,
}

impl Snapshot {
    /// Records the current state of `world`.
    pub fn take(world: &PhysicsWorld) -> Self {
        let bodies = world
            .bodies
            .iter()
            .map(|(handle, body)| {
                let state = BodyState {
                    pose: *body.position(),
                    local_com: body.local_center_of_mass(),
                    linvel: body.linvel(),
                    angvel: body.angvel(),
                    body_type: body.body_type(),
                };
                (handle, state)
            })
            .collect();
        let colliders = world
            .colliders
            .iter()
            .map(|(handle, collider)| (handle, *collider.position()))
            .collect();
        Self { bodies, colliders }
    }

    /// Centre of mass of `body`, if it exists.
    pub fn com(&self, body: RigidBodyHandle) -> Option<Vector> {
        self.bodies.get(&body).map(BodyState::com)
    }
}
