//! The earliest-root search over many distance functions at once.
//!
//! The input is a set of *pairs*; each pair is a list of *axis* functions
//! `D_k(τ)`, each enclosed by the [`GapSet`] over any node of time. A pair is
//! apart at `τ` when **any** of its axes is positive (separating axes compose
//! as AND); the set is apart when **every** pair is (shapes compose as OR),
//! docs/design.md §3. Skins are the gap functions' business: an axis is written
//! so that `D_k > 0` means "farther apart than the skin".
//!
//! The search walks nodes of time depth-first, earlier half first. On each
//! node it
//! 1. evaluates the alive axes of the alive pairs;
//! 2. drops pairs that an axis proves apart (lower bound > 0), and inside a
//!    surviving pair drops axes that can never separate on this node's
//!    sub-nodes (upper bound below another axis's lower bound); a surviving
//!    pair keeps the window where it may touch, and sub-nodes outside it
//!    pass it over;
//! 3. clips the node with each axis's linear lower bound (docs/design.md §6): only
//!    where every axis of some pair may be `≤ 0` can a root lie;
//! 4. stops when the clipped node is at most `ε` wide, reporting its start:
//!    every earlier time has been excluded, so the report is never late;
//! 5. re-evaluates the clipped node when clipping removed enough of it, and
//!    bisects it otherwise.
//!
//! Buffers live in a [`Solver`] that callers keep between queries; the node
//! loop itself allocates nothing once they have grown.

use crate::enclosure::{Enclosure, TimeSpan};
use crate::error::CcdError;

/// The most axes one pair may have (a bit mask of `u64` tracks them).
pub const MAX_AXES: usize = 64;

/// A set of pairs of shapes, each a list of axis gap functions.
pub trait GapSet<E: Enclosure> {
    /// How many pairs the set starts with; pairs are numbered from 0.
    fn pair_count(&self) -> usize;

    /// How many axes pair `pair` has (at most [`MAX_AXES`]).
    fn axis_count(&self, pair: usize) -> usize;

    /// Called once per node before any pair is evaluated on it, e.g. to
    /// compute each body's pose once for all its pairs.
    fn begin_node(&mut self, _span: TimeSpan) {}

    /// Enclose, over `span`, each axis `k` of `pair` whose bit is set in
    /// `axes`, into `out[k]`. Other entries of `out` are left as they are.
    fn eval(&mut self, pair: usize, span: TimeSpan, axes: u64, out: &mut [E]);

    /// True when the pair's axes are *exact*: every axis `≤ 0` at a time
    /// means the shapes do touch then (two balls' distance, a box pair's 15
    /// separating axes). Only then may the solver use the axes' upper
    /// bounds to bracket a root; adaptive axes, chosen for a node's middle,
    /// may fail to separate elsewhere on the node. The default: not exact.
    fn is_exact(&self, _pair: usize) -> bool {
        false
    }

    /// The widest node (a fraction of the step) whose evaluation can
    /// usually prove something: a wider node that must be split is cut
    /// straight into pieces this wide instead of halves. Only a hint for
    /// speed (every piece is searched, earlier first); the default, and any
    /// value that is not positive and finite, means no limit.
    fn useful_width(&self) -> f64 {
        f64::INFINITY
    }

    /// A composite pair (a shape against a mesh, say) may stand for many
    /// sub-pairs. When `pair` is one and was not proved apart on `span`, push
    /// the numbers of the sub-pairs that may touch on `span` into `out` and
    /// return `true`: the search then follows those instead (a wide node
    /// that has opened many pieces leaves the pair whole for its
    /// sub-nodes). The default: no pair is composite.
    fn expand(&mut self, _pair: usize, _span: TimeSpan, _out: &mut Vec<u32>) -> bool {
        false
    }

    /// True when `pair` is composite ([`GapSet::expand`]): its axes bound
    /// its sub-pairs, and saying they all overlap says nothing of a touch.
    fn is_composite(&self, _pair: usize) -> bool {
        false
    }
}

/// Search parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOptions {
    /// Accuracy in time, as a fraction of the step: the reported time is at
    /// most `epsilon` before the true one (for a transversal contact).
    pub epsilon: f64,
    /// The most pair evaluations one search may spend. When it runs out the
    /// answer is the earliest time not yet excluded, never "no hit".
    pub max_evaluations: u64,
    /// The part of the step to search, within `[0, 1]`.
    pub span: TimeSpan,
    /// What to do with pairs that touch at the start of the span.
    pub initial_contact: InitialContact,
    /// The caller knows every pair apart at the start of the span (it
    /// proved them so, as the query's advancement does): the search makes
    /// no check there.
    pub start_apart: bool,
}

