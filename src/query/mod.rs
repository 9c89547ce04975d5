//! The public queries: the time of impact of moving shapes.
//!
//! [`time_of_impact`] answers for one pair of parry shapes, each with its
//! [`Motion`]; [`time_of_impact_many`] for several moving shapes (a body's
//! colliders) against many targets at once, in one search: the solver prunes
//! whole pairs as soon as they are proved apart, so a target far from the
//! path costs one evaluation.
//!
//! ```
//! use affine_ccd::query::{time_of_impact, QueryOptions};
//! use affine_ccd::{Motion, RootStatus};
//! use nalgebra::{Isometry3, Point3, Vector3};
//! use rapier3d::parry::shape::Ball;
//!
//! // A 0.1 m ball flying at 100 m/s towards a ball 1 m away, for 1/60 s.
//! let start = Isometry3::translation(0.0, 0.0, 0.0);
//! let bullet = Motion::from_velocities(
//!     start, Point3::origin(), Vector3::new(100.0, 0.0, 0.0), Vector3::zeros(), 1.0 / 60.0,
//! ).unwrap();
//! let target = Motion::fixed(Isometry3::translation(1.0, 0.0, 0.0)).unwrap();
//! let toi = time_of_impact(&Ball::new(0.1), &bullet, &Ball::new(0.1), &target, &QueryOptions::default())
//!     .unwrap()
//!     .expect("they meet");
//! assert_eq!(toi.status, RootStatus::Hit);
//! // The centres meet 0.2 m apart: after 0.8 m, at 0.008 s.
//! assert!((toi.time - 0.008).abs() < 1e-4 / 60.0);
//! ```

mod advance;
mod balls;
mod contact;
mod frames;
mod pairs;
mod primitives;
mod profile;
mod sat;

pub(crate) use contact::{Settle, StartContact, Witness, contact, contact_settled, start_contact};
#[cfg(test)]
pub(crate) use contact::{cross_mesh, floors, grid};
pub use primitives::{PrimitiveToi, edge_edge_toi, vertex_face_toi};
pub use profile::{Family, FamilyEvaluations};

use crate::enclosure::{Arithmetic, TimeSpan};
use crate::error::{CcdError, check_finite};
use crate::gap;
use crate::gap::composite::{self, PairSide};
use crate::motion::Motion;
use crate::solve::{InitialContact, RootStatus, SolveOptions, SolveOutcome, SolveStats, Solver};
use balls::Balls;
use frames::{FrameBuffers, FrameDef};
use nalgebra::{Point3, Vector3};
use pairs::{CompositePair, PairContent, PairEntry, Search, Searched};
use rapier3d::parry::shape::Shape;
use smallvec::SmallVec;

/// How a query searches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryOptions {
    /// Accuracy in time as a fraction of the step: the reported time is at
    /// most this much before the true first contact (transversal contacts).
    pub epsilon: f64,
    /// Shapes closer than this (metres) count as touching.
    pub skin: f64,
    /// The enclosure arithmetic to search in.
    pub arithmetic: Arithmetic,
    /// The most pair evaluations one query may spend; past it the answer is
    /// the earliest time not yet excluded (`BudgetExhausted`).
    pub max_evaluations: u64,
    /// The part of the step to search, fractions within `[0, 1]`.
    pub time_range: TimeSpan,
    /// Pairs touching at the start: report them (`InitiallyTouching`) or
    /// leave them out and search the rest.
    pub initial_contact: InitialContact,
}

impl Default for QueryOptions {
    fn default() -> QueryOptions {
        QueryOptions {
            epsilon: 1.0e-4,
            skin: 0.0,
            arithmetic: Arithmetic::Affine,
            max_evaluations: 100_000,
            time_range: TimeSpan::STEP,
            initial_contact: InitialContact::Report,
        }
    }
}

impl QueryOptions {
    pub(crate) fn solve_options(&self) -> Result<SolveOptions, CcdError> {
        check_finite("skin", self.skin)?;
        if self.skin < 0.0 {
            return Err(CcdError::BadParameter {
                what: "skin",
                value: self.skin,
                expected: "skin >= 0 metres",
            });
        }
        let options = SolveOptions {
            epsilon: self.epsilon,
            max_evaluations: self.max_evaluations,
            span: self.time_range,
            initial_contact: self.initial_contact,
            start_apart: false,
        };
        options.validate()?;
        Ok(options)
    }
}

