//! What one step of the CCD stage did: counts, clamps and skipped bodies.

use crate::query::{FamilyEvaluations, Query};
use rapier3d::prelude::{ColliderHandle, RigidBodyHandle, Vector};
use std::time::Duration;

/// One clamp: a fast body stopped short of a collider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CcdHitEvent {
    pub body: RigidBodyHandle,
    /// The body's collider that would have hit first.
    pub collider1: ColliderHandle,
    /// What it would have hit.
    pub collider2: ColliderHandle,
    /// When, as a fraction of the step.
    pub fraction: f64,
    /// When, seconds from the start of the step.
    pub time: f64,
    /// Contact point on `collider1` at the hit, world, metres.
    pub point: Vector,
    /// Contact normal at the hit, world, unit, from `collider1` towards
    /// `collider2`.
    pub normal: Vector,
}

/// Why a body that might have needed a sweep was left alone this step.
#[derive(Clone, Debug, PartialEq)]
pub enum SkipReason {
    /// Its pose or velocity was NaN or infinite (before or after the step).
    NonFinite,
    /// The time-of-impact query failed; the message says why.
    Query(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct SkippedBody {
    pub body: RigidBodyHandle,
    pub reason: SkipReason,
}

/// The CCD stage's account of one step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CcdReport {
    /// Fast bodies swept.
    pub bodies_swept: usize,
    /// Collider pairs handed to the time-of-impact query (a pair of two
    /// fast colliders counts once when one's sweep proves them apart over
    /// the whole step: the other's takes that answer).
    pub pairs: usize,
    /// Pairs of a sweep against everything (a fast body's first) whose
    /// bodies move together: no point of one nears or leaves the other by
    /// more than `fast_factor` times the thinner one's thickness over the
    /// step, so neither can pass through the other. They are left to
    /// rapier's contacts, as slow bodies are, and not counted in `pairs`.
    pub pairs_moving_together: usize,
    /// Pairs already within the skin at the start of the step, left to
    /// rapier's contacts unless they sink deeper than `CcdConfig::sink`.
    pub pairs_touching_at_start: usize,
    /// Contacts made during the step too late to get deeper than
    /// `CcdConfig::sink`, left to rapier's contacts (no clamp).
    pub shallow_contacts: usize,
    /// Pair evaluations the query spent.
    pub evaluations: u64,
    /// The same evaluations by what each was spent on (which gap family,
    /// a composite's bounding box, or a shortcut): they add up to
    /// `evaluations`.
    pub evaluations_by_family: FamilyEvaluations,
    /// One event per clamped body.
    pub hits: Vec<CcdHitEvent>,
    /// Sensor crossings inside the step reported as Started + Stopped.
    pub sensor_crossings: usize,
    pub skipped: Vec<SkippedBody>,
    /// Solver pieces the step ran (1 unless `CcdConfig::substeps` > 1).
    pub pieces: usize,
    /// Length of the shortest piece, seconds.
    pub shortest_piece: f64,
    /// Time spent in the stage's sweeps, queries and clamps and, with
    /// `substeps` > 1, in predicting the pieces; rapier's own step is
    /// excluded, and so are the pose copy before it and the selection of
    /// fast bodies after it (a comparison per body, cheaper than reading the
    /// clock).
    pub elapsed: Duration,
}

impl CcdReport {
    /// Number of bodies clamped.
    pub fn clamps(&self) -> usize {
        self.hits.len()
    }

    /// Adds the account of a piece of the step that began `start` seconds
    /// into a step of `dt` seconds (hit times become the whole step's; a
    /// piece that is the whole step keeps them to the bit).
    pub(crate) fn absorb(&mut self, piece: &CcdReport, start: f64, dt: f64) {
        self.bodies_swept += piece.bodies_swept;
        self.pairs += piece.pairs;
        self.pairs_moving_together += piece.pairs_moving_together;
        self.pairs_touching_at_start += piece.pairs_touching_at_start;
        self.shallow_contacts += piece.shallow_contacts;
        self.evaluations += piece.evaluations;
        self.evaluations_by_family += piece.evaluations_by_family;
        self.sensor_crossings += piece.sensor_crossings;
        // A piece's own report has one piece: its length.
        let (offset, share) = (start / dt, piece.shortest_piece / dt);
        for hit in &piece.hits {
            self.hits.push(CcdHitEvent {
                time: start + hit.time,
                fraction: offset + hit.fraction * share,
                ..*hit
            });
        }
        for s in &piece.skipped {
            self.skip(s.body, s.reason.clone());
        }
        self.shortest_piece = if self.pieces == 0 {
            piece.shortest_piece
        } else {
            self.shortest_piece.min(piece.shortest_piece)
        };
        self.pieces += piece.pieces;
        self.elapsed += piece.elapsed;
    }

    /// Adds what the last search of `query` spent, hit or miss.
    pub(crate) fn count(&mut self, query: &Query) {
        self.evaluations += query.spent().pair_evaluations;
        self.evaluations_by_family += query.spent_by_family();
    }

    /// Back to an empty account, keeping the buffers.
    pub(crate) fn clear(&mut self) {
        let (mut hits, mut skipped) = (
            std::mem::take(&mut self.hits),
            std::mem::take(&mut self.skipped),
        );
        hits.clear();
        skipped.clear();
        *self = CcdReport {
            hits,
            skipped,
            ..CcdReport::default()
        };
    }

    pub(crate) fn skip(&mut self, body: RigidBodyHandle, reason: SkipReason) {
        if !self.skipped.iter().any(|s| s.body == body) {
            self.skipped.push(SkippedBody { body, reason });
        }
    }
}
