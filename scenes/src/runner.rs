//! Runs one scene under one backend and reports what the two oracles saw,
//! and what the fidelity counters ([`super::fidelity`]) saw.

use super::Scene;
pub use super::backend::{Backend, BackendConfig, StageProfile, Stepper, make_stepper};
use super::counter::{self, ContactKind};
use super::fidelity::{self, EnergyMeter, FrozenCounter, RestGap};
use super::guard::GuardWatch;
use super::snapshot::{BodyState, Snapshot};
use super::svg::Trace;
use rapier3d::prelude::{PhysicsWorld, Real, RigidBodyHandle, Vector};
use std::collections::BTreeMap;
use std::fmt;
use std::time::{Duration, Instant};

/// How to run a scene.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunOptions {
    /// Number of steps; `None` for the scene's own.
    pub steps: Option<usize>,
    /// Handed to the backend (see [`BackendConfig`]).
    pub backend: BackendConfig,
    /// Keep trajectories and event positions for an SVG drawing.
    pub trace: bool,
    /// Metres every dynamic body is raised (against gravity; along y
    /// without it) before the first step: a perturbation for telling how
    /// reproducible a run's outcome is (see [`SceneReport::compare_rest`]).
    pub lift: Real,
}

/// Why a scene could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunError {
    /// The backend is not built yet.
    Unavailable(Backend),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Unavailable(backend) => write!(f, "{backend}: not built yet"),
        }
    }
}

impl std::error::Error for RunError {}

/// What one run of one scene under one backend gave.
#[derive(Clone, Debug)]
pub struct SceneReport {
    pub scene: &'static str,
    pub backend: Backend,
    /// Per-scene invariant violations ([`super::guard`]).
    pub tunnelling: usize,
    /// Contacts deeper than the limit between the poses only ([`super::counter`]).
    pub missed_contacts: usize,
    /// Steps that started shallow and ended deep ([`super::counter`]).
    pub deep_ends: usize,
    /// Steps run.
    pub steps: usize,
    /// Median wall time of one step (milliseconds), the oracles excluded.
    pub median_step_ms: f64,
    /// Wall time of all steps together (milliseconds), the oracles
    /// excluded: where most steps are idle (a world that falls asleep), the
    /// median is the idle step and this is what the busy ones cost.
    pub total_step_ms: f64,
    /// Median wall time of one step less the backend's own CCD time
    /// (milliseconds), when the backend can measure it: what rapier's
    /// pipeline spent on this run's world. A backend that keeps bodies in
    /// play that another loses steps a busier world, so this, not the other
    /// backend's step, is the fair base for what the CCD stage itself costs.
    pub median_pipeline_ms: Option<f64>,
    /// Total time spent in CCD (milliseconds), when the backend can measure it.
    pub ccd_ms: Option<f64>,
    /// What the affine stage did over the run (`None` for other backends).
    pub profile: Option<StageProfile>,
    /// The drawing material, when asked for.
    pub trace: Option<Trace>,
    /// Body-steps a dynamic body was held while its velocity said it moves,
    /// in runs of at least [`fidelity::HELD_RUN`] steps ([`FrozenCounter`]),
    /// and not held when rapier alone (CCD off) takes that step from the
    /// same state (see `held_by_backend`).
    pub frozen: usize,
    /// Body-steps whose free path touched nothing but whose velocity the
    /// step changed ([`fidelity::deflected`]).
    pub deflected: usize,
    /// The largest one-step rise of the mechanical energy and its scale;
    /// `None` in scenes with kinematic scripts (energy is not closed there).
    pub energy: Option<EnergyMeter>,
    /// Whether the scene settles (`Effects::settles`): its rest poses can be
    /// compared with rapier's ([`SceneReport::compare_rest`]).
    pub settles: bool,
    /// The final state of every body, in handle order.
    pub final_bodies: Vec<(RigidBodyHandle, BodyState)>,
    /// The bodies some guard saw pass an obstacle (once each).
    pub tunnelled: Vec<RigidBodyHandle>,
    /// The unit vertical of the scene (against gravity; y without it).
    pub up: Vector,
    /// Distance of the final poses from a reference run's, once
    /// [`SceneReport::compare_rest`] was called on a settling scene.
    pub rest: Option<RestGap>,
}