/// A time of impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toi {
    /// When, as a fraction of the step.
    pub fraction: f64,
    /// When, in seconds from the step's start (`fraction · dt`).
    pub time: f64,
    /// `Hit`, `InitiallyTouching`, or `BudgetExhausted` (a conservative
    /// time: the earliest not excluded).
    pub status: RootStatus,
    /// The closest point of shape 1 at the reported pose (world, metres).
    pub witness1: Point3<f64>,
    /// The closest point of shape 2 at the reported pose (world, metres).
    pub witness2: Point3<f64>,
    /// Unit normal from shape 1 towards shape 2 at the reported pose
    /// (world); zero when parry cannot say (e.g. the shapes' centres meet).
    pub normal1: Vector3<f64>,
    /// What the search spent.
    pub stats: SolveStats,
}

/// A shape with its motion over the step.
#[derive(Clone, Copy)]
pub struct ShapeMotion<'a> {
    pub shape: &'a dyn Shape,
    pub motion: Motion,
}

/// The earliest impact among many pairs before its witness is read: the
/// search's outcome (the time and status) and which pair it was. The
/// witness, parry's contact at that time, costs a few thousand
/// instructions, and a caller that reads only the time (a ball's or
/// capsule's contact, whose stop is searched next) need not pay for it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Found {
    pub outcome: SolveOutcome,
    /// Index into the `moving` slice.
    pub moving: usize,
    /// Index into the `targets` slice.
    pub target: usize,
    skin: f64,
}

impl Found {
    /// The hit with its witness, as [`Query::many`] reports it, from the
    /// slices the search was given.
    pub fn described(&self, moving: &[ShapeMotion], targets: &[ShapeMotion]) -> ManyToi {
        ManyToi {
            toi: self.toi(&moving[self.moving], &targets[self.target]),
            moving: self.moving,
            target: self.target,
        }
    }

    /// The hit with its witness, from the pair the search was given.
    pub fn toi(&self, moving: &ShapeMotion, target: &ShapeMotion) -> Toi {
        contact::describe(
            &self.outcome,
            self.skin,
            moving.shape,
            &moving.motion,
            target.shape,
            &target.motion,
        )
    }
}

/// The earliest impact among many pairs, and which pair it was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManyToi {
    pub toi: Toi,
    /// Index into the `moving` slice.
    pub moving: usize,
    /// Index into the `targets` slice.
    pub target: usize,
}

/// One moving shape and one target, as the slices [`Query::many`] takes.
pub(crate) fn lone_pair<'a>(
    shape1: &'a dyn Shape,
    motion1: &Motion,
    shape2: &'a dyn Shape,
    motion2: &Motion,
) -> ([ShapeMotion<'a>; 1], [ShapeMotion<'a>; 1]) {
    let moving = ShapeMotion {
        shape: shape1,
        motion: *motion1,
    };
    let target = ShapeMotion {
        shape: shape2,
        motion: *motion2,
    };
    ([moving], [target])
}

/// The time two moving shapes first come within `options.skin`, or `None`
/// when they stay apart over the searched range.
pub fn time_of_impact(
    shape1: &dyn Shape,
    motion1: &Motion,
    shape2: &dyn Shape,
    motion2: &Motion,
    options: &QueryOptions,
) -> Result<Option<Toi>, CcdError> {
    with_query(|query| query.one(shape1, motion1, shape2, motion2, options))
}

/// The earliest time any of `moving` comes within `options.skin` of any of
/// `targets` (every moving shape against every target, one search).
pub fn time_of_impact_many(
    moving: &[ShapeMotion],
    targets: &[ShapeMotion],
    options: &QueryOptions,
) -> Result<Option<ManyToi>, CcdError> {
    with_query(|query| query.many(moving, targets, options))
}

thread_local! {
    /// The free functions' query context, one per thread: a fresh one
    /// allocates its buffers anew each call, 8 % of a ball–ball query's
    /// instructions (the queries bench's cases).
    static QUERY: std::cell::RefCell<Query> = std::cell::RefCell::new(Query::new());
}

/// Runs `f` on this thread's query context, or on a fresh one when that
/// context is in use (a query asked while another runs on this thread,
/// which the crate itself never does; the dispatcher's casts, on rapier's
/// worker threads with its `parallel` feature, each get their thread's).
/// The rapier stage's counted queries run here too.
pub(crate) fn with_query<T>(f: impl FnOnce(&mut Query) -> T) -> T {
    QUERY.with(|cell| match cell.try_borrow_mut() {
        Ok(mut query) => f(&mut query),
        Err(_) => f(&mut Query::new()),
    })
}

