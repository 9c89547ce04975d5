//! Test scenes for continuous collision detection, the oracle that counts
//! tunnelling in them, and the dense-sampling ground truth the tests and
//! benches of `affine-ccd` compare against ([`truth`]). This crate is not part
//! of the library: the library's stage depends on none of it.
//!
//! A [`Scene`] is a plain description: a name, a time step, a number of steps,
//! the effects it exercises, and a builder that fills a rapier
//! `PhysicsWorld` with bodies and colliders.
//! The builder returns a [`Setup`]: the guards (which body must stay on which
//! side of which obstacle) and the scripts that drive kinematic bodies.
//!
//! Three families of counters judge a run:
//!
//! - [`guard`]: a per-scene geometric invariant. A body ended on the wrong
//!   side of an obstacle it should have hit ("tunnelling events").
//! - [`counter`]: a generic check for every scene. Each step, every pair of
//!   colliders that may collide is sampled along the motion between its two
//!   poses; a contact that only exists between the poses is a "missed
//!   contact", a step that starts shallow and ends deep is a "deep end".
//! - [`fidelity`]: what a CCD backend must *not* do besides removing
//!   tunnelling: hold a body still against its velocity ("frozen"), change
//!   the velocity of a body whose free path touches nothing ("deflected"),
//!   let mechanical energy rise, or rest bodies elsewhere than rapier does.
//!
//! [`runner`] steps a scene under a [`Backend`] and returns a
//! [`SceneReport`]; [`svg`] draws a run.
//!
//! Units: metres, seconds, radians, radians per second.

pub mod backend;
pub mod bullets;
pub mod catalog;
pub mod contraptions;
pub mod counter;
pub mod fidelity;
pub mod floors;
pub mod guard;
pub mod kit;
pub mod near_miss;
pub mod reported;
pub mod runner;
pub mod script;
pub mod settle;
pub mod snapshot;
pub mod spinners;
pub mod step_path;
pub mod svg;
pub mod truth;

pub use catalog::{all, find};
pub use guard::Guard;
pub use runner::{Backend, RunOptions, SceneReport, run_scene};
pub use script::Script;

use rapier3d::prelude::PhysicsWorld;

/// The physical effects a scene needs from the engine (and so from a CCD
/// backend that wants to stay faithful to it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Effects {
    /// Gravity is on (the builder may tilt it, e.g. the pinball table).
    pub gravity: bool,
    /// Bodies rotate fast enough for rotation to matter within a step.
    pub rotation: bool,
    /// Some colliders bounce (restitution > 0).
    pub restitution: bool,
    /// Friction shapes the outcome (sliding, rolling, stacking).
    pub friction: bool,
    /// Kinematic bodies are driven by scripts.
    pub kinematic: bool,
    /// The bodies come to rest, each on its own (no pile, no chain of
    /// collisions): their final poses can be compared with rapier's.
    pub settles: bool,
}

/// What the builder hands back besides the filled world.
#[derive(Clone, Debug, Default)]
pub struct Setup {
    /// The per-scene invariants: which body must not pass which obstacle.
    pub guards: Vec<Guard>,
    /// Scripted kinematic bodies, moved before every step.
    pub scripts: Vec<Script>,
}

/// One test scene: a plain description, cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    /// Short unique name, used by `--scene` (substring match).
    pub name: &'static str,
    /// One line saying what happens.
    pub about: &'static str,
    /// Time step in seconds.
    pub dt: f32,
    /// Number of steps a full run takes.
    pub steps: usize,
    /// Effects the scene exercises; `effects.gravity` says whether gravity is on.
    pub effects: Effects,
    /// Whether the scene is built so that a world without CCD tunnels or
    /// ends deep in something (the oracle must see it); `false` for control
    /// scenes, on which no backend may show anything.
    pub built_to_tunnel: bool,
    /// The two world axes of the side view drawn by [`svg`] (0 = x, 1 = y, 2 = z):
    /// horizontal, then vertical.
    pub view: [usize; 2],
    /// Fills an empty world (already holding `dt` and gravity) with the scene.
    pub build: fn(&mut PhysicsWorld) -> Setup,
}

impl Scene {
    /// Whether gravity is on in this scene.
    pub fn gravity(&self) -> bool {
        self.effects.gravity
    }

    /// A fresh world holding the scene at its initial state, and its setup.
    ///
    /// Gravity is `-9.81 m/s²` along y when on (the builder may change it),
    /// zero otherwise; `dt` is set from the scene.
    pub fn instantiate(&self) -> (PhysicsWorld, Setup) {
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = self.dt;
        if !self.gravity() {
            world.gravity = rapier3d::math::Vector::ZERO;
        }
        let setup = (self.build)(&mut world);
        (world, setup)
    }
}
