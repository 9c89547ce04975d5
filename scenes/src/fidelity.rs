//! Fidelity counters: what a CCD backend changed besides tunnelling.
//!
//! A CCD backend may remove tunnelling and nothing else. Four counters look
//! for anything else it did, the same way for every backend:
//!
//! - **frozen** ([`FrozenCounter`]): a dynamic body held in place (it moved
//!   less than [`HELD_MOVE`] and turned less than [`HELD_TURN`] over the
//!   step) while its velocity says it moves (faster than [`HELD_LINVEL`] or
//!   [`HELD_ANGVEL`]), for [`HELD_RUN`] steps in a row or more. Every
//!   body-step of such a run counts, unless rapier alone (CCD off), taking
//!   that step from the same state, holds the body too: the runner replays
//!   each counted step to tell (rapier's solver holds a box rattling in a
//!   corner whatever the backend).
//! - **rest** ([`rest_gap`]): in scenes whose bodies settle, how far each
//!   body's final pose is from rapier's own (same scene, same steps).
//! - **energy** ([`EnergyMeter`]): the largest rise over one step of the
//!   total mechanical energy of the dynamic bodies
//!   (Σ ½ m |v|² + ½ ωᵀ I ω − m·s·g·c, with `s` the gravity scale), and the
//!   largest kinetic energy seen (the scale the rise is compared with).
//! - **deflected** ([`deflected`]): a body whose *free path* over the step
//!   (start pose, start velocities, gravity) provably touches nothing, yet
//!   whose velocity the step changed beyond what gravity adds.
//!
//! All arithmetic here is plain and per body; the runner
//! ([`super::runner`]) calls it once per step with the snapshots taken
//! before and after the step.

use super::snapshot::{BodyState, Snapshot};
use affine_ccd::Motion;
use affine_ccd::convert::{iso_from_pose, point_from_glam, vec_from_glam};
use affine_ccd::query::{QueryOptions, ShapeMotion, time_of_impact_many};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::prelude::{Collider, ColliderHandle, PhysicsWorld, RigidBodyHandle, RigidBodyType};
use std::collections::HashMap;

// ---------------------------------------------------------------- frozen --

/// A held body's centre of mass moves less than this over the step (metres).
pub const HELD_MOVE: Real = 1.0e-3;
/// A held body turns less than this over the step (radians).
pub const HELD_TURN: Real = 0.01;
/// A body "moves" by its velocity when its end-of-step linear speed
/// exceeds this (m/s)...
pub const HELD_LINVEL: Real = 1.0;
/// ... or its end-of-step angular speed exceeds this (rad/s).
pub const HELD_ANGVEL: Real = 1.0;
/// Shortest run of consecutive held steps of one body that counts.
pub const HELD_RUN: usize = 10;

/// Whether a dynamic body was held over one step: its pose barely changed
/// although its velocity at the end of the step says it moves. A non-finite
/// pose or velocity says nothing: `false`.
pub fn is_held(before: &BodyState, after: &BodyState) -> bool {
    let moved = (after.com() - before.com()).length();
    let turned = before.pose.rotation.angle_between(after.pose.rotation);
    let finite = after.linvel.is_finite() && after.angvel.is_finite();
    let fast =
        finite && (after.linvel.length() > HELD_LINVEL || after.angvel.length() > HELD_ANGVEL);
    moved < HELD_MOVE && turned < HELD_TURN && fast
}

/// Counts the body-steps of runs of at least [`HELD_RUN`] held steps.
#[derive(Clone, Debug, Default)]
pub struct FrozenCounter {
    /// The steps of the current run of held steps, per body.
    runs: HashMap<RigidBodyHandle, Vec<usize>>,
    /// The body-steps counted so far: step index and body.
    pub counted: Vec<(usize, RigidBodyHandle)>,
}

impl FrozenCounter {
    /// Body-steps counted so far.
    pub fn count(&self) -> usize {
        self.counted.len()
    }

    /// Records whether `body` was held over step `step`, the one that just
    /// ran.
    pub fn observe(&mut self, body: RigidBodyHandle, step: usize, held: bool) {
        if !held {
            self.runs.remove(&body);
            return;
        }
        let run = self.runs.entry(body).or_default();
        run.push(step);
        if run.len() == HELD_RUN {
            // The run just became long enough: all its steps count.
            self.counted.extend(run.iter().map(|&s| (s, body)));
        } else if run.len() > HELD_RUN {
            self.counted.push((step, body));
        }
    }

