//! Which bodies moved, and which of them can tunnel.
//!
//! Before the step we record the pose of every enabled, non-fixed body,
//! asleep or not (targets that move need their start pose too, and a
//! sleeping body may be woken and thrown during the step): an awake one in
//! the list of starts, a sleeping one only in a table by arena index, which
//! is read after the step for the bodies rapier woke (those in its awake
//! set that were not in the starts). A body that sleeps through the step
//! is not looked at again. After the step we keep the
//! dynamic ones whose fastest point went farther than `fast_factor` times
//! their thinnest extent: rapier's post-solve test, with the rotation
//! counted as an arc (whole turns included, through the velocity term)
//! instead of a chord. Everything here reads bodies, never writes them,
//! so a step with no fast body leaves rapier's state untouched.

use super::config::CcdConfig;
use super::moved::{Moved, Start, angle_bound, angle_short, half_angle_sine, travel_bound};
use super::report::{CcdReport, SkipReason};
use super::turns::turn_hint;
use rapier3d::parry::shape::{Shape, TypedShape};
use rapier3d::prelude::{
    ColliderSet, IslandManager, Pose, RigidBody, RigidBodyHandle, RigidBodySet, Vector,
};
use std::f64::consts::PI;

fn finite_vels(rb: &RigidBody) -> bool {
    rb.linvel().is_finite() && rb.angvel().is_finite()
}

/// The poses of the bodies asleep before the step, by arena index, each
/// with the number of the step that wrote it (only this step's are read).
#[derive(Default)]
pub(crate) struct Asleep {
    step: u32,
    /// How many entries this step wrote.
    count: usize,
    poses: Vec<(u32, Pose)>,
}

impl Asleep {
    fn put(&mut self, handle: RigidBodyHandle, pose: &Pose) {
        let index = handle.into_raw_parts().0 as usize;
        if index >= self.poses.len() {
            self.grow(index);
        }
        let entry = &mut self.poses[index];
        entry.0 = self.step;
        entry.1 = *pose;
        self.count += 1;
    }

    #[cold]
    fn grow(&mut self, index: usize) {
        self.poses.resize(index + 1, (0, Pose::IDENTITY));
    }

    /// The pose `handle`'s body had before this step, if it was asleep.
    fn get(&self, handle: RigidBodyHandle) -> Option<Pose> {
        let (step, pose) = *self.poses.get(handle.into_raw_parts().0 as usize)?;
        (step == self.step).then_some(pose)
    }
}

/// The poses of the bodies that may move during the next step, sleeping
/// ones included: a body asleep at the start can be woken by a hit during
/// the step and leave it fast (the long soak lost a resting compound
/// through the floor that way). Awake ones go to `out`; sleeping ones to
/// `asleep`, which [`add_woken`] reads after the step: most sleeping
/// bodies are never woken, and looking each one up and comparing its pose
/// after the step cost more than rapier's whole step in a world of
/// sleeping bodies (which rapier skips). A body with a non-finite
/// state is recorded as it is: rapier's step quarantines it (disables it
/// and names it, and the stage reports it), and [`moved`] checks what it
/// reads after the step.
pub(crate) fn record(bodies: &RigidBodySet, out: &mut Vec<Start>, asleep: &mut Asleep) {
    out.clear();
    // Never 0, the step number of an entry not yet written.
    asleep.step = asleep.step.checked_add(1).unwrap_or(1);
    asleep.count = 0;
    for (handle, rb) in bodies.iter() {
        // Tested first, as most bodies of a large world sleep. A fixed or
        // disabled one in the table is harmless: never in rapier's awake
        // set, it is never read.
        if rb.is_sleeping() {
            asleep.put(handle, rb.position());
        } else if !rb.is_fixed() && rb.is_enabled() {
            out.push(Start {
                handle,
                pose: *rb.position(),
            });
        }
    }
}

/// Adds to `starts` the bodies rapier woke during the step: those of its
/// awake set that were asleep before it, at the pose `record` kept. A
/// body rapier moves is in its awake set, and a body it wakes stays awake
/// for a while (a wake-up resets its sleep timer), so no body that moved is
/// left out. (With a sleep timer set to zero a woken body could fall
/// asleep again at the end of the step; rapier then found it slow and
/// hardly displaced, and it is left out as a target that did not move.)
/// `starts` stays in arena order, the order `record` writes.
pub(crate) fn add_woken(islands: &IslandManager, asleep: &Asleep, starts: &mut Vec<Start>) {
    if asleep.count == 0 {
        return;
    }
    let recorded = starts.len();
    for handle in islands.active_bodies() {
        if let Some(pose) = asleep.get(handle) {
            starts.push(Start { handle, pose });
        }
    }
    if starts.len() > recorded {
        starts.sort_unstable_by_key(|s| s.handle.into_raw_parts().0);
    }
}

