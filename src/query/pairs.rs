//! The pairs of one query as the solver sees them.

use super::balls::Balls;
use super::frames::{FrameBuffers, Frames};
use super::profile::{Family, FamilyEvaluations};
use crate::convert::glam_from_vec;
use crate::enclosure::Interval;
use crate::enclosure::{Enclosure, InArithmetic, TimeSpan};
use crate::error::CcdError;
use crate::gap::composite::{self, Bounds, Carried, PairSide, Region, SubRegion};
use crate::gap::{self, Built, PairGap, Relative, Side};
use crate::motion::Motion;
use crate::solve::{GapSet, SolveOptions, SolveOutcome, Solver};
use rapier3d::parry::shape::Shape;

/// One search over a query's pairs, in whichever arithmetic the query
/// chose ([`Searched`]). A gap that could not be built mid-search (a piece with
/// bad parameters) is reported as its error after the search.
pub(super) struct Search<'a, 's> {
    pub solver: &'a mut Solver,
    /// The frames, taken for the search and given back after it (the
    /// caller keeps the buffers).
    pub frames: &'a mut FrameBuffers,
    pub pairs: Vec<PairEntry<'s>>,
    pub skin: f64,
    pub options: &'a SolveOptions,
}

/// What one [`Search`] found and spent.
pub(super) struct Searched {
    pub outcome: SolveOutcome,
    /// The caller's (moving, target) indices of the pair that may touch.
    pub hit: Option<(usize, usize)>,
    /// The pair evaluations, by family (the solver's stats count them all).
    pub evaluated: FamilyEvaluations,
}

impl InArithmetic for Search<'_, '_> {
    type Output = Result<Searched, CcdError>;

    fn run<E: Enclosure>(self) -> Self::Output {
        let Search {
            solver,
            frames,
            pairs,
            skin,
            options,
        } = self;
        // A frame's rotation is enclosed only if some pair reads it (pairs
        // that composites create later only involve frames of composite
        // pairs, which read it).
        let mut rotation_read = vec![false; frames.defs.len()];
        for pair in &pairs {
            let [a, b] = match &pair.kind {
                PairContent::Leaf(gap, swapped) => gap.reads_rotation_as(*swapped),
                _ => [true, true],
            };
            rotation_read[pair.a as usize] |= a;
            rotation_read[pair.b as usize] |= b;
        }
        // The most the two sides of a pair turn against each other over the
        // step, radians (sides whose rotation no pair reads count 0).
        let turn = |f: u32| {
            let f = f as usize;
            if rotation_read[f] {
                frames.defs[f].motion.rotation().norm()
            } else {
                0.0
            }
        };
        let widest_turn = pairs
            .iter()
            .map(|p| turn(p.a) + turn(p.b))
            .fold(0.0, f64::max);
        let mut set = PairSet::<E> {
            widest_turn,
            frames: Frames::new(frames, rotation_read),
            initial: pairs.len(),
            pairs,
            skin,
            scratch: Vec::new(),
            sweeps: Vec::new(),
            carried: Vec::new(),
            prepared: Vec::new(),
            evaluated: FamilyEvaluations::default(),
            error: None,
        };
        let outcome = solver.solve(&mut set, options);
        set.frames.into_buffers(frames);
        let outcome = outcome?;
        if let Some(error) = set.error {
            return Err(error);
        }
        let hit = outcome
            .pair
            .map(|p| (set.pairs[p].moving as usize, set.pairs[p].target as usize));
        Ok(Searched {
            outcome,
            hit,
            evaluated: set.evaluated,
        })
    }
}

/// What a pair is.
pub(super) enum PairContent<'s> {
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
pub(super) struct CompositePair<'s> {
    a: PairSide<'s>,
    b: PairSide<'s>,
    split_b: bool,
    kids: Option<Vec<(SubRegion<'s>, Option<u32>)>>,
}

impl<'s> CompositePair<'s> {
    pub fn new(a: PairSide<'s>, b: PairSide<'s>) -> CompositePair<'s> {
        CompositePair {
            split_b: composite::split_b(&a, &b),
            a,
            b,
            kids: None,
        }
    }
}