/// What the search does with pairs that already touch when it starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum InitialContact {
    /// Answer `InitiallyTouching` at once.
    #[default]
    Report,
    /// Leave those pairs out and search the others: a physics step hands
    /// pairs in contact at its start to the contact solver, as rapier does.
    Ignore,
}

impl Default for SolveOptions {
    fn default() -> SolveOptions {
        SolveOptions {
            epsilon: 1.0e-4,
            max_evaluations: 100_000,
            span: TimeSpan::STEP,
            initial_contact: InitialContact::Report,
            start_apart: false,
        }
    }
}

impl SolveOptions {
    /// `Ok` when every parameter is in range.
    pub fn validate(&self) -> Result<(), CcdError> {
        if !(self.epsilon > 0.0 && self.epsilon <= 1.0) {
            return Err(CcdError::BadParameter {
                what: "epsilon",
                value: self.epsilon,
                expected: "0 < epsilon <= 1 (a fraction of the step)",
            });
        }
        if self.max_evaluations == 0 {
            return Err(CcdError::BadParameter {
                what: "max_evaluations",
                value: 0.0,
                expected: "at least 1",
            });
        }
        let TimeSpan { lo, hi } = self.span;
        if !(0.0 <= lo && lo <= hi && hi <= 1.0) {
            return Err(CcdError::BadParameter {
                what: "time range",
                value: if (0.0..=1.0).contains(&lo) { hi } else { lo },
                expected: "0 <= start <= end <= 1",
            });
        }
        Ok(())
    }
}

/// How a search ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RootStatus {
    /// Some pair may touch at the reported time, and at no earlier time.
    Hit,
    /// Some pair may already touch at the start of the span.
    InitiallyTouching,
    /// Every pair is apart over the whole span.
    Separated,
    /// The evaluation budget ran out; the reported time is the earliest not
    /// yet excluded (a conservative answer).
    BudgetExhausted,
}

/// What one search spent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Nodes of time visited.
    pub nodes: u64,
    /// Pair evaluations (one pair on one node).
    pub pair_evaluations: u64,
    /// Axis evaluations (one axis function on one node).
    pub axis_evaluations: u64,
    /// Conservative advancement steps taken before the search (one
    /// distance bound at one time; pairs that turn fast).
    pub advances: u64,
}

impl std::ops::AddAssign for SolveStats {
    fn add_assign(&mut self, o: SolveStats) {
        self.nodes += o.nodes;
        self.pair_evaluations += o.pair_evaluations;
        self.axis_evaluations += o.axis_evaluations;
        self.advances += o.advances;
    }
}

/// The answer of a search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOutcome {
    pub status: RootStatus,
    /// The reported time, a fraction of the step (`span.hi` when separated).
    pub time: f64,
    /// The pair that may touch (none when separated).
    pub pair: Option<usize>,
    pub stats: SolveStats,
}

/// One node waiting on the depth-first stack: its span and the range of
/// the arena that lists its alive pairs.
#[derive(Clone, Copy, Debug)]
struct Frame {
    span: TimeSpan,
    start: usize,
    end: usize,
}

/// An alive pair on a node: its number, its alive axes, and its window:
/// the times where the node that kept it found it may touch (outside it
/// some axis's linear lower bound is positive, so the pair is apart there).
/// Sub-nodes and single-time checks pass over a pair whose window misses
/// them without evaluating it: on a shape against a mesh each triangle's
/// window is much narrower than the node.
#[derive(Clone, Copy, Debug)]
struct Alive {
    pair: u32,
    axes: u64,
    window: TimeSpan,
}

impl Alive {
    /// A pair with every one of its `axes` alive, not yet judged on
    /// `span`.
    fn fresh(pair: u32, axes: usize, span: TimeSpan) -> Alive {
        Alive {
            pair,
            axes: full_mask(axes),
            window: span,
        }
    }

    /// Whether the pair may touch somewhere on `span` (or at a single
    /// time, `span.lo == span.hi`) for all its window says.
    fn may_touch_on(&self, span: TimeSpan) -> bool {
        self.window.lo <= span.hi && span.lo <= self.window.hi
    }
}

/// When clipping leaves less than this share of a node, the clipped node
/// is evaluated again instead of bisected: near a simple root the linear
/// bound converges much faster than halving (docs/design.md §6); a smaller
/// shrink is not worth an evaluation of its own.
const RECLIP_SHARE: f64 = 0.6;

