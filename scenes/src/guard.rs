//! The per-scene invariant: a body ended on the wrong side of an obstacle it
//! should have hit. Each violation is one "tunnelling event".
//!
//! Three kinds of guard cover the scenes:
//!
//! - [`Guard::Crossing`]: the centre of mass of a body must not enter or pass
//!   through an obstacle (a wall, a floor, a terrain, another body). Tested in
//!   the obstacle's frame, so moving obstacles work too: the segment from the
//!   old to the new centre of mass, both expressed relative to the obstacle,
//!   is cast against the obstacle's shape. A centre of mass that already
//!   started inside is not counted again.
//! - [`Guard::Beyond`]: no point of a body may reach past the far face of a
//!   thin wall, inside the wall's footprint. This catches a spinning rod whose
//!   tip went through while its centre of mass stayed on the near side.
//! - [`Guard::Inside`]: the centre of mass must stay inside a closed region
//!   (the bounce house, the pinball table).
//!
//! `Beyond` and `Inside` count a violation when it starts, not on every step
//! it lasts.

use super::snapshot::Snapshot;
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::parry::query::Ray;
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyHandle};

/// How far past a wall's far face a point must reach to count (metres): only
/// to absorb rounding, a body stopped by the wall never gets near the far face.
const BEYOND_TOLERANCE: Real = 1.0e-3;

/// A rectangle on a plane: the far face of a thin wall.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    /// A point of the face, its centre (world, metres).
    pub center: Vector,
    /// Unit normal pointing to the forbidden side (away from the wall).
    pub normal: Vector,
    /// First in-plane unit axis and the half-length along it.
    pub u: Vector,
    pub half_u: Real,
    /// Second in-plane unit axis and the half-length along it.
    pub v: Vector,
    pub half_v: Real,
}

impl Face {
    /// The far face of an axis-aligned box wall centred at `center` with half
    /// extents `half`, on the side of world axis `axis` (0, 1, 2) given by `sign`.
    pub fn of_box(center: Vector, half: Vector, axis: usize, sign: Real) -> Self {
        let axis = axis.min(2);
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let unit = |i: usize| Vector::AXES[i];
        let normal = unit(axis) * sign.signum();
        Self {
            center: center + normal * half[axis],
            normal,
            u: unit(a),
            half_u: half[a],
            v: unit(b),
            half_v: half[b],
        }
    }

    /// Whether `point` lies past the face, inside its footprint.
    pub fn is_passed_by(&self, point: Vector) -> bool {
        let d = point - self.center;
        d.dot(self.normal) > BEYOND_TOLERANCE
            && d.dot(self.u).abs() <= self.half_u
            && d.dot(self.v).abs() <= self.half_v
    }
}

/// One invariant of a scene.
#[derive(Clone, Copy, Debug)]
pub enum Guard {
    /// The centre of mass of `body` must not enter or cross `obstacle`.
    Crossing {
        body: RigidBodyHandle,
        obstacle: ColliderHandle,
    },
    /// No point of `body` may pass `face`.
    Beyond { body: RigidBodyHandle, face: Face },
    /// The centre of mass of `body` must stay in `region`.
    Inside { body: RigidBodyHandle, region: Aabb },
}

impl Guard {
    /// The guarded body.
    pub fn body(&self) -> RigidBodyHandle {
        match *self {
            Guard::Crossing { body, .. }
            | Guard::Beyond { body, .. }
            | Guard::Inside { body, .. } => body,
        }
    }
}

/// One tunnelling event.
#[derive(Clone, Copy, Debug)]
pub struct GuardEvent {
    /// Index of the guard in the scene's list.
    pub guard: usize,
    /// Step at whose end the event was seen (0-based).
    pub step: usize,
    /// Where: the body's centre of mass after the step (world, metres).
    pub at: Vector,
}

/// Remembers which guards are already violated, so a lasting violation is
/// counted once.
#[derive(Clone, Debug)]
pub struct GuardWatch {
    violated: Vec<bool>,
}

impl GuardWatch {
    /// Starts watching; a guard already violated at the start is not counted.
    pub fn new(world: &PhysicsWorld, guards: &[Guard]) -> Self {
        let violated = guards.iter().map(|g| is_violated_now(world, g)).collect();
        Self { violated }
    }

