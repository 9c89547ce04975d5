//! # affine-ccd
//!
//! Sound continuous collision detection for rapier3d, by enclosure arithmetic.
//!
//! A body's motion over one step becomes polynomials in the step fraction
//! τ ∈ [0, 1] ([`motion`]). For each shape pair a distance function D(τ) is
//! positive while the shapes are apart. Enclosure arithmetic ([`enclosure`]:
//! intervals, affine forms, Taylor models) bounds D over a whole τ-interval at
//! once, and an earliest-root search ([`solve`]) finds the first τ at which
//! some pair may touch, for many pairs at once, pruning pairs proved apart.
//!
//! Data goes one way: motion → distance functions → solver → the caller.

pub mod convert;
pub mod enclosure;
pub mod error;
pub(crate) mod gap;
pub(crate) mod hashing;
pub mod motion;
pub mod query;
pub mod rapier;
pub mod solve;

pub use enclosure::{
    Affine, Arithmetic, Enclosure, InArithmetic, Interval, Taylor, Taylor2, Taylor3, TimeSpan,
};
pub use error::CcdError;

pub use motion::{Motion, Pose, Trajectory};
pub use query::{ManyToi, QueryOptions, ShapeMotion, Toi, time_of_impact, time_of_impact_many};
pub use solve::{
    GapSet, InitialContact, RootStatus, SolveOptions, SolveOutcome, SolveStats, Solver,
};

/// The README's examples, compiled and run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