/// A node at most `ε` wide whose pairs cannot be seen touching at its end
/// is split further, down to this share of `ε`: past it the pair only
/// grazes (its gap stays within rounding of zero) and the node's start is
/// reported.
const FLOOR_SHARE: f64 = 1.0 / 64.0;

/// Where a converged start's touch is checked, as a share of `ε` after
/// it (below one, so that the bracket it confirms is within `ε` after
/// rounding); a likely touch that close to the start is checked there
/// too.
const PROBE_SHARE: f64 = 0.999;

/// A likely touch more than `ε` after the node's start is first checked
/// this share of the way there: the root mostly lies much nearer the
/// start (a tenth to a fifth of the way on the cone queries traced), so
/// the check mostly confirms a bracket half as wide, and a failed one
/// costs one single-time evaluation before the check at the likely time
/// itself. Queries bench instructions against checking the likely time
/// only (ordinary spins / 200–1000 rad/s): cone −5 % / 0 %, capsule
/// −10 % / −2 %, cylinder +1 % / −2 %, hull–mesh −1 % / +0.5 %; a quarter
/// of the way did worse, 0.7 of the way about as well.
const EARLY: f64 = 0.5;

/// Composite pieces one node wider than [`NARROW_NODE`] opens at most;
/// the pieces it meets past that stay whole (see [`Solver::visit`]).
/// Measured on the demo scenes (callgrind instructions, every final state
/// unchanged): 64 takes 6.5 % off `settle_wavy` and 6.7 % off
/// `settle_heightfield`, where a 2 m plate falls on a mesh of 20 cm cells;
/// 128 takes 3.9 %; 32 takes 7.8 % but costs `spinning_trimesh` 0.9 %.
const MOST_OPENED: usize = 64;

/// Nodes at most this wide (a share of the step) open every composite
/// piece that may touch on them. On the plate landings of
/// `tests/gap_composite.rs` (a 2 m plate on 10 cm cells), 1/8 takes 54 %
/// of the pair evaluations off, and the slowest landing's 4,979 down to
/// 3,072; 1/32 takes 39 % off but leaves the slowest at 4,768, as narrow
/// nodes meet many pieces still kept whole. The demo scenes do not tell
/// 1/64 from 1/4.
const NARROW_NODE: f64 = 1.0 / 8.0;

/// The most pieces one node is cut into at once.
const MAX_PIECES: usize = 32;

/// How many pieces a node `width` wide is cut into when the gap set finds
/// nodes wider than `useful` of little use (2, a halving, when it does not).
fn pieces_for(width: f64, useful: f64) -> usize {
    if !(useful > 0.0 && useful.is_finite()) || width <= 2.0 * useful {
        return 2;
    }
    ((width / useful).ceil() as usize).clamp(2, MAX_PIECES)
}

/// Reusable buffers for searches; keep one per thread and call
/// [`Solver::solve`] as often as needed.
#[derive(Debug, Default)]
pub struct Solver {
    stack: Vec<Frame>,
    arena: Vec<Alive>,
    pending: Vec<Alive>,
    children: Vec<u32>,
    /// Pairs touching at the start, left out of the search.
    ignored: Vec<u32>,
}

impl Solver {
    pub fn new() -> Solver {
        Solver::default()
    }

