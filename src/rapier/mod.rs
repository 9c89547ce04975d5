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
//! old to their new pose and put each back where rapier's own CCD would
//! have stopped it, found from its first true contact (velocities kept;
//! see `backoff`): a body that passes close to something without touching
//! it is left alone. A step without fast bodies touches nothing. After a
//! clamp, what it changed is swept again against the cut motions (see
//! `rounds`). A pair already touching at the start is rapier's contacts'
//! unless it goes deeper than allowed (sampled, see `touching`); a body
//! such a pair holds where it started stops, so no velocity piles up in a
//! body held still. Fast kinematic bodies (rapier never sweeps them) push
//! the dynamic bodies they would pass, in time order: each is carried
//! from its time of impact, ends a skin ahead of its
//! pusher with the pusher's velocity, and pushes in turn what it meets (see
//! `push`). With `CcdConfig::substeps` > 1 the step is first cut at the
//! earliest impact predicted from velocities, forces and gravity, and each
//! piece is stepped and swept as above (see `substep`).

// The phases of one step, in the order the data passes through them.
mod apply; // the plan written back to the world
mod backoff; // where a clamp stands: where rapier's CCD would stop the body
mod candidates; // what a fast collider may meet (broad phase, pair rules)
mod clamp; // cut and carried motions
mod mesh_planes; // a convex body within a still mesh's triangle planes
mod moved; // a moved body's two poses and travel bounds
mod push; // fast kinematic bodies carry what they meet
mod rounds; // the first sweep and the re-sweeps after clamps
mod search; // the stage's time-of-impact queries, their work counted
mod select; // which bodies moved, which can tunnel
mod substep; // a step cut into pieces at the first predicted impact
mod sweep; // one body's earliest impact
#[cfg(test)]
mod testing; // what the stage's tests share
mod touching; // pairs already touching at the start
pub mod turns; // how many whole turns a step made
mod world; // what the stage reads of the world

pub mod config;
pub mod dispatcher;
pub mod report;

pub use config::{CcdConfig, SweepTargets};
pub use dispatcher::AffineDispatcher;
pub use report::{CcdHitEvent, CcdReport, SkipReason, SkippedBody};

use crate::InitialContact;
use crate::enclosure::TimeSpan;
use crate::query::QueryOptions;
use moved::{Moved, Start};
use rapier3d::prelude::{
    BroadPhaseBvh, CCDSolver, ColliderSet, EventHandler, ImpulseJointSet, IntegrationParameters,
    IslandManager, MultibodyJointSet, NarrowPhase, PhysicsHooks, PhysicsPipeline, PhysicsWorld,
    RigidBodySet, SoftBodySet, Vector,
};
use std::time::Instant;
use sweep::Workspace;
use world::StageWorld;

/// The CCD stage: configuration, buffers and the last step's report.
#[derive(Default)]
pub struct AffineCcd {
    config: CcdConfig,
    report: CcdReport,
    starts: Vec<Start>,
    /// Poses of the bodies asleep before the step.
    asleep: select::Asleep,
    /// The first pass of `select::moved`.
    seen: Vec<select::Seen>,
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
            initial_contact: InitialContact::Report,
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
        // One piece (the default) reports in `self.report` directly; with
        // more, each piece's report is absorbed into the step's total.
        let mut total = (dt > 0.0 && self.config.substeps > 1).then(CcdReport::default);
        if total.is_some() {
            substep::record_aims(bodies, &mut self.aims);
        }
        let (mut remaining, mut left) = (dt, self.config.substeps.max(1));
        // Whether the last piece ended at a predicted impact.
        let mut at_impact = false;
        while left > 0 {
            let (mut length, mut after) = (remaining, 0);
            if let Some(total) = total.as_mut() {
                // Predict over the rest of the step; the piece ends at the
                // first impact. Right after one it is the shortest allowed:
                // the contact just made bounces there (see
                // `substep::piece`).
                let clock = Instant::now();
                let impact = if at_impact {
                    Some(0.0)
                } else if left > 1 {
                    self.predict_impact(
                        &params,
                        gravity,
                        remaining as f64,
                        broad_phase,
                        narrow_phase,
                        bodies,
                        colliders,
                        impulse_joints,
                        hooks,
                        total,
                    )
                } else {
                    None
                };
                (length, after) = substep::piece(remaining, left, impact, params.min_ccd_dt);
                at_impact = impact.is_some_and(|t| t > 0.0) && after > 0;
                // The last piece aims at the user's target itself.
                let share = if after == 0 {
                    1.0
                } else {
                    (dt - remaining + length) / dt
                };
                substep::aim(bodies, &self.aims, share);
                total.elapsed += clock.elapsed();
            }
            let done = dt - remaining;
            // The step's own length is `dt`; what reads `params` past here
            // wants the piece's.
            params.dt = length;
            self.report.clear();
            self.step_piece(
                pipeline,
                gravity,
                &params,
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
            if let Some(total) = total.as_mut() {
                total.absorb(&self.report, done as f64, dt as f64);
            }
            remaining -= length;
            left = after;
        }
        if let Some(total) = total {
            self.report = total;
        }
        &self.report
    }

