//! The step system: bevy_rapier's step with affine-ccd's stage in place of
//! `PhysicsPipeline::step`.
//!
//! Why this is a rewrite and not a call: bevy_rapier 0.37's
//! `RapierContextSimulation::step_simulation` calls `PhysicsPipeline::step`
//! itself, with no hook to put another step in its place, and the state it
//! keeps around the step (its event queue, the map of removed colliders, the
//! quarantine lists) is private. So the logic of its step system was read and
//! written again here: the three timestep modes with their substeps, the
//! interpolation start poses taken before the last step of an update, zero
//! `dt` skipped, `physics_pipeline_active`, collision and contact-force
//! events with entities (the user's own event handler still called), and the
//! quarantine of non-finite bodies. Contexts in `SimulationMode::CollisionOnly`
//! have no dynamics to sweep: they go through bevy_rapier's own step as is.

use crate::{
    AffineCcdConfig, AffineCcdStage, CcdHit, ContextCcdConfig, PluginCcdConfig, RemovedColliders,
    config_for,
};
use affine_ccd::rapier::CcdReport;
use bevy::ecs::system::{StaticSystemParam, SystemParamItem};
use bevy::prelude::*;
use bevy_rapier3d::plugin::context::SimulationToRenderTime;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::prelude::{
    BroadPhaseBvh, ColliderHandle, ColliderSet, CollisionEvent as RapierCollisionEvent,
    ContactForceEvent as RapierContactForceEvent, ContactModificationContext, ContactPair,
    EventHandler, IntegrationParameters, IslandManager, NarrowPhase, PairFilterContext,
    PhysicsHooks, PhysicsPipeline, Real, RigidBodySet, SoftBodySet,
    SoftBodyTearEvent as RapierTearEvent, SolverFlags,
};
use std::collections::HashMap;
use std::sync::Mutex;

/// Turns rapier's events into bevy_rapier's messages (entities from the
/// colliders' user data, or from the map of colliders removed since the last
/// step) and forwards them to the context's own event handler, if any.
struct Events<'a> {
    removed: &'a HashMap<ColliderHandle, Entity>,
    user: Option<&'a (dyn EventHandler + Send + Sync)>,
    collisions: Mutex<Vec<CollisionEvent>>,
    forces: Mutex<Vec<ContactForceEvent>>,
}

impl Events<'_> {
    fn entity(&self, colliders: &ColliderSet, handle: ColliderHandle) -> Option<Entity> {
        colliders
            .get(handle)
            .and_then(|co| Entity::try_from_bits(co.user_data as u64))
            .or_else(|| self.removed.get(&handle).copied())
    }
}

impl EventHandler for Events<'_> {
    fn handle_collision_event(
        &self,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        event: RapierCollisionEvent,
        contact_pair: Option<&ContactPair>,
    ) {
        let (h1, h2) = (event.collider1(), event.collider2());
        if let (Some(e1), Some(e2)) = (self.entity(colliders, h1), self.entity(colliders, h2)) {
            let ours = match event {
                RapierCollisionEvent::Started(_, _, flags) => {
                    CollisionEvent::Started(e1, e2, flags)
                }
                RapierCollisionEvent::Stopped(_, _, flags) => {
                    CollisionEvent::Stopped(e1, e2, flags)
                }
            };
            if let Ok(mut queue) = self.collisions.lock() {
                queue.push(ours);
            }
        }
        if let Some(user) = self.user {
            user.handle_collision_event(bodies, colliders, event, contact_pair);
        }
    }

    fn handle_contact_force_event(
        &self,
        dt: Real,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        contact_pair: &ContactPair,
        total_force_magnitude: Real,
    ) {
        let raw =
            RapierContactForceEvent::from_contact_pair(dt, contact_pair, total_force_magnitude);
        if let (Some(collider1), Some(collider2)) = (
            self.entity(colliders, raw.collider1),
            self.entity(colliders, raw.collider2),
        ) {
            let ours = ContactForceEvent {
                collider1,
                collider2,
                total_force: raw.total_force,
                total_force_magnitude: raw.total_force_magnitude,
                max_force_direction: raw.max_force_direction,
                max_force_magnitude: raw.max_force_magnitude,
                started: raw.started,
            };
            if let Ok(mut queue) = self.forces.lock() {
                queue.push(ours);
            }
        }
        if let Some(user) = self.user {
            user.handle_contact_force_event(
                dt,
                bodies,
                colliders,
                contact_pair,
                total_force_magnitude,
            );
        }
    }

    fn handle_soft_body_tear_event(&self, soft_bodies: &SoftBodySet, event: &RapierTearEvent) {
        if let Some(user) = self.user {
            user.handle_soft_body_tear_event(soft_bodies, event);
        }
    }
}

