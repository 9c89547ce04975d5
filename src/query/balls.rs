//! The balls test: a cheap bound tried before a turning pair's family.
//!
//! However a body turns, each of its shapes stays within a ball about the
//! body's rotation centre, and the centres move without turning (a
//! straight or parabolic path). When those balls are apart over a node, so
//! are the shapes, and no pose need be enclosed: a few dozen flops against
//! the rotation series and the family's axes. It pays on the many nodes a
//! fast spin is cut into (each turning up to half a radian) that lie far
//! from the contact; on nodes that turn little the family's own axes are
//! tight and the balls seldom prove what they cannot, so they are not
//! asked there.

use super::pairs::PairContent;
use crate::convert::vec_from_glam;
use crate::enclosure::TimeSpan;
use crate::enclosure::rounding::{down, up};
use crate::motion::Motion;
use rapier3d::parry::shape::{Shape, ShapeType};

/// The least turn of a node (radians, both sides together) on which the
/// balls are asked.
const BALLS_TURN: f64 = 0.3;

/// The balls of a leaf pair.
#[derive(Clone, Copy, Debug)]
pub(super) struct Balls {
    /// Both balls' radii plus the skin, metres (rounded up).
    apart: f64,
    /// How much the sides turn over the step together, radians.
    turn: f64,
}

impl Balls {
    /// The balls of a leaf pair of shapes `a.1` and `b.1` in frames moving
    /// by `a.0` and `b.0`; `None` for a composite pair, a pair that never
    /// turns more than [`BALLS_TURN`] over the step (a side whose rotation
    /// the family does not read counts as still), and unbounded shapes.
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
        // parry's `f32` sphere is off by a few ulps: padded by far more.
        let radius = |(motion, shape): (&Motion, &dyn Shape)| {
            let sphere = shape.compute_local_bounding_sphere();
            let radius = up(f64::from(sphere.radius) * (1.0 + 1.0e-5) + 1.0e-9);
            motion.reach(&vec_from_glam(sphere.center), radius)
        };
        let apart = up(up(radius(a) + radius(b)) + skin);
        apart.is_finite().then_some(Balls { apart, turn })
    }

    /// A positive lower bound of the pair's gap beyond the skin over
    /// `span`, when the balls show one (only asked on nodes that turn more
    /// than [`BALLS_TURN`]). `a` and `b` move the frames in the order the
    /// balls were made with.
    pub fn gap(&self, a: &Motion, b: &Motion, span: TimeSpan) -> Option<f64> {
        if self.turn * span.width() <= BALLS_TURN {
            return None;
        }
        let gap = down(a.centres_gap(b, span) - self.apart);
        (gap > 0.0).then_some(gap)
    }
}
