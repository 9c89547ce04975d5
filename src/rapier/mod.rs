//! affine-ccd as rapier3d 0.36's continuous collision detection.
//!
//! ```no_run
//! use affine_ccd::rapier::AffineCcd;
//! use rapier3d::prelude::PhysicsWorld;
//!
//! let mut world = PhysicsWorld::default();
//! let mut ccd = AffineCcd::default();
//! ccd.install(&mut world); // our dispatcher in, built-in CCD off
//! for _ in 0..60 {
//!     ccd.step(&mut world); // instead of world.step()
//! }
//! ```
//!
//! Rapier 0.36 has no hook between its velocity solve and the position
//! commit, and its CCD asks the query dispatcher only for a few pairs, so
//! the stage wraps the step: record the poses, let rapier step (its CCD
//! off), then sweep the bodies that moved fast enough to tunnel from their
//! old to their new pose and put each back to its pose just before its
//! first impact (velocities kept). A step without fast bodies touches
//! nothing. After a clamp, what it changed is swept again against the cut
//! motions (see `sweep_all`). A pair already touching at the start is
//! rapier's contacts' unless it goes deeper than `CcdConfig::sink`
//! (sampled, see `sweep::touching_pair`). Fast kinematic bodies (rapier
//! never sweeps them) push the dynamic bodies they would pass, in time
//! order: each is carried from its time of impact, ends a skin ahead of its
//! pusher with the pusher's velocity, and pushes in turn what it meets (see
//! `push`). With `CcdConfig::substeps` > 1 the step is first cut at the
//! earliest impact predicted from velocities, forces and gravity, and each
//! piece is stepped and swept as above (see `substep`).

mod candidates;
mod clamp;
pub mod config;
pub mod dispatcher;
mod push;
pub mod report;
mod select;
mod substep;
mod sweep;

use crate::{convert, query};

pub use config::{CcdConfig, SweepTargets};
pub use dispatcher::AffineDispatcher;
pub use report::{CcdHitEvent, CcdReport, SkipReason, SkippedBody};

use crate::enclosure::TimeSpan;
use candidates::{Motions, Scene};
use query::QueryOptions;
use rapier3d::prelude::{
    BroadPhaseBvh, CCDSolver, ColliderSet, CollisionEvent, CollisionEventFlags, EventHandler,
    ImpulseJointSet, IntegrationParameters, IslandManager, MultibodyJointSet, NarrowPhase,
    PhysicsHooks, PhysicsPipeline, PhysicsWorld, RigidBodyHandle, RigidBodySet, SoftBodySet,
    Vector,
};
use select::{Moved, Start};
use std::time::Instant;
use sweep::{SensorPair, Workspace};

/// The CCD stage: configuration, buffers and the last step's report.
#[derive(Default)]
pub struct AffineCcd {
    config: CcdConfig,
    report: CcdReport,
    starts: Vec<Start>,
    moved: Vec<Moved>,
    workspace: Workspace,
    /// Position-based kinematic targets of a step cut into pieces.
    aims: Vec<substep::Aim>,
    /// Handed to rapier's step, which wants one; unused with
    /// `max_ccd_substeps = 0`.
    unused_ccd: CCDSolver,
}

impl AffineCcd {
    pub fn new(config: CcdConfig) -> AffineCcd {
        AffineCcd {
            config,
            ..AffineCcd::default()
        }
    }

    pub fn config(&self) -> &CcdConfig {
        &self.config
    }

    pub fn config_mut(&mut self) -> &mut CcdConfig {
        &mut self.config
    }

    /// What the last step did.
    pub fn report(&self) -> &CcdReport {
        &self.report
    }

    /// The query options of this configuration (skin in metres).
    fn options(&self, params: &IntegrationParameters) -> QueryOptions {
        QueryOptions {
            epsilon: self.config.epsilon,
            skin: self
                .config
                .skin
                .min(0.5 * params.prediction_distance() as f64)
                .max(0.0),
            arithmetic: self.config.arithmetic,
            max_evaluations: self.config.max_evaluations,
            time_range: TimeSpan::STEP,
            // Pairs touching at the start are handled one by one in
            // `sweep::earliest`.
            initial_contact: crate::InitialContact::Report,
        }
    }

    /// A dispatcher answering shape casts with this configuration.
    pub fn dispatcher(&self) -> AffineDispatcher {
        AffineDispatcher::new(QueryOptions {
            skin: 0.0,
            ..self.options(&IntegrationParameters::default())
        })
    }