/// bevy_rapier's hooks system parameter as rapier's `PhysicsHooks` (its
/// own adapter is crate-private; this one does the same three calls).
struct Hooks<H>(H);

impl<H: BevyPhysicsHooks> PhysicsHooks for Hooks<H> {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        self.0
            .filter_contact_pair(PairFilterContextView { raw: context })
    }

    fn filter_intersection_pair(&self, context: &PairFilterContext) -> bool {
        self.0
            .filter_intersection_pair(PairFilterContextView { raw: context })
    }

    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        self.0
            .modify_solver_contacts(ContactModificationContextView { raw: context })
    }
}

fn take_queue<T>(queue: &Mutex<Vec<T>>) -> Vec<T> {
    std::mem::take(&mut *queue.lock().unwrap_or_else(|e| e.into_inner()))
}

/// What the quarantine of the steps of one update caught, as entities.
#[derive(Default)]
struct Quarantined {
    bodies: Vec<Entity>,
    colliders: Vec<Entity>,
    soft_bodies: Vec<Entity>,
}

/// The sets of one context, borrowed for its steps.
struct Context<'a> {
    sim: &'a mut RapierContextSimulation,
    colliders: &'a mut RapierContextColliders,
    joints: &'a mut RapierContextJoints,
    bodies: &'a mut RapierRigidBodySet,
}

impl Context<'_> {
    /// One rapier step through the stage; its report is pushed on `stage`.
    #[allow(clippy::too_many_arguments)]
    fn step_once(
        &mut self,
        stage: &mut AffineCcdStage,
        gravity: Vec3,
        params: &IntegrationParameters,
        hooks: &dyn PhysicsHooks,
        removed: &HashMap<ColliderHandle, Entity>,
        events: &mut (Vec<CollisionEvent>, Vec<ContactForceEvent>),
        quarantined: &mut Quarantined,
    ) {
        let sim = &mut *self.sim;
        let handler = Events {
            removed,
            user: None,
            collisions: Mutex::new(std::mem::take(&mut events.0)),
            forces: Mutex::new(std::mem::take(&mut events.1)),
        };
        // The step itself, with the context's parts it mutates handed in.
        let mut step = |pipeline: &mut PhysicsPipeline,
                        islands: &mut IslandManager,
                        broad_phase: &mut BroadPhaseBvh,
                        narrow_phase: &mut NarrowPhase,
                        events: &dyn EventHandler| {
            let report = stage.stage.step_pipeline(
                pipeline,
                gravity,
                params,
                islands,
                broad_phase,
                narrow_phase,
                &mut self.bodies.bodies,
                &mut self.colliders.colliders,
                &mut self.joints.impulse_joints,
                &mut self.joints.multibody_joints,
                &mut self.bodies.soft_bodies,
                hooks,
                events,
            );
            stage.reports.push(report.clone());
        };
        if sim.event_handler().is_none() {
            step(
                &mut sim.pipeline,
                &mut sim.islands,
                &mut sim.broad_phase,
                &mut sim.narrow_phase,
                &handler,
            );
        } else {
            // The user's handler is reachable only through `&self` of the
            // whole context: the parts the step mutates are moved out for
            // the step and put back right after.
            let mut pipeline = std::mem::take(&mut sim.pipeline);
            let mut islands = std::mem::take(&mut sim.islands);
            let mut broad_phase = std::mem::take(&mut sim.broad_phase);
            let mut narrow_phase = std::mem::take(&mut sim.narrow_phase);
            let with_user = Events {
                removed,
                user: sim.event_handler(),
                collisions: Mutex::new(take_queue(&handler.collisions)),
                forces: Mutex::new(take_queue(&handler.forces)),
            };
            step(
                &mut pipeline,
                &mut islands,
                &mut broad_phase,
                &mut narrow_phase,
                &with_user,
            );
            *handler.collisions.lock().unwrap_or_else(|e| e.into_inner()) =
                with_user.collisions.into_inner().unwrap_or_default();
            *handler.forces.lock().unwrap_or_else(|e| e.into_inner()) =
                with_user.forces.into_inner().unwrap_or_default();
            sim.pipeline = pipeline;
            sim.islands = islands;
            sim.broad_phase = broad_phase;
            sim.narrow_phase = narrow_phase;
        }
        events.0 = handler.collisions.into_inner().unwrap_or_default();
        events.1 = handler.forces.into_inner().unwrap_or_default();

        let quarantine = sim.pipeline.quarantine();
        if !quarantine.is_empty() {
            quarantined.bodies.extend(
                quarantine
                    .bodies()
                    .iter()
                    .filter_map(|h| self.bodies.rigid_body_entity(*h)),
            );
            quarantined.colliders.extend(
                quarantine
                    .colliders()
                    .iter()
                    .filter_map(|h| self.colliders.collider_entity(*h)),
            );
            quarantined.soft_bodies.extend(
                quarantine
                    .soft_bodies()
                    .iter()
                    .filter_map(|h| self.bodies.soft_body_entity(*h)),
            );
        }
    }
}

