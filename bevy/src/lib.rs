//! affine-ccd for bevy_rapier3d 0.37: sound continuous collision detection in
//! place of rapier's.
//!
//! ```no_run
//! use affine_ccd_bevy::AffineCcdPlugin;
//! use bevy::prelude::*;
//! use bevy_rapier3d::prelude::*;
//!
//! App::new()
//!     .add_plugins((MinimalPlugins, RapierPhysicsPlugin::<NoUserData>::default()))
//!     .add_plugins(AffineCcdPlugin::default()) // rapier's CCD out, affine-ccd's stage in
//!     .run();
//! ```
//!
//! The plugin takes bevy_rapier's step system (`systems::step_simulation`)
//! out of the schedule it was put in and puts [`step_simulation_with_ccd`]
//! in its place, in [`PhysicsSet::StepSimulation`]: each context is stepped
//! by [`AffineCcd::step_pipeline`] with the context's own sets, parameters,
//! hooks and events, honouring [`TimestepMode`] and [`RapierConfiguration`].
//!
//! - Configuration: [`AffineCcdConfig`] as a resource (every context),
//!   [`ContextCcdConfig`] on a context entity (that context); else the
//!   plugin's.
//! - Report: [`AffineCcdStage`] on each context entity (a required component
//!   of `RapierContextSimulation`) holds the stage and the reports of the steps of the last update.
//! - Messages: one [`CcdHit`] per clamp, with entities.

mod step;

pub use step::{step_simulation_with_ccd, track_removed_colliders};

use affine_ccd::rapier::{AffineCcd, CcdConfig, CcdReport};
use bevy::ecs::schedule::{ScheduleCleanupPolicy, ScheduleLabel};
use bevy::ecs::system::SystemParamItem;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::prelude::ColliderHandle;
use std::collections::HashMap;
use std::marker::PhantomData;

/// Steps every rapier context through affine-ccd's CCD stage instead of
/// bevy_rapier's own step. `PhysicsHooks` must be the hooks type given to
/// `RapierPhysicsPlugin` (its step system is found by that type).
pub struct AffineCcdPlugin<PhysicsHooks = NoUserData> {
    config: CcdConfig,
    _hooks: PhantomData<fn() -> PhysicsHooks>,
}

impl Default for AffineCcdPlugin<NoUserData> {
    fn default() -> Self {
        Self::new(CcdConfig::default())
    }
}

impl AffineCcdPlugin<NoUserData> {
    /// The stage's configuration for contexts without a [`ContextCcdConfig`],
    /// when there is no [`AffineCcdConfig`] resource either.
    pub fn new(config: CcdConfig) -> Self {
        Self::with_hooks(config)
    }
}

impl<H> AffineCcdPlugin<H> {
    /// For `RapierPhysicsPlugin::<H>` with hooks `H` other than
    /// `NoUserData`: `AffineCcdPlugin::<H>::with_hooks(config)`.
    pub fn with_hooks(config: CcdConfig) -> Self {
        AffineCcdPlugin {
            config,
            _hooks: PhantomData,
        }
    }
}

/// A [`CcdConfig`] for every context (over the plugin's own), read at every
/// step.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Deref, DerefMut)]
pub struct AffineCcdConfig(pub CcdConfig);

/// A [`CcdConfig`] for one context: a component of its context entity (the
/// one with `RapierContextSimulation`), over [`AffineCcdConfig`].
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Deref, DerefMut)]
pub struct ContextCcdConfig(pub CcdConfig);

/// The configuration given to the plugin, used when neither a
/// [`ContextCcdConfig`] nor an [`AffineCcdConfig`] is there.
#[derive(Resource, Clone, Copy, Debug)]
pub struct PluginCcdConfig(pub CcdConfig);

/// The CCD stage of one context and what it did in the last update, on the
/// context entity (added with `RapierContextSimulation`, or by the first
/// step of a context spawned before the plugin was built).
#[derive(Component, Default)]
pub struct AffineCcdStage {
    stage: AffineCcd,
    reports: Vec<CcdReport>,
}

impl AffineCcdStage {
    /// One report per rapier step run in the last update (none when no step
    /// ran; several with substeps or when interpolation catches up).
    pub fn reports(&self) -> &[CcdReport] {
        &self.reports
    }

    /// The last step's report, if a step has run in the last update.
    pub fn last_report(&self) -> Option<&CcdReport> {
        self.reports.last()
    }

