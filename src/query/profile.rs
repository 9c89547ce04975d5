//! Where a search's pair evaluations go, by gap family: the families cost
//! very differently (two balls' one squared distance against two boxes'
//! fifteen axes, or a support-map pair's adaptive axes), so a count of
//! evaluations alone does not say where a query's time goes.

use crate::gap::PairGap;
use std::ops::AddAssign;

/// What one pair evaluation was spent on: a gap family's axes (over a node
/// of time, or at one time), a composite's bounding axes, or a shortcut
/// that settled the pair before its family was asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Two balls.
    BallBall,
    /// A ball against a triangle.
    BallTriangle,
    /// A ball against a segment.
    BallSegment,
    /// Two triangles.
    TriangleTriangle,
    /// A ball against a box.
    BallCuboid,
    /// Two boxes: their fifteen separating axes.
    CuboidCuboid,
    /// A box against a triangle: their thirteen separating axes.
    CuboidTriangle,
    /// A convex shape against a half-space.
    HalfSpace,
    /// Any other pair of convex shapes (capsules, cylinders, cones, hulls,
    /// rounded shapes, and boxes searched with a skin): support points
    /// along adaptive axes.
    SupportMap,
    /// A mesh's, heightfield's or compound's bounding box against the
    /// other side, on its way down the shape's tree.
    Composite,
    /// A pair settled before its family was asked: apart by the balls
    /// about each side's centre, by a mesh piece's box, or from the exact
    /// poses at the node's middle; or left unknown on a node over which it
    /// turns too far for its family to tell more (or, a mesh piece whose
    /// gap could not be built, never apart: its error ends the query).
    Shortcut,
}

impl Family {
    /// Every family, in the order [`FamilyEvaluations::iter`] gives them.
    pub const ALL: [Family; 11] = [
        Family::BallBall,
        Family::BallTriangle,
        Family::BallSegment,
        Family::TriangleTriangle,
        Family::BallCuboid,
        Family::CuboidCuboid,
        Family::CuboidTriangle,
        Family::HalfSpace,
        Family::SupportMap,
        Family::Composite,
        Family::Shortcut,
    ];

    /// A short name, for tables.
    pub fn name(self) -> &'static str {
        match self {
            Family::BallBall => "ball-ball",
            Family::BallTriangle => "ball-triangle",
            Family::BallSegment => "ball-segment",
            Family::TriangleTriangle => "triangle-triangle",
            Family::BallCuboid => "ball-box",
            Family::CuboidCuboid => "box-box",
            Family::CuboidTriangle => "box-triangle",
            Family::HalfSpace => "half-space",
            Family::SupportMap => "support map",
            Family::Composite => "composite",
            Family::Shortcut => "shortcut",
        }
    }

    /// The family a leaf pair's gap belongs to.
    pub(crate) fn of(gap: &PairGap) -> Family {
        match gap {
            PairGap::BallBall(_) => Family::BallBall,
            PairGap::BallTriangle(_) => Family::BallTriangle,
            PairGap::BallSegment(_) => Family::BallSegment,
            PairGap::TriangleTriangle(_) => Family::TriangleTriangle,
            PairGap::BallCuboid(_) => Family::BallCuboid,
            PairGap::CuboidCuboid(_) => Family::CuboidCuboid,
            PairGap::CuboidTriangle(_) => Family::CuboidTriangle,
            PairGap::HalfSpace(_) => Family::HalfSpace,
            PairGap::SupportMap(_) => Family::SupportMap,
        }
    }
}

/// Pair evaluations by [`Family`]; they add up to the search's
/// `SolveStats::pair_evaluations`.
///
/// ```
/// use affine_ccd::query::{Family, Query, QueryOptions};
/// use affine_ccd::Motion;
/// use nalgebra::{Isometry3, Point3, Vector3};
/// use rapier3d::parry::shape::Cuboid;
/// use rapier3d::prelude::Vector;
///
/// // A box falling at 20 m/s onto a floor box 0.3 m below it.
/// let falling = Motion::from_velocities(
///     Isometry3::translation(0.0, 0.5, 0.0), Point3::new(0.0, 0.5, 0.0),
///     Vector3::new(0.0, -20.0, 0.0), Vector3::zeros(), 1.0 / 60.0,
/// ).unwrap();
/// let floor = Motion::fixed(Isometry3::identity()).unwrap();
/// let (cube, slab) = (Cuboid::new(Vector::splat(0.1)), Cuboid::new(Vector::new(2.0, 0.1, 2.0)));
/// let mut query = Query::new();
/// let hit = query.one(&cube, &falling, &slab, &floor, &QueryOptions::default()).unwrap();
/// assert!(hit.is_some());
/// let by_family = query.spent_by_family();
/// assert_eq!(by_family.total(), query.spent().pair_evaluations);
/// assert!(by_family.get(Family::CuboidCuboid) > 0);
/// for (family, count) in by_family.iter().filter(|(_, n)| *n > 0) {
///     println!("{}: {count}", family.name());
/// }
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FamilyEvaluations {
    counts: [u64; Family::ALL.len()],
}

