//! The balls test: a cheap bound tried before a turning pair's family.
//!
//! However a body turns, each of its shapes stays within a ball about the
//! body's rotation centre, and the centres move without turning (a
//! straight or parabolic path). When those balls are apart over a node, so
//! are the shapes, and no pose need be enclosed: a few dozen flops against
//! the rotation series and the family's axes. Where one side does not turn
//! (a wall, a floor's triangle, a sliding box), the other's ball is held
//! against that side's own box instead, in its frame: tighter than its
//! ball, and as cheap. It pays on the many nodes a fast spin is cut into
//! (each turning up to half a radian) that lie far from the contact; on
//! nodes that turn little the family's own axes are tight and the balls
//! seldom prove what they cannot, so they are not asked there.

use super::pairs::PairContent;
use crate::convert::vec_from_glam;
use crate::enclosure::TimeSpan;
use crate::enclosure::rounding::{down, up};
use crate::motion::Motion;
use nalgebra::Vector3;
use rapier3d::parry::shape::{Shape, ShapeType};

/// The least turn of a node (radians, both sides together) on which the
/// balls are asked.
const BALLS_TURN: f64 = 0.3;

/// The balls of a leaf pair.
#[derive(Clone, Copy, Debug)]
pub(super) struct Balls {
    /// The balls' radii (only the turning side's when one side is
    /// [`Still`]) plus the skin, metres (rounded up).
    apart: f64,
    /// How much the sides turn over the step together, radians.
    turn: f64,
    still: Option<Still>,
}

/// A side that does not turn, seen as its box in its own frame.
#[derive(Clone, Copy, Debug)]
struct Still {
    /// Whether it is the pair's `b` side.
    is_b: bool,
    center: Vector3<f64>,
    half: Vector3<f64>,
}

impl Balls {
    /// The balls of a leaf pair of shapes `a.1` and `b.1` in frames moving
    /// by `a.0` and `b.0`; `None` for a composite pair, a pair that never
    /// turns more than [`BALLS_TURN`] over the step (a side whose rotation
    /// the family does not read, a ball's, counts as not turning), and
    /// unbounded shapes.
    pub fn new(
        kind: &PairContent,
        a: (&Motion, &dyn Shape),
        b: (&Motion, &dyn Shape),
        skin: f64,
    ) -> Option<Balls> {
        let PairContent::Leaf(gap, swapped) = kind else {
            return None;
        };
        let [reads_a, reads_b] = gap.reads_rotation();
        let (reads_a, reads_b) = if *swapped {
            (reads_b, reads_a)
        } else {
            (reads_a, reads_b)
        };
        let square = |reads: bool, m: &Motion| {
            if reads {
                m.rotation().norm_squared()
            } else {
                0.0
            }
        };
        let (qa, qb) = (square(reads_a, a.0), square(reads_b, b.0));
        // |θa| + |θb| ≤ √(2(|θa|² + |θb|²)): most pairs leave here, with
        // no square root taken.
        if 2.0 * (qa + qb) <= BALLS_TURN * BALLS_TURN {
            return None;
        }
        let turn = qa.sqrt() + qb.sqrt();
        let unbounded = |s: &dyn Shape| s.shape_type() == ShapeType::HalfSpace;
        if turn <= BALLS_TURN || unbounded(a.1) || unbounded(b.1) {
            return None;
        }
        // parry's `f32` sphere and box are off by a few ulps: padded by far
        // more.
        let pad = |x: f64| up(x * (1.0 + 1.0e-5) + 1.0e-9);
        let radius = |(motion, shape): (&Motion, &dyn Shape)| {
            let sphere = shape.compute_local_bounding_sphere();
            motion.reach(&vec_from_glam(sphere.center), pad(f64::from(sphere.radius)))
        };
        let boxed = |shape: &dyn Shape, is_b: bool| {
            let aabb = shape.compute_local_aabb();
            let (lo, hi) = (vec_from_glam(aabb.mins), vec_from_glam(aabb.maxs));
            Still {
                is_b,
                center: (lo + hi) * 0.5,
                half: ((hi - lo) * 0.5).map(pad),
            }
        };
        // The side `centre_seen_from` can look from, if either.
        let (radii, still) = if !b.0.turns() {
            (radius(a), Some(boxed(b.1, true)))
        } else if !a.0.turns() {
            (radius(b), Some(boxed(a.1, false)))
        } else {
            (up(radius(a) + radius(b)), None)
        };
        let apart = up(radii + skin);
        apart.is_finite().then_some(Balls { apart, turn, still })
    }

    /// A positive lower bound of the pair's gap beyond the skin over
    /// `span`, when the balls show one (only asked on nodes that turn more
    /// than [`BALLS_TURN`]). `a` and `b` move the frames in the order the
    /// balls were made with.
    pub fn gap(&self, a: &Motion, b: &Motion, span: TimeSpan) -> Option<f64> {
        if self.turn * span.width() <= BALLS_TURN {
            return None;
        }
        let centres = match &self.still {
            None => a.centres_gap(b, span),
            Some(still) => {
                let (frame, other) = if still.is_b { (b, a) } else { (a, b) };
                let (seen, stray) = frame.centre_seen_from(other, span)?;
                let outside = ((seen - still.center).abs() - still.half).sup(&Vector3::zeros());
                outside.norm() - stray
            }
        };
        let gap = down(centres - self.apart);
        (gap > 0.0).then_some(gap)
    }
}