    /// Puts our dispatcher (chained to parry's) in the world's narrow phase
    /// and turns rapier's own CCD off (`max_ccd_substeps = 0`).
    pub fn install(&self, world: &mut PhysicsWorld) {
        world
            .narrow_phase
            .set_query_dispatcher(self.dispatcher().chained());
        world.integration_parameters.max_ccd_substeps = 0;
    }

    /// One step of the world with the CCD stage, no hooks, no events.
    pub fn step(&mut self, world: &mut PhysicsWorld) -> &CcdReport {
        self.step_with_events(world, &(), &())
    }

    /// One step of the world with the CCD stage.
    pub fn step_with_events(
        &mut self,
        world: &mut PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
    ) -> &CcdReport {
        self.step_pipeline(
            &mut world.physics_pipeline,
            world.gravity,
            &world.integration_parameters,
            &mut world.islands,
            &mut world.broad_phase,
            &mut world.narrow_phase,
            &mut world.bodies,
            &mut world.colliders,
            &mut world.impulse_joints,
            &mut world.multibody_joints,
            &mut world.soft_bodies,
            hooks,
            events,
        )
    }

    /// What `PhysicsPipeline::step` takes, minus the `CCDSolver`. Rapier's
    /// CCD is off for this step whatever `max_ccd_substeps` says; the
    /// stage's own pieces are `CcdConfig::substeps`.
    #[allow(clippy::too_many_arguments)]
    pub fn step_pipeline(
        &mut self,
        pipeline: &mut PhysicsPipeline,
        gravity: Vector,
        integration_parameters: &IntegrationParameters,
        islands: &mut IslandManager,
        broad_phase: &mut BroadPhaseBvh,
        narrow_phase: &mut NarrowPhase,
        bodies: &mut RigidBodySet,
        colliders: &mut ColliderSet,
        impulse_joints: &mut ImpulseJointSet,
        multibody_joints: &mut MultibodyJointSet,
        soft_bodies: &mut SoftBodySet,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
    ) -> &CcdReport {
        let mut params = *integration_parameters;
        params.max_ccd_substeps = 0;
        let dt = params.dt;
        let substeps = if dt > 0.0 {
            self.config.substeps.max(1)
        } else {
            1
        };
        let mut total = CcdReport::default();
        if substeps > 1 {
            substep::record_aims(bodies, &mut self.aims);
        } else {
            self.aims.clear();
        }
        let (mut remaining, mut left) = (dt, substeps);
        // Whether the last piece ended at a predicted impact.
        let mut at_impact = false;
        // One piece, the whole step, unless `substeps` > 1.
        while left > 0 {
            // Predict over the rest of the step; the piece ends at the first
            // impact. Right after one it is the shortest allowed: the
            // contact just made bounces there (see `substep::piece`).
            let clock = Instant::now();
            let impact = if at_impact {
                Some(0.0)
            } else if left > 1 {
                let opts = self.options(&params);
                let scene = Scene {
                    bodies,
                    colliders,
                    joints: impulse_joints,
                    hooks,
                    config: &self.config,
                };
                substep::predict(
                    &scene,
                    gravity,
                    &self.aims,
                    remaining as f64,
                    &mut self.moved,
                );
                substep::first_impact(
                    &scene,
                    broad_phase,
                    narrow_phase,
                    &self.moved,
                    remaining as f64,
                    &opts,
                    &mut self.workspace,
                    &mut total,
                )
            } else {
                None
            };
            let (length, after) = substep::piece(remaining, left, impact, params.min_ccd_dt);
            at_impact = impact.is_some_and(|t| t > 0.0) && after > 0;
            let done = dt - remaining;
            // The last piece aims at the user's target itself.
            let share = if after == 0 {
                1.0
            } else {
                (done + length) / dt
            };
            substep::aim(bodies, &self.aims, share);
            total.elapsed += clock.elapsed();

            let mut piece = params;
            piece.dt = length;
            self.report = CcdReport::default();
            self.step_piece(
                pipeline,
                gravity,
                &piece,
                dt,
                islands,
                broad_phase,
                narrow_phase,
                bodies,
                colliders,
                impulse_joints,
                multibody_joints,
                soft_bodies,
                hooks,
                events,
            );
            total.absorb(&self.report, done as f64, dt as f64);
            remaining -= length;
            left = after;
        }
        self.report = total;
        &self.report
    }

