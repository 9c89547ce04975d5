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

use crate::convert::{pose_from_iso, vec_from_glam};
use crate::enclosure::{Affine, Arithmetic, Enclosure, Interval, Taylor2, Taylor3, TimeSpan};
use crate::error::{CcdError, check_finite};
use crate::gap::{self, PairGap, Side};
use crate::motion::{Motion, Pose, Trajectory};
use crate::solve::{GapSet, RootStatus, SolveOptions, SolveOutcome, SolveStats, Solver};
use nalgebra::{Point3, Vector3};
use rapier3d::parry::shape::Shape;

pub use crate::gap::primitives::{PrimitiveToi, edge_edge_toi, vertex_face_toi};

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
}

impl Default for QueryOptions {
    fn default() -> QueryOptions {
        QueryOptions {
            epsilon: 1.0e-4,
            skin: 0.0,
            arithmetic: Arithmetic::Affine,
            max_evaluations: 100_000,
            time_range: TimeSpan::STEP,
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

/// The earliest impact among many pairs, and which pair it was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManyToi {
    pub toi: Toi,
    /// Index into the `moving` slice.
    pub moving: usize,
    /// Index into the `targets` slice.
    pub target: usize,
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
    let moving = [ShapeMotion {
        shape: shape1,
        motion: *motion1,
    }];
    let targets = [ShapeMotion {
        shape: shape2,
        motion: *motion2,
    }];
    Ok(time_of_impact_many(&moving, &targets, options)?.map(|hit| hit.toi))
}

/// The earliest time any of `moving` comes within `options.skin` of any of
/// `targets` (every moving shape against every target, one search).
pub fn time_of_impact_many(
    moving: &[ShapeMotion],
    targets: &[ShapeMotion],
    options: &QueryOptions,
) -> Result<Option<ManyToi>, CcdError> {
    Query::default().many(moving, targets, options)
}

/// `true` when the crate has a distance function for this pair of shapes.
pub fn is_supported(shape1: &dyn Shape, shape2: &dyn Shape) -> bool {
    !matches!(
        gap::build(shape1, shape2, 0.0),
        Err(CcdError::Unsupported { .. })
    )
}

/// A reusable query context: keeps the solver's buffers between queries
/// (the rapier stage keeps one).
#[derive(Debug, Default)]
pub struct Query {
    solver: Solver,
}

impl Query {
    pub fn new() -> Query {
        Query::default()
    }

    /// [`time_of_impact_many`] with this context's buffers.
    pub fn many(
        &mut self,
        moving: &[ShapeMotion],
        targets: &[ShapeMotion],
        options: &QueryOptions,
    ) -> Result<Option<ManyToi>, CcdError> {
        let solve_options = options.solve_options()?;
        let mut motions: Vec<Motion> = Vec::with_capacity(moving.len() + targets.len());
        motions.extend(moving.iter().map(|m| m.motion));
        motions.extend(targets.iter().map(|t| t.motion));
        let mut pairs = Vec::with_capacity(moving.len() * targets.len());
        for (i, m) in moving.iter().enumerate() {
            for (j, t) in targets.iter().enumerate() {
                let built = gap::build(m.shape, t.shape, options.skin)?;
                let (a, b) = (i, moving.len() + j);
                let (a, b) = if built.swapped { (b, a) } else { (a, b) };
                pairs.push(PairEntry {
                    gap: built.gap,
                    a,
                    b,
                    moving: i,
                    target: j,
                });
            }
        }
        let outcome = match options.arithmetic {
            Arithmetic::Interval => self.run::<Interval>(&motions, &pairs, &solve_options),
            Arithmetic::Affine => self.run::<Affine>(&motions, &pairs, &solve_options),
            Arithmetic::Taylor2 => self.run::<Taylor2>(&motions, &pairs, &solve_options),
            Arithmetic::Taylor3 => self.run::<Taylor3>(&motions, &pairs, &solve_options),
        }?;
        let Some(pair) = outcome.pair else {
            return Ok(None);
        };
        let entry = &pairs[pair];
        let (i, j) = (entry.moving, entry.target);
        let toi = describe(
            &outcome,
            moving[i].shape,
            &moving[i].motion,
            targets[j].shape,
            &targets[j].motion,
        );
        Ok(Some(ManyToi {
            toi,
            moving: i,
            target: j,
        }))
    }

    fn run<E: Enclosure>(
        &mut self,
        motions: &[Motion],
        pairs: &[PairEntry],
        options: &SolveOptions,
    ) -> Result<SolveOutcome, CcdError> {
        let mut set = PairSet::<E> {
            motions,
            pairs,
            poses: vec![None; motions.len()],
        };
        self.solver.solve(&mut set, options)
    }
}

/// One pair of the search: its gap, the motions of its two sides, and the
/// caller's indices.
struct PairEntry {
    gap: PairGap,
    a: usize,
    b: usize,
    moving: usize,
    target: usize,
}

/// The pairs of a query as the solver sees them. Each motion's pose is
/// enclosed once per node, on first use, for all the pairs that share it.
struct PairSet<'q, E: Enclosure> {
    motions: &'q [Motion],
    pairs: &'q [PairEntry],
    poses: Vec<Option<Pose<E>>>,
}

impl<E: Enclosure> PairSet<'_, E> {
    fn pose(&mut self, index: usize, span: TimeSpan) -> Pose<E> {
        *self.poses[index].get_or_insert_with(|| self.motions[index].pose(span))
    }
}