/// The thinnest extent rapier's test compares the motion with, metres.
/// Meshes, polylines and heightfields have no thickness in parry (0); they
/// get their local box's smallest half extent instead, so that a slowly
/// moving mesh body is not swept every step.
pub(crate) fn thickness(shape: &dyn Shape) -> f64 {
    match shape.as_typed_shape() {
        TypedShape::TriMesh(_)
        | TypedShape::Polyline(_)
        | TypedShape::HeightField(_)
        | TypedShape::Voxels(_) => shape.compute_local_aabb().half_extents().min_element() as f64,
        // Parry's `ccd_thickness` of the two commonest shapes, read without
        // a second dynamic call (this runs for every moving body every step).
        TypedShape::Ball(ball) => ball.radius as f64,
        TypedShape::Cuboid(cuboid) => cuboid.half_extents.min_element() as f64,
        _ => shape.ccd_thickness() as f64,
    }
}

/// How far the body's colliders reach from its centre of mass, for how
/// far they move when it turns, metres: rapier's `max_extent`, except that
/// a body of balls counts only their centres (a ball turns into itself: a
/// rolling ball moves no farther than its centre does).
pub(crate) fn turning_extent(rb: &RigidBody, colliders: &ColliderSet) -> f64 {
    let com = rb.local_center_of_mass();
    let mut extent = 0.0f64;
    for co in rb.colliders().iter().filter_map(|h| colliders.get(*h)) {
        if !co.is_enabled() {
            continue;
        }
        // One dispatch on the shape's type (`as_ball` takes two).
        match (co.shape().as_typed_shape(), co.position_wrt_parent()) {
            (TypedShape::Ball(_), Some(local)) => {
                extent = extent.max((local.translation - com).length() as f64);
            }
            _ => return rb.mass_properties().max_extent() as f64,
        }
    }
    extent
}

/// The thinnest of the body's enabled colliders (`thickness`), metres;
/// infinite for a body without one. A plain loop: it runs for every
/// moving body every step.
pub(crate) fn body_thickness(rb: &RigidBody, colliders: &ColliderSet) -> f64 {
    let mut thinnest = f64::INFINITY;
    for handle in rb.colliders() {
        if let Some(co) = colliders.get(*handle)
            && co.is_enabled()
        {
            thinnest = thinnest.min(thickness(co.shape()));
        }
    }
    thinnest
}

/// Whether `rb`, which moved from `start` to `end`, may tunnel: its
/// fastest point went (or its velocity would take it) farther than
/// `fast_factor` times its thickness within `horizon` (at least `dt`)
/// seconds. The rotation counts as an arc (whole turns included, through
/// the velocity term) instead of rapier's chord.
///
/// Most bodies that move are slow, so a cheap bound is tried first: the
/// short angle is at most `π·|sin(angle/2)|` (no atan2), the centre of
/// mass moves at most the origin's shift plus its chord (no pose
/// transforms), and rapier's
/// `max_extent` bounds every collider's distance from the centre of mass
/// (no walk over the colliders for it; rapier's step has just brought it
/// up to date with any collider the user changed). Only a body that bound
/// cannot clear gets the exact test, whose answer is then the one returned,
/// with what it measured (for the body's `travel`).
fn tunnels(
    rb: &RigidBody,
    colliders: &ColliderSet,
    start: &Pose,
    end: &Pose,
    dt: f64,
    horizon: f64,
    fast_factor: f64,
) -> (bool, Option<Measured>) {
    let com = rb.local_center_of_mass();
    let (linvel, angvel) = (rb.linvel().length() as f64, rb.angvel().length() as f64);
    let spin = angvel * dt;
    let horizon = horizon.max(dt);
    let allowed = fast_factor * body_thickness(rb, colliders);
    // Cheap upper bound of the exact measure below, padded for rounding.
    // `sine` is |sin(angle/2)|: the centre of mass moves by the origin's
    // shift plus at most its chord, `2·sine·|com|` (no pose transforms).
    let sine = half_angle_sine(start, end);
    let offset = com.length() as f64;
    let origin_shift = (end.translation - start.translation).length() as f64;
    let shift_bound = origin_shift + 2.0 * sine * offset + 1.0e-5 * offset;
    let reach = rb.mass_properties().max_extent() as f64;
    let bound =
        (shift_bound + reach * (PI * sine).max(spin)).max((linvel + angvel * reach) * horizon);
    if bound * (1.0 + 1.0e-6) <= allowed {
        return (false, None);
    }
    let shift = (*end * com - *start * com).length() as f64;
    let extent = turning_extent(rb, colliders);
    let short = angle_short(start, end);
    // Arc length of the farthest point; the velocity term is rapier's.
    let arc = shift + extent * short.max(spin);
    let by_velocity = (linvel + angvel * extent) * horizon;
    // Not `max`, which would drop a NaN: a body in a non-finite state
    // counts as fast, and the records' pass reports it.
    let slow = arc <= allowed && by_velocity <= allowed;
    let measured = Measured {
        short,
        extent,
        shift,
    };
    (!slow, Some(measured))
}