/// The lengths of the rapier steps of this update, as bevy_rapier's
/// `TimestepMode` makes them; `Interpolated` also tells, for each step,
/// whether it is the first substep of the update's last step (the
/// interpolation start poses are taken right before it).
fn plan(
    mode: TimestepMode,
    frame_dt: f32,
    sim_to_render: &mut SimulationToRenderTime,
    params: &mut IntegrationParameters,
    steps: &mut Vec<(Real, bool)>,
) {
    steps.clear();
    // A zero dt (the first update in `Variable`, a zero time scale) runs no
    // step.
    fn push(steps: &mut Vec<(Real, bool)>, dt: Real, substeps: usize, mark_first: bool) {
        if dt > 0.0 {
            for i in 0..substeps {
                steps.push((dt, mark_first && i == 0));
            }
        }
    }
    match mode {
        TimestepMode::Fixed { dt, substeps } => {
            params.dt = dt;
            push(steps, dt / substeps as Real, substeps, false);
        }
        TimestepMode::Variable {
            max_dt,
            time_scale,
            substeps,
        } => {
            params.dt = (frame_dt * time_scale).min(max_dt);
            push(steps, params.dt / substeps as Real, substeps, false);
        }
        TimestepMode::Interpolated {
            dt,
            time_scale,
            substeps,
        } => {
            params.dt = dt;
            sim_to_render.diff += frame_dt;
            // At least one step runs per `dt` of lag; the same float
            // comparisons as bevy_rapier's so that both run the same steps.
            while sim_to_render.diff > 0.0 {
                let last = sim_to_render.diff - dt <= 0.0;
                let before = steps.len();
                push(steps, dt / substeps as Real * time_scale, substeps, last);
                if last && steps.len() == before {
                    // No step this round (zero time scale): the start poses
                    // are still taken, as bevy_rapier does.
                    steps.push((0.0, true));
                }
                sim_to_render.diff -= dt;
            }
        }
    }
}