    /// The earliest time in `options.span` at which some pair of `gaps`
    /// may touch, searched in the arithmetic `E`.
    pub fn solve<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        options: &SolveOptions,
    ) -> Result<SolveOutcome, CcdError> {
        options.validate()?;
        let mut stats = SolveStats::default();
        // The axes' enclosures, reused by every node: only the alive axes'
        // slots are written and read.
        let mut out = [E::zero(); MAX_AXES];
        let span = options.span;
        self.stack.clear();
        self.arena.clear();
        for pair in 0..gaps.pair_count() {
            let axes = gaps.axis_count(pair);
            if axes > MAX_AXES {
                return Err(CcdError::BadParameter {
                    what: "axes in one pair",
                    value: axes as f64,
                    expected: "at most 64",
                });
            }
            self.arena.push(Alive::fresh(pair as u32, axes, span));
        }
        let (start, end) = (0, self.arena.len());
        let root = Frame { span, start, end };
        // The whole span first: most searches end here, every pair apart
        // over it (so at its start too), with no evaluation at the start.
        self.ignored.clear();
        let Some(root_node) = self.visit(gaps, root, &mut out, &mut stats) else {
            return Ok(SolveOutcome {
                status: RootStatus::Separated,
                time: span.hi,
                pair: None,
                stats,
            });
        };
        // Pairs touching at the very start: the answer, or left out. The
        // check is made lazily, on the node that reaches the start (depth-
        // first, earlier first: while the start is open, every node does)
        // when its exact axes say some pair surely touches from its start
        // on, or before a report at the start. Most searches never make it: some
        // node's clip leaves the start, or proves every pair apart there,
        // first. (Made as soon as a root saw a touch anywhere, it was a sixth
        // of the slowest hull–mesh query, for a start the next clip left.)
        let ignore = options.initial_contact == InitialContact::Ignore;
        let mut start_open = !options.start_apart;
        let mut first = Some((root, root_node));
        loop {
            let (frame, node) = match first.take() {
                Some(reused) => reused,
                None => {
                    let Some(frame) = self.stack.pop() else {
                        break;
                    };
                    self.arena.truncate(frame.end);
                    if stats.pair_evaluations >= options.max_evaluations {
                        return Ok(SolveOutcome {
                            status: RootStatus::BudgetExhausted,
                            time: frame.span.lo,
                            pair: self.arena.get(frame.start).map(|a| a.pair as usize),
                            stats,
                        });
                    }
                    let Some(node) = self.visit(gaps, frame, &mut out, &mut stats) else {
                        // Every pair apart on this node (so at its start).
                        start_open = false;
                        continue;
                    };
                    (frame, node)
                }
            };
            if start_open && node.span.lo > span.lo {
                start_open = false;
            }
            let queued = self.stack.len();
            let report = self.decide(gaps, options, frame, &node, &mut out, &mut stats);
            if start_open && (node.sure_at_start || report.is_some()) {
                // A sure touch at the start, or a report of the start itself:
                // the deferred check first.
                start_open = false;
                let revisit = (frame, queued);
                match self
                    .deferred_start_check(gaps, span, &node, revisit, ignore, &mut out, &mut stats)
                {
                    StartCheck::Touching(touching) => return Ok(touching),
                    StartCheck::Again => continue,
                    StartCheck::Clear => {}
                }
            }
            let Some(time) = report else {
                continue;
            };
            return Ok(hit(time, node.earliest_pair, stats));
        }
        Ok(SolveOutcome {
            status: RootStatus::Separated,
            time: span.hi,
            pair: None,
            stats,
        })
    }

    /// The start check on a node that reaches the start of `span`, visited
    /// as `node` from `frame`: the answer when a pair touches there and
    /// touches are reported; `Again` when pairs are now left out. Then the
    /// node is queued to be visited without them, in place of the
    /// sub-nodes it queued (the stack above `queued`: they counted those
    /// pairs, and their pairs lie in the part of the arena the new visit
    /// writes again). Only the node's surviving pairs are checked: it
    /// proved the others apart over its span, its start among it.
    #[allow(clippy::too_many_arguments)]
    fn deferred_start_check<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        span: TimeSpan,
        node: &Visited,
        (frame, queued): (Frame, usize),
        ignore: bool,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) -> StartCheck {
        debug_assert!(frame.span.lo <= span.lo);
        let pairs = (node.start, node.end);
        if let Some(touching) = self.check_start(gaps, span, pairs, ignore, out, stats) {
            return StartCheck::Touching(touching);
        }
        if self.ignored.is_empty() {
            return StartCheck::Clear;
        }
        self.stack.truncate(queued);
        self.stack.push(frame);
        StartCheck::Again
    }

    /// What a visited node leads to: `Some(time)`, a hit to report at
    /// `time` (its clipped start), or `None` with its sub-nodes queued.
    fn decide<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        options: &SolveOptions,
        frame: Frame,
        node: &Visited,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) -> Option<f64> {
        let clipped = node.span;
        // Report only a node that was itself evaluated at width ≤ ε, and
        // only once some pair is seen touching by its end (so the true
        // time is within ε after the report) or the node reached the
        // floor width (a near-touch that never quite closes).
        if frame.span.width() <= options.epsilon {
            let floor = frame.span.width() <= options.epsilon * FLOOR_SHARE;
            if floor || self.touching_at(gaps, clipped.hi, node, out, stats) {
                return Some(clipped.lo);
            }
        }
        let (start, end) = (node.start, node.end);
        // A likely touch confirmed at its single time (where adaptive
        // axes are chosen for that very time) is as good as certain.
        // A likely time within `ε` of the node's start is checked
        // `ε` after the start instead: such a time is mostly an
        // adaptive axis taken at the node's middle that reads low at
        // the start (the shapes are apart there, but less so along that
        // direction), and the check at it failed; one `ε` on confirms
        // a root that close, and the bracket is then settled. (Cone
        // queries 3–5 % fewer instructions, cylinder 2–4 %; skipping
        // such checks instead cost 3–19 % more.)
        let likely = node.likely.map(|t| {
            let near = clipped.lo + PROBE_SHARE * options.epsilon;
            if t < near && near < clipped.hi {
                near
            } else {
                t
            }
        });
        let confirmed = match (node.certain, likely) {
            (None, Some(t)) => {
                // First `EARLY` of the way to it, where the root
                // mostly lies already.
                let early = clipped.lo + EARLY * (t - clipped.lo);
                if t - clipped.lo > options.epsilon
                    && early > clipped.lo
                    && self.touching_at(gaps, early, node, out, stats)
                {
                    Some(early)
                } else if self.touching_at(gaps, t, node, out, stats) {
                    Some(t)
                } else {
                    None
                }
            }
            (certain, _) => certain,
        };
        if let Some(sure) = confirmed {
            // A root lies in [clipped.lo, sure]: report when that is
            // narrow enough, else look there first (the bracket shrinks
            // quadratically near a simple root; the calibration's "split next
            // to the left end", guarded by certainty).
            let bracket = sure - clipped.lo;
            if bracket <= options.epsilon {
                return Some(clipped.lo);
            }
            // The start has converged (this node's clip moved it, but
            // by less than `ε`) while the confirmed time creeps towards
            // it from above, a few times closer per node (a pair whose
            // enclosure is wide, spinning or turning into contact): one
            // touch check just inside `ε` after the start settles the
            // bracket at once when the start is the root already. (A
            // start the clip did not move at all has not converged,
            // its bound is merely loose there: the check would fail.)
            let moved = clipped.lo - frame.span.lo;
            let probe = clipped.lo + PROBE_SHARE * options.epsilon;
            if moved > 0.0
                && moved < options.epsilon
                && probe < sure
                && self.touching_at(gaps, probe, node, out, stats)
            {
                return Some(clipped.lo);
            }
            // A bracket that kept most of the node is halved as well:
            // where the gap closes slowly (a grazing or sliding pair)
            // the confirmed time creeps towards the root by a few
            // percent per node while the start never moves (false
            // position's one-sided convergence), up to 150 nodes where
            // halving needs 20.
            let mid = clipped.lo + 0.5 * bracket;
            let halve = bracket >= RECLIP_SHARE * frame.span.width();
            if halve && clipped.lo < mid && mid < sure {
                self.stack.push(Frame {
                    span: TimeSpan::new(sure, clipped.hi),
                    start,
                    end,
                });
                self.push_halves(TimeSpan::new(clipped.lo, sure), mid, start, end);
            } else {
                self.push_halves(clipped, sure, start, end);
            }
            return None;
        }
        if !self.requeue(frame.span.width(), node, gaps.useful_width()) {
            return Some(clipped.lo);
        }
        None
    }

    /// If `pair` is composite, queue its sub-pairs that may touch on
    /// `span` (all their axes alive) and return `true`.
    fn expand_into_pending<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        pair: usize,
        span: TimeSpan,
    ) -> bool {
        self.children.clear();
        if !gaps.expand(pair, span, &mut self.children) {
            return false;
        }
        for &child in &self.children {
            let n = gaps.axis_count(child as usize).min(MAX_AXES);
            self.pending.push(Alive::fresh(child, n, span));
        }
        true
    }

    /// Queue a visited node that no bracket settled: its clipped span again
    /// when clipping left less than [`RECLIP_SHARE`] of the `width` it was
    /// visited at, else cut into pieces. `false` when it cannot be split
    /// (no float between its ends).
    fn requeue(&mut self, width: f64, node: &Visited, useful: f64) -> bool {
        let (clipped, start, end) = (node.span, node.start, node.end);
        if clipped.width() < RECLIP_SHARE * width {
            self.stack.push(Frame {
                span: clipped,
                start,
                end,
            });
            return true;
        }
        let mid = clipped.lo + 0.5 * clipped.width();
        if !(clipped.lo < mid && mid < clipped.hi) {
            return false;
        }
        self.push_pieces(clipped, pieces_for(clipped.width(), useful), start, end);
        true
    }

    /// Push `[span.lo, cut]` and `[cut, span.hi]` so that the earlier one
    /// is searched first; both keep the alive pairs `arena[start..end]`.
    fn push_halves(&mut self, span: TimeSpan, cut: f64, start: usize, end: usize) {
        for half in [TimeSpan::new(cut, span.hi), TimeSpan::new(span.lo, cut)] {
            self.stack.push(Frame {
                span: half,
                start,
                end,
            });
        }
    }

    /// Push `span` cut into `pieces` equal parts, the earliest on top; the
    /// cuts are taken from the ends so the parts cover `span` exactly (two
    /// pieces: the halves at `span.lo + 0.5·span.width()`).
    fn push_pieces(&mut self, span: TimeSpan, pieces: usize, start: usize, end: usize) {
        let cut = |k: usize| {
            if k == pieces {
                span.hi
            } else {
                span.lo + span.width() * (k as f64 / pieces as f64)
            }
        };
        for k in (0..pieces).rev() {
            let (lo, hi) = (cut(k), cut(k + 1));
            if lo < hi {
                self.stack.push(Frame {
                    span: TimeSpan::new(lo, hi),
                    start,
                    end,
                });
            }
        }
    }

    /// True when some surviving pair of `node` has every alive axis `≤ 0`
    /// (upper bounds) at the single time `t`: the pair touches by then.
    /// Composites kept whole are passed over: their axes bound pieces.
    fn touching_at<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        t: f64,
        node: &Visited,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) -> bool {
        let span = TimeSpan::new(t, t);
        gaps.begin_node(span);
        for alive in &self.arena[node.start..node.end] {
            if !alive.may_touch_on(span) || gaps.is_composite(alive.pair as usize) {
                continue;
            }
            gaps.eval(alive.pair as usize, span, alive.axes, out);
            stats.pair_evaluations += 1;
            stats.axis_evaluations += u64::from(alive.axes.count_ones());
            let touching = set_bits(alive.axes).all(|k| out[k].range().hi <= 0.0);
            if touching {
                return true;
            }
        }
        false
    }

    /// The check for pairs touching at the start of `span`, on
    /// `arena[pairs.0..pairs.1]`: the answer when one is and they are
    /// reported (`ignore == false`); otherwise `None`, with the pairs to
    /// leave out in `self.ignored`.
    fn check_start<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        span: TimeSpan,
        pairs: (usize, usize),
        ignore: bool,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) -> Option<SolveOutcome> {
        let at_start = TimeSpan::new(span.lo, span.lo);
        self.touching_at_start(gaps, at_start, pairs, ignore, out, stats);
        if ignore {
            return None;
        }
        self.ignored.first().map(|&pair| SolveOutcome {
            status: RootStatus::InitiallyTouching,
            time: span.lo,
            pair: Some(pair as usize),
            stats: *stats,
        })
    }

    /// The pairs in `arena[start..end]` (composites followed down to their
    /// leaves) that may touch at the single time `span`, into
    /// `self.ignored`, sorted; with `all == false`, stop at the first.
    fn touching_at_start<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        span: TimeSpan,
        (start, end): (usize, usize),
        all: bool,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) {
        gaps.begin_node(span);
        stats.nodes += 1;
        self.ignored.clear();
        self.pending.clear();
        self.pending.extend_from_slice(&self.arena[start..end]);
        while let Some(item) = self.pending.pop() {
            if !item.may_touch_on(span) {
                continue;
            }
            let pair = item.pair as usize;
            gaps.eval(pair, span, item.axes, out);
            stats.pair_evaluations += 1;
            stats.axis_evaluations += u64::from(item.axes.count_ones());
            if set_bits(item.axes).any(|k| out[k].range().lo > 0.0) {
                continue;
            }
            if self.expand_into_pending(gaps, pair, span) {
                continue;
            }
            self.ignored.push(item.pair);
            if !all {
                break;
            }
        }
        self.ignored.sort_unstable();
        self.ignored.dedup();
    }

    /// Evaluate one node: prune, drop axes, clip. `None` when every pair is
    /// apart; otherwise the clipped span and the surviving pairs, appended
    /// to the arena.
    fn visit<E: Enclosure, G: GapSet<E>>(
        &mut self,
        gaps: &mut G,
        frame: Frame,
        out: &mut [E; MAX_AXES],
        stats: &mut SolveStats,
    ) -> Option<Visited> {
        let span = frame.span;
        gaps.begin_node(span);
        stats.nodes += 1;
        // Feasible part of the node in the local symbol e ∈ [−1, 1].
        let (mut e_lo, mut e_hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut e_certain = f64::INFINITY;
        // The same for pairs with adaptive axes: a likely touch, to be
        // confirmed by a point evaluation before it is relied on.
        let mut e_likely = f64::INFINITY;
        let mut earliest_pair = 0usize;
        let (m, h) = span.center_radius();
        // τ = m + h·e takes two roundings: step out by a few ulps of the sum.
        let to_time = |e: f64, direction: f64| {
            let t = m + h * e;
            t + direction * 4.0 * f64::EPSILON * (m.abs() + (h * e).abs())
        };
        // `[lo, hi]` in `e` as times within the node, rounded outward (the
        // whole node where rounding crossed the ends over): a pair's
        // window, and the clipped node.
        let to_span = |lo: f64, hi: f64| {
            let (from, to) = (
                to_time(lo, -1.0).max(span.lo),
                to_time(hi, 1.0).min(span.hi),
            );
            if from <= to {
                TimeSpan::new(from, to)
            } else {
                span
            }
        };
        // Pairs to look at: the frame's list (left intact for its sibling
        // node), then any sub-pairs that composites expand into.
        let mut cursor = frame.start;
        self.pending.clear();
        let mut opened = 0;
        loop {
            let item = if cursor < frame.end {
                cursor += 1;
                self.arena[cursor - 1]
            } else if let Some(item) = self.pending.pop() {
                item
            } else {
                break;
            };
            if !item.may_touch_on(span) || self.ignored.binary_search(&item.pair).is_ok() {
                continue;
            }
            let pair = item.pair as usize;
            gaps.eval(pair, span, item.axes, out);
            stats.pair_evaluations += 1;
            stats.axis_evaluations += u64::from(item.axes.count_ones());
            let Some(judged) = judge_pair(out, item.axes) else {
                continue;
            };
            // Dominated axes are dropped only from exact axis sets: an
            // adaptive axis is chosen anew on every node, so being dominated
            // on this one says nothing about its sub-nodes.
            let axes = if gaps.is_exact(pair) {
                judged.axes
            } else {
                item.axes
            };
            let (lo, hi) = (judged.lo, judged.hi);
            // A composite is opened into its pieces, unless the node is
            // wide and has opened many already: it then stays whole, its
            // bound clipping the node as a piece's does, and the sub-nodes
            // open it. On a wide node most pieces of a mesh survive (a
            // plate a few centimetres above terrain may meet every
            // triangle under it over the step), and opening all of them
            // evaluated hundreds the next, narrower node proved apart a
            // few boxes at a time.
            let opens = opened < MOST_OPENED || span.width() <= NARROW_NODE;
            if opens && self.expand_into_pending(gaps, pair, span) {
                opened += self.children.len();
                continue;
            }
            if lo > hi {
                continue;
            }
            if lo < e_lo {
                e_lo = lo;
                earliest_pair = pair;
            }
            e_hi = e_hi.max(hi);
            // (A composite kept whole bounds its pieces: its boxes surely
            // overlapping says nothing of a touch.)
            if let Some(c) = judged.certain {
                if gaps.is_exact(pair) {
                    e_certain = e_certain.min(c.max(lo));
                } else if !gaps.is_composite(pair) {
                    e_likely = e_likely.min(c.max(lo));
                }
            }
            self.arena.push(Alive {
                pair: item.pair,
                axes,
                window: to_span(lo, hi),
            });
        }
        if e_lo > e_hi {
            return None;
        }
        let clipped = to_span(e_lo, e_hi);
        // A time by which some pair surely touches, inside the clipped node.
        let inside = |t: &f64| *t > clipped.lo && *t < clipped.hi;
        let likely = (e_likely <= 1.0)
            .then(|| to_time(e_likely, 1.0))
            .filter(inside);
        let certain = (e_certain <= 1.0)
            .then(|| to_time(e_certain, 1.0))
            .filter(|&t| t > clipped.lo && t < clipped.hi);
        Some(Visited {
            span: clipped,
            certain,
            likely,
            sure_at_start: e_certain <= -1.0,
            start: frame.end,
            end: self.arena.len(),
            earliest_pair,
        })
    }
}