    /// Observes every body dynamic at both ends of step `step`.
    pub fn check_step(&mut self, before: &Snapshot, after: &Snapshot, step: usize) {
        for (&handle, end) in &after.bodies {
            let Some(start) = before.bodies.get(&handle) else {
                continue;
            };
            let dynamic = start.body_type == RigidBodyType::Dynamic
                && end.body_type == RigidBodyType::Dynamic;
            self.observe(handle, step, dynamic && is_held(start, end));
        }
    }
}

// ------------------------------------------------------------------ rest --

/// How far final poses are from a reference run's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RestGap {
    /// Largest distance between a body's final centre of mass and the
    /// reference's (metres); infinite when a body is missing or not finite.
    pub distance: Real,
    /// Largest rotation angle between a body's final orientation and the
    /// reference's (radians); infinite as above.
    pub angle: Real,
    /// Largest difference of a body's final height (its centre of mass
    /// along `up`, metres): whether it rests *on* what the reference's
    /// rests on, whatever it slid or rolled sideways.
    pub height: Real,
    /// Largest angle between the body axes that point `up` in the two runs
    /// (radians): whether it rests on the same face, as flat, whatever it
    /// turned about the vertical.
    pub tilt: Real,
}

/// Compares the final dynamic bodies of a run with those of a reference run
/// of the same scene (handles match: the build order is deterministic),
/// leaving out the bodies in `skip` (those the reference lost through
/// something: its pose there is no reference). `up` is the unit vertical.
pub fn rest_gap(
    bodies: &[(RigidBodyHandle, BodyState)],
    reference: &[(RigidBodyHandle, BodyState)],
    skip: &[RigidBodyHandle],
    up: Vector,
) -> RestGap {
    let reference: HashMap<RigidBodyHandle, &BodyState> =
        reference.iter().map(|(h, s)| (*h, s)).collect();
    let mut gap = RestGap::default();
    for (handle, state) in bodies {
        if state.body_type != RigidBodyType::Dynamic || skip.contains(handle) {
            continue;
        }
        let (distance, angle, height, tilt) = match reference.get(handle) {
            Some(r) => {
                let body_up = state.pose.rotation.inverse() * up;
                let their_up = r.pose.rotation.inverse() * up;
                (
                    (state.com() - r.com()).length(),
                    state.pose.rotation.angle_between(r.pose.rotation),
                    (state.com() - r.com()).dot(up).abs(),
                    body_up.angle_between(their_up),
                )
            }
            None => (
                Real::INFINITY,
                Real::INFINITY,
                Real::INFINITY,
                Real::INFINITY,
            ),
        };
        // NaN compares false: make it visible as infinity.
        let finite_or_inf = |x: Real| if x.is_finite() { x } else { Real::INFINITY };
        gap.distance = gap.distance.max(finite_or_inf(distance));
        gap.angle = gap.angle.max(finite_or_inf(angle));
        gap.height = gap.height.max(finite_or_inf(height));
        gap.tilt = gap.tilt.max(finite_or_inf(tilt));
    }
    gap
}

// ---------------------------------------------------------------- energy --

/// The mechanical energy of the dynamic bodies of one snapshot (joules).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// Kinetic plus gravitational potential energy.
    pub total: f64,
    /// Kinetic energy only (translation and rotation).
    pub kinetic: f64,
}

/// Σ ½ m |v|² + ½ ωᵀ I ω − m·s·g·c over the dynamic bodies of `snapshot`
/// (`g` the world's gravity, `s` each body's gravity scale, `c` its centre
/// of mass), in `f64`.
pub fn mechanical_energy(snapshot: &Snapshot, gravity: Vector) -> Energy {
    let mut energy = Energy::default();
    for state in snapshot.bodies.values() {
        if state.body_type == RigidBodyType::Dynamic {
            energy.add(state, gravity);
        }
    }
    energy
}