impl SceneReport {
    /// Whether either oracle saw anything (tunnelling, missed contacts, deep
    /// ends; the fidelity counters are left to [`SceneReport::is_faithful`]).
    pub fn is_clean(&self) -> bool {
        self.tunnelling == 0 && self.missed_contacts == 0 && self.deep_ends == 0
    }

    /// Whether the backend held or deflected no body.
    pub fn is_faithful(&self) -> bool {
        self.frozen == 0 && self.deflected == 0
    }

    /// The largest one-step energy rise in percent of the run's largest
    /// kinetic energy; `None` in scenes with kinematic scripts.
    pub fn energy_rise_percent(&self) -> Option<f64> {
        self.energy.map(|e| e.rise_percent())
    }

    /// Sets [`SceneReport::rest`] from a reference run of the same scene
    /// (rapier's, same steps) when the scene settles. A different scene or
    /// step count leaves it unset.
    pub fn compare_rest(&mut self, reference: &SceneReport) {
        if self.settles && reference.scene == self.scene && reference.steps == self.steps {
            self.rest = Some(fidelity::rest_gap(
                &self.final_bodies,
                &reference.final_bodies,
                &reference.tunnelled,
                self.up,
            ));
        }
    }
}

/// Runs `scene` under `backend`.
///
/// Each step: scripted kinematic bodies get their targets, a snapshot is
/// taken, the backend steps (timed), then the guards and the contact
/// counter judge the step, and the fidelity counters compare the snapshots
/// before and after it. [`SceneReport::rest`] is left unset: it needs a
/// reference run ([`SceneReport::compare_rest`]).
pub fn run_scene(
    scene: &Scene,
    backend: Backend,
    options: &RunOptions,
) -> Result<SceneReport, RunError> {
    let mut stepper =
        make_stepper(backend, &options.backend).ok_or(RunError::Unavailable(backend))?;
    let (mut world, setup) = scene.instantiate();
    if options.lift != 0.0 {
        lift_dynamic_bodies(&mut world, options.lift);
    }
    stepper.install(&mut world);
    let steps = options.steps.unwrap_or(scene.steps);
    let mut watch = GuardWatch::new(&world, &setup.guards);
    let mut trace = options.trace.then(|| Trace::start(&world, scene.view));
    let mut times = Vec::with_capacity(steps);
    let mut pipeline_times = Vec::with_capacity(steps);
    let (mut tunnelling, mut missed_contacts, mut deep_ends) = (0, 0, 0);
    let mut tunnelled = Vec::new();
    let mut frozen = FrozenCounter::default();
    let mut deflected = 0;
    let closed = !scene.effects.kinematic;
    let mut energy = EnergyMeter::default();
    for step in 0..steps {
        let end_time = (step + 1) as f32 * scene.dt;
        for script in &setup.scripts {
            script.apply(&mut world, end_time);
        }
        let before = Snapshot::take(&world);
        let ccd_before = stepper.ccd_time();
        let started = Instant::now();
        stepper.step(&mut world);
        let took = started.elapsed();
        times.push(took);
        if let (Some(before), Some(after)) = (ccd_before, stepper.ccd_time()) {
            pipeline_times.push(took.saturating_sub(after.saturating_sub(before)));
        }
        let tunnels = watch.check(&world, &setup.guards, &before, step);
        let contacts = counter::check_step(&world, &before, step);
        tunnelling += tunnels.len();
        for event in &tunnels {
            let body = setup.guards[event.guard].body();
            if !tunnelled.contains(&body) {
                tunnelled.push(body);
            }
        }
        for event in &contacts {
            match event.kind {
                ContactKind::Missed => missed_contacts += 1,
                ContactKind::DeepEnd => deep_ends += 1,
            }
        }
        let after = Snapshot::take(&world);
        frozen.check_step(&before, &after, step);
        deflected += fidelity::deflected(&world, &before, &after).len();
        if closed {
            let (e0, e1) = fidelity::step_energies(&before, &after, world.gravity);
            energy.observe_step(e0, e1);
        }
        if let Some(trace) = &mut trace {
            trace.record(&world);
            trace.tunnels.extend(tunnels.iter().map(|e| e.at));
            trace.contacts.extend(contacts.iter().map(|e| e.at));
        }
    }
    let mut final_bodies: Vec<(RigidBodyHandle, BodyState)> =
        Snapshot::take(&world).bodies.into_iter().collect();
    final_bodies.sort_by_key(|(h, _)| h.into_raw_parts());
    Ok(SceneReport {
        scene: scene.name,
        backend,
        tunnelling,
        missed_contacts,
        deep_ends,
        steps,
        total_step_ms: times.iter().map(|d| d.as_secs_f64() * 1e3).sum(),
        median_step_ms: median_ms(&mut times),
        median_pipeline_ms: (!pipeline_times.is_empty()).then(|| median_ms(&mut pipeline_times)),
        ccd_ms: stepper.ccd_time().map(|d| d.as_secs_f64() * 1e3),
        profile: stepper.profile(),
        trace,
        frozen: held_by_backend(scene, backend, options, &frozen.counted),
        deflected,
        energy: closed.then_some(energy),
        settles: scene.effects.settles,
        final_bodies,
        tunnelled,
        up: (-world.gravity).try_normalize().unwrap_or(Vector::Y),
        rest: None,
    })
}

