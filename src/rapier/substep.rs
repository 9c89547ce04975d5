//! Cutting a step into pieces at the first predicted impact
//! (`CcdConfig::substeps` > 1, rapier's `max_ccd_substeps`).
//!
//! Before each piece, every awake body's motion over the rest of the step
//! is predicted from its velocities, the forces on it and gravity, and the
//! fast bodies are swept along it; the earliest impact ends the piece.
//! Rapier then solves the piece and the stage clamps it as in a whole step,
//! so the prediction need not be sound: a piece that ends after the real
//! impact is clamped, one that ends before it costs one more piece.
//! (Colliders added since the last step are not in the broad phase yet,
//! so the prediction does not see them; the piece's clamp does.)
//!
//! Unlike rapier, a piece ends *at* the predicted impact rather than a
//! share of the remaining time after it: the body arrives touching (a skin
//! apart) and a short next piece's contacts bounce it, where a clamp would
//! leave it waiting at the wall for the rest of the piece (see [`piece`]).
//! No piece is shorter than `min_ccd_dt`.
//!
//! A position-based kinematic body goes to its target in whatever time its
//! step is given, so each piece aims it at its pose interpolated at the
//! piece's end (the centre of mass on a line, the rotation by slerp: the
//! constant velocities rapier itself would give it over the whole step).

use super::moved::Moved;
use super::report::CcdReport;
use super::select::body_thickness;
use super::sweep::{self, Targets, Workspace};
use super::world::{StageWorld, StepMotions};
use crate::query::QueryOptions;
use rapier3d::prelude::{
    BroadPhaseBvh, NarrowPhase, Pose, RigidBodyHandle, RigidBodySet, RigidBodyType, Rotation,
    Vector,
};

/// A position-based kinematic body's pose at the step's start and the
/// target the user set for its end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Aim {
    handle: RigidBodyHandle,
    start: Pose,
    target: Pose,
    /// Centre of mass, body frame.
    com: Vector,
}

/// The targets of the position-based kinematic bodies, before the step.
pub(crate) fn record_aims(bodies: &RigidBodySet, out: &mut Vec<Aim>) {
    out.clear();
    for (handle, rb) in bodies.iter() {
        if rb.body_type() == RigidBodyType::KinematicPositionBased && rb.is_enabled() {
            out.push(Aim {
                handle,
                start: *rb.position(),
                target: *rb.next_position(),
                com: rb.local_center_of_mass(),
            });
        }
    }
}

/// The pose of `aim` at `share` of the step (its exact target at 1).
fn pose_at(aim: &Aim, share: f32) -> Pose {
    if share >= 1.0 {
        return aim.target;
    }
    let rotation: Rotation = aim.start.rotation.slerp(aim.target.rotation, share);
    let com = (aim.start * aim.com).lerp(aim.target * aim.com, share);
    Pose::from_parts(com - rotation * aim.com, rotation)
}

/// Aims every position-based kinematic body at its pose at `share` of the
/// step, the end of the coming piece.
pub(crate) fn aim(bodies: &mut RigidBodySet, aims: &[Aim], share: f32) {
    for a in aims {
        if let Some(rb) = bodies.get_mut(a.handle) {
            rb.set_next_kinematic_position(pose_at(a, share));
        }
    }
}

/// Every awake body's motion over the next `horizon` seconds, without
/// contacts: velocity, angular velocity and (dynamic bodies) gravity and
/// the user's force as a constant acceleration. Position-based kinematic
/// bodies go to their target (it is `horizon` away). Fast ones are marked
/// as after a step (`select::moved`).
pub(crate) fn predict(
    scene: &StageWorld,
    gravity: Vector,
    aims: &[Aim],
    horizon: f64,
    out: &mut Vec<Moved>,
) {
    out.clear();
    let h = horizon as f32;
    for (handle, rb) in scene.bodies.iter() {
        if rb.is_fixed() || !rb.is_enabled() || rb.is_sleeping() {
            continue;
        }
        let (start, v, w) = (*rb.position(), rb.linvel(), rb.angvel());
        if !start.is_finite() || !v.is_finite() || !w.is_finite() {
            continue;
        }
        let local_com = rb.local_center_of_mass();
        let aimed = aims.iter().find(|a| a.handle == handle);
        let (end, accel) = match aimed {
            Some(a) => (a.target, Vector::ZERO),
            None => {
                let rotation = Rotation::from_scaled_axis(w * h) * start.rotation;
                let com = start * local_com + v * h;
                let accel = if rb.is_dynamic() {
                    let mass = rb.mass();
                    let force = if mass > 0.0 {
                        rb.user_force() / mass
                    } else {
                        Vector::ZERO
                    };
                    gravity * rb.gravity_scale() + force
                } else {
                    Vector::ZERO
                };
                (
                    Pose::from_parts(com - rotation * local_com, rotation),
                    accel,
                )
            }
        };
        if !end.is_finite() || !accel.is_finite() {
            continue;
        }
        let extent = super::select::turning_extent(rb, scene.colliders);
        let shift = (end * local_com - start * local_com).length() as f64
            + 0.5 * (accel.length() as f64) * horizon * horizon;
        // An aimed body turns the short way (its velocity is last step's).
        let (spin, angvel) = match aimed {
            Some(_) => (super::moved::angle_short(&start, &end), Vector::ZERO),
            None => (w.length() as f64 * horizon, w),
        };
        let travel = super::moved::travel_bound(shift, extent, spin);
        let tunnels =
            shift + extent * spin > scene.config.fast_factor * body_thickness(rb, scene.colliders);
        out.push(Moved {
            handle,
            start,
            end,
            angvel,
            accel,
            fast: rb.is_dynamic() && !scene.config.opted_out(rb.user_data) && tunnels,
            pusher: rb.is_kinematic() && scene.config.targets.kinematic && tunnels,
            travel,
        });
    }
}

