//! The CCD backends a scene can run under, behind one small trait.
//!
//! - `off`: rapier with CCD disabled world-wide
//!   (`integration_parameters.max_ccd_substeps = 0`, which also zeroes the
//!   CCD velocities), whatever the bodies' `ccd_enabled` flag says.
//! - `rapier`: rapier's defaults (`max_ccd_substeps = 1`, the post-solve
//!   clamp) honouring the scenes' `ccd_enabled` bodies.
//! - `affine`: this crate's stage, `affine_ccd::rapier::AffineCcd`. Not
//!   built yet: [`make_stepper`] answers `None` for it.

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
    /// Target separation for the affine backend (metres); `None` for its
    /// default. Ignored by `off` and `rapier`.
    pub epsilon: Option<f64>,
}

/// Steps a world, with or without a CCD stage.
pub trait Stepper {
    /// Prepares a freshly built world (called once, before the first step).
    fn install(&mut self, world: &mut PhysicsWorld);
    /// Advances the world by one step of `world.integration_parameters.dt`.
    fn step(&mut self, world: &mut PhysicsWorld);
    /// Time spent in CCD over all steps so far, when the backend can tell.
    fn ccd_time(&self) -> Option<Duration>;
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

/// Rapier's defaults with its own CCD.
struct Rapier;

impl Stepper for Rapier {
    fn install(&mut self, world: &mut PhysicsWorld) {
        // Rapier's default; set explicitly in case a scene changed it.
        world.integration_parameters.max_ccd_substeps = 1;
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

/// The one place a backend becomes a stepper. `None`: not available (yet).
pub fn make_stepper(backend: Backend, config: &BackendConfig) -> Option<Box<dyn Stepper>> {
    let _ = config.epsilon; // Only the affine backend will read it.
    match backend {
        Backend::Off => Some(Box::new(Off)),
        Backend::Rapier => Some(Box::new(Rapier)),
        // AFFINE WIRE-IN: wrap `affine_ccd::rapier::AffineCcd::default()`
        // (epsilon from `config`) in a `Stepper` whose `install` calls
        // `ccd.install(world)` and whose `step` calls `ccd.step(world)`.
        Backend::Affine => None,
    }
}