/// A hit at `time` by `pair`.
fn hit(time: f64, pair: usize, stats: SolveStats) -> SolveOutcome {
    SolveOutcome {
        status: RootStatus::Hit,
        time,
        pair: Some(pair),
        stats,
    }
}

/// What the deferred start check found.
enum StartCheck {
    /// A pair touches at the start, and such touches are reported.
    Touching(SolveOutcome),
    /// Pairs touching at the start are now left out; the node is queued
    /// again.
    Again,
    /// No pair touches at the start.
    Clear,
}

/// A visited node that may hold a root.
struct Visited {
    span: TimeSpan,
    /// A time within `span` by which some pair surely touches.
    certain: Option<f64>,
    /// A time within `span` by which a pair with adaptive axes likely
    /// touches (not yet confirmed).
    likely: Option<f64>,
    /// Some pair surely touches from the node's start on.
    sure_at_start: bool,
    start: usize,
    end: usize,
    earliest_pair: usize,
}

/// The mask with the low `n` bits set.
fn full_mask(n: usize) -> u64 {
    if n >= 64 { u64::MAX } else { (1u64 << n) - 1 }
}

/// What one evaluation says of a pair that is not proved apart.
struct Judgement {
    /// The axes worth keeping on sub-nodes.
    axes: u64,
    /// Where in `e ∈ [−1, 1]` every axis's linear lower bound is `≤ 0`
    /// (empty, `lo > hi`, when the linear bounds alone exclude the node).
    lo: f64,
    hi: f64,
    /// The earliest `e` at which every axis's linear *upper* bound is
    /// `≤ 0`: by then the pair surely touches (for families whose axes are
    /// exact), so a root lies in `[lo, certain]`.
    certain: Option<f64>,
}