    /// The earliest impact predicted over the `horizon` seconds left of the
    /// step, as a fraction of them (see `substep`).
    #[allow(clippy::too_many_arguments)]
    fn predict_impact(
        &mut self,
        params: &IntegrationParameters,
        gravity: Vector,
        horizon: f64,
        broad_phase: &BroadPhaseBvh,
        narrow_phase: &NarrowPhase,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        joints: &ImpulseJointSet,
        hooks: &dyn PhysicsHooks,
        report: &mut CcdReport,
    ) -> Option<f64> {
        let opts = self.options(params);
        let scene = StageWorld {
            bodies,
            colliders,
            joints,
            hooks,
            config: &self.config,
            // A piece ends at the predicted contact itself: its solve
            // bounces there (rapier's stops are for clamps).
            slop: 0.0,
        };
        substep::predict(&scene, gravity, &self.aims, horizon, &mut self.moved);
        substep::first_impact(
            &scene,
            broad_phase,
            narrow_phase,
            &self.moved,
            horizon,
            &opts,
            &mut self.workspace,
            report,
        )
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
        // Recording and selection are a pose copy per body (and, after the
        // step, a comparison per awake one) and are not timed: the clock
        // reads would cost more than they do (a step with no fast body
        // reads no clock).
        select::record(bodies, &mut self.starts, &mut self.asleep);

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

        self.report.pieces = 1;
        self.report.shortest_piece = params.dt as f64;
        for &h in pipeline.quarantine().bodies() {
            self.report.skip(h, SkipReason::NonFinite);
        }
        let dt = params.dt as f64;
        if dt > 0.0 {
            select::add_woken(islands, &self.asleep, &mut self.starts);
            select::moved(
                &self.starts,
                bodies,
                colliders,
                dt,
                step_dt as f64,
                &self.config,
                &mut self.report,
                &mut self.seen,
                &mut self.moved,
            );
            if self.moved.iter().any(|m| m.fast || m.pusher) {
                let clock = Instant::now();
                let opts = self.options(params);
                let scene = StageWorld {
                    bodies,
                    colliders,
                    joints: impulse_joints,
                    hooks,
                    config: &self.config,
                    slop: params.allowed_linear_error() as f64,
                };
                // The moved list goes through the rounds and comes back
                // (cut), so its buffer is reused rather than copied.
                let plan = rounds::sweep_rounds(
                    &scene,
                    broad_phase,
                    narrow_phase,
                    std::mem::take(&mut self.moved),
                    dt,
                    &opts,
                    &mut self.workspace,
                    &mut self.report,
                );
                apply::apply(
                    &plan,
                    bodies,
                    colliders,
                    dt,
                    &opts,
                    events,
                    &mut self.report,
                );
                self.moved = plan.moved;
                self.report.elapsed = clock.elapsed();
            }
        }
        self.workspace.remember_holds(&self.report.hits);
    }
}