/// How many of the held body-steps `counted` ([`FrozenCounter`]) are the
/// backend's doing: each such step is taken again from the same state (the
/// scene replayed up to it under the same backend) by rapier with its CCD
/// off, and a body rapier alone holds there too is rapier's, not the
/// backend's (a box rattling in a corner, its spin reversing every step,
/// is held by rapier's solver under any backend). Under `Off` every step
/// is rapier's alone: none are the backend's.
fn held_by_backend(
    scene: &Scene,
    backend: Backend,
    options: &RunOptions,
    counted: &[(usize, RigidBodyHandle)],
) -> usize {
    if backend == Backend::Off {
        return 0;
    }
    held_by_stepper(
        scene,
        &|| make_stepper(backend, &options.backend),
        options.lift,
        counted,
    )
}

/// [`held_by_backend`] for the steppers `make` builds (`None`: it cannot,
/// and every counted body-step is taken as the stepper's).
fn held_by_stepper(
    scene: &Scene,
    make: &dyn Fn() -> Option<Box<dyn Stepper>>,
    lift: Real,
    counted: &[(usize, RigidBodyHandle)],
) -> usize {
    let mut by_step: BTreeMap<usize, Vec<RigidBodyHandle>> = BTreeMap::new();
    for &(step, body) in counted {
        by_step.entry(step).or_default().push(body);
    }
    let mut theirs = 0;
    for (&step, bodies) in &by_step {
        let Some((before, after)) = make().map(|s| replay_plain(scene, s, lift, step)) else {
            theirs += bodies.len();
            continue;
        };
        theirs += bodies
            .iter()
            .filter(|b| match (before.bodies.get(b), after.bodies.get(b)) {
                (Some(start), Some(end)) => !fidelity::is_held(start, end),
                _ => true,
            })
            .count();
    }
    theirs
}

