//! The CCD backends a scene can run under, behind one small trait.
//!
//! - `off`: rapier with CCD disabled world-wide
//!   (`integration_parameters.max_ccd_substeps = 0`, which also zeroes the
//!   CCD velocities), whatever the bodies' `ccd_enabled` flag says.
//! - `rapier`: rapier's defaults (`max_ccd_substeps = 1`, the post-solve
//!   clamp, or `BackendConfig::substeps`) honouring the scenes'
//!   `ccd_enabled` bodies.
//! - `affine`: this crate's stage, [`affine_ccd::rapier::AffineCcd`], installed
//!   into the world (its dispatcher in, rapier's CCD off).

use affine_ccd::query::FamilyEvaluations;
use rapier3d::prelude::PhysicsWorld;
use std::fmt;
use std::str::FromStr;
use std::time::Duration;

/// A way of stepping a world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// No CCD at all.
    Off,
    /// Rapier's own CCD.
    Rapier,
    /// This crate's sound CCD stage.
    Affine,
}

impl Backend {
    /// Every backend, in table order.
    pub const ALL: [Backend; 3] = [Backend::Off, Backend::Rapier, Backend::Affine];

    /// The name used on the command line and in tables.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Off => "off",
            Backend::Rapier => "rapier",
            Backend::Affine => "affine",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = String;

    /// Parses `off`, `rapier` or `affine` (case-insensitive; `none` for `off`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "off" | "none" => Ok(Backend::Off),
            "rapier" => Ok(Backend::Rapier),
            "affine" => Ok(Backend::Affine),
            other => Err(format!(
                "unknown backend `{other}` (expected off, rapier or affine)"
            )),
        }
    }
}

/// Settings handed to a backend when it is made.
#[derive(Clone, Copy, Debug, Default)]
pub struct BackendConfig {
    /// Accuracy of the affine backend as a fraction of the step; `None` for
    /// its default. Ignored by `off` and `rapier`.
    pub epsilon: Option<f64>,
    /// Solver pieces per step at most, for `rapier` (`max_ccd_substeps`)
    /// and `affine` (`CcdConfig::substeps`); `None` for their default (1).
    pub substeps: Option<u32>,
}

/// Steps a world, with or without a CCD stage.
pub trait Stepper {
    /// Prepares a freshly built world (called once, before the first step).
    fn install(&mut self, world: &mut PhysicsWorld);
    /// Advances the world by one step of `world.integration_parameters.dt`.
    fn step(&mut self, world: &mut PhysicsWorld);
    /// Time spent in CCD over all steps so far, when the backend can tell.
    fn ccd_time(&self) -> Option<Duration>;
    /// What the CCD stage did over all steps so far (affine only).
    fn profile(&self) -> Option<StageProfile> {
        None
    }
}

/// The affine stage's work summed over a run: where its time goes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageProfile {
    /// Steps run.
    pub steps: usize,
    /// Bodies swept (first sweeps and re-sweeps).
    pub bodies_swept: usize,
    /// Collider pairs handed to the time-of-impact query.
    pub pairs: usize,
    /// Pairs moving together (left to rapier's contacts, not queried).
    pub together: usize,
    /// Pairs touching at the start of a step (sampled, left to rapier).
    pub touching: usize,
    /// Contacts made too late in a step to get deep (left to rapier).
    pub shallow: usize,
    /// Pair evaluations the queries spent.
    pub evaluations: u64,
    /// The same by what each was spent on (gap family, composite bounding
    /// box or shortcut).
    pub families: FamilyEvaluations,
    /// Bodies clamped.
    pub clamps: usize,
}

impl StageProfile {
    fn add(&mut self, r: &affine_ccd::rapier::CcdReport) {
        self.steps += 1;
        self.bodies_swept += r.bodies_swept;
        self.pairs += r.pairs;
        self.together += r.pairs_moving_together;
        self.touching += r.pairs_touching_at_start;
        self.shallow += r.shallow_contacts;
        self.evaluations += r.evaluations;
        self.families += r.evaluations_by_family;
        self.clamps += r.clamps();
    }
}

/// Rapier with CCD disabled world-wide.
struct Off;

impl Stepper for Off {
    fn install(&mut self, world: &mut PhysicsWorld) {
        world.integration_parameters.max_ccd_substeps = 0;
    }

    fn step(&mut self, world: &mut PhysicsWorld) {
        world.step();
    }

    fn ccd_time(&self) -> Option<Duration> {
        None
    }
}

/// Rapier's own CCD with this many substeps (its default: 1).
struct Rapier {
    substeps: usize,
}

impl Stepper for Rapier {
    fn install(&mut self, world: &mut PhysicsWorld) {
        // Set explicitly in case a scene changed it.
        world.integration_parameters.max_ccd_substeps = self.substeps;
    }

    fn step(&mut self, world: &mut PhysicsWorld) {
        world.step();
    }

    /// Rapier times its CCD only with its `profiler` feature, which this
    /// crate does not enable: its timers then read zero. So: not measurable.
    fn ccd_time(&self) -> Option<Duration> {
        None
    }
}

/// This crate's CCD stage, timed by its own report.
struct Affine {
    ccd: affine_ccd::rapier::AffineCcd,
    ccd_time: Duration,
    profile: StageProfile,
}

impl Stepper for Affine {
    fn install(&mut self, world: &mut PhysicsWorld) {
        self.ccd.install(world);
    }

    fn step(&mut self, world: &mut PhysicsWorld) {
        let report = self.ccd.step(world);
        self.ccd_time += report.elapsed;
        self.profile.add(report);
    }

    fn ccd_time(&self) -> Option<Duration> {
        Some(self.ccd_time)
    }

    fn profile(&self) -> Option<StageProfile> {
        Some(self.profile)
    }
}

/// The one place a backend becomes a stepper. `None`: not available.
pub fn make_stepper(backend: Backend, config: &BackendConfig) -> Option<Box<dyn Stepper>> {
    match backend {
        Backend::Off => Some(Box::new(Off)),
        Backend::Rapier => Some(Box::new(Rapier {
            substeps: config.substeps.unwrap_or(1).max(1) as usize,
        })),
        Backend::Affine => {
            let mut ccd = affine_ccd::rapier::AffineCcd::default();
            if let Some(epsilon) = config.epsilon {
                ccd.config_mut().epsilon = epsilon;
            }
            if let Some(substeps) = config.substeps {
                ccd.config_mut().substeps = substeps;
            }
            Some(Box::new(Affine {
                ccd,
                ccd_time: Duration::ZERO,
                profile: StageProfile::default(),
            }))
        }
    }
}