/// A piece of a split composite, as [`PairEntry::piece`] keeps it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    /// The composite pair it came from.
    parent: u32,
    /// Its box in that pair's split frame.
    bounds: Bounds,
    /// The width of the node it was split off on, or last retested on.
    width: f64,
}

/// One pair of the search: what it is, the frames of its two sides, and
/// the caller's indices of the shapes it came from.
pub(super) struct PairEntry<'s> {
    pub kind: PairContent<'s>,
    pub a: u32,
    pub b: u32,
    /// The balls test tried before a leaf pair's family (`None` for
    /// pairs that turn too little for it to pay, and for composites).
    pub balls: Option<Balls>,
    /// For a piece of a split composite: the composite pair it came from
    /// and its box in that pair's split frame, for the test it passed
    /// when it was split off, asked again on later nodes (see `eval`).
    pub piece: Option<Piece>,
    /// Other pairs have the same two frames: the caller's targets that
    /// move alike (a mesh's triangles, each a target of its own) share
    /// one frame, as a split composite's pieces do, and keep their
    /// relative poses and exact poses for the node.
    pub shares_frames: bool,
    /// The widest node a leaf pair's family is evaluated on, a fraction
    /// of the step (see [`BLIND_TURN`]); infinite for composites.
    pub blind_width: f64,
    /// The caller's indices of the shapes the pair came from (`u32`, as
    /// the frames are: the entry is copied for every pair a composite
    /// splits into).
    pub moving: u32,
    pub target: u32,
}

/// The widest node a leaf pair's family is worth evaluating on, a fraction
/// of the step: where its sides turn by [`BLIND_TURN`] against each other,
/// or no limit when one is flat across its turn. A side whose rotation the
/// family does not read (a ball's) does not count.
pub(super) fn blind_width(
    built: &Built,
    (shape_a, motion_a): (&dyn Shape, &Motion),
    (shape_b, motion_b): (&dyn Shape, &Motion),
) -> f64 {
    let [reads_a, reads_b] = built.reads_rotation();
    let turn = |motion: &Motion, reads: bool| {
        if reads { motion.rotation().norm() } else { 0.0 }
    };
    let both = turn(motion_a, reads_a) + turn(motion_b, reads_b);
    // No node is wider than the step: a slower pair is never skipped, and
    // the shapes need not be read.
    if both <= BLIND_TURN {
        return f64::INFINITY;
    }
    let flat = (reads_a && flat_across_turn(shape_a, motion_a))
        || (reads_b && flat_across_turn(shape_b, motion_b));
    if flat {
        f64::INFINITY
    } else {
        BLIND_TURN / both
    }
}

/// Whether `shape`, carried by `motion`, is flat across the axis it turns
/// about: its extent along that axis (between its support points), which
/// no turn about it changes, is under [`FLAT_SHARE`] of its local box's
/// diagonal. Only a hint for which nodes to evaluate (any answer is sound);
/// a leaf with no support map is a half-space, never flat.
fn flat_across_turn(shape: &dyn Shape, motion: &Motion) -> bool {
    let (Some(axis), Some(support)) = (
        motion.rotation().try_normalize(f64::MIN_POSITIVE),
        shape.as_support_map(),
    ) else {
        return false;
    };
    // The axis in the shape's own frame.
    let k = glam_from_vec(&(motion.start_rotation_matrix().transpose() * axis));
    let along = (support.local_support_point(k) - support.local_support_point(-k)).dot(k);
    let half = shape.compute_local_aabb().half_extents();
    f64::from(along) < FLAT_SHARE * 2.0 * f64::from(half.length())
}

/// The most a pair's sides turn against each other over a node worth
/// evaluating, radians: over wider turns the enclosures of the turned
/// shapes are too loose to prove a close pair apart. Measured on the
/// accuracy cases (instructions per batch): 0.35–0.5 rad is best at
/// ordinary spins and at 200–1000 rad/s alike; 1 rad keeps half the gain.
const TURN_PER_NODE: f64 = 0.5;