/// bevy_rapier's `step_simulation` with affine-ccd's stage in place of
/// `PhysicsPipeline::step`; [`AffineCcdPlugin`](crate::AffineCcdPlugin)
/// puts it in `PhysicsSet::StepSimulation` in place of bevy_rapier's. Add it
/// yourself (and take bevy_rapier's out) if you set bevy_rapier's systems up
/// by hand.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn step_simulation_with_ccd<Hooks>(
    mut commands: Commands,
    mut contexts: Query<(
        Entity,
        &mut RapierContextSimulation,
        &mut RapierContextColliders,
        &mut RapierContextJoints,
        &mut RapierRigidBodySet,
        &RapierConfiguration,
        &mut SimulationToRenderTime,
        Option<&ContextCcdConfig>,
        Option<&mut AffineCcdStage>,
        Option<&mut RemovedColliders>,
    )>,
    configs: (Option<Res<AffineCcdConfig>>, Option<Res<PluginCcdConfig>>),
    timestep_mode: Res<TimestepMode>,
    hooks: StaticSystemParam<Hooks>,
    time: Res<Time>,
    mut writers: (
        MessageWriter<CollisionEvent>,
        MessageWriter<ContactForceEvent>,
        MessageWriter<PhysicsQuarantineEvent>,
        MessageWriter<CcdHit>,
    ),
    mut interpolation_query: Query<(&RapierRigidBodyHandle, &mut TransformInterpolation)>,
    mut steps: Local<Vec<(Real, bool)>>,
) where
    Hooks: 'static + BevyPhysicsHooks,
    for<'w, 's> SystemParamItem<'w, 's, Hooks>: BevyPhysicsHooks,
{
    let hooks = Hooks(hooks.into_inner());
    let (config_res, plugin_default) = configs;
    let (collision_w, force_w, quarantine_w, hit_w) = &mut writers;

    for (
        context_entity,
        mut sim,
        mut colliders,
        mut joints,
        mut bodies,
        config,
        mut sim_to_render,
        ccd_config,
        stage,
        removed,
    ) in contexts.iter_mut()
    {
        let mut fresh = None;
        let stage = match stage {
            Some(stage) => stage.into_inner(),
            None => fresh.insert(AffineCcdStage::default()),
        };
        *stage.stage.config_mut() =
            config_for(ccd_config, config_res.as_deref(), plugin_default.as_deref());
        stage.reports.clear();
        let mut removed_now = removed
            .map(|mut r| std::mem::take(&mut r.0))
            .unwrap_or_default();

        if !config.physics_pipeline_active {
            bodies.propagate_modified_body_positions_to_colliders(&mut colliders);
        } else if config.simulation_mode == SimulationMode::CollisionOnly {
            // Nothing moves by dynamics: bevy_rapier's own step, untouched.
            sim.set_num_threads(config.num_threads);
            sim.step_simulation(
                &mut colliders,
                &mut joints,
                &mut bodies,
                config.gravity,
                config.simulation_mode,
                *timestep_mode,
                Some((&*collision_w, &*force_w)),
                &hooks,
                &time,
                &mut sim_to_render,
                Some(&mut interpolation_query),
            );
            sim.send_bevy_events(collision_w, force_w);
            removed_now.clear();
        } else {
            sim.set_num_threads(config.num_threads);
            plan(
                *timestep_mode,
                time.delta_secs(),
                &mut sim_to_render,
                &mut sim.integration_parameters,
                &mut steps,
            );
            let mut events = (Vec::new(), Vec::new());
            let mut quarantined = Quarantined::default();
            let mut executed = 0;
            let mut context = Context {
                sim: &mut sim,
                colliders: &mut colliders,
                joints: &mut joints,
                bodies: &mut bodies,
            };
            for &(dt, take_starts) in steps.iter() {
                if take_starts {
                    for (handle, mut interpolation) in interpolation_query.iter_mut() {
                        if let Some(body) = context.bodies.bodies.get(handle.0) {
                            interpolation.start = Some(*body.position());
                            interpolation.end = None;
                        }
                    }
                }
                if dt <= 0.0 {
                    continue;
                }
                let mut params = context.sim.integration_parameters;
                params.dt = dt;
                context.step_once(
                    stage,
                    config.gravity,
                    &params,
                    &hooks,
                    &removed_now,
                    &mut events,
                    &mut quarantined,
                );
                executed += 1;
            }
            if executed == 0 {
                // No step: colliders still follow bodies the user moved, and
                // the removed colliders wait for the next step's events.
                bodies.propagate_modified_body_positions_to_colliders(&mut colliders);
            } else {
                removed_now.clear();
            }
            collision_w.write_batch(events.0);
            force_w.write_batch(events.1);
            send_hits(context_entity, &bodies, &colliders, &stage.reports, hit_w);
            quarantine(&mut commands, context_entity, quarantined, quarantine_w);
        }

        if !removed_now.is_empty() {
            commands
                .entity(context_entity)
                .try_insert(RemovedColliders(removed_now));
        }
        if let Some(fresh) = fresh {
            commands.entity(context_entity).try_insert(fresh);
        }
    }
}

