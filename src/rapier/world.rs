//! What the stage reads of the world during one step: the rapier sets and
//! the user's hooks ([`StageWorld`]), and the moved bodies' motions by handle
//! ([`StepMotions`]).

use super::backoff::HandBack;
use super::candidates::{rough_swept_box, swept_aabb};
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
use std::convert::Infallible;
use std::sync::atomic::{AtomicU64, Ordering};

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

impl<'a> StageWorld<'a> {
    /// The enabled colliders of `body`, with their handles.
    pub fn colliders_of(
        &self,
        body: RigidBodyHandle,
    ) -> impl Iterator<Item = (ColliderHandle, &'a Collider)> + 'a {
        let colliders = self.colliders;
        let handles = self.bodies.get(body).map_or(&[][..], |rb| rb.colliders());
        handles
            .iter()
            .filter_map(move |&h| colliders.get(h).map(|co| (h, co)))
            .filter(|(_, co)| co.is_enabled())
    }

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
///
/// Entries sit at their collider handle's slot (a hash of the handle cost
/// more than the lookup itself), each marked with the handle and the step it
/// was built in, so clearing is one counter.
#[derive(Default)]
pub(crate) struct MotionCache {
    built: Vec<Option<Slot<Built>>>,
    /// Rough boxes (`candidates::rough_swept_box`) by collider slot: the
    /// broad phase finds the same moving colliders again in every sweep of
    /// a step (each query box is widened by the largest travel), most of
    /// whose motions are never built.
    rough: Vec<Option<Slot<Aabb>>>,
    step: u64,
}

/// A value kept at a collider's slot, with what it was made from.
struct Slot<T> {
    handle: ColliderHandle,
    step: u64,
    stamp: Option<Stamp>,
    /// The last motion set (`StepMotions::id`) it was made or found fresh
    /// under: asked under the same set again, it is fresh without
    /// comparing the stamp (two poses and two vectors).
    seen: u64,
    value: T,
}

/// The fresh value at collider `handle`'s slot of `slots` for `step` and
/// `motions`, made with `make` when missing or stale (`make`'s error
/// leaves the slot as it was).
fn fresh_slot<'s, T, E>(
    slots: &'s mut Vec<Option<Slot<T>>>,
    step: u64,
    motions: &StepMotions,
    handle: ColliderHandle,
    co: &Collider,
    make: impl FnOnce() -> Result<T, E>,
) -> Result<&'s mut T, E> {
    let i = handle.into_raw_parts().0 as usize;
    if i >= slots.len() {
        slots.resize_with(i + 1, || None);
    }
    let ours = |s: &Slot<T>| s.handle == handle && s.step == step;
    if !slots[i]
        .as_ref()
        .is_some_and(|s| ours(s) && s.seen == motions.id)
    {
        let stamp = Stamp::of(motions, co);
        match &mut slots[i] {
            Some(s) if ours(s) && s.stamp == stamp => s.seen = motions.id,
            slot => {
                *slot = Some(Slot {
                    handle,
                    step,
                    stamp,
                    seen: motions.id,
                    value: make()?,
                })
            }
        }
    }
    Ok(&mut slots[i].as_mut().expect("just made").value)
}

/// A collider's motion and, once asked for, the box it sweeps.
struct Built {
    motion: Motion,
    swept: Option<Aabb>,
}