/// The most a leaf pair's sides turn against each other over a node its
/// family is evaluated on, radians. Over a wider turn the enclosed
/// rotations are a few times looser than the turned shapes' bounding balls
/// (or, for a composite's piece, the boxes that let it join): the family
/// proves nothing more there, and such a node (a fast spin's first nodes:
/// 4 to 17 rad) is cut into pieces that turn less anyway (see
/// [`TURN_PER_NODE`]). The pair is known nothing of on such a node, except
/// when a side is flat across the axis it turns about
/// ([`flat_across_turn`]): a blade spinning flat over a floor stays within
/// its slab however far it turns, and its family proves it apart on the
/// whole step at once. Measured on the queries bench at 200–1000 rad/s
/// (instructions): hull–mesh −27 %, cuboid, capsule, cylinder −5 to −6 %,
/// cone −4 %, ball–cuboid −4 %, cuboid–triangle −1 %; ordinary spins never
/// turn this far in a step. 2 rad did the same.
const BLIND_TURN: f64 = 4.0;

/// A lone pair whose sides turn more than this over the step together
/// (radians: a fast spin, cut into six or more pieces) is first tested
/// from the exact poses at the middle of each node over which it turns at
/// least [`MIDDLE_TURN`] (its pieces), before its poses are enclosed: its
/// gap there along one direction less how fast that gap can close, times
/// the half-width (see `SupportMap::apart_from_middle`). Over half a
/// radian the enclosed poses are loose and dear, the node is short, and
/// the bound proves a piece apart as often. Measured on the queries bench
/// at 200–1000 rad/s (instructions): capsule −8 %, cylinder −7 %, cone
/// −5 %. Ordinary spins (under 3 rad a step) are not tested so: over their
/// wider nodes the relative motion, which the enclosed axes read signed,
/// is most of the bound (cylinder queries +2 % with them). Nor are a
/// composite's pieces, which share their poses (hull–mesh +2 %).
const FAST_TURN: f64 = 3.0;

/// See [`FAST_TURN`]: just under [`TURN_PER_NODE`], so that the pieces of
/// the pair that turns the most are tested and their halves are not.
const MIDDLE_TURN: f64 = 0.45;

/// A side is flat across its turning axis when its extent along that axis
/// is under this share of its local box's diagonal. At 0.5 the exemption
/// took a third of the hull–mesh gain back (random hulls and cuboids are
/// often flattish); a blade or disc is under 0.05.
const FLAT_SHARE: f64 = 0.2;

/// Every alive axis of `axes` in `out` the whole line: nothing known.
#[cold]
#[inline(never)]
fn unknown<E: Enclosure>(axes: u64, out: &mut [E]) {
    let mut bits = axes;
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if let Some(slot) = out.get_mut(k) {
            *slot = E::from_interval(Interval::ENTIRE);
        }
    }
}

/// A piece of a split composite is tested against its parent's swept box
/// again (a box test, where its family's evaluation costs a pose and a few
/// supports) on nodes at most this share as wide as the one it was split
/// off on or last retested on: each retest that does not exclude it waits
/// for a node this much narrower again.
const PIECE_RETEST: f64 = 0.25;

/// ... and only when the sides turn more than this (radians) against each
/// other over that node: a turn is what swells a swept box over a wide
/// node. (Measured, 100 hull–mesh queries: without a turn the retests cost
/// more than they save, 0.4 %; at 200–1000 rad/s they save a third.)
const PIECE_TURN: f64 = 0.1;

/// The pairs of a query as the solver sees them: the caller's pairs first,
/// then the pairs that splitting composites creates during the search (an
/// arena that only grows within a query; each child pair is made once per
/// parent and child). Poses come from the shared [`Frames`].
struct PairSet<'s, E: Enclosure> {
    frames: Frames<E>,
    /// The largest relative turn of a pair's sides over the step, radians.
    widest_turn: f64,
    pairs: Vec<PairEntry<'s>>,
    initial: usize,
    skin: f64,
    scratch: Vec<SubRegion<'s>>,
    /// The boxes the other sides of composite pairs sweep over the current
    /// node, in their split frames, made on first need and cleared with
    /// every node. Keyed by what the box is made of (the split frame, the
    /// other side's frame and its box), not by pair: the pairs of a hull
    /// with a mesh's tree nodes all share one.
    sweeps: Vec<(SweepKey, [Interval; 3])>,
    /// The same sides' boxes carried into the split frame
    /// (`composite::carried`), for the bounding axes.
    carried: Vec<(SweepKey, Carried<E>)>,
    /// Whole shapes that composite children pair with, read once
    /// ([`gap::Prepared`]), by the shape's address (the shapes are borrowed
    /// for the whole query, so an address names one shape).
    prepared: Vec<(usize, Option<gap::Prepared>)>,
    /// The evaluations so far, by what each was spent on.
    evaluated: FamilyEvaluations,
    error: Option<CcdError>,
}