/// What the exact test of [`tunnels`] measured of a body's motion: its
/// short angle, turning extent and centre of mass's shift, which its
/// record's travel is bounded from.
#[derive(Clone, Copy, Debug)]
struct Measured {
    short: f64,
    extent: f64,
    shift: f64,
}

/// A moved body as the first pass of [`moved`] saw it: its index in the
/// starts, whether it may tunnel, and what the exact test measured if it
/// ran.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Seen {
    start: u32,
    tunnels: bool,
    exact: Option<Measured>,
}

/// The bodies of `starts` that moved during `dt` seconds, each marked fast
/// or not; none when no body is fast (nor a fast kinematic pusher), for
/// then nothing is swept. A body counts as fast when its velocity would
/// take it across its thickness within `horizon` seconds (`dt`, or the
/// whole step when `dt` is a piece of it: a body that tunnels over the
/// step is swept in every piece, however short). A body in a non-finite
/// state counts as fast, and is reported and left out of the records.
///
/// Two passes: the first tests every moved body into `seen`, the second
/// (only when one is fast) builds their records, the targets the fast ones
/// are swept against.
#[allow(clippy::too_many_arguments)]
pub(crate) fn moved(
    starts: &[Start],
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    dt: f64,
    horizon: f64,
    config: &CcdConfig,
    report: &mut CcdReport,
    seen: &mut Vec<Seen>,
    out: &mut Vec<Moved>,
) {
    out.clear();
    seen.clear();
    let mut any_fast = false;
    for (i, start) in starts.iter().enumerate() {
        let Some((rb, end)) = moved_body(start, bodies) else {
            continue;
        };
        let (tunnels, exact) = if may_flag(rb, config) {
            tunnels(
                rb,
                colliders,
                &start.pose,
                end,
                dt,
                horizon,
                config.fast_factor,
            )
        } else {
            (false, None)
        };
        any_fast |= tunnels;
        seen.push(Seen {
            start: i as u32,
            tunnels,
            exact,
        });
    }
    if !any_fast {
        return;
    }
    for s in seen.iter() {
        let start = &starts[s.start as usize];
        let Some((rb, end)) = moved_body(start, bodies) else {
            continue;
        };
        // Rapier's quarantine leaves no enabled body in a non-finite state
        // after its step; checked again before anything is swept.
        if !start.pose.is_finite() || !end.is_finite() || !finite_vels(rb) {
            report.skip(start.handle, SkipReason::NonFinite);
            continue;
        }
        let end = *end;
        let spin = rb.angvel().length() as f64 * dt;
        // A body the cheap bound cleared gets the same kind of bound on its
        // travel: rapier's reach for the turning extent, and `π·|sin(θ/2)|`
        // for the short angle (no atan2, no walk over the colliders).
        let Measured {
            short,
            extent,
            shift,
        } = s.exact.unwrap_or_else(|| {
            let com = rb.local_center_of_mass();
            let sine = half_angle_sine(&start.pose, &end).min(1.0);
            Measured {
                short: (PI * sine) * (1.0 + 1.0e-6),
                extent: rb.mass_properties().max_extent() as f64,
                shift: (end * com - start.pose * com).length() as f64,
            }
        });
        out.push(Moved {
            handle: start.handle,
            start: start.pose,
            end,
            angvel: turn_hint(rb, &start.pose, &end, dt),
            accel: Vector::ZERO,
            fast: rb.is_dynamic() && s.tunnels,
            pusher: rb.is_kinematic() && s.tunnels,
            travel: travel_bound(shift, extent, angle_bound(short, spin)),
        });
    }
}