    /// Clamps in the last update, all steps together.
    pub fn clamps(&self) -> usize {
        self.reports.iter().map(CcdReport::clamps).sum()
    }

    /// The stage itself (its current configuration, its last step's report).
    pub fn stage(&self) -> &AffineCcd {
        &self.stage
    }
}

/// One clamp: a fast body was put back just before it would have hit
/// something (affine-ccd's `CcdHitEvent`, with entities).
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub struct CcdHit {
    /// The entity of the rapier context.
    pub context: Entity,
    /// The clamped body.
    pub body: Entity,
    /// The body's collider that would have hit first.
    pub collider1: Entity,
    /// What it would have hit.
    pub collider2: Entity,
    /// Which rapier step of the update (0 unless substeps or interpolation
    /// ran several).
    pub step: usize,
    /// When, as a fraction of that step.
    pub fraction: f64,
    /// When, seconds from the start of that step.
    pub time: f64,
    /// Contact point on `collider1` at the hit, world.
    pub point: Vec3,
    /// Contact normal at the hit, world, unit, from `collider1` towards
    /// `collider2`.
    pub normal: Vec3,
}

/// Colliders removed since the last step of a context, with their entities:
/// bevy_rapier keeps such a map for the `REMOVED` collision events of the
/// next step, but privately, so the plugin keeps its own.
#[derive(Component, Default, Debug)]
pub struct RemovedColliders(pub(crate) HashMap<ColliderHandle, Entity>);

impl<H> Plugin for AffineCcdPlugin<H>
where
    H: 'static + BevyPhysicsHooks,
    for<'w, 's> SystemParamItem<'w, 's, H>: BevyPhysicsHooks,
{
    fn build(&self, app: &mut App) {
        app.insert_resource(PluginCcdConfig(self.config))
            .add_message::<CcdHit>();
        // Every context gets its stage and its removed-collider map when it
        // is spawned (the steps add them too, for a context spawned before
        // the plugin was built).
        let _ = app.try_register_required_components::<RapierContextSimulation, AffineCcdStage>();
        let _ = app.try_register_required_components::<RapierContextSimulation, RemovedColliders>();
    }

    /// bevy_rapier adds its systems in its `build`; by `finish` every
    /// plugin's systems are in, whatever the order the plugins were added.
    fn finish(&self, app: &mut App) {
        let labels: Vec<_> = app
            .world()
            .resource::<Schedules>()
            .iter()
            .filter(|(_, schedule)| {
                schedule
                    .graph()
                    .system_sets
                    .contains(PhysicsSet::StepSimulation)
            })
            .map(|(_, schedule)| schedule.label())
            .collect();
        let mut replaced = 0;
        let mut done_post_update = false;
        for label in labels {
            // bevy_rapier has no switch for its step alone, so its step
            // system is taken out (the set and its ordering stay) and ours
            // goes into the same set.
            let removed = app.remove_systems_in_set(
                label,
                bevy_rapier3d::plugin::systems::step_simulation::<H>,
                ScheduleCleanupPolicy::RemoveSystemsOnly,
            );
            match removed {
                Ok(n) if n > 0 => {
                    app.add_systems(
                        label,
                        step_simulation_with_ccd::<H>.in_set(PhysicsSet::StepSimulation),
                    );
                    app.add_systems(
                        label,
                        track_removed_colliders
                            .before(bevy_rapier3d::plugin::systems::sync_removals),
                    );
                    replaced += 1;
                    done_post_update |= label == PostUpdate.intern();
                }
                _ => {}
            }
        }
        if replaced == 0 {
            log::warn!(
                "AffineCcdPlugin: no bevy_rapier step system (with these hooks) was found; \
                 add `step_simulation_with_ccd` to `PhysicsSet::StepSimulation` yourself"
            );
        }
        // bevy_rapier runs its removal systems in `PostUpdate` too when the
        // physics runs in another schedule: removals seen there are tracked
        // there.
        if replaced > 0 && !done_post_update {
            app.add_systems(
                PostUpdate,
                track_removed_colliders.before(bevy_rapier3d::plugin::systems::sync_removals),
            );
        }
    }
}

/// The stage configuration a context uses: its component, else the
/// resource, else the plugin's default.
fn config_for(
    component: Option<&ContextCcdConfig>,
    resource: Option<&AffineCcdConfig>,
    fallback: Option<&PluginCcdConfig>,
) -> CcdConfig {
    component
        .map(|c| c.0)
        .or(resource.map(|c| c.0))
        .or(fallback.map(|d| d.0))
        .unwrap_or_default()
}