/// What a swept box is made of: the other side's box, carried from its
/// frame into the split frame.
#[derive(Clone, Copy, PartialEq)]
struct SweepKey {
    split: u32,
    other: u32,
    bounds: Bounds,
}

impl<'s, E: Enclosure> PairSet<'s, E> {
    /// A new pair between two items, in this order; returns its id.
    fn make_pair(
        &mut self,
        a: PairSide<'s>,
        b: PairSide<'s>,
        piece: Piece,
        moving: u32,
        target: u32,
    ) -> u32 {
        let mut blind = f64::INFINITY;
        let kind = match (a.part.shape(), b.part.shape()) {
            (Some(sa), Some(sb)) => {
                let built = self.prepared(&a.part).and_then(|pa| {
                    let pb = self.prepared(&b.part)?;
                    gap::build_prepared((sa, pa.as_ref()), (sb, pb.as_ref()), self.skin)
                });
                match built {
                    Ok(built) => {
                        let (ma, mb) = (self.frames.motion(a.frame), self.frames.motion(b.frame));
                        blind = blind_width(&built, (sa, ma), (sb, mb));
                        PairContent::Leaf(built.gap, built.swapped)
                    }
                    Err(e) => {
                        self.error.get_or_insert(e);
                        PairContent::Broken
                    }
                }
            }
            _ => PairContent::Composite(CompositePair::new(a, b)),
        };
        // A composite's child pair takes no balls test: its parent's
        // bounding axes already pruned it on this node.
        self.pairs.push(PairEntry {
            kind,
            a: a.frame,
            b: b.frame,
            balls: None,
            piece: Some(piece),
            shares_frames: false,
            blind_width: blind,
            moving,
            target,
        });
        (self.pairs.len() - 1) as u32
    }

    /// The box the other side of composite pair `pair` sweeps over `span`
    /// in the pair's split frame (`composite::swept`), once per node.
    fn sweep_of(&mut self, pair: u32, span: TimeSpan) -> [Interval; 3] {
        let PairContent::Composite(c) = &self.pairs[pair as usize].kind else {
            // Not a composite: nothing is excluded.
            return [Interval::new(f64::NEG_INFINITY, f64::INFINITY); 3];
        };
        let (split, other) = if c.split_b { (c.b, c.a) } else { (c.a, c.b) };
        let key = SweepKey {
            split: split.frame,
            other: other.frame,
            bounds: other.bounds,
        };
        if let Some((_, sweep)) = self.sweeps.iter().find(|(k, _)| *k == key) {
            return *sweep;
        }
        let rel = self.frames.relative(split.frame, other.frame, span);
        let sweep = composite::swept(&rel, &other.bounds);
        self.sweeps.push((key, sweep));
        sweep
    }

    /// A whole shape of the query, read once ([`gap::Prepared`]); `None`
    /// for a composite's own parts (made on the fly) and for shapes that
    /// are not bounded convex ones.
    fn prepared(&mut self, part: &Region<'s>) -> Result<Option<gap::Prepared>, CcdError> {
        let Region::Shape(shape) = *part else {
            return Ok(None);
        };
        let key = shape as *const dyn Shape as *const () as usize;
        if let Some((_, p)) = self.prepared.iter().find(|(k, _)| *k == key) {
            return Ok(p.clone());
        }
        let p = gap::Prepared::of(shape)?;
        self.prepared.push((key, p.clone()));
        Ok(p)
    }
}