/// The body of `start` and its pose now, if it is enabled and moved (a
/// non-finite pose never equals itself, so it counts as moved).
fn moved_body<'a>(start: &Start, bodies: &'a RigidBodySet) -> Option<(&'a RigidBody, &'a Pose)> {
    let rb = bodies.get(start.handle)?;
    let end = rb.position();
    (rb.is_enabled() && *end != start.pose).then_some((rb, end))
}

/// Whether `rb` can be marked fast (a dynamic body not opted out) or a
/// pusher (a kinematic one, when kinematic targets are swept).
fn may_flag(rb: &RigidBody, config: &CcdConfig) -> bool {
    (rb.is_dynamic() && !config.opted_out(rb.user_data))
        || (rb.is_kinematic() && config.targets.kinematic)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder, Rotation};

    /// The exact measure `tunnels` compares with the allowed distance,
    /// without its cheap first bound.
    fn exact_measure(rb: &RigidBody, colliders: &ColliderSet, start: &Pose, end: &Pose) -> f64 {
        let (dt, com) = (1.0 / 60.0, rb.local_center_of_mass());
        let shift = (*end * com - *start * com).length() as f64;
        let extent = turning_extent(rb, colliders);
        let spin = rb.angvel().length() as f64 * dt;
        let arc = shift + extent * angle_short(start, end).max(spin);
        let by_velocity = (rb.linvel().length() as f64 + rb.angvel().length() as f64 * extent) * dt;
        arc.max(by_velocity)
    }

    /// `add_woken` reads only the poses the last `record` wrote: a body
    /// asleep in an earlier step and awake since is not taken for woken.
    #[test]
    fn asleep_poses_are_read_only_in_the_step_that_wrote_them() {
        let mut bodies = RigidBodySet::new();
        let sleeper = bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(1.0, 2.0, 3.0))
                .sleeping(true),
        );
        let (mut starts, mut asleep) = (Vec::new(), Asleep::default());
        record(&bodies, &mut starts, &mut asleep);
        assert!(starts.is_empty(), "a sleeping body is not in the starts");
        let pose = asleep.get(sleeper).expect("kept in the table");
        assert_eq!(pose.translation, Vector::new(1.0, 2.0, 3.0));
        bodies[sleeper].wake_up(true);
        record(&bodies, &mut starts, &mut asleep);
        assert_eq!(starts.len(), 1, "an awake body is in the starts");
        assert!(asleep.get(sleeper).is_none(), "last step's entry is stale");
    }

    proptest! {
        /// A moved body's travel bounds how far its points move, whether
        /// the exact test measured it or the cheap bound cleared it (then
        /// from rapier's reach and `π·|sin(θ/2)|`): a body of a ball and a
        /// box, turned and shifted every way, swept with a fast ball so
        /// that the records are built.
        #[test]
        fn the_travel_bounds_the_motion(
            axis in prop::array::uniform3(-1.0f32..1.0),
            angle in -3.1f32..3.1,
            shift in prop::array::uniform3(-0.05f32..0.05),
            spin in prop::array::uniform3(-2.0f32..2.0),
        ) {
            let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
            let body = bodies.insert(RigidBodyBuilder::dynamic().angvel(Vector::from(spin)));
            for part in [
                ColliderBuilder::ball(0.2).translation(Vector::new(0.0, 0.6, 0.0)),
                ColliderBuilder::cuboid(0.3, 0.4, 0.3),
            ] {
                colliders.insert_with_parent(part.build(), body, &mut bodies);
            }
            bodies[body].recompute_mass_properties_from_colliders(&colliders);
            let bullet = bodies.insert(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(5.0, 0.0, 0.0))
                    .linvel(Vector::new(300.0, 0.0, 0.0)),
            );
            colliders.insert_with_parent(ColliderBuilder::ball(0.05).build(), bullet, &mut bodies);
            let starts = [body, bullet].map(|handle| Start {
                handle,
                pose: *bodies[handle].position(),
            });
            let end = Pose::from_parts(
                Vector::from(shift),
                Rotation::from_axis_angle(Vector::from(axis).normalize_or(Vector::X), angle),
            );
            bodies[body].set_position(end, true);
            bodies[bullet].set_translation(Vector::new(10.0, 0.0, 0.0), true);
            let (config, mut report) = (CcdConfig::default(), CcdReport::default());
            let (mut seen, mut out) = (Vec::new(), Vec::new());
            let dt = 1.0 / 60.0;
            moved(&starts, &bodies, &colliders, dt, dt, &config, &mut report, &mut seen, &mut out);
            let record = out.iter().find(|m| m.handle == body).expect("the body moved");
            let rb = &bodies[body];
            let com = rb.local_center_of_mass();
            let exact_shift = (end * com - starts[0].pose * com).length() as f64;
            let exact = travel_bound(
                exact_shift,
                turning_extent(rb, &colliders),
                angle_bound(angle_short(&starts[0].pose, &end), rb.angvel().length() as f64 * dt),
            );
            prop_assert!(record.travel >= exact, "travel {} below {}", record.travel, exact);
        }

        /// The cheap bound never clears a body the exact test would flag:
        /// with the allowed distance set anywhere around the exact measure,
        /// `tunnels` answers as the exact test does. Bodies of one ball, of
        /// balls off the centre of mass (whose turning extent is their
        /// centres'), and of a ball and a box.
        #[test]
        fn the_cheap_bound_agrees_with_the_exact_test(
            body in 0usize..3,
            at in prop::array::uniform3(-50.0f32..50.0),
            axis in prop::array::uniform3(-1.0f32..1.0),
            angle in -3.2f32..3.2,
            turn in (prop::array::uniform3(-1.0f32..1.0), prop::sample::select(vec![0.0f32, 1.0e-4, 0.01, 0.5, 3.1])),
            shift in prop::array::uniform3(-0.2f32..0.2),
            linvel in prop::array::uniform3(-20.0f32..20.0),
            angvel in prop::array::uniform3(-300.0f32..300.0),
            slow in prop::sample::select(vec![0.0f32, 1.0e-3, 1.0]),
            share in 0.5f64..2.0,
        ) {
            let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
            let start = Pose::from_parts(
                Vector::from(at),
                Rotation::from_axis_angle(Vector::from(axis).normalize_or(Vector::Z), angle),
            );
            let handle = bodies.insert(
                RigidBodyBuilder::dynamic()
                    .pose(start)
                    .linvel(Vector::from(linvel) * slow)
                    .angvel(Vector::from(angvel) * slow),
            );
            let parts = match body {
                0 => vec![ColliderBuilder::ball(0.3)],
                1 => vec![
                    ColliderBuilder::ball(0.2).translation(Vector::new(0.5, 0.1, 0.0)),
                    ColliderBuilder::ball(0.1).translation(Vector::new(-0.3, 0.0, 0.4)).density(3.0),
                ],
                _ => vec![
                    ColliderBuilder::ball(0.2).translation(Vector::new(0.0, 0.6, 0.0)),
                    ColliderBuilder::cuboid(0.05, 0.4, 0.3),
                ],
            };
            for part in parts {
                colliders.insert_with_parent(part.build(), handle, &mut bodies);
            }
            // What rapier's step does for a body whose colliders changed
            // (`max_extent` among it); `moved` runs after the step.
            bodies[handle].recompute_mass_properties_from_colliders(&colliders);
            let end = Pose::from_parts(
                start.translation + Vector::from(shift),
                Rotation::from_axis_angle(Vector::from(turn.0).normalize_or(Vector::X), turn.1)
                    * start.rotation,
            );
            let rb = &bodies[handle];
            let measure = exact_measure(rb, &colliders, &start, &end);
            let thickness = body_thickness(rb, &colliders);
            // The allowed distance anywhere from half the measure to twice it.
            let fast_factor = measure * share / thickness;
            let expected = measure > fast_factor * thickness;
            let (got, _) = tunnels(rb, &colliders, &start, &end, 1.0 / 60.0, 1.0 / 60.0, fast_factor);
            prop_assert_eq!(got, expected, "measure {} allowed {}", measure, fast_factor * thickness);
        }
    }
}
