//! parry's contact query, asked the one way that is right, and the
//! [`Toi`] built from it: the witness points and normal at the reported
//! time.

use super::Toi;
use super::box_overlap::{BoxPair, box_pair};
use crate::convert::{pose_from_iso, vec_from_glam};
use crate::motion::{Motion, Trajectory};
use crate::solve::{RootStatus, SolveOutcome, SolveStats};
use nalgebra::{Isometry3, Point3, Vector3};
use rapier3d::parry::math::Pose;
use rapier3d::parry::query::Contact;
use rapier3d::parry::shape::Shape;

/// parry's contact between two posed shapes within `prediction` metres
/// (`Ok(None)`: farther apart; `Err`: parry has no answer for the pair).
///
/// parry 0.31.1 answers a convex shape against a *second* half-space
/// wrongly (it uses the relative pose where it needs its inverse, so the
/// depth grows with the distance from the plane's origin): the half-space
/// is asked first and the answer flipped back. Two boxes that overlap are
/// answered by their separating axes instead of EPA (see `box_overlap`).
pub(crate) fn contact(
    pose1: &Pose,
    shape1: &dyn Shape,
    pose2: &Pose,
    shape2: &dyn Shape,
    prediction: f32,
) -> Result<Option<Contact>, rapier3d::parry::query::Unsupported> {
    if let (Some(c1), Some(c2)) = (shape1.as_cuboid(), shape2.as_cuboid()) {
        match box_pair(pose1, c1, pose2, c2, prediction as f64) {
            BoxPair::Beyond => return Ok(None),
            BoxPair::Overlap(c) => return Ok(Some(c)),
            BoxPair::Apart => {}
        }
    }
    let flip = shape2.as_halfspace().is_some() && shape1.as_halfspace().is_none();
    if flip {
        rapier3d::parry::query::contact(pose2, shape2, pose1, shape1, prediction)
            .map(|c| c.map(|c| c.flipped()))
    } else {
        rapier3d::parry::query::contact(pose1, shape1, pose2, shape2, prediction)
    }
}

/// Where two shapes meet at a reported time: a point on each (world,
/// metres) and the unit normal from shape 1 towards shape 2.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Witness {
    pub point1: Point3<f64>,
    pub point2: Point3<f64>,
    pub normal1: Vector3<f64>,
}

impl Witness {
    /// The points and normal of a parry contact.
    pub fn of(contact: &Contact) -> Witness {
        Witness {
            point1: Point3::from(vec_from_glam(contact.point1)),
            point2: Point3::from(vec_from_glam(contact.point2)),
            normal1: vec_from_glam(contact.normal1),
        }
    }

    /// When parry cannot say: the frames' origins and the direction between
    /// them (zero when they coincide).
    pub fn origins(iso1: &Isometry3<f64>, iso2: &Isometry3<f64>) -> Witness {
        let (o1, o2) = (iso1.translation.vector, iso2.translation.vector);
        Witness {
            point1: Point3::from(o1),
            point2: Point3::from(o2),
            normal1: (o2 - o1).try_normalize(0.0).unwrap_or_else(Vector3::zeros),
        }
    }
}

impl Toi {
    /// The time of impact at `fraction` of a step of `dt` seconds.
    pub(crate) fn new(
        fraction: f64,
        dt: f64,
        status: RootStatus,
        witness: Witness,
        stats: SolveStats,
    ) -> Toi {
        Toi {
            fraction,
            time: fraction * dt,
            status,
            witness1: witness.point1,
            witness2: witness.point2,
            normal1: witness.normal1,
            stats,
        }
    }
}

/// The [`Toi`] of a search outcome: the time, and the witness points and
/// normal from parry's contact query at the poses of that time.
pub(super) fn describe(
    outcome: &SolveOutcome,
    skin: f64,
    shape1: &dyn Shape,
    motion1: &Motion,
    shape2: &dyn Shape,
    motion2: &Motion,
) -> Toi {
    let fraction = outcome.time;
    let dt = motion1.dt().max(motion2.dt());
    let (iso1, iso2) = (motion1.pose_at(fraction), motion2.pose_at(fraction));
    let (pose1, pose2) = (pose_from_iso(&iso1), pose_from_iso(&iso2));
    // At the reported time the shapes are about `skin` apart. A bounded
    // prediction keeps parry's composite contact to the mesh parts nearby
    // (an unbounded one visits every triangle); widen it only if needed.
    let witness = [1.0e-2f32, 1.0, 1.0e2, f32::MAX]
        .into_iter()
        .find_map(|extra| {
            contact(&pose1, shape1, &pose2, shape2, skin as f32 + extra)
                .ok()
                .flatten()
        })
        .map_or_else(|| Witness::origins(&iso1, &iso2), |c| Witness::of(&c));
    Toi::new(fraction, dt, outcome.status, witness, outcome.stats)
}