/// Seconds from now to the earliest impact of a fast body (or fast
/// kinematic body) on its predicted motion over `horizon`; `None` when
/// none is predicted. Pairs touching at the start are left out: they are
/// the contact solver's (a resting body pulled into the ground would
/// otherwise cut every step). A failed query predicts nothing: the
/// piece's own sweep reports it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn first_impact(
    scene: &StageWorld,
    broad_phase: &BroadPhaseBvh,
    narrow_phase: &NarrowPhase,
    predicted: &[Moved],
    horizon: f64,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
) -> Option<f64> {
    let opts = QueryOptions {
        initial_contact: crate::InitialContact::Ignore,
        ..*opts
    };
    let motions = StepMotions::new(predicted, horizon);
    ws.motions.clear();
    let mut earliest: Option<f64> = None;
    let mut sensors = Vec::new();
    for body in predicted.iter().filter(|m| m.fast || m.pusher) {
        // The prediction's own work is counted, its hits are not clamps.
        let mut scratch = CcdReport::default();
        let found = sweep::sweep_body(
            scene,
            broad_phase,
            narrow_phase.query_dispatcher(),
            &motions,
            body,
            Targets::All,
            &opts,
            ws,
            &mut scratch,
            &mut sensors,
        );
        report.evaluations += scratch.evaluations;
        sensors.clear();
        if let Ok(Some(hit)) = found
            && hit.toi.fraction < 1.0
        {
            let t = hit.toi.fraction * horizon;
            earliest = Some(earliest.map_or(t, |e| e.min(t)));
        }
    }
    earliest
}

/// The length of the next piece (seconds) with `remaining` of the step
/// left, `left` pieces allowed (at least 1) and an impact predicted
/// `impact` seconds ahead; and the pieces allowed after it.
///
/// The piece ends at the impact, but not before `min_dt` (rapier's
/// `1/dt` stays sane) and not `min_dt` or less before the step's end. A
/// short piece is what a bounce wants: rapier's solver turns a velocity
/// in the step that meets the contact but does not move the body in it,
/// so the piece after one that ended at an impact is asked with an impact
/// at 0, the shortest allowed.
pub(crate) fn piece(remaining: f32, left: u32, impact: Option<f64>, min_dt: f32) -> (f32, u32) {
    if left <= 1 {
        return (remaining, 0);
    }
    let Some(impact) = impact else {
        return (remaining, 0);
    };
    let min_dt = min_dt.max(0.0);
    let length = (impact as f32).clamp(min_dt.min(remaining), remaining);
    if remaining - length <= min_dt {
        (remaining, 0)
    } else {
        (length, left - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::piece;

    #[test]
    fn a_piece_ends_at_the_impact_within_its_floors() {
        let dt = 1.0 / 60.0;
        let min = dt / 100.0;
        // No impact, or the last piece allowed: the rest of the step.
        assert_eq!(piece(dt, 4, None, min), (dt, 0));
        assert_eq!(piece(dt, 1, Some(0.001), min), (dt, 0));
        // An impact half way: the piece ends there.
        assert_eq!(piece(dt, 4, Some(0.5 * dt as f64), min), (0.5 * dt, 3));
        // An impact right away (the piece after an impact): the shortest
        // piece, for rapier's contacts to bounce it.
        assert_eq!(piece(dt, 4, Some(0.0), min), (min, 3));
        // An impact at the very end: no sliver piece after it.
        assert_eq!(piece(dt, 4, Some(0.999 * dt as f64), min), (dt, 0));
    }
}