/// `true` when the crate has a distance function for this pair of shapes.
pub fn is_supported(shape1: &dyn Shape, shape2: &dyn Shape) -> bool {
    let checked = if composite::is_composite(shape1) || composite::is_composite(shape2) {
        composite::check_leaves(shape1, shape2, 0.0)
    } else {
        gap::build(shape1, shape2, 0.0).map(|_| ())
    };
    !matches!(checked, Err(CcdError::Unsupported { .. }))
}

/// A reusable query context: keeps the solver's buffers between queries
/// (the rapier stage keeps one).
#[derive(Debug, Default)]
pub struct Query {
    solver: Solver,
    /// The search's frames, kept for their buffers (given to each search
    /// and taken back after it).
    frames: FrameBuffers,
    /// What the last search spent, hit or miss.
    spent: SolveStats,
    /// The same search's pair evaluations, by family.
    spent_by_family: FamilyEvaluations,
}

impl Query {
    pub fn new() -> Query {
        Query::default()
    }

    /// [`time_of_impact`] with this context's buffers.
    pub fn one(
        &mut self,
        shape1: &dyn Shape,
        motion1: &Motion,
        shape2: &dyn Shape,
        motion2: &Motion,
        options: &QueryOptions,
    ) -> Result<Option<Toi>, CcdError> {
        let (moving, targets) = lone_pair(shape1, motion1, shape2, motion2);
        Ok(self.many(&moving, &targets, options)?.map(|hit| hit.toi))
    }

    /// What the last [`Query::many`] (or [`Query::one`]) spent, whether it found an impact or
    /// not (a miss's work shows nowhere else).
    pub fn spent(&self) -> SolveStats {
        self.spent
    }

    /// The pair evaluations of the last [`Query::many`] (or [`Query::one`])
    /// by what each was spent on; they add up to
    /// [`spent`](Query::spent)`().pair_evaluations`.
    pub fn spent_by_family(&self) -> FamilyEvaluations {
        self.spent_by_family
    }

    /// [`time_of_impact_many`] with this context's buffers.
    pub fn many(
        &mut self,
        moving: &[ShapeMotion],
        targets: &[ShapeMotion],
        options: &QueryOptions,
    ) -> Result<Option<ManyToi>, CcdError> {
        Ok(self
            .found(moving, targets, options)?
            .map(|hit| hit.described(moving, targets)))
    }

    /// [`Query::many`] without the hit's witness: read it with
    /// [`Found::toi`] where it is needed.
    pub(crate) fn found(
        &mut self,
        moving: &[ShapeMotion],
        targets: &[ShapeMotion],
        options: &QueryOptions,
    ) -> Result<Option<Found>, CcdError> {
        self.spent = SolveStats::default();
        self.spent_by_family = FamilyEvaluations::default();
        let solve_options = options.solve_options()?;
        // Built before the advancement, so that a pair the crate cannot
        // search is an error whatever the advancement finds.
        let frames = target_frames(moving.len(), targets);
        let pairs = pairs_of(moving, targets, &frames, options.skin)?;
        // Pairs that turn fast are first advanced to where they may come
        // close (see `advance`): the search starts at the earliest such
        // time, and is not needed at all if every pair stays apart. Where
        // a pair's advancement also found the shapes overlapping at a
        // later time, the first impact is no later: the search ends there.
        let span = solve_options.span;
        let (mut start, mut touch_by) = (span.hi, span.hi);
        let mut advances = 0;
        'pairs: for m in moving {
            for t in targets {
                let advanced = advance::apart_until(m, t, span, options.skin);
                advances += advanced.steps;
                start = start.min(advanced.until);
                touch_by = touch_by.min(advanced.overlap_at.unwrap_or(span.hi));
                if start <= span.lo {
                    break 'pairs;
                }
            }
        }
        self.spent.advances = advances;
        if start >= span.hi {
            return Ok(None);
        }
        // Advanced past the span's start, every pair is proved apart at
        // the new start (each stops short of where its proof ends): the
        // search need not check for pairs touching there.
        let first = SolveOptions {
            span: TimeSpan::new(start, touch_by.max(start)),
            start_apart: start > span.lo,
            ..solve_options
        };
        let Searched {
            mut outcome,
            mut hit,
            evaluated,
        } = self.search(moving, targets, &frames, pairs, options, &first)?;
        self.spent_by_family = evaluated;
        if hit.is_none() && touch_by < span.hi {
            // The overlap at `touch_by` (GJK's, in `f64`) should have left
            // a touch in the first part; should rounding have misled it,
            // the rest of the span is searched as well.
            let rest = SolveOptions {
                span: TimeSpan::new(touch_by, span.hi),
                start_apart: false,
                ..solve_options
            };
            let pairs = pairs_of(moving, targets, &frames, options.skin)?;
            let stats = outcome.stats;
            let rest = self.search(moving, targets, &frames, pairs, options, &rest)?;
            (outcome, hit) = (rest.outcome, rest.hit);
            outcome.stats += stats;
            self.spent_by_family += rest.evaluated;
        }
        self.spent = SolveStats {
            advances,
            ..outcome.stats
        };
        Ok(hit.map(|(i, j)| Found {
            outcome,
            moving: i,
            target: j,
            skin: options.skin,
        }))
    }

    /// One search of `pairs` over `solve_options.span`: its outcome, the
    /// (moving, target) indices of the pair that may touch, and its
    /// evaluations by family.
    fn search<'s>(
        &mut self,
        moving: &[ShapeMotion],
        targets: &[ShapeMotion],
        target_frames: &[(u32, bool)],
        pairs: Vec<PairEntry<'s>>,
        options: &QueryOptions,
        solve_options: &SolveOptions,
    ) -> Result<Searched, CcdError> {
        let frames = &mut self.frames;
        frames.defs.clear();
        frames
            .defs
            .extend(moving.iter().map(|m| FrameDef::root(m.motion)));
        // One frame per target, but one for a run of targets that move
        // alike (as `pairs_of` numbered them).
        for (t, &(frame, _)) in targets.iter().zip(target_frames) {
            if frame as usize == frames.defs.len() {
                frames.defs.push(FrameDef::root(t.motion));
            }
        }
        options.arithmetic.dispatch(Search {
            solver: &mut self.solver,
            frames,
            pairs,
            skin: options.skin,
            options: solve_options,
        })
    }
}

