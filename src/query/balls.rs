//! The balls test: a cheap bound tried before a turning pair's family.
//!
//! However a body turns, each of its shapes stays within a ball about the
//! body's rotation centre, and the centres move without turning (a
//! straight or parabolic path). When those balls are apart over a node, so
//! are the shapes, and no pose need be enclosed: a few dozen flops against
//! the rotation series and the family's axes. Where one side does not turn
//! (a wall, a floor's triangle, a sliding box), the other's ball is held
//! against that side's own box instead, in its frame: tighter than its
//! ball, and as cheap; and a triangle's against its plane too (the box of
//! a tilted triangle is a thick slab around it). It pays on the many nodes
//! a fast spin is cut into (each turning up to half a radian) that lie far
//! from the contact; on nodes that turn little the family's own axes are
//! tight and the balls seldom prove what they cannot, so they are not
//! asked there.

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

/// A side that does not turn, seen as its box in its own frame (and, for
/// a flat one, a triangle, its plane: a tilted triangle's box is a thick
/// slab around it, which a ball passing over the triangle meets).
#[derive(Clone, Copy, Debug)]
struct Still {
    /// Whether it is the pair's `b` side.
    is_b: bool,
    center: Vector3<f64>,
    half: Vector3<f64>,
    /// A unit normal `n` of the triangle's plane, its offset `n·v` (any
    /// vertex `v`) and a pad for their rounding (metres).
    plane: Option<(Vector3<f64>, f64, f64)>,
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
        let [reads_a, reads_b] = gap.reads_rotation_as(*swapped);
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
            let plane = shape.as_triangle().and_then(|t| {
                let [a, b, c] = [t.a, t.b, t.c].map(vec_from_glam);
                let n = (b - a).cross(&(c - a)).try_normalize(1.0e-12)?;
                // parry's `f32` vertices are exact in `f64`; the normal and
                // the dot products are rounded a few times, in terms no
                // larger than the vertices: 1e-12 of them covers that.
                let size = a.norm().max(b.norm()).max(c.norm());
                Some((n, n.dot(&a), 1.0e-12 * size + f64::MIN_POSITIVE))
            });
            Still {
                is_b,
                center: (lo + hi) * 0.5,
                half: ((hi - lo) * 0.5).map(pad),
                plane,
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

    /// How much the sides turn over the step together, radians.
    pub fn turn(&self) -> f64 {
        self.turn
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
                // Both the box and the plane hold the triangle: the
                // centre is at least the farther of the two from it.
                let off_plane = still.plane.map_or(0.0, |(n, offset, pad)| {
                    (n.dot(&seen) - offset).abs() - pad - 1.0e-12 * seen.norm()
                });
                outside.norm().max(off_plane) - stray
            }
        };
        let gap = down(centres - self.apart);
        (gap > 0.0).then_some(gap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap;
    use crate::motion::Trajectory;
    use nalgebra::{Isometry3, Point3, UnitQuaternion};
    use parry3d_f64::shape::{Cuboid as Cuboid64, Triangle as Triangle64};
    use rapier3d::parry::math::Vector;
    use rapier3d::parry::shape::{Cuboid, Triangle};

    /// A box spinning at 300 rad/s near a tilted triangle, from 1,500
    /// random starts, each step cut into 8 nodes: wherever the balls give
    /// a gap over a node, the box is at least that far from the triangle
    /// at 40 times of the node (parry3d-f64's distance); and the plane
    /// answers where the triangle's box alone (a thick slab around it)
    /// would not, on many nodes.
    #[test]
    fn a_ball_beside_a_tilted_triangle_is_held_against_its_plane() {
        let (half, corners) = (
            [0.3, 0.1, 0.2],
            [[-2.0f32, -2.0, -1.0], [2.0, 2.0, -1.0], [0.0, 0.0, 2.0]],
        );
        let cuboid = Cuboid::new(Vector::new(half[0], half[1], half[2]));
        let [a, b, c] = corners.map(|p| Vector::new(p[0], p[1], p[2]));
        let triangle = Triangle::new(a, b, c);
        let v64 =
            |p: [f32; 3]| parry3d_f64::math::Vector::new(p[0].into(), p[1].into(), p[2].into());
        let cuboid64 = Cuboid64::new(v64(half));
        let triangle64 = Triangle64::new(v64(corners[0]), v64(corners[1]), v64(corners[2]));
        let built = gap::build(&cuboid, &triangle, 0.0).unwrap();
        let kind = PairContent::Leaf(built.gap, built.swapped);
        let still = Motion::fixed(Isometry3::identity()).unwrap();
        let mut seed = 3u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut answered, mut by_plane) = (0, 0);
        for _ in 0..1500 {
            let at = Vector3::new(next(), next(), next()) * 2.5;
            let axis = Vector3::new(next(), next(), next());
            let start =
                Isometry3::from_parts(at.into(), UnitQuaternion::from_scaled_axis(axis * 2.0));
            let spin = axis.try_normalize(1.0e-6).unwrap_or(Vector3::y()) * 300.0;
            let velocity = Vector3::new(next(), next(), next()) * 30.0;
            let spinning =
                Motion::from_velocities(start, Point3::from(at), velocity, spin, 1.0 / 60.0)
                    .unwrap();
            let balls = Balls::new(&kind, (&spinning, &cuboid), (&still, &triangle), 0.0)
                .expect("a fast turn against a still triangle");
            for k in 0..8 {
                let span = TimeSpan::new(k as f64 / 8.0, (k + 1) as f64 / 8.0);
                let Some(gap) = balls.gap(&spinning, &still, span) else {
                    continue;
                };
                answered += 1;
                for i in 0..=40 {
                    let t = span.lo + span.width() * i as f64 / 40.0;
                    let pose = crate::convert::pose64_from_iso(&spinning.pose_at(t));
                    let d = parry3d_f64::query::distance(
                        &pose,
                        &cuboid64,
                        &parry3d_f64::math::Pose::IDENTITY,
                        &triangle64,
                    )
                    .unwrap()
                    .distance;
                    assert!(
                        d >= gap - 1.0e-9,
                        "balls {gap} apart, the shapes {d} at {t}"
                    );
                }
                // The triangle's box alone, as the balls were before.
                let still_side = balls.still.as_ref().unwrap();
                let (seen, stray) = still.centre_seen_from(&spinning, span).unwrap();
                let outside =
                    ((seen - still_side.center).abs() - still_side.half).sup(&Vector3::zeros());
                if outside.norm() - stray - balls.apart <= 0.0 {
                    by_plane += 1;
                }
            }
        }
        assert!(
            answered > 1000 && by_plane > 200,
            "answered {answered}, by the plane alone {by_plane}"
        );
    }
}
