//! Applying an impact: the body goes back to its pose at the reported time.
//!
//! The time is already where the body should stand (`backoff` chose it
//! from the true contact). Velocities are kept: the next step's
//! speculative contacts stop the body, as with rapier's own CCD.

use super::moved::Moved;
use crate::convert::{iso_from_pose, point_from_glam, pose_from_iso, vec_from_glam};
use crate::error::CcdError;
use crate::motion::{Motion, Trajectory};
use rapier3d::prelude::{ColliderSet, RigidBodySet};

/// The body's motion cut short at `fraction`: it ends at its pose at
/// `fraction`, and runs between its two poses as every motion between two
/// poses does in the stage (whole turns from the angular velocity only when
/// it matches, `select::turn_hint`). `true` with it when that is not the
/// same path as the part of the old motion (a fast spinner cut where its
/// orientation matches a free spin again): the cut motion then needs a
/// full sweep.
pub(crate) fn truncate(
    bodies: &RigidBodySet,
    body: &Moved,
    fraction: f64,
    dt: f64,
) -> Result<(Moved, bool), CcdError> {
    let Some(rb) = bodies.get(body.handle) else {
        return Ok((*body, false));
    };
    let com = point_from_glam(rb.local_center_of_mass());
    let motion = Motion::from_poses(
        iso_from_pose(&body.start),
        iso_from_pose(&body.end),
        com,
        dt,
        vec_from_glam(body.angvel),
    )?;
    let pose = pose_from_iso(&motion.pose_at(fraction));
    if !pose.is_finite() {
        return Err(CcdError::NonFinite {
            what: "clamped pose",
            value: f64::NAN,
        });
    }
    let hint = super::turns::turn_hint(rb, &body.start, &pose, dt);
    let cut = Motion::from_poses(
        iso_from_pose(&body.start),
        iso_from_pose(&pose),
        com,
        dt,
        vec_from_glam(hint),
    )?;
    let rerouted = (cut.rotation() - motion.rotation() * fraction).norm() > 1.0e-3;
    Ok((
        Moved {
            end: pose,
            angvel: hint,
            accel: rapier3d::prelude::Vector::ZERO,
            ..*body
        },
        rerouted,
    ))
}

/// The body carried from `fraction` on by `pusher` (a kinematic body, or a
/// body it carries): its pose at `fraction` moved rigidly with the pusher
/// to the pusher's end, and the pusher's velocity at its centre of mass
/// there. It ends touching the pusher (a skin apart), so the next step's
/// contacts push it on; between its two poses it keeps the relative
/// approach of its first `fraction` of the step, so it meets the pusher
/// nowhere before.
pub(crate) fn carry(
    bodies: &RigidBodySet,
    body: &Moved,
    pusher: &Moved,
    fraction: f64,
    dt: f64,
) -> Result<(Moved, rapier3d::prelude::Vector), CcdError> {
    let (Some(rb), Some(pb)) = (bodies.get(body.handle), bodies.get(pusher.handle)) else {
        return Err(CcdError::NonFinite {
            what: "carried body",
            value: f64::NAN,
        });
    };
    let motion = |m: &Moved, com| {
        Motion::from_poses(
            iso_from_pose(&m.start),
            iso_from_pose(&m.end),
            point_from_glam(com),
            dt,
            vec_from_glam(m.angvel),
        )
    };
    let own = motion(body, rb.local_center_of_mass())?;
    let push = motion(pusher, pb.local_center_of_mass())?;
    let end = push.pose_at(1.0) * push.pose_at(fraction).inverse() * own.pose_at(fraction);
    let end = pose_from_iso(&end);
    if !end.is_finite() {
        return Err(CcdError::NonFinite {
            what: "carried pose",
            value: f64::NAN,
        });
    }
    let com = end * rb.local_center_of_mass();
    let pcom = pusher.end * pb.local_center_of_mass();
    let velocity = pb.linvel() + pb.angvel().cross(com - pcom);
    let travel = super::moved::travel_between(rb, &body.start, &end);
    Ok((
        Moved {
            end,
            angvel: rapier3d::prelude::Vector::ZERO,
            accel: rapier3d::prelude::Vector::ZERO,
            travel: travel.max(body.travel),
            ..*body
        },
        velocity,
    ))
}

/// Moves the body to the end of its (cut) motion. `set_position` marks it
/// modified, so rapier resyncs its colliders and broad-phase boxes at the
/// next step's start; call [`sync_colliders`] once after all clamps for
/// queries in between.
pub(crate) fn clamp(bodies: &mut RigidBodySet, body: &Moved) {
    if let Some(rb) = bodies.get_mut(body.handle) {
        rb.set_position(body.end, true);
    }
}

/// Brings the colliders of clamped bodies to their new poses now, so that
/// scene queries and reads between steps see them.
pub(crate) fn sync_colliders(bodies: &RigidBodySet, colliders: &mut ColliderSet) {
    bodies.propagate_modified_body_positions_to_colliders(colliders);
}