impl FamilyEvaluations {
    /// The evaluations spent on `family`.
    pub fn get(&self, family: Family) -> u64 {
        self.counts[family as usize]
    }

    /// Every family with its evaluations, in [`Family::ALL`]'s order.
    pub fn iter(&self) -> impl Iterator<Item = (Family, u64)> + '_ {
        Family::ALL.iter().map(|&f| (f, self.get(f)))
    }

    /// All evaluations.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Counts one evaluation of `family`.
    pub(crate) fn count(&mut self, family: Family) {
        self.counts[family as usize] += 1;
    }
}

impl AddAssign for FamilyEvaluations {
    fn add_assign(&mut self, other: FamilyEvaluations) {
        for (mine, theirs) in self.counts.iter_mut().zip(other.counts) {
            *mine += theirs;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Motion;
    use crate::query::{Query, QueryOptions, ShapeMotion, grid};
    use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
    use rapier3d::parry::shape::{Ball, Capsule, Cuboid, Shape};
    use rapier3d::prelude::Vector;

    /// `Family as usize` indexes the counts: `ALL` must list the families
    /// in their declared order.
    #[test]
    fn all_lists_the_families_in_order() {
        for (i, f) in Family::ALL.iter().enumerate() {
            assert_eq!(*f as usize, i, "{}", f.name());
        }
    }

    /// A shape flying at 20 m/s and turning at 10 rad/s from 1 m above the
    /// origin straight down (dt = 1/60 s: it drops a third of a metre).
    fn falling(height: f64) -> Motion {
        let start = Isometry3::from_parts(
            Vector3::new(0.1, height, 0.05).into(),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.3, 0.2, 0.1)),
        );
        Motion::from_velocities(
            start,
            Point3::new(0.1, height, 0.05),
            Vector3::new(0.0, -20.0, 0.0),
            Vector3::new(10.0, 0.0, 3.0),
            1.0 / 60.0,
        )
        .unwrap()
    }

    /// What one query spent, in all and by family.
    fn spent(moving: &dyn Shape, target: &dyn Shape, height: f64) -> (u64, FamilyEvaluations) {
        let mut query = Query::new();
        let fixed = Motion::fixed(Isometry3::identity()).unwrap();
        let moving = [ShapeMotion {
            shape: moving,
            motion: falling(height),
        }];
        let targets = [ShapeMotion {
            shape: target,
            motion: fixed,
        }];
        query
            .many(&moving, &targets, &QueryOptions::default())
            .unwrap();
        (query.spent().pair_evaluations, query.spent_by_family())
    }

    /// The counts by family add up to the search's evaluations, and each
    /// pair's evaluations land on its own family: two boxes on the box
    /// family, a capsule and a box on the support-map family, a ball over
    /// a mesh on the ball–triangle family and the mesh's bounding boxes.
    #[test]
    fn evaluations_land_on_their_family() {
        let (boxy, ball, rod) = (
            Cuboid::new(Vector::new(0.3, 0.1, 0.2)),
            Ball::new(0.1),
            Capsule::new_y(0.2, 0.05),
        );
        let floor = Cuboid::new(Vector::new(2.0, 0.1, 2.0));
        let mesh = grid(9, 0.5, |i, j| 0.05 * ((i + j) % 3) as f32);
        let cases: [(&dyn Shape, &dyn Shape, &[Family]); 3] = [
            (&boxy, &floor, &[Family::CuboidCuboid]),
            (&rod, &floor, &[Family::SupportMap]),
            (&ball, &mesh, &[Family::BallTriangle, Family::Composite]),
        ];
        for (moving, target, expected) in cases {
            // Hitting the target's top (0.1 m up, the mesh 0.1 m at most)
            // within the step, and missing it from higher up.
            for height in [0.4, 1.0] {
                let (all, by) = spent(moving, target, height);
                assert!(all > 0, "{expected:?} from {height} m: no evaluation");
                assert_eq!(by.total(), all, "{expected:?} from {height} m: {by:?}");
                let own: u64 = expected.iter().map(|&f| by.get(f)).sum();
                // Only shortcuts may take the rest.
                assert_eq!(
                    own + by.get(Family::Shortcut),
                    all,
                    "{expected:?} from {height} m: {by:?}"
                );
                // A hit is searched down to its pieces (a mesh's
                // triangles); a miss may be proved at the top of the tree.
                if height < 0.5 {
                    assert!(
                        expected.iter().all(|&f| by.get(f) > 0),
                        "{expected:?} from {height} m: {by:?}"
                    );
                }
            }
        }
    }
}