/// Judge one pair from its enclosed axes: `None` when an axis proves it
/// apart.
fn judge_pair<E: Enclosure>(out: &[E], axes: u64) -> Option<Judgement> {
    let mut best_lo = f64::NEG_INFINITY;
    let (mut e_lo, mut e_hi) = (-1.0f64, 1.0f64);
    let (mut sure_lo, mut sure_hi) = (-1.0f64, 1.0f64);
    // The alive axes' upper bounds, in the order of their bits: the first
    // `KEPT_HIGHS` (every family's count but a few composites'; the rest
    // are read again below). A short array: zeroing one of `MAX_AXES` was
    // a `memset` call per judgement.
    const KEPT_HIGHS: usize = 16;
    let mut highs = [0.0f64; KEPT_HIGHS];
    for (i, k) in set_bits(axes).enumerate() {
        let range = out[k].range();
        if range.lo > 0.0 {
            return None;
        }
        if let Some(high) = highs.get_mut(i) {
            *high = range.hi;
        }
        best_lo = best_lo.max(range.lo);
        // a + b·e ≤ 0 where the axis may be non-positive.
        let (a, b) = out[k].linear_lower();
        if b > 0.0 {
            e_hi = e_hi.min(widen_out((-a) / b, 1.0));
        } else if b < 0.0 {
            e_lo = e_lo.max(widen_out((-a) / b, -1.0));
        } else if a > 0.0 {
            e_lo = 1.0;
            e_hi = -1.0;
        }
        // a + b·e ≤ 0 where the axis surely is non-positive (moved inward).
        let (a, b) = out[k].linear_upper();
        if b > 0.0 {
            sure_hi = sure_hi.min(widen_out((-a) / b, -1.0));
        } else if b < 0.0 {
            sure_lo = sure_lo.max(widen_out((-a) / b, 1.0));
        } else if a.is_nan() || a > 0.0 {
            sure_lo = f64::INFINITY;
        }
    }
    // An axis whose upper bound is below another's lower bound never
    // separates where that other one does not: drop it.
    let mut kept = axes;
    for (i, k) in set_bits(axes).enumerate() {
        let high = highs.get(i).copied().unwrap_or_else(|| out[k].range().hi);
        if high < best_lo {
            kept &= !(1u64 << k);
        }
    }
    Some(Judgement {
        axes: kept,
        lo: e_lo,
        hi: e_hi,
        certain: (sure_lo <= sure_hi).then_some(sure_lo),
    })
}

/// The indices of the set bits of `mask`, lowest first.
fn set_bits(mask: u64) -> impl Iterator<Item = usize> {
    let mut rest = mask;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let k = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            k
        })
    })
}

/// A root of the linear bound computed in floats, moved outward (towards
/// `direction`) past its rounding error so no feasible `e` is cut off.
fn widen_out(q: f64, direction: f64) -> f64 {
    if q.is_nan() {
        return direction;
    }
    q + direction * (1.0e-12 * (1.0 + q.abs()))
}