/// The energies before and after one step, summed over the same bodies:
/// those dynamic at both ends whose mass and inertia were known at both
/// ends. Rapier computes a new body's mass properties during its first
/// step, so before the first step a body reads mass 0: counting it would
/// make its whole energy look like a rise.
pub fn step_energies(before: &Snapshot, after: &Snapshot, gravity: Vector) -> (Energy, Energy) {
    let (mut e0, mut e1) = (Energy::default(), Energy::default());
    for (handle, end) in &after.bodies {
        let Some(start) = before.bodies.get(handle) else {
            continue;
        };
        let dynamic =
            start.body_type == RigidBodyType::Dynamic && end.body_type == RigidBodyType::Dynamic;
        let known = start.mass == end.mass && start.inertia.is_zero() == end.inertia.is_zero();
        if dynamic && known {
            e0.add(start, gravity);
            e1.add(end, gravity);
        }
    }
    (e0, e1)
}

impl Energy {
    /// Adds one body's kinetic and potential energy.
    fn add(&mut self, state: &BodyState, gravity: Vector) {
        let g = vec_from_glam(gravity);
        let m = f64::from(state.mass);
        let v = vec_from_glam(state.linvel);
        let w = vec_from_glam(state.angvel);
        // ωᵀ I ω with the symmetric world inertia written out.
        let i = &state.inertia;
        let (i11, i12, i13) = (f64::from(i.m11), f64::from(i.m12), f64::from(i.m13));
        let (i22, i23, i33) = (f64::from(i.m22), f64::from(i.m23), f64::from(i.m33));
        let iw_w = i11 * w.x * w.x
            + i22 * w.y * w.y
            + i33 * w.z * w.z
            + 2.0 * (i12 * w.x * w.y + i13 * w.x * w.z + i23 * w.y * w.z);
        let kinetic = 0.5 * m * v.norm_squared() + 0.5 * iw_w;
        let c = vec_from_glam(state.com());
        let potential = -m * f64::from(state.gravity_scale) * g.dot(&c);
        self.kinetic += kinetic;
        self.total += kinetic + potential;
    }
}

/// The largest rise of the mechanical energy over one step, and the scale.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyMeter {
    /// Largest `after.total − before.total` over the steps (joules, ≥ 0).
    pub max_rise: f64,
    /// Largest kinetic energy seen at either end of any step (joules).
    pub scale: f64,
}

impl EnergyMeter {
    /// Records one step. A step with a non-finite energy is left out.
    pub fn observe_step(&mut self, before: Energy, after: Energy) {
        let all = [before.total, before.kinetic, after.total, after.kinetic];
        if !all.iter().all(|x| x.is_finite()) {
            return;
        }
        self.scale = self.scale.max(before.kinetic).max(after.kinetic);
        self.max_rise = self.max_rise.max(after.total - before.total);
    }

    /// The largest rise as a percentage of the scale (0 when the scale is 0).
    pub fn rise_percent(&self) -> f64 {
        if self.scale > 0.0 {
            100.0 * self.max_rise / self.scale
        } else {
            0.0
        }
    }
}

// ------------------------------------------------------------- deflected --

/// A velocity change smaller than this (m/s, rad/s) is no change...
pub const DEFLECT_TOLERANCE: Real = 1.0e-6;
/// ... plus this many `f32` epsilons of the speeds involved: rapier adds
/// gravity in several substeps, each rounded to `f32`, so a 100 m/s bullet
/// picks up a few 1e-6 m/s of rounding in free flight.
pub const DEFLECT_ROUNDING_EPSILONS: Real = 16.0;

/// Whether the step changed the body's velocity beyond what gravity adds
/// (|v1 − (v0 + s·g·dt)| or |ω1 − ω0| above the tolerance). The angular
/// test is skipped when rapier's gyroscopic correction alone would change
/// ω by more than the tolerance (a tumbling body with unequal inertias:
/// the correction is applied per substep and cannot be replayed exactly).
pub fn velocity_changed(before: &BodyState, after: &BodyState, gravity: Vector, dt: Real) -> bool {
    let kick = gravity * (before.gravity_scale * dt);
    let expected = before.linvel + kick;
    let rounding = |speed: Real| DEFLECT_ROUNDING_EPSILONS * Real::EPSILON * speed;
    let lin_tol = DEFLECT_TOLERANCE
        + rounding(before.linvel.length() + kick.length() + after.linvel.length());
    let linear = (after.linvel - expected).length() > lin_tol;
    let gyro_drift = (before.gyro_angvel - before.angvel).length();
    let ang_tol = DEFLECT_TOLERANCE + rounding(before.angvel.length() + after.angvel.length());
    let angular =
        gyro_drift <= DEFLECT_TOLERANCE && (after.angvel - before.angvel).length() > ang_tol;
    linear || angular
}

