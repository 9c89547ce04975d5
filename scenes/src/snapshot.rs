//! The state of every body and collider at one instant, kept between steps.
//!
//! Rapier overwrites poses in place; the oracle needs the pose before a step
//! and the pose after it, so the runner takes a [`Snapshot`] before each step.

use rapier3d::math::{AngularInertia, Pose, Real, Vector};
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBody, RigidBodyHandle, RigidBodyType};
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
    /// Mass (kg); 0 for a body of infinite mass (fixed, kinematic).
    pub mass: Real,
    /// World-space angular inertia about the centre of mass (kg·m²), locked
    /// axes zeroed; zero for a body that does not turn under forces.
    pub inertia: AngularInertia,
    /// The body's gravity scale (gravity acting on it is `gravity_scale · g`).
    pub gravity_scale: Real,
    /// The angular velocity rapier's gyroscopic correction alone would give
    /// after one step (rad/s, world); `angvel` when the correction is off.
    pub gyro_angvel: Vector,
    /// Whether rapier has put the body to sleep (velocities then read zero).
    pub sleeping: bool,
}

impl BodyState {
    /// The state of `body` now; `dt` (seconds) for the gyroscopic prediction.
    pub fn of(body: &RigidBody, dt: Real) -> Self {
        let mprops = body.mass_properties();
        let inertia = if mprops.effective_world_inv_inertia.is_zero() {
            AngularInertia::zero()
        } else {
            mprops.effective_angular_inertia()
        };
        let gyro_angvel = if body.is_dynamic() && body.gyroscopic_forces_enabled() {
            body.angvel_with_gyroscopic_forces(dt)
        } else {
            body.angvel()
        };
        BodyState {
            pose: *body.position(),
            local_com: body.local_center_of_mass(),
            linvel: body.linvel(),
            angvel: body.angvel(),
            body_type: body.body_type(),
            mass: body.mass(),
            inertia,
            gravity_scale: body.gravity_scale(),
            gyro_angvel,
            sleeping: body.is_sleeping(),
        }
    }

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
        let dt = world.integration_parameters.dt;
        let bodies = world
            .bodies
            .iter()
            .map(|(handle, body)| (handle, BodyState::of(body, dt)))
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