    /// One rapier step of `params.dt` (a piece of a step of `step_dt`) and
    /// the sweeps and clamps after it, accounted in `self.report`.
    #[allow(clippy::too_many_arguments)]
    fn step_piece(
        &mut self,
        pipeline: &mut PhysicsPipeline,
        gravity: Vector,
        params: &IntegrationParameters,
        step_dt: f32,
        islands: &mut IslandManager,
        broad_phase: &mut BroadPhaseBvh,
        narrow_phase: &mut NarrowPhase,
        bodies: &mut RigidBodySet,
        colliders: &mut ColliderSet,
        impulse_joints: &mut ImpulseJointSet,
        multibody_joints: &mut MultibodyJointSet,
        soft_bodies: &mut SoftBodySet,
        hooks: &dyn PhysicsHooks,
        events: &dyn EventHandler,
    ) {
        let clock = Instant::now();
        select::record(bodies, &self.config, &mut self.report, &mut self.starts);
        let mut elapsed = clock.elapsed();

        pipeline.step(
            gravity,
            params,
            islands,
            broad_phase,
            narrow_phase,
            bodies,
            colliders,
            impulse_joints,
            multibody_joints,
            soft_bodies,
            &mut self.unused_ccd,
            hooks,
            events,
        );

        let clock = Instant::now();
        self.report.pieces = 1;
        self.report.shortest_piece = params.dt as f64;
        for &h in pipeline.quarantine().bodies() {
            self.report.skip(h, SkipReason::NonFinite);
        }
        let dt = params.dt as f64;
        if dt > 0.0 {
            select::moved(
                &self.starts,
                bodies,
                colliders,
                dt,
                step_dt as f64,
                &self.config,
                &mut self.report,
                &mut self.moved,
            );
            if self.moved.iter().any(|m| m.fast || m.pusher) {
                let opts = self.options(params);
                let scene = Scene {
                    bodies,
                    colliders,
                    joints: impulse_joints,
                    hooks,
                    config: &self.config,
                };
                let plan = sweep_all(
                    &scene,
                    broad_phase,
                    narrow_phase,
                    &self.moved,
                    dt,
                    &opts,
                    &mut self.workspace,
                    &mut self.report,
                );
                self.apply(plan, bodies, colliders, dt, &opts, events);
            }
        }
        elapsed += clock.elapsed();
        self.report.elapsed = elapsed;
    }

    /// Clamps the hit bodies, then reports the sensors crossed before each
    /// body's stop.
    fn apply(
        &mut self,
        plan: Plan,
        bodies: &mut RigidBodySet,
        colliders: &mut ColliderSet,
        dt: f64,
        opts: &QueryOptions,
        events: &dyn EventHandler,
    ) {
        let mut stops = std::collections::HashMap::new();
        for (i, hit) in &plan.hits {
            let body = &plan.moved[*i];
            clamp::clamp(bodies, body);
            if let (Some(v), Some(rb)) = (plan.velocity[*i], bodies.get_mut(body.handle)) {
                rb.set_linvel(v, true);
            }
            let fraction = plan.scale[*i];
            stops.insert(body.handle, fraction);
            self.report.hits.push(CcdHitEvent {
                body: body.handle,
                collider1: hit.collider1,
                collider2: hit.collider2,
                fraction,
                time: fraction * dt,
                point: convert::glam_from_vec(&hit.toi.witness1.coords),
                normal: convert::glam_from_vec(&hit.toi.normal1),
            });
        }
        if !plan.hits.is_empty() {
            clamp::sync_colliders(bodies, colliders);
        }
        for pair in &plan.sensors {
            let Some(body) = colliders[pair.collider1].parent() else {
                continue;
            };
            let until = stops.get(&body).copied().unwrap_or(1.0);
            let (s1, s2) = (
                colliders[pair.collider1].shape(),
                colliders[pair.collider2].shape(),
            );
            match sweep::first_crossing(s1, pair, s2, until, opts) {
                Ok(Some(_)) if !touches_at(s1, pair, s2, until) => {
                    self.report.sensor_crossings += 1;
                    for event in [CollisionEvent::Started, CollisionEvent::Stopped] {
                        let e = event(pair.collider1, pair.collider2, CollisionEventFlags::SENSOR);
                        events.handle_collision_event(bodies, colliders, e, None);
                    }
                }
                Ok(_) => {}
                Err(e) => self.report.skip(body, SkipReason::Query(e.to_string())),
            }
        }
    }
}

/// True when the pair overlaps with the body at `until` and the target at
/// its end: rapier's narrow phase then reports it itself.
fn touches_at(
    s1: &dyn rapier3d::parry::shape::Shape,
    pair: &SensorPair,
    s2: &dyn rapier3d::parry::shape::Shape,
    until: f64,
) -> bool {
    use crate::motion::Trajectory;
    use rapier3d::parry::query::{DefaultQueryDispatcher, QueryDispatcher};
    let p1 = convert::pose_from_iso(&pair.motion1.pose_at(until));
    let p2 = convert::pose_from_iso(&pair.motion2.pose_at(1.0));
    DefaultQueryDispatcher
        .intersection_test(&p1.inv_mul(&p2), s1, s2)
        .is_ok_and(|i| i.intersecting)
}