/// The bodies deflected over the step that just ran: dynamic, free of
/// joints, damping and user forces, with at least one solid collider; their
/// free path touches nothing ([`free_path_is_clear`]) but their velocity
/// changed ([`velocity_changed`]). `world` is after the step, `before` and
/// `after` the snapshots taken before and after it.
pub fn deflected(
    world: &PhysicsWorld,
    before: &Snapshot,
    after: &Snapshot,
) -> Vec<RigidBodyHandle> {
    deflected_within(world, before, after, 0.0)
}

/// [`deflected`], with "touches" meaning "comes within `skin` metres"
/// (e.g. rapier's prediction distance, to leave out the impulses of its
/// speculative contacts, which act at small positive gaps).
pub fn deflected_within(
    world: &PhysicsWorld,
    before: &Snapshot,
    after: &Snapshot,
    skin: Real,
) -> Vec<RigidBodyHandle> {
    let dt = world.integration_parameters.dt;
    let mut found = Vec::new();
    for (handle, body) in world.bodies.iter() {
        let (Some(start), Some(end)) = (before.bodies.get(&handle), after.bodies.get(&handle))
        else {
            continue;
        };
        let dynamic =
            start.body_type == RigidBodyType::Dynamic && end.body_type == RigidBodyType::Dynamic;
        // Sleeping zeroes velocities: not a deflection.
        if !dynamic || end.sleeping || start.sleeping {
            continue;
        }
        let constrained = world
            .impulse_joints
            .attached_joints(handle)
            .next()
            .is_some()
            || world.multibody_joints.rigid_body_link(handle).is_some()
            || body.linear_damping() != 0.0
            || body.angular_damping() != 0.0
            || body.user_force() != Vector::ZERO
            || body.user_torque() != Vector::ZERO;
        if constrained || !has_solid_collider(world, handle) {
            continue;
        }
        if !velocity_changed(start, end, world.gravity, dt) {
            continue;
        }
        if free_path_is_clear(world, before, handle, skin) {
            found.push(handle);
        }
    }
    found
}

/// Whether `body` has an enabled, non-sensor collider.
fn has_solid_collider(world: &PhysicsWorld, body: RigidBodyHandle) -> bool {
    world.bodies.get(body).is_some_and(|rb| {
        rb.colliders()
            .iter()
            .any(|&h| world.colliders.get(h).is_some_and(is_solid))
    })
}

fn is_solid(collider: &Collider) -> bool {
    collider.is_enabled() && !collider.is_sensor()
}

/// A collider's motion over the step, as the deflection test sees it.
struct Path {
    motion: Motion,
    /// Box containing every pose the collider takes along `motion`.
    swept: Aabb,
}

/// The free path of a collider of a dynamic body: start pose, start
/// velocities, constant angular velocity, the centre of mass accelerated by
/// `s·g`. `None` when the state is not finite (the query refuses it).
fn free_path(
    collider: &Collider,
    pose0: &Pose,
    state: &BodyState,
    gravity: Vector,
    dt: Real,
) -> Option<Path> {
    let motion = Motion::from_velocities(
        iso_from_pose(pose0),
        point_from_glam(state.com()),
        vec_from_glam(state.linvel),
        vec_from_glam(state.angvel),
        f64::from(dt),
    )
    .ok()?
    .with_acceleration(vec_from_glam(gravity * state.gravity_scale))
    .ok()?;
    Some(Path {
        swept: swept_box(collider, pose0, &motion)?,
        motion,
    })
}

/// The path a moving collider actually took: the constant-velocity motion
/// from its start pose to its end pose (rapier's own integration, whole
/// turns chosen by the end angular velocity).
fn actual_path(
    collider: &Collider,
    pose0: &Pose,
    state0: &BodyState,
    angvel1: Vector,
    dt: Real,
) -> Option<Path> {
    let local_center = pose0.inverse_transform_point(state0.com());
    let motion = Motion::from_poses(
        iso_from_pose(pose0),
        iso_from_pose(collider.position()),
        point_from_glam(local_center),
        f64::from(dt),
        vec_from_glam(angvel1),
    )
    .ok()?;
    Some(Path {
        swept: swept_box(collider, pose0, &motion)?,
        motion,
    })
}

