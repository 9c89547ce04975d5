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
use crate::gap::composite::{self, Child, Item, Part};
use crate::gap::{self, PairGap, Side};
use crate::motion::{Motion, Pose, Trajectory};
use crate::solve::{
    GapSet, InitialContact, RootStatus, SolveOptions, SolveOutcome, SolveStats, Solver,
};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use rapier3d::parry::shape::Shape;
use std::collections::HashMap;

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
        let mut frames: Vec<FrameDef> = Vec::with_capacity(moving.len() + targets.len());
        frames.extend(moving.iter().map(|m| FrameDef::root(m.motion)));
        frames.extend(targets.iter().map(|t| FrameDef::root(t.motion)));
        let mut pairs = Vec::with_capacity(moving.len() * targets.len());
        for (i, m) in moving.iter().enumerate() {
            for (j, t) in targets.iter().enumerate() {
                let (a, b) = (i as u32, (moving.len() + j) as u32);
                let kind = if composite::is_composite(m.shape) || composite::is_composite(t.shape) {
                    composite::check_leaves(m.shape, t.shape, options.skin)?;
                    let (ia, ib) = (Item::whole(m.shape, a), Item::whole(t.shape, b));
                    PairKind::Composite(CompositePair::new(ia, ib))
                } else {
                    let built = gap::build(m.shape, t.shape, options.skin)?;
                    PairKind::Leaf(built.gap, built.swapped)
                };
                pairs.push(PairEntry {
                    kind,
                    a,
                    b,
                    moving: i,
                    target: j,
                });
            }
        }
        let (outcome, hit) = match options.arithmetic {
            Arithmetic::Interval => run::<Interval>(
                &mut self.solver,
                frames,
                pairs,
                options.skin,
                &solve_options,
            ),
            Arithmetic::Affine => run::<Affine>(
                &mut self.solver,
                frames,
                pairs,
                options.skin,
                &solve_options,
            ),
            Arithmetic::Taylor2 => run::<Taylor2>(
                &mut self.solver,
                frames,
                pairs,
                options.skin,
                &solve_options,
            ),
            Arithmetic::Taylor3 => run::<Taylor3>(
                &mut self.solver,
                frames,
                pairs,
                options.skin,
                &solve_options,
            ),
        }?;
        let Some((i, j)) = hit else {
            return Ok(None);
        };
        let toi = describe(
            &outcome,
            options.skin,
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
}

/// One search in the arithmetic `E`: the outcome and the caller's
/// (moving, target) indices of the pair that may touch. A gap that could
/// not be built mid-search (a piece with bad parameters) is reported as
/// its error after the search.
fn run<E: Enclosure>(
    solver: &mut Solver,
    frames: Vec<FrameDef>,
    pairs: Vec<PairEntry<'_>>,
    skin: f64,
    options: &SolveOptions,
) -> Result<(SolveOutcome, Option<(usize, usize)>), CcdError> {
    // A frame's rotation is enclosed only if some pair reads it (pairs
    // that composites create later only involve frames of composite
    // pairs, which read it).
    let mut rotation_read = vec![false; frames.len()];
    for pair in &pairs {
        let [a, b] = match &pair.kind {
            PairKind::Leaf(gap, false) => gap.reads_rotation(),
            PairKind::Leaf(gap, true) => {
                let [a, b] = gap.reads_rotation();
                [b, a]
            }
            _ => [true, true],
        };
        rotation_read[pair.a as usize] |= a;
        rotation_read[pair.b as usize] |= b;
    }
    let mut set = PairSet::<E> {
        poses: vec![None; frames.len()],
        rotation_read,
        frames,
        initial: pairs.len(),
        pairs,
        skin,
        child_frames: HashMap::new(),
        relative: Vec::new(),
        scratch: Vec::new(),
        error: None,
    };
    let outcome = solver.solve(&mut set, options)?;
    if let Some(error) = set.error {
        return Err(error);
    }
    let hit = outcome
        .pair
        .map(|p| (set.pairs[p].moving, set.pairs[p].target));
    Ok((outcome, hit))
}