fn send_hits(
    context: Entity,
    bodies: &RapierRigidBodySet,
    colliders: &RapierContextColliders,
    reports: &[CcdReport],
    writer: &mut MessageWriter<CcdHit>,
) {
    for (step, report) in reports.iter().enumerate() {
        for hit in &report.hits {
            let (Some(body), Some(collider1), Some(collider2)) = (
                bodies.rigid_body_entity(hit.body),
                colliders.collider_entity(hit.collider1),
                colliders.collider_entity(hit.collider2),
            ) else {
                continue;
            };
            writer.write(CcdHit {
                context,
                body,
                collider1,
                collider2,
                step,
                fraction: hit.fraction,
                time: hit.time,
                point: hit.point,
                normal: hit.normal,
            });
        }
    }
}

/// As bevy_rapier does: the quarantined entities get their `*Disabled`
/// component (removing it re-enables them) and one message tells which.
fn quarantine(
    commands: &mut Commands,
    context: Entity,
    q: Quarantined,
    writer: &mut MessageWriter<PhysicsQuarantineEvent>,
) {
    if q.bodies.is_empty() && q.colliders.is_empty() && q.soft_bodies.is_empty() {
        return;
    }
    for e in &q.bodies {
        commands.entity(*e).try_insert(RigidBodyDisabled);
    }
    for e in &q.colliders {
        commands.entity(*e).try_insert(ColliderDisabled);
    }
    for e in &q.soft_bodies {
        commands.entity(*e).try_insert(SoftBodyDisabled);
    }
    log::warn!(
        "non-finite (NaN or infinite) state in rapier context {context}; rolled back and \
         disabled: bodies {:?}, colliders {:?}, soft bodies {:?}",
        q.bodies,
        q.colliders,
        q.soft_bodies
    );
    writer.write(PhysicsQuarantineEvent {
        context,
        bodies: q.bodies,
        colliders: q.colliders,
        soft_bodies: q.soft_bodies,
    });
}

/// Keeps, per context, the entities of the colliders bevy_rapier is about to
/// remove (it runs right before bevy_rapier's `sync_removals`), so that the
/// next step's `REMOVED` collision events name them.
#[allow(clippy::type_complexity)]
pub fn track_removed_colliders(
    mut commands: Commands,
    mut removed: RemovedComponents<RapierColliderHandle>,
    still_there: Query<(), With<RapierColliderHandle>>,
    orphans: Query<(Entity, &RapierColliderHandle), Without<Collider>>,
    mut contexts: Query<(
        Entity,
        &RapierContextColliders,
        Option<&mut RemovedColliders>,
    )>,
) {
    let gone: Vec<Entity> = removed
        .read()
        .filter(|e| !still_there.contains(*e))
        .collect();
    if gone.is_empty() && orphans.is_empty() {
        return;
    }
    for (context, colliders, map) in contexts.iter_mut() {
        let mut found = HashMap::new();
        for e in &gone {
            if let Some(h) = colliders.entity2collider().get(e) {
                found.insert(*h, *e);
            }
        }
        for (e, h) in orphans.iter() {
            if colliders.entity2collider().get(&e) == Some(&h.0) {
                found.insert(h.0, e);
            }
        }
        if found.is_empty() {
            continue;
        }
        match map {
            Some(mut map) => map.0.extend(found),
            None => {
                commands.entity(context).try_insert(RemovedColliders(found));
            }
        }
    }
}