/// The collider's box at `pose0`, loosened by a bound on how far any of its
/// points travels along `motion` (plus a millimetre for rounding).
fn swept_box(collider: &Collider, pose0: &Pose, motion: &Motion) -> Option<Aabb> {
    let shape = collider.shape();
    let sphere = shape.compute_local_bounding_sphere();
    let radius = f64::from(sphere.center.length() + sphere.radius);
    let travel = motion.travel_bound(radius) as Real;
    if !travel.is_finite() {
        return None;
    }
    Some(shape.compute_aabb(pose0).loosened(travel * 1.001 + 1.0e-3))
}

/// Whether the free path of `body` over the step provably stays apart
/// (gap > `skin`, 0 for [`deflected`]) from every collider it may collide with. Fixed colliders stay
/// at their start poses; colliders of other dynamic bodies are taken along
/// both their free path and the path they actually took; kinematic ones
/// along the path they took. Candidates come from swept boxes; the test
/// itself is `affine_ccd`'s sound query with zero skin. Any reported hit,
/// error, unsupported pair or non-finite state means "not clear".
pub fn free_path_is_clear(
    world: &PhysicsWorld,
    before: &Snapshot,
    body: RigidBodyHandle,
    skin: Real,
) -> bool {
    let dt = world.integration_parameters.dt;
    let Some((rb, state)) = world.bodies.get(body).zip(before.bodies.get(&body)) else {
        return false;
    };
    // The body's own solid colliders along its free path.
    let mut own: Vec<(ColliderHandle, &Collider, Path)> = Vec::new();
    for &handle in rb.colliders() {
        let Some(collider) = world.colliders.get(handle).filter(|c| is_solid(c)) else {
            continue;
        };
        let Some(pose0) = before.colliders.get(&handle) else {
            return false;
        };
        let Some(path) = free_path(collider, pose0, state, world.gravity, dt) else {
            return false;
        };
        own.push((handle, collider, path));
    }
    let Some(reach) = own
        .iter()
        .map(|(_, _, p)| p.swept.loosened(skin.max(0.0)))
        .reduce(|a, b| a.merged(&b))
    else {
        return true;
    };
    // Every other collider whose swept box meets ours and that may collide
    // with one of ours, along each of its paths.
    let mut targets: Vec<(&Collider, Path)> = Vec::new();
    for (handle, collider) in world.colliders.iter() {
        if collider.parent() == Some(body) || !is_solid(collider) {
            continue;
        }
        let Some(pose0) = before.colliders.get(&handle) else {
            continue;
        };
        let other = collider.parent().and_then(|h| before.bodies.get(&h));
        let other_type = other.map_or(RigidBodyType::Fixed, |s| s.body_type);
        let may = own
            .iter()
            .any(|(_, mine, _)| may_collide(mine, state.body_type, collider, other_type));
        if !may {
            continue;
        }
        let paths: Vec<Option<Path>> = match other {
            Some(s) if s.body_type == RigidBodyType::Dynamic => {
                let angvel1 = collider
                    .parent()
                    .and_then(|h| world.bodies.get(h))
                    .map_or(s.angvel, |b| b.angvel());
                vec![
                    free_path(collider, pose0, s, world.gravity, dt),
                    actual_path(collider, pose0, s, angvel1, dt),
                ]
            }
            Some(s) if s.body_type != RigidBodyType::Fixed => {
                let angvel1 = collider
                    .parent()
                    .and_then(|h| world.bodies.get(h))
                    .map_or(s.angvel, |b| b.angvel());
                vec![actual_path(collider, pose0, s, angvel1, dt)]
            }
            _ => {
                let fixed = Motion::fixed(iso_from_pose(pose0)).ok().map(|motion| Path {
                    swept: collider.shape().compute_aabb(pose0),
                    motion,
                });
                vec![fixed]
            }
        };
        for path in paths {
            // A path we cannot build may be anywhere: not clear.
            let Some(path) = path else {
                return false;
            };
            if path.swept.intersects(&reach) {
                targets.push((collider, path));
            }
        }
    }
    if targets.is_empty() {
        return true;
    }
    let moving: Vec<ShapeMotion> = own
        .iter()
        .map(|(_, c, p)| ShapeMotion {
            shape: c.shape(),
            motion: p.motion,
        })
        .collect();
    let targets: Vec<ShapeMotion> = targets
        .iter()
        .map(|(c, p)| ShapeMotion {
            shape: c.shape(),
            motion: p.motion,
        })
        .collect();
    let options = QueryOptions {
        skin: f64::from(skin),
        ..QueryOptions::default()
    };
    matches!(time_of_impact_many(&moving, &targets, &options), Ok(None))
}