/// A frame of the search: a body's motion, or a frame fixed to another at
/// a local pose (a compound's part).
struct FrameDef {
    motion: Motion,
    /// The parent frame and this frame's rotation and origin in it.
    parent: Option<(u32, Matrix3<f64>, Vector3<f64>)>,
}

impl FrameDef {
    fn root(motion: Motion) -> FrameDef {
        FrameDef {
            motion,
            parent: None,
        }
    }
}

/// What a pair is.
enum PairKind<'s> {
    /// A gap family; `true` when its `a` side is the entry's `b` frame.
    Leaf(PairGap, bool),
    /// A bounding gap over two parts, one of which splits.
    Composite(CompositePair<'s>),
    /// A piece whose gap could not be built: never apart (the error is
    /// reported after the search).
    Broken,
}

/// A composite pair and, once split, its children with their pair ids
/// (made on first need and kept: repeated splits on later nodes reuse them).
struct CompositePair<'s> {
    a: Item<'s>,
    b: Item<'s>,
    split_b: bool,
    kids: Option<Vec<(Child<'s>, Option<u32>)>>,
}

impl<'s> CompositePair<'s> {
    fn new(a: Item<'s>, b: Item<'s>) -> CompositePair<'s> {
        CompositePair {
            split_b: composite::split_b(&a, &b),
            a,
            b,
            kids: None,
        }
    }
}

/// One pair of the search: what it is, the frames of its two sides, and
/// the caller's indices of the shapes it came from.
struct PairEntry<'s> {
    kind: PairKind<'s>,
    a: u32,
    b: u32,
    moving: usize,
    target: usize,
}

/// The pairs of a query as the solver sees them: the caller's pairs first,
/// then the pairs that splitting composites creates during the search (an
/// arena that only grows within a query; each child pair is made once per
/// parent and child). Each frame's pose is enclosed once per node, on first
/// use, for all the pairs that share it; so are the relative poses that
/// composite pairs use.
struct PairSet<'s, E: Enclosure> {
    frames: Vec<FrameDef>,
    poses: Vec<Option<Pose<E>>>,
    /// Per frame: does any pair read its rotation? (Balls read only their
    /// origin, which saves enclosing a rotating matrix per node.)
    rotation_read: Vec<bool>,
    pairs: Vec<PairEntry<'s>>,
    initial: usize,
    skin: f64,
    /// (parent frame, part index) → the part's frame.
    child_frames: HashMap<(u32, u32), u32>,
    /// `(to, from, pose of from in to)` for this node.
    relative: Vec<(u32, u32, Pose<E>)>,
    scratch: Vec<Child<'s>>,
    error: Option<CcdError>,
}

impl<'s, E: Enclosure> PairSet<'s, E> {
    fn pose(&mut self, index: u32, span: TimeSpan) -> Pose<E> {
        let i = index as usize;
        if let Some(p) = self.poses[i] {
            return p;
        }
        let pose = match self.frames[i].parent {
            None if !self.rotation_read[i] => {
                // Only the origin is read: the rotation stays at its start.
                let motion = &self.frames[i].motion;
                let mut pose = Pose::constant(&motion.start_rotation_matrix(), &Vector3::zeros());
                pose.translation = motion.origin(span);
                pose
            }
            None => self.frames[i].motion.pose(span),
            Some((parent, rotation, origin)) => {
                let p = self.pose(parent, span);
                Pose {
                    rotation: Matrix3::from_fn(|r, c| {
                        p.rotation[(r, 0)] * rotation[(0, c)]
                            + p.rotation[(r, 1)] * rotation[(1, c)]
                            + p.rotation[(r, 2)] * rotation[(2, c)]
                    }),
                    translation: p.transform_point(&origin),
                }
            }
        };
        self.poses[i] = Some(pose);
        pose
    }