impl<E: Enclosure> GapSet<E> for PairSet<'_, E> {
    fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    fn axis_count(&self, pair: usize) -> usize {
        self.pairs[pair].gap.axis_count()
    }

    fn begin_node(&mut self, _span: TimeSpan) {
        self.poses.iter_mut().for_each(|p| *p = None);
    }

    fn eval(&mut self, pair: usize, span: TimeSpan, axes: u64, out: &mut [E]) {
        let entry = &self.pairs[pair];
        let (ia, ib) = (entry.a, entry.b);
        let (pa, pb) = (self.pose(ia, span), self.pose(ib, span));
        let a = Side {
            pose: &pa,
            motion: &self.motions[ia],
        };
        let b = Side {
            pose: &pb,
            motion: &self.motions[ib],
        };
        self.pairs[pair].gap.eval(span, &a, &b, axes, out);
    }
}

/// The [`Toi`] of a search outcome: the time, and the witness points and
/// normal from parry's contact query at the poses of that time.
fn describe(
    outcome: &SolveOutcome,
    shape1: &dyn Shape,
    motion1: &Motion,
    shape2: &dyn Shape,
    motion2: &Motion,
) -> Toi {
    let fraction = outcome.time;
    let dt = motion1.dt().max(motion2.dt());
    let (iso1, iso2) = (motion1.pose_at(fraction), motion2.pose_at(fraction));
    let (pose1, pose2) = (pose_from_iso(&iso1), pose_from_iso(&iso2));
    let contact = rapier3d::parry::query::contact(&pose1, shape1, &pose2, shape2, f32::MAX)
        .ok()
        .flatten();
    let (witness1, witness2, normal1) = match contact {
        Some(c) => (
            Point3::from(vec_from_glam(c.point1)),
            Point3::from(vec_from_glam(c.point2)),
            vec_from_glam(c.normal1),
        ),
        None => {
            let (o1, o2) = (iso1.translation.vector, iso2.translation.vector);
            let normal = (o2 - o1).try_normalize(0.0).unwrap_or_else(Vector3::zeros);
            (Point3::from(o1), Point3::from(o2), normal)
        }
    };
    Toi {
        fraction,
        time: fraction * dt,
        status: outcome.status,
        witness1,
        witness2,
        normal1,
        stats: outcome.stats,
    }
}