/// Rapier's own filters between two colliders of different bodies:
/// collision and solver groups, active collision types.
fn may_collide(a: &Collider, type_a: RigidBodyType, b: &Collider, type_b: RigidBodyType) -> bool {
    if !a.collision_groups().test(b.collision_groups())
        || !a.solver_groups().test(b.solver_groups())
    {
        return false;
    }
    a.active_collision_types().test(type_a, type_b)
        || b.active_collision_types().test(type_a, type_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};

    /// A dynamic body state at `com` moving at `linvel`, unit mass.
    fn state(com: Vector, linvel: Vector) -> BodyState {
        BodyState {
            pose: Pose::from_translation(com),
            local_com: Vector::ZERO,
            linvel,
            angvel: Vector::ZERO,
            body_type: RigidBodyType::Dynamic,
            mass: 1.0,
            inertia: rapier3d::math::AngularInertia::zero(),
            gravity_scale: 1.0,
            gyro_angvel: Vector::ZERO,
            sleeping: false,
        }
    }

    #[test]
    fn frozen_counts_only_runs_of_ten_or_more() {
        let body = RigidBodyHandle::from_raw_parts(0, 0);
        let held_start = state(Vector::ZERO, Vector::X * 5.0);
        let held_end = state(Vector::X * 1.0e-4, Vector::X * 5.0);
        let moving_end = state(Vector::X * 0.08, Vector::X * 5.0);
        assert!(is_held(&held_start, &held_end));
        assert!(!is_held(&held_start, &moving_end));
        // A slow body that stays put is not held.
        assert!(!is_held(
            &state(Vector::ZERO, Vector::ZERO),
            &state(Vector::ZERO, Vector::X * 0.5)
        ));
        let mut counter = FrozenCounter::default();
        // Nine held steps, a free one: nothing.
        for step in 0..9 {
            counter.observe(body, step, is_held(&held_start, &held_end));
        }
        counter.observe(body, 9, is_held(&held_start, &moving_end));
        assert_eq!(counter.count(), 0);
        // Twelve held steps: all twelve count, each with its step.
        for step in 10..22 {
            counter.observe(body, step, is_held(&held_start, &held_end));
        }
        assert_eq!(counter.count(), 12);
        let steps: Vec<usize> = counter.counted.iter().map(|&(s, _)| s).collect();
        assert_eq!(steps, (10..22).collect::<Vec<_>>());
    }

    #[test]
    fn rest_gap_of_a_body_one_centimetre_away_is_ten_millimetres() {
        let body = RigidBodyHandle::from_raw_parts(3, 0);
        let ours = [(body, state(Vector::new(0.01, 0.5, 0.0), Vector::ZERO))];
        let reference = [(body, state(Vector::new(0.0, 0.5, 0.0), Vector::ZERO))];
        let gap = rest_gap(&ours, &reference, &[], Vector::Y);
        assert!((gap.distance * 1e3 - 10.0).abs() < 1e-3, "{gap:?}");
        assert_eq!((gap.angle, gap.height, gap.tilt), (0.0, 0.0, 0.0));
        assert_eq!(
            rest_gap(&reference, &reference, &[], Vector::Y),
            RestGap::default()
        );
        // 1 cm higher and tipped 0.1 rad: the height and the tilt see it.
        let tipped = state(Vector::new(0.0, 0.51, 0.0), Vector::ZERO);
        let tipped = BodyState {
            pose: Pose::from_parts(
                tipped.pose.translation,
                rapier3d::math::Rotation::from_rotation_z(0.1),
            ),
            ..tipped
        };
        let gap = rest_gap(&[(body, tipped)], &reference, &[], Vector::Y);
        assert!(
            (gap.height - 0.01).abs() < 1e-5 && (gap.tilt - 0.1).abs() < 1e-4,
            "{gap:?}"
        );
        // A body the reference lost is not compared.
        assert_eq!(
            rest_gap(&[(body, tipped)], &reference, &[body], Vector::Y),
            RestGap::default()
        );
    }

    #[test]
    fn energy_rises_when_a_velocity_is_doubled_by_hand() {
        let gravity = Vector::new(0.0, -9.81, 0.0);
        let body = RigidBodyHandle::from_raw_parts(0, 0);
        let mut before = Snapshot::default();
        before
            .bodies
            .insert(body, state(Vector::Y, Vector::X * 2.0));
        let mut after = before.clone();
        if let Some(s) = after.bodies.get_mut(&body) {
            s.linvel *= 2.0;
        }
        let (e0, e1) = (
            mechanical_energy(&before, gravity),
            mechanical_energy(&after, gravity),
        );
        // ½·1·2² = 2 J, then ½·1·4² = 8 J; potential 9.81 J both times.
        assert!((e0.kinetic - 2.0).abs() < 1e-9 && (e1.kinetic - 8.0).abs() < 1e-9);
        assert!((e0.total - (2.0 + 9.81)).abs() < 1e-5);
        let mut meter = EnergyMeter::default();
        meter.observe_step(e0, e1);
        assert!((meter.max_rise - 6.0).abs() < 1e-6, "{meter:?}");
        assert!((meter.rise_percent() - 75.0).abs() < 1e-4);
        // The way back is a fall, not a rise; NaN is left out.
        meter.observe_step(e1, e0);
        meter.observe_step(
            e0,
            Energy {
                total: f64::NAN,
                kinetic: 0.0,
            },
        );
        assert!((meter.max_rise - 6.0).abs() < 1e-6);
    }

    /// A world without gravity: a 0.1 m ball at the origin flying at
    /// 10 m/s along x, and (when `wall`) a wall 0.1 m ahead of it.
    fn ball_world(wall: bool) -> (PhysicsWorld, RigidBodyHandle) {
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::ZERO;
        world.integration_parameters.dt = 1.0 / 60.0;
        let (ball, _) = world.insert(
            RigidBodyBuilder::dynamic().linvel(Vector::X * 10.0),
            ColliderBuilder::ball(0.1),
        );
        if wall {
            world.insert_collider(
                ColliderBuilder::cuboid(0.05, 1.0, 1.0).translation(Vector::new(0.25, 0.0, 0.0)),
                None,
            );
        }
        (world, ball)
    }

    #[test]
    fn a_ball_in_empty_space_whose_velocity_changes_is_deflected() {
        for wall in [false, true] {
            let (mut world, ball) = ball_world(wall);
            let before = Snapshot::take(&world);
            // Move it along its free path and slow it by hand.
            if let Some(rb) = world.bodies.get_mut(ball) {
                rb.set_translation(Vector::X * (10.0 / 60.0), true);
                rb.set_linvel(Vector::X * 7.0, true);
            }
            let after = Snapshot::take(&world);
            let found = deflected(&world, &before, &after);
            if wall {
                // Its free path hits the wall: the change is no deflection.
                assert!(found.is_empty(), "aimed at a wall: {found:?}");
            } else {
                assert_eq!(found, vec![ball], "in empty space");
            }
            // Left alone, nothing changes: never deflected.
            let (world, _) = ball_world(wall);
            let snap = Snapshot::take(&world);
            assert!(deflected(&world, &snap, &snap).is_empty());
        }
    }

    #[test]
    fn nan_velocities_count_nothing_and_do_not_panic() {
        let (mut world, ball) = ball_world(true);
        let before = Snapshot::take(&world);
        if let Some(rb) = world.bodies.get_mut(ball) {
            rb.set_linvel(Vector::new(Real::NAN, 0.0, 0.0), true);
            rb.set_angvel(Vector::new(0.0, Real::INFINITY, 0.0), true);
        }
        let after = Snapshot::take(&world);
        // NaN at the end: the wall is in the free path, "not clear"; NaN
        // at the start: the query refuses the motion, "not clear" too.
        assert!(deflected(&world, &before, &after).is_empty());
        assert!(deflected(&world, &after, &after).is_empty());
        let mut frozen = FrozenCounter::default();
        for step in 0..20 {
            frozen.check_step(&after, &after, step);
        }
        assert_eq!(frozen.count(), 0);
        let mut meter = EnergyMeter::default();
        let (e0, e1) = step_energies(&before, &after, Vector::ZERO);
        meter.observe_step(e0, e1);
        assert_eq!(meter, EnergyMeter::default());
        let gap = rest_gap(
            &[(ball, after.bodies[&ball])],
            &[(ball, before.bodies[&ball])],
            &[],
            Vector::Y,
        );
        assert_eq!(gap.distance, 0.0);
    }
}