    /// The pose of frame `from` in frame `to`'s coordinates over the node.
    fn relative(&mut self, to: u32, from: u32, span: TimeSpan) -> Pose<E> {
        if let Some((_, _, p)) = self.relative.iter().find(|r| r.0 == to && r.1 == from) {
            return *p;
        }
        let (pt, pf) = (self.pose(to, span), self.pose(from, span));
        let rel = pt.relative(&pf);
        self.relative.push((to, from, rel));
        rel
    }

    /// The frame of part `index` of a compound in frame `parent`.
    fn child_frame(&mut self, parent: u32, index: u32, local: &Isometry3<f64>) -> u32 {
        if let Some(&f) = self.child_frames.get(&(parent, index)) {
            return f;
        }
        let motion = self.frames[parent as usize].motion.with_local_frame(local);
        let rotation = *local.rotation.to_rotation_matrix().matrix();
        let id = self.frames.len() as u32;
        self.frames.push(FrameDef {
            motion,
            parent: Some((parent, rotation, local.translation.vector)),
        });
        self.poses.push(None);
        self.rotation_read.push(true);
        self.child_frames.insert((parent, index), id);
        id
    }

    /// A new pair between two items, in this order; returns its id.
    fn make_pair(&mut self, a: Item<'s>, b: Item<'s>, moving: usize, target: usize) -> u32 {
        let kind = match (a.part.shape(), b.part.shape()) {
            (Some(sa), Some(sb)) => match gap::build(sa, sb, self.skin) {
                Ok(built) => PairKind::Leaf(built.gap, built.swapped),
                Err(e) => {
                    self.error.get_or_insert(e);
                    PairKind::Broken
                }
            },
            _ => PairKind::Composite(CompositePair::new(a, b)),
        };
        self.pairs.push(PairEntry {
            kind,
            a: a.frame,
            b: b.frame,
            moving,
            target,
        });
        (self.pairs.len() - 1) as u32
    }
}

impl<E: Enclosure> GapSet<E> for PairSet<'_, E> {
    fn pair_count(&self) -> usize {
        self.initial
    }

    fn axis_count(&self, pair: usize) -> usize {
        match &self.pairs[pair].kind {
            PairKind::Leaf(gap, _) => gap.axis_count(),
            PairKind::Composite(_) => composite::AXES,
            PairKind::Broken => 1,
        }
    }

    fn is_exact(&self, pair: usize) -> bool {
        matches!(&self.pairs[pair].kind, PairKind::Leaf(gap, _) if gap.is_exact())
    }

    fn begin_node(&mut self, _span: TimeSpan) {
        // A fixed frame's pose is the same on every node: keep it.
        for (pose, frame) in self.poses.iter_mut().zip(&self.frames) {
            if !frame.motion.is_fixed() {
                *pose = None;
            }
        }
        self.relative.clear();
    }

    fn eval(&mut self, pair: usize, span: TimeSpan, axes: u64, out: &mut [E]) {
        let entry = &self.pairs[pair];
        let (fa, fb) = (entry.a, entry.b);
        match &entry.kind {
            PairKind::Leaf(_, swapped) => {
                let (fa, fb) = if *swapped { (fb, fa) } else { (fa, fb) };
                let (pa, pb) = (self.pose(fa, span), self.pose(fb, span));
                let a = Side {
                    pose: &pa,
                    motion: &self.frames[fa as usize].motion,
                };
                let b = Side {
                    pose: &pb,
                    motion: &self.frames[fb as usize].motion,
                };
                if let PairKind::Leaf(gap, _) = &self.pairs[pair].kind {
                    gap.eval(span, &a, &b, axes, out);
                }
            }
            PairKind::Composite(c) => {
                let (small, big) = if c.split_b { (c.a, c.b) } else { (c.b, c.a) };
                let rel = self.relative(big.frame, small.frame, span);
                composite::bounding_axes(&rel, &small.bounds, &big.bounds, self.skin, out);
            }
            PairKind::Broken => out[0] = E::zero(),
        }
    }

    fn expand(&mut self, pair: usize, span: TimeSpan, out: &mut Vec<u32>) -> bool {
        let PairKind::Composite(c) = &mut self.pairs[pair].kind else {
            return false;
        };
        let (split, other) = if c.split_b { (c.b, c.a) } else { (c.a, c.b) };
        let split_b = c.split_b;
        if c.kids.is_none() {
            self.scratch.clear();
            composite::children(&split.part, &mut self.scratch);
            c.kids = Some(self.scratch.iter().map(|k| (*k, None)).collect());
        }
        let (moving, target) = (self.pairs[pair].moving, self.pairs[pair].target);
        let rel = self.relative(split.frame, other.frame, span);
        let sweep = composite::swept(&rel, &other.bounds);
        let count = match &self.pairs[pair].kind {
            PairKind::Composite(c) => c.kids.as_ref().map_or(0, Vec::len),
            _ => 0,
        };
        for k in 0..count {
            let (child, id) = match &self.pairs[pair].kind {
                PairKind::Composite(c) => c.kids.as_ref().expect("split above")[k],
                _ => unreachable!("a composite pair stays one"),
            };
            if !composite::child_meets(&child, &sweep, self.skin) {
                continue;
            }
            let id = match id {
                Some(id) => id,
                None => {
                    let item = match child.local {
                        None => Item {
                            part: child.part,
                            frame: split.frame,
                            bounds: child.bounds,
                        },
                        Some((index, local)) => {
                            let frame = self.child_frame(split.frame, index, &local);
                            match child.part {
                                Part::Shape(s) => Item::whole(s, frame),
                                part => Item {
                                    part,
                                    frame,
                                    bounds: child.bounds,
                                },
                            }
                        }
                    };
                    let id = if split_b {
                        self.make_pair(other, item, moving, target)
                    } else {
                        self.make_pair(item, other, moving, target)
                    };
                    if let PairKind::Composite(c) = &mut self.pairs[pair].kind {
                        if let Some(kids) = c.kids.as_mut() {
                            kids[k].1 = Some(id);
                        }
                    }
                    id
                }
            };
            out.push(id);
        }
        true
    }
}

