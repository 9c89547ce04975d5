//! What the stage reads of the world during one step: the rapier sets and
//! the user's hooks ([`StageWorld`]), and the moved bodies' motions by handle
//! ([`StepMotions`]).

use super::backoff::HandBack;
use super::candidates::swept_aabb;
use super::config::CcdConfig;
use super::moved::Moved;
use crate::convert::{iso_from_pose, point_from_glam, vec_from_glam};
use crate::error::CcdError;
use crate::motion::Motion;
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::prelude::{
    Collider, ColliderHandle, ColliderSet, ImpulseJointSet, PhysicsHooks, Pose, RigidBodyHandle,
    RigidBodySet, Vector,
};
use std::collections::HashMap;

/// Everything the pair rules read.
pub(crate) struct StageWorld<'a> {
    pub bodies: &'a RigidBodySet,
    pub colliders: &'a ColliderSet,
    pub joints: &'a ImpulseJointSet,
    pub hooks: &'a dyn PhysicsHooks,
    pub config: &'a CcdConfig,
    /// Rapier's allowed linear error, metres: where its own CCD stops a
    /// pair (see `backoff`).
    pub slop: f64,
}

impl StageWorld<'_> {
    /// The rules a hit is handed back by.
    pub fn hand_back(&self) -> HandBack {
        HandBack {
            sink: self.config.sink,
            slop: self.slop,
        }
    }
}

/// Collider motions built this step, each with what it was built from
/// and, once asked for, its swept box: a step asks for the same motions
/// and boxes in every round and every push (the box of a moving candidate
/// takes two parry boxes and two poses). A body whose motion a round cut
/// gets a new one. Clear it between steps.
#[derive(Default)]
pub(crate) struct MotionCache {
    built: HashMap<ColliderHandle, Built>,
}

struct Built {
    stamp: Option<Stamp>,
    motion: Motion,
    swept: Option<Aabb>,
}

/// What a collider's motion is built from: its body's two poses, turn hint
/// and acceleration, and the step length (`None`: the collider's body did
/// not move, its motion is its pose).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stamp {
    start: Pose,
    end: Pose,
    angvel: Vector,
    accel: Vector,
    dt: f64,
}

impl MotionCache {
    pub fn clear(&mut self) {
        self.built.clear();
    }

    /// The motion of collider `handle` over the step, built once per body
    /// motion.
    pub fn get(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<Motion, CcdError> {
        Ok(self.entry(motions, handle, co, bodies)?.motion)
    }

    /// The motion of collider `handle` and the box it sweeps
    /// (`candidates::swept_aabb`), each built once per body motion.
    pub fn get_swept(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<(Motion, Aabb), CcdError> {
        let built = self.entry(motions, handle, co, bodies)?;
        let motion = built.motion;
        let swept = *built
            .swept
            .get_or_insert_with(|| swept_aabb(co.shape(), &motion));
        Ok((motion, swept))
    }

    fn entry(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<&mut Built, CcdError> {
        let stamp = co.parent().and_then(|h| motions.body(h)).map(|m| Stamp {
            start: m.start,
            end: m.end,
            angvel: m.angvel,
            accel: m.accel,
            dt: motions.dt,
        });
        let stale = self.built.get(&handle).is_none_or(|b| b.stamp != stamp);
        if stale {
            let motion = motions.collider(co, bodies)?;
            self.built.insert(
                handle,
                Built {
                    stamp,
                    motion,
                    swept: None,
                },
            );
        }
        Ok(self.built.get_mut(&handle).expect("just built"))
    }
}

/// The moved bodies of this step, by handle, and the step length.
pub(crate) struct StepMotions<'a> {
    pub moved: &'a [Moved],
    pub index: HashMap<RigidBodyHandle, usize>,
    pub dt: f64,
    /// Largest travel of any moved body, metres.
    pub margin: f64,
}

impl<'a> StepMotions<'a> {
    pub fn new(moved: &'a [Moved], dt: f64) -> StepMotions<'a> {
        StepMotions {
            moved,
            index: moved
                .iter()
                .enumerate()
                .map(|(i, m)| (m.handle, i))
                .collect(),
            dt,
            margin: moved.iter().map(|m| m.travel).fold(0.0, f64::max),
        }
    }

    pub fn body(&self, handle: RigidBodyHandle) -> Option<&Moved> {
        self.index.get(&handle).map(|i| &self.moved[*i])
    }

    /// A collider's motion over the step: its body's, or none.
    pub fn collider(&self, co: &Collider, bodies: &RigidBodySet) -> Result<Motion, CcdError> {
        let moved = co.parent().and_then(|h| self.body(h));
        match (
            moved,
            co.position_wrt_parent(),
            co.parent().and_then(|h| bodies.get(h)),
        ) {
            (Some(m), Some(local), Some(rb)) => {
                let motion = Motion::from_poses(
                    iso_from_pose(&(m.start * *local)),
                    iso_from_pose(&(m.end * *local)),
                    point_from_glam(local.inverse_transform_point(rb.local_center_of_mass())),
                    self.dt,
                    vec_from_glam(m.angvel),
                )?;
                if m.accel == Vector::ZERO {
                    Ok(motion)
                } else {
                    motion.with_acceleration(vec_from_glam(m.accel))
                }
            }
            _ => Motion::fixed(iso_from_pose(co.position())),
        }
    }
}