    /// Checks every guard after a step. `before` is the state before the step.
    pub fn check(
        &mut self,
        world: &PhysicsWorld,
        guards: &[Guard],
        before: &Snapshot,
        step: usize,
    ) -> Vec<GuardEvent> {
        let mut events = Vec::new();
        for (index, guard) in guards.iter().enumerate() {
            let Some(body) = world.bodies.get(guard.body()) else {
                continue;
            };
            let at = body.center_of_mass();
            let hit = match *guard {
                Guard::Crossing { body, obstacle } => crossed(world, before, body, obstacle),
                Guard::Beyond { .. } | Guard::Inside { .. } => {
                    let now = is_violated_now(world, guard);
                    let started = now && !self.violated.get(index).copied().unwrap_or(false);
                    if let Some(flag) = self.violated.get_mut(index) {
                        *flag = now;
                    }
                    started
                }
            };
            if hit {
                events.push(GuardEvent {
                    guard: index,
                    step,
                    at,
                });
            }
        }
        events
    }
}

/// Whether a state guard (`Beyond`, `Inside`) is violated in the current
/// world. `Crossing` is about a step, never violated "now".
fn is_violated_now(world: &PhysicsWorld, guard: &Guard) -> bool {
    let Some(body) = world.bodies.get(guard.body()) else {
        return false;
    };
    match *guard {
        Guard::Crossing { .. } => false,
        Guard::Inside { region, .. } => {
            let c = body.center_of_mass();
            !(c.cmpge(region.mins).all() && c.cmple(region.maxs).all())
        }
        Guard::Beyond { face, .. } => body.colliders().iter().any(|&handle| {
            world.colliders.get(handle).is_some_and(|collider| {
                let point = extreme_point(collider.shape(), collider.position(), face.normal);
                face.is_passed_by(point)
            })
        }),
    }
}

/// Whether the centre of mass of `body` entered or crossed `obstacle` over the
/// last step, seen from the obstacle's frame.
fn crossed(
    world: &PhysicsWorld,
    before: &Snapshot,
    body: RigidBodyHandle,
    obstacle: ColliderHandle,
) -> bool {
    let (Some(rb), Some(collider)) = (world.bodies.get(body), world.colliders.get(obstacle)) else {
        return false;
    };
    let (Some(com0), Some(pose0)) = (before.com(body), before.colliders.get(&obstacle)) else {
        return false;
    };
    let shape = collider.shape();
    let p0 = pose0.inverse_transform_point(com0);
    let p1 = collider
        .position()
        .inverse_transform_point(rb.center_of_mass());
    let dir = p1 - p0;
    if !dir.is_finite() || dir == Vector::ZERO || shape.contains_local_point(p0) {
        return false;
    }
    shape
        .cast_local_ray(&Ray::new(p0, dir), 1.0, true)
        .is_some()
}

/// The point of `shape` (placed at `pose`) farthest along `dir`.
///
/// Exact for convex shapes, compounds of convex shapes and triangle meshes;
/// the bounding-box corner for anything else (conservative: it may report a
/// point a little farther out than the shape reaches).
pub fn extreme_point(shape: &dyn Shape, pose: &Pose, dir: Vector) -> Vector {
    if let Some(support) = shape.as_support_map() {
        return support.support_point(pose, dir);
    }
    match shape.as_typed_shape() {
        TypedShape::Compound(compound) => compound
            .shapes()
            .iter()
            .map(|(child_pose, child)| extreme_point(child.as_ref(), &(*pose * *child_pose), dir))
            .max_by(|a, b| a.dot(dir).total_cmp(&b.dot(dir)))
            .unwrap_or(pose.translation),
        TypedShape::TriMesh(mesh) => mesh
            .vertices()
            .iter()
            .map(|v| pose.transform_point(*v))
            .max_by(|a, b| a.dot(dir).total_cmp(&b.dot(dir)))
            .unwrap_or(pose.translation),
        _ => {
            let aabb = shape.compute_aabb(pose);
            Vector::new(
                if dir.x >= 0.0 {
                    aabb.maxs.x
                } else {
                    aabb.mins.x
                },
                if dir.y >= 0.0 {
                    aabb.maxs.y
                } else {
                    aabb.mins.y
                },
                if dir.z >= 0.0 {
                    aabb.maxs.z
                } else {
                    aabb.mins.z
                },
            )
        }
    }
}
