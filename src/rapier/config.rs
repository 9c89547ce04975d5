//! What the CCD stage does, as plain serialisable data.

use crate::enclosure::Arithmetic;
use serde::{Deserialize, Serialize};

/// Mirror of [`Arithmetic`] for serde: the core type stays free of serde.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Arithmetic", rename_all = "lowercase")]
enum ArithmeticDef {
    Interval,
    Affine,
    Taylor2,
    Taylor3,
}

/// Which kinds of collider a fast dynamic body is swept against. A collider
/// without a parent body counts as fixed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct SweepTargets {
    pub fixed: bool,
    /// Kinematic bodies; also whether fast kinematic bodies push the
    /// dynamic bodies they would pass (carried from their impact on).
    pub kinematic: bool,
    /// Other dynamic bodies, with their own motion over the step (fast ones
    /// both ways).
    pub dynamic: bool,
}

impl Default for SweepTargets {
    /// Everything a dynamic body can collide with.
    fn default() -> SweepTargets {
        SweepTargets {
            fixed: true,
            kinematic: true,
            dynamic: true,
        }
    }
}

/// Settings of [`AffineCcd`](super::AffineCcd).
///
/// Where a clamped body stands is not a setting: it is where rapier's own
/// CCD stops it, read from the world's `IntegrationParameters`
/// (`allowed_linear_error`, 5 mm by default): a pair of unrounded shapes
/// (boxes, triangles, hulls) that far before its true contact, a pair with
/// a ball or capsule in it that deep after it, found as closely as rapier
/// finds it: within parry's tolerance (a quarter of that error) of that
/// depth, never deeper, however small `epsilon` is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CcdConfig {
    /// Accuracy of each time of impact, a fraction of the step: a reported
    /// contact is at most this much before the true one.
    pub epsilon: f64,
    /// Metres: the band within which a pair counts as touching at the start
    /// of a step (rapier's contacts own it then; a slow pair also within
    /// rapier's tolerance of its stop), and ten times the distance a clamp
    /// backs off from the true contact where rapier's CCD stops at the
    /// contact itself (moving targets, cylinders, cones, half-spaces) or a
    /// search ran out of budget. A hit is always the true contact (zero
    /// distance): a shape that passes within the skin of something without
    /// touching it is not clamped. Used as `min(skin, ½·prediction
    /// distance)`; rapier's prediction distance is 2 cm by default.
    pub skin: f64,
    /// Metres a contact may go deep within a step before the stage steps
    /// in. A fast body touching something at the start may sink this far
    /// (or beyond its start depth, or a ball or capsule a little beyond
    /// rapier's stop depth, or, where its contact point is not driven in,
    /// as a rolling cone's is not, a quarter of the thinner shape;
    /// rapier's contacts own such pairs, this only keeps the solver from
    /// pushing a fast body deep, such as a spinning edge into a wall),
    /// and a contact rapier casts to the contact itself
    /// made so late in the step that the pair cannot move this far after
    /// it is left to rapier's contacts as well (a slow landing is not
    /// clamped).
    pub sink: f64,
    #[serde(with = "ArithmeticDef")]
    pub arithmetic: Arithmetic,
    /// Evaluation budget per swept collider per step. When it runs out the
    /// body is clamped at the earliest time not yet excluded (never a miss).
    pub max_evaluations: u64,
    /// A body is swept when its fastest point moves more than this share
    /// of its thinnest extent in the step (rapier uses 0.5).
    pub fast_factor: f64,
    pub targets: SweepTargets,
    /// Solver pieces per step at most. 1 (the default): rapier solves the
    /// whole step and the stage clamps fast bodies at their impact (they
    /// wait there for the next step's contacts). More: the step is cut at
    /// the earliest impact predicted from velocities, forces and gravity,
    /// and each piece is solved and clamped in turn, so a body that hits
    /// early in the step bounces within it (rapier's `max_ccd_substeps`).
    /// Pieces are never shorter than rapier's `min_ccd_dt`.
    pub substeps: u32,
    /// Per-body opt-out: a dynamic body whose `RigidBody::user_data` has
    /// this bit (0–127) set is never swept or clamped (it still serves as
    /// a target). `None`: no opt-out. A bit, not a handle set, so the choice
    /// lives with the body and survives snapshots.
    pub opt_out_bit: Option<u8>,
}

impl Default for CcdConfig {
    fn default() -> CcdConfig {
        CcdConfig {
            epsilon: 1.0e-4,
            skin: 1.0e-3,
            sink: 5.0e-3,
            arithmetic: Arithmetic::default(),
            max_evaluations: 100_000,
            fast_factor: 0.5,
            targets: SweepTargets::default(),
            substeps: 1,
            opt_out_bit: None,
        }
    }
}

impl CcdConfig {
    /// True when `user_data` opts its body out of the stage.
    pub fn opted_out(&self, user_data: u128) -> bool {
        self.opt_out_bit
            .is_some_and(|bit| bit < 128 && user_data & (1u128 << bit) != 0)
    }
}