/// The [`Toi`] of a search outcome: the time, and the witness points and
/// normal from parry's contact query at the poses of that time.
fn describe(
    outcome: &SolveOutcome,
    skin: f64,
    shape1: &dyn Shape,
    motion1: &Motion,
    shape2: &dyn Shape,
    motion2: &Motion,
) -> Toi {
    let fraction = outcome.time;
    let dt = motion1.dt().max(motion2.dt());
    let (iso1, iso2) = (motion1.pose_at(fraction), motion2.pose_at(fraction));
    let (pose1, pose2) = (pose_from_iso(&iso1), pose_from_iso(&iso2));
    // parry 0.31.1's support-map/half-space contact is wrong when the
    // half-space comes second and is rotated (it uses pos12 where it needs
    // its inverse): ask with the half-space first and swap the answer back.
    let half_space_second = matches!(
        shape2.shape_type(),
        rapier3d::parry::shape::ShapeType::HalfSpace
    );
    let ask = |prediction: f32| {
        if half_space_second {
            rapier3d::parry::query::contact(&pose2, shape2, &pose1, shape1, prediction)
                .ok()
                .flatten()
                .map(|c| (c.point2, c.point1, c.normal2))
        } else {
            rapier3d::parry::query::contact(&pose1, shape1, &pose2, shape2, prediction)
                .ok()
                .flatten()
                .map(|c| (c.point1, c.point2, c.normal1))
        }
    };
    // At the reported time the shapes are about `skin` apart. A bounded
    // prediction keeps parry's composite contact to the mesh parts nearby
    // (an unbounded one visits every triangle); widen it only if needed.
    let contact = [1.0e-2f32, 1.0, 1.0e2, f32::MAX]
        .into_iter()
        .find_map(|extra| ask(skin as f32 + extra));
    let (witness1, witness2, normal1) = match contact {
        Some((p1, p2, n1)) => (
            Point3::from(vec_from_glam(p1)),
            Point3::from(vec_from_glam(p2)),
            vec_from_glam(n1),
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