/// The scene run by `stepper` up to step `step`, which rapier then takes
/// with its CCD off: the snapshots before and after that step.
fn replay_plain(
    scene: &Scene,
    mut stepper: Box<dyn Stepper>,
    lift: Real,
    step: usize,
) -> (Snapshot, Snapshot) {
    let (mut world, setup) = scene.instantiate();
    if lift != 0.0 {
        lift_dynamic_bodies(&mut world, lift);
    }
    stepper.install(&mut world);
    for k in 0..=step {
        let end_time = (k + 1) as f32 * scene.dt;
        for script in &setup.scripts {
            script.apply(&mut world, end_time);
        }
        if k < step {
            stepper.step(&mut world);
        }
    }
    let before = Snapshot::take(&world);
    let ccd = world.integration_parameters.max_ccd_substeps;
    world.integration_parameters.max_ccd_substeps = 0;
    world.step();
    world.integration_parameters.max_ccd_substeps = ccd;
    (before, Snapshot::take(&world))
}

/// Raises every dynamic body by `by` metres against gravity.
fn lift_dynamic_bodies(world: &mut PhysicsWorld, by: Real) {
    let up = (-world.gravity).try_normalize().unwrap_or(Vector::Y);
    for (_, rb) in world.bodies.iter_mut() {
        if rb.is_dynamic() {
            let mut pose = *rb.position();
            pose.translation += up * by;
            rb.set_position(pose, true);
        }
    }
}

/// Median of `times` in milliseconds (0 when empty).
fn median_ms(times: &mut [Duration]) -> f64 {
    if times.is_empty() {
        return 0.0;
    }
    times.sort_unstable();
    times[times.len() / 2].as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Effects, Setup};
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};

    /// A ball sliding at 5 m/s along a floor, gravity off.
    fn sliding(world: &mut PhysicsWorld) -> Setup {
        world.insert_collider(ColliderBuilder::cuboid(50.0, 0.5, 50.0), None);
        world.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, 1.0, 0.0))
                .linvel(Vector::new(5.0, 0.0, 0.0)),
            ColliderBuilder::ball(0.5),
        );
        Setup::default()
    }

    const SLIDING: Scene = Scene {
        name: "sliding",
        about: "a ball sliding along a floor",
        dt: 1.0 / 60.0,
        steps: 30,
        effects: Effects {
            gravity: false,
            rotation: false,
            restitution: false,
            friction: false,
            kinematic: false,
            settles: false,
        },
        built_to_tunnel: false,
        view: [0, 1],
        build: sliding,
    };

    /// Steps the world, then puts every dynamic body back where it started
    /// the step, velocities kept: a backend that freezes bodies.
    struct Pinning;

    impl Stepper for Pinning {
        fn install(&mut self, _: &mut PhysicsWorld) {}

        fn step(&mut self, world: &mut PhysicsWorld) {
            let start: Vec<_> = world
                .bodies
                .iter()
                .map(|(h, rb)| (h, *rb.position()))
                .collect();
            world.step();
            for (h, pose) in start {
                if let Some(rb) = world.bodies.get_mut(h).filter(|rb| rb.is_dynamic()) {
                    rb.set_position(pose, true);
                }
            }
        }

        fn ccd_time(&self) -> Option<Duration> {
            None
        }
    }

    /// A backend that pins a sliding ball holds it every step, and the
    /// replays (rapier alone from each pinned state moves it) charge the
    /// backend with every one of those steps.
    #[test]
    fn a_backend_that_pins_bodies_is_charged_with_every_held_step() {
        let (mut world, _) = SLIDING.instantiate();
        let mut frozen = FrozenCounter::default();
        for step in 0..SLIDING.steps {
            let before = Snapshot::take(&world);
            Pinning.step(&mut world);
            frozen.check_step(&before, &Snapshot::take(&world), step);
        }
        assert_eq!(frozen.count(), SLIDING.steps);
        let theirs = held_by_stepper(&SLIDING, &|| Some(Box::new(Pinning)), 0.0, &frozen.counted);
        assert_eq!(theirs, SLIDING.steps);
    }
}