impl Built {
    /// The box the collider sweeps, made on first need.
    fn swept(&mut self, co: &Collider) -> Aabb {
        let motion = &self.motion;
        *self
            .swept
            .get_or_insert_with(|| swept_aabb(co.shape(), motion))
    }
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

impl Stamp {
    /// What collider `co`'s motion is built from, if its body moved.
    fn of(motions: &StepMotions, co: &Collider) -> Option<Stamp> {
        co.parent().and_then(|h| motions.body(h)).map(|m| Stamp {
            start: m.start,
            end: m.end,
            angvel: m.angvel,
            accel: m.accel,
            dt: motions.dt,
        })
    }
}

impl MotionCache {
    pub fn clear(&mut self) {
        self.step += 1;
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

    /// The box collider `handle` sweeps (`candidates::swept_aabb`) and its
    /// motion, each built once per body motion, from one lookup; the
    /// motion read in place (a test that only reads it need not copy its
    /// 240 bytes).
    pub fn swept_motion(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<(Aabb, &Motion), CcdError> {
        let built = self.entry(motions, handle, co, bodies)?;
        Ok((built.swept(co), &built.motion))
    }

    /// The box collider `handle` sweeps over the step, built once per body
    /// motion (without copying the motion out: a broad-phase filter asks
    /// for the boxes of every candidate and the motions of few).
    pub fn swept(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<Aabb, CcdError> {
        Ok(self.entry(motions, handle, co, bodies)?.swept(co))
    }

    /// The rough box of collider `handle` over the step
    /// (`candidates::rough_swept_box`), made once per body motion.
    pub fn rough(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Aabb {
        let make = || Ok::<_, Infallible>(rough_swept_box(motions, co, bodies));
        let Ok(rough) = fresh_slot(&mut self.rough, self.step, motions, handle, co, make);
        *rough
    }

    fn entry(
        &mut self,
        motions: &StepMotions,
        handle: ColliderHandle,
        co: &Collider,
        bodies: &RigidBodySet,
    ) -> Result<&mut Built, CcdError> {
        fresh_slot(&mut self.built, self.step, motions, handle, co, || {
            Ok(Built {
                motion: motions.collider(co, bodies)?,
                swept: None,
            })
        })
    }
}

/// The moved bodies of this step, by handle, and the step length.
pub(crate) struct StepMotions<'a> {
    pub moved: &'a [Moved],
    /// Tells this set from every other one built before (see
    /// [`MotionCache`]): while it lives, each body's motion in it is fixed.
    id: u64,
    /// Per body handle slot, its index in `moved` (`u32::MAX`: none).
    index: Vec<u32>,
    pub dt: f64,
    /// Largest travel of any moved body, metres.
    pub margin: f64,
}

impl<'a> StepMotions<'a> {
    pub fn new(moved: &'a [Moved], dt: f64) -> StepMotions<'a> {
        let slot = |h: RigidBodyHandle| h.into_raw_parts().0 as usize;
        let slots = moved.iter().map(|m| slot(m.handle) + 1).max().unwrap_or(0);
        let mut index = vec![u32::MAX; slots];
        for (i, m) in moved.iter().enumerate() {
            index[slot(m.handle)] = i as u32;
        }
        // A counter for identity only (no state rides on it): a round's
        // motions are built anew in the same vector, so its address would
        // not tell one round's set from the next.
        static NEXT_ID: AtomicU64 = AtomicU64::new(0);
        StepMotions {
            moved,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            index,
            dt,
            margin: moved.iter().map(|m| m.travel).fold(0.0, f64::max),
        }
    }

    /// What tells this set from every other one (see [`MotionCache`]).
    pub fn id(&self) -> u64 {
        self.id
    }

    pub fn body(&self, handle: RigidBodyHandle) -> Option<&Moved> {
        let i = *self.index.get(handle.into_raw_parts().0 as usize)?;
        self.moved.get(i as usize).filter(|m| m.handle == handle)
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

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder, Rotation};

    /// The cached rough box is the one `rough_swept_box` makes for the
    /// motion asked about: a body whose motion a round cut (same step, a
    /// nearer end) gets a new box, and the next step starts afresh.
    #[test]
    fn a_cut_motion_gets_a_new_rough_box() {
        let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
        let body = bodies.insert(RigidBodyBuilder::dynamic());
        let h = colliders.insert_with_parent(
            ColliderBuilder::cuboid(0.5, 0.1, 0.2).build(),
            body,
            &mut bodies,
        );
        let co = &colliders[h];
        let record = |end: Vector| Moved {
            handle: body,
            start: Pose::IDENTITY,
            end: Pose::from_parts(end, Rotation::from_rotation_z(0.3)),
            angvel: Vector::new(0.0, 0.0, 18.0),
            accel: Vector::ZERO,
            fast: true,
            pusher: false,
            travel: 10.0,
        };
        let mut cache = MotionCache::default();
        for step in 0..2 {
            cache.clear();
            for end in [
                Vector::new(8.0, 0.0, 0.0),
                Vector::new(2.0 + step as f32, 0.0, 0.0),
            ] {
                let moved = [record(end)];
                let motions = StepMotions::new(&moved, 1.0 / 60.0);
                let direct = rough_swept_box(&motions, co, &bodies);
                // Asked twice: made once, then read back.
                for _ in 0..2 {
                    assert_eq!(cache.rough(&motions, h, co, &bodies), direct, "end {end}");
                }
            }
        }
    }
}