/// What the sweeps found, applied after all of them (so that the order of
/// the bodies does not matter).
struct Plan {
    /// The moved bodies, each with its motion as cut by the sweeps.
    moved: Vec<Moved>,
    /// Per moved body, the share of its motion it keeps (1: not clamped).
    scale: Vec<f64>,
    /// Per moved body, the velocity a pusher gave it.
    velocity: Vec<Option<rapier3d::prelude::Vector>>,
    /// Index into `moved` of each clamped body, and its last impact.
    hits: Vec<(usize, sweep::BodyHit)>,
    sensors: Vec<SensorPair>,
}

/// Rounds of re-sweeping after clamps (the first sweep included).
const MAX_ROUNDS: usize = 8;

/// What one body is swept against in a round.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Against {
    /// Everything (a fast body's first sweep, a rerouted body).
    All,
    /// The moving bodies (a clamped body: its timing changed).
    Moving,
    /// The bodies changed in the last round.
    Changed,
    /// Everything but dynamic bodies and pushers (a carried body).
    Blockers,
}

/// Sweeps the fast bodies; then, while some body was clamped, sweeps again
/// what the clamps changed: a clamped body against the moving bodies (its
/// timing changed), and every dynamic body near a clamped one against it
/// (it was solved against the uncut motion). Re-sweeps use half the skin,
/// so a pair left a skin apart by an earlier clamp does not clamp again.
///
/// Fast kinematic bodies ("pushers") are swept against too: rapier never
/// sweeps them, so a fast paddle passes through resting boxes. A dynamic
/// body (awake or not, moving or not) that a pusher would pass is
/// *carried*: from its time of impact on it moves rigidly with the pusher,
/// ends a skin ahead of it and gets the pusher's velocity at its centre of
/// mass (an inelastic push; the next step's contacts go on from there).
/// What a carried body meets on the way is carried in turn; anything else
/// stops it (it is then squeezed, rapier's contacts' business).
#[allow(clippy::too_many_arguments)]
fn sweep_all(
    scene: &Scene,
    broad_phase: &BroadPhaseBvh,
    narrow_phase: &NarrowPhase,
    moved: &[Moved],
    dt: f64,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
) -> Plan {
    use rapier3d::parry::bounding_volume::BoundingVolume;
    use std::collections::HashSet;
    let dispatcher = narrow_phase.query_dispatcher();
    let mut current = moved.to_vec();
    let mut dirty: Vec<(usize, Against)> = (0..moved.len())
        .filter(|&i| moved[i].fast)
        .map(|i| (i, Against::All))
        .collect();
    let mut pushing: HashSet<RigidBodyHandle> = moved
        .iter()
        .filter(|m| m.pusher)
        .map(|m| m.handle)
        .collect();
    let pushed = if pushing.is_empty() {
        Vec::new()
    } else {
        push::push(
            scene,
            broad_phase,
            dispatcher,
            &mut current,
            &mut pushing,
            dt,
            opts,
            ws,
            report,
        )
    };
    let n = current.len();
    let mut scale = vec![1.0; n];
    let mut velocity: Vec<Option<rapier3d::prelude::Vector>> = vec![None; n];
    let mut last: Vec<Option<sweep::BodyHit>> = vec![None; n];
    let mut carried: HashSet<RigidBodyHandle> = HashSet::new();
    for (i, hit, v) in pushed {
        velocity[i] = Some(v);
        last[i] = Some(hit);
        carried.insert(current[i].handle);
    }
    // A carried body is swept against what can stop it, not against what
    // carries it or what it carries.
    dirty.retain(|(i, _)| !carried.contains(&current[*i].handle));
    for (i, m) in current.iter().enumerate() {
        if carried.contains(&m.handle) {
            dirty.push((i, Against::Blockers));
        }
    }
    let mut sensors = Vec::new();
    let mut changed_set: HashSet<RigidBodyHandle> = HashSet::new();
    let mut changed: Vec<usize> = Vec::new();
    // Clamped bodies whose cut motion is not part of the old path.
    let mut rerouted: HashSet<RigidBodyHandle> = HashSet::new();
    let resweep = QueryOptions {
        skin: 0.5 * opts.skin,
        ..*opts
    };
    for round in 0..MAX_ROUNDS {
        if dirty.is_empty() {
            break;
        }
        let motions = Motions::new(&current, dt);
        ws.motions.clear();
        let mut found = Vec::new();
        for &(i, against) in &dirty {
            let body = &current[i];
            let targets = match against {
                Against::All => sweep::Targets::All,
                Against::Moving => sweep::Targets::Moving,
                Against::Changed => sweep::Targets::Only(&changed_set),
                Against::Blockers => sweep::Targets::Blockers(&pushing),
            };
            let round_opts = if round == 0 { opts } else { &resweep };
            report.bodies_swept += 1;
            let mut body_sensors = Vec::new();
            match sweep::sweep_body(
                scene,
                broad_phase,
                dispatcher,
                &motions,
                body,
                targets,
                round_opts,
                ws,
                report,
                &mut body_sensors,
            ) {
                Ok(hit) => {
                    if let Some(hit) = hit.filter(|h| h.toi.fraction < 1.0) {
                        found.push((i, hit));
                    }
                    if round == 0 {
                        sensors.append(&mut body_sensors);
                    }
                }
                Err(e) => report.skip(body.handle, SkipReason::Query(e.to_string())),
            }
        }
        // Cut (or carry) the motions after all sweeps of the round.
        changed.clear();
        changed_set.clear();
        rerouted.clear();
        let before = current.clone();
        for (i, hit) in found {
            let by = scene.colliders[hit.collider2]
                .parent()
                .filter(|h| pushing.contains(h))
                .and_then(|h| before.iter().position(|m| m.handle == h));
            let f = hit.toi.fraction;
            let handle = current[i].handle;
            match by {
                Some(p) => match clamp::carry(scene.bodies, &before[i], &before[p], f, dt) {
                    Ok((cut, v)) => {
                        current[i] = cut;
                        velocity[i] = Some(velocity[p].unwrap_or(v));
                        carried.insert(handle);
                        rerouted.insert(handle);
                    }
                    Err(e) => {
                        report.skip(handle, SkipReason::Query(e.to_string()));
                        continue;
                    }
                },
                None => match clamp::truncate(scene.bodies, &before[i], f, dt) {
                    Ok((cut, new_path)) => {
                        if new_path {
                            rerouted.insert(handle);
                        }
                        current[i] = cut;
                        scale[i] *= f;
                    }
                    Err(e) => {
                        report.skip(handle, SkipReason::Query(e.to_string()));
                        continue;
                    }
                },
            }
            last[i] = Some(hit);
            changed.push(i);
            changed_set.insert(handle);
        }
        pushing.extend(carried.iter().copied());
        // Next round: the changed bodies, and the dynamic bodies whose
        // swept box meets a changed body's.
        dirty.clear();
        if changed.is_empty() {
            break;
        }
        for &i in &changed {
            let h = current[i].handle;
            let against = if carried.contains(&h) {
                Against::Blockers
            } else if rerouted.contains(&h) {
                Against::All
            } else {
                Against::Moving
            };
            dirty.push((i, against));
        }
        let boxes: Vec<_> = changed
            .iter()
            .filter_map(|&i| body_box(scene, &current[i]))
            .collect();
        for (j, m) in current.iter().enumerate() {
            // A carried body rides with its pusher: what it meets is
            // carried in turn, it is not stopped by it.
            if changed_set.contains(&m.handle) || carried.contains(&m.handle) {
                continue;
            }
            let Some(rb) = scene.bodies.get(m.handle) else {
                continue;
            };
            if !rb.is_dynamic() || scene.config.opted_out(rb.user_data) {
                continue;
            }
            if let Some(b) = body_box(scene, m)
                && boxes.iter().any(|c| c.intersects(&b))
            {
                dirty.push((j, Against::Changed));
            }
        }
    }
    let hits = last
        .iter()
        .enumerate()
        .filter_map(|(i, h)| h.map(|h| (i, h)))
        .collect();
    Plan {
        moved: current,
        scale,
        velocity,
        hits,
        sensors,
    }
}

/// A box holding the body's colliders over its whole (uncut) motion: their
/// end boxes grown by the body's travel bound.
pub(super) fn body_box(scene: &Scene, m: &Moved) -> Option<rapier3d::parry::bounding_volume::Aabb> {
    use rapier3d::parry::bounding_volume::BoundingVolume;
    let rb = scene.bodies.get(m.handle)?;
    let margin = ((m.travel * (1.0 + 1.0e-5)) as f32).next_up() + 1.0e-5;
    rb.colliders()
        .iter()
        .filter_map(|h| scene.colliders.get(*h))
        .filter(|co| co.is_enabled())
        .map(|co| co.compute_aabb().loosened(margin))
        .reduce(|a, b| a.merged(&b))
}