/// Each target's frame, and whether another target shares it: the
/// moving shapes' frames come first, then one per target, except that a
/// convex target moving exactly as the one before it shares that one's
/// frame (the triangles of a mesh a caller splits into targets of their
/// own), so that the search encloses their pose and the relative poses
/// their pairs read once per node, not once per pair. (A composite keeps
/// its own: its parts' frames are its frame's children.)
fn target_frames(moving: usize, targets: &[ShapeMotion]) -> SmallVec<[(u32, bool); 8]> {
    let mut frames: SmallVec<[(u32, bool); 8]> = SmallVec::with_capacity(targets.len());
    let mut next = moving as u32;
    for (j, t) in targets.iter().enumerate() {
        let alike = j > 0 && {
            let before = &targets[j - 1];
            t.motion == before.motion
                && !composite::is_composite(t.shape)
                && !composite::is_composite(before.shape)
        };
        if alike {
            let last = frames.len() - 1;
            frames[last].1 = true;
            frames.push((frames[last].0, true));
        } else {
            frames.push((next, false));
            next += 1;
        }
    }
    frames
}

/// Every moving shape against every target, as the search's pairs (the
/// moving shapes' frames first, then the targets', see [`target_frames`]).
fn pairs_of<'s>(
    moving: &[ShapeMotion<'s>],
    targets: &[ShapeMotion<'s>],
    frames: &[(u32, bool)],
    skin: f64,
) -> Result<Vec<PairEntry<'s>>, CcdError> {
    let mut pairs = Vec::with_capacity(moving.len() * targets.len());
    for (i, m) in moving.iter().enumerate() {
        for (j, t) in targets.iter().enumerate() {
            let (a, (b, shares_frames)) = (i as u32, frames[j]);
            let mut blind = f64::INFINITY;
            let kind = if composite::is_composite(m.shape) || composite::is_composite(t.shape) {
                composite::check_leaves(m.shape, t.shape, skin)?;
                let (ia, ib) = (PairSide::whole(m.shape, a), PairSide::whole(t.shape, b));
                PairContent::Composite(CompositePair::new(ia, ib))
            } else {
                let built = gap::build(m.shape, t.shape, skin)?;
                blind = pairs::blind_width(&built, (m.shape, &m.motion), (t.shape, &t.motion));
                PairContent::Leaf(built.gap, built.swapped)
            };
            let balls = Balls::new(&kind, (&m.motion, m.shape), (&t.motion, t.shape), skin);
            pairs.push(PairEntry {
                kind,
                a,
                b,
                balls,
                piece: None,
                shares_frames,
                blind_width: blind,
                moving: i as u32,
                target: j as u32,
            });
        }
    }
    Ok(pairs)
}