impl<E: Enclosure> GapSet<E> for PairSet<'_, E> {
    fn pair_count(&self) -> usize {
        self.initial
    }

    fn axis_count(&self, pair: usize) -> usize {
        match &self.pairs[pair].kind {
            PairContent::Leaf(gap, _) => gap.axis_count(),
            PairContent::Composite(_) => composite::AXES,
            PairContent::Broken => 1,
        }
    }

    fn is_exact(&self, pair: usize) -> bool {
        matches!(&self.pairs[pair].kind, PairContent::Leaf(gap, _) if gap.is_exact())
    }

    fn is_composite(&self, pair: usize) -> bool {
        matches!(&self.pairs[pair].kind, PairContent::Composite(_))
    }

    fn begin_node(&mut self, _span: TimeSpan) {
        self.frames.begin_node();
        self.sweeps.clear();
        self.carried.clear();
    }

    /// A node over which the sides turn by more than [`TURN_PER_NODE`]
    /// against each other encloses the turned shapes too loosely to prove
    /// anything close: the solver cuts it straight into pieces that turn
    /// less (a 1000 rad/s blade turns 17 rad in a step; halving would
    /// evaluate five levels of useless nodes on the way down).
    fn useful_width(&self) -> f64 {
        TURN_PER_NODE / self.widest_turn
    }

    fn eval(&mut self, pair: usize, span: TimeSpan, axes: u64, out: &mut [E]) {
        // A piece whose box the other side's swept box no longer meets on
        // this node (the test it passed when it was split off on a wider
        // node) is apart: a positive axis says so, for a box test instead
        // of the family's evaluation.
        if let Some(piece) = self.pairs[pair].piece
            && self.widest_turn * piece.width > PIECE_TURN
            && span.hi - span.lo <= PIECE_RETEST * piece.width
        {
            if !piece
                .bounds
                .meets(&self.sweep_of(piece.parent, span), self.skin)
            {
                let first = (axes.trailing_zeros() as usize).min(out.len() - 1);
                out[first] = E::constant(f64::MAX);
                self.evaluated.count(Family::Shortcut);
                return;
            }
            // Still within reach: retested only on a node narrower again.
            if let Some(kept) = self.pairs[pair].piece.as_mut() {
                kept.width = span.hi - span.lo;
            }
        }
        let entry = &self.pairs[pair];
        let (fa, fb) = (entry.a, entry.b);
        match &entry.kind {
            PairContent::Leaf(gap, swapped) => {
                // Balls apart over the node: the first alive axis takes
                // their gap, a positive lower bound of the pair's, which
                // proves the pair apart as a family's positive axis would
                // (and, like a family stopping early, leaves the other axes
                // unread). Most nodes of a fast spin, far from the contact,
                // end here, with no pose enclosed.
                let first = axes.trailing_zeros() as usize;
                if let Some(balls) = &entry.balls
                    && let Some(gap) =
                        balls.gap(self.frames.motion(fa), self.frames.motion(fb), span)
                    && first < out.len()
                {
                    out[first] = E::constant(gap);
                    self.evaluated.count(Family::Shortcut);
                    return;
                }
                // Turned too far over the node for the family to tell
                // more than the balls (or a piece's boxes) did: nothing
                // known (see `BLIND_TURN`), every alive axis the whole line.
                if span.hi - span.lo > entry.blind_width {
                    unknown(axes, out);
                    self.evaluated.count(Family::Shortcut);
                    return;
                }
                let (fa, fb) = if *swapped { (fb, fa) } else { (fa, fb) };
                // A fast spin's piece: first from the exact poses at its
                // middle (see `FAST_TURN`), kept for the family.
                let piece_of_spin = entry.balls.is_some_and(|balls| {
                    balls.turn() > FAST_TURN && balls.turn() * (span.hi - span.lo) >= MIDDLE_TURN
                });
                if piece_of_spin
                    && let Some(lo) = gap.apart_from_middle(
                        span,
                        (self.frames.motion(fa), self.frames.kept(fa)),
                        (self.frames.motion(fb), self.frames.kept(fb)),
                    )
                    && first < out.len()
                {
                    out[first] = E::constant(lo);
                    self.evaluated.count(Family::Shortcut);
                    return;
                }
                // From here on the family itself is asked.
                self.evaluated.count(Family::of(gap));
                if span.lo == span.hi
                    && gap.eval_at_a_time(
                        span.lo,
                        self.frames.motion(fa),
                        self.frames.motion(fb),
                        axes,
                        out,
                    )
                {
                    return;
                }
                self.frames.enclose(fa, span);
                self.frames.enclose(fb, span);
                // The pieces of a split composite share their frames (a box
                // against each triangle of a mesh), as do the caller's
                // targets that move alike: the relative poses their family
                // reads are kept for the node.
                let shared = entry.piece.is_some() || entry.shares_frames;
                let [b_in_a, a_in_b] = if shared {
                    self.frames.keep_relatives(gap.reads_relative(), [fa, fb])
                } else {
                    [None, None]
                };
                let relative = Relative {
                    b_in_a: b_in_a.map(|kept| self.frames.kept_relative(kept)),
                    a_in_b: a_in_b.map(|kept| self.frames.kept_relative(kept)),
                };
                // So do their exact poses at the node's middle (a lone
                // pair reads each once, nothing to keep, unless its middle
                // was just tested).
                let keeps = shared || piece_of_spin;
                let kept = |f| keeps.then(|| self.frames.kept(f));
                let a = Side {
                    pose: self.frames.pose_of(fa),
                    motion: self.frames.motion(fa),
                    kept: kept(fa),
                };
                let b = Side {
                    pose: self.frames.pose_of(fb),
                    motion: self.frames.motion(fb),
                    kept: kept(fb),
                };
                gap.eval(span, &a, &b, &relative, axes, out);
            }
            PairContent::Composite(c) => {
                let (small, big) = if c.split_b { (c.a, c.b) } else { (c.b, c.a) };
                let key = SweepKey {
                    split: big.frame,
                    other: small.frame,
                    bounds: small.bounds,
                };
                let carried = match self.carried.iter().find(|(k, _)| *k == key) {
                    Some((_, carried)) => *carried,
                    None => {
                        let rel = self.frames.relative(big.frame, small.frame, span);
                        let carried = composite::carried(&rel, &small.bounds);
                        self.carried.push((key, carried));
                        carried
                    }
                };
                composite::bounding_axes(&carried, &big.bounds, self.skin, out);
                self.evaluated.count(Family::Composite);
            }
            PairContent::Broken => {
                out[0] = E::zero();
                self.evaluated.count(Family::Shortcut);
            }
        }
    }

    fn expand(&mut self, pair: usize, span: TimeSpan, out: &mut Vec<u32>) -> bool {
        let PairContent::Composite(c) = &mut self.pairs[pair].kind else {
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
        let sweep = self.sweep_of(pair as u32, span);
        let count = match &self.pairs[pair].kind {
            PairContent::Composite(c) => c.kids.as_ref().map_or(0, Vec::len),
            _ => 0,
        };
        for k in 0..count {
            let (child, id) = match &self.pairs[pair].kind {
                PairContent::Composite(c) => c.kids.as_ref().expect("split above")[k],
                _ => unreachable!("a composite pair stays one"),
            };
            if !composite::child_meets(&child, &sweep, self.skin) {
                continue;
            }
            let id = match id {
                Some(id) => id,
                None => {
                    let item = match child.local {
                        None => PairSide {
                            part: child.part,
                            frame: split.frame,
                            bounds: child.bounds,
                        },
                        Some((index, local)) => {
                            let frame = self.frames.child(split.frame, index, &local);
                            match child.part {
                                Region::Shape(s) => PairSide::whole(s, frame),
                                part => PairSide {
                                    part,
                                    frame,
                                    bounds: child.bounds,
                                },
                            }
                        }
                    };
                    let piece = Piece {
                        parent: pair as u32,
                        bounds: child.bounds,
                        width: span.hi - span.lo,
                    };
                    let id = if split_b {
                        self.make_pair(other, item, piece, moving, target)
                    } else {
                        self.make_pair(item, other, piece, moving, target)
                    };
                    if let PairContent::Composite(c) = &mut self.pairs[pair].kind {
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
