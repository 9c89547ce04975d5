//! Two overlapping boxes: their contact by the 15 separating axes, in
//! `f64`, instead of parry's EPA.
//!
//! parry 0.31 sends a box pair's contact query to GJK, and on to EPA when
//! the boxes overlap (its dispatcher's box–box path is commented out, and
//! the function behind it ends in `unreachable!()` on a degenerate edge
//! pair), and EPA was most of what the stage paid for a box resting or
//! sliding on another (written here, not borrowed, for that reason). For
//! two convex polyhedra the least translation that separates them is along
//! one of the separating-axis candidates (their Minkowski difference has no
//! other face normals), so minus the largest separation over the 15 axes
//! is the penetration depth, exactly; only near-parallel edge pairs are
//! left out, whose cross product has no stable direction (their thin face
//! of the Minkowski difference lies within `PARALLEL` radians of others).
//!
//! When some axis separates, the axes only bound the distance from below:
//! beyond the prediction that settles it, within it the caller asks parry
//! (GJK alone, no EPA, for separated shapes).

use crate::convert::{glam_from_vec, vec_from_glam};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rapier3d::parry::math::Pose;
use rapier3d::parry::query::Contact;
use rapier3d::parry::shape::Cuboid;

/// Edge pairs closer to parallel than this (the sine of their angle) give
/// no axis of their own.
const PARALLEL: f64 = 1.0e-6;

/// What the 15 axes say about two boxes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum BoxPair {
    /// Farther apart than the prediction along some axis: no contact.
    Beyond,
    /// Apart along some axis, by less than the prediction: the axes do not
    /// give the distance (ask parry).
    Apart,
    /// Overlapping or touching: the contact, world frame, normal from the
    /// first box towards the second, `dist` minus the depth.
    Overlap(Contact),
}

/// A box in the world frame, in `f64`.
struct WorldBox {
    center: Vector3<f64>,
    /// Unit axes, as columns.
    axes: Matrix3<f64>,
    half: Vector3<f64>,
}

impl WorldBox {
    fn new(pose: &Pose, cuboid: &Cuboid) -> WorldBox {
        let q = pose.rotation;
        let rotation = UnitQuaternion::new_normalize(nalgebra::Quaternion::new(
            q.w as f64, q.x as f64, q.y as f64, q.z as f64,
        ));
        WorldBox {
            center: vec_from_glam(pose.translation),
            axes: *rotation.to_rotation_matrix().matrix(),
            half: vec_from_glam(cuboid.half_extents),
        }
    }

    /// Half the box's extent along the unit direction `n`.
    fn reach(&self, n: &Vector3<f64>) -> f64 {
        (0..3)
            .map(|i| self.half[i] * self.axes.column(i).dot(n).abs())
            .sum()
    }

    /// A point of the box farthest along `n`; along an axis square to `n`
    /// the middle (a face or an edge of points equally far: its centre).
    fn support(&self, n: &Vector3<f64>) -> Vector3<f64> {
        let mut p = self.center;
        for i in 0..3 {
            let a = self.axes.column(i);
            let along = a.dot(n);
            if along.abs() > PARALLEL {
                p += a * (self.half[i] * along.signum());
            }
        }
        p
    }
}

/// Which kind of axis separates least.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    FaceOfFirst,
    FaceOfSecond,
    Edges,
}

/// The boxes `c1` at `pose1` and `c2` at `pose2` by their 15 axes, with
/// `prediction` metres as in parry's contact query.
pub(crate) fn box_pair(
    pose1: &Pose,
    c1: &Cuboid,
    pose2: &Pose,
    c2: &Cuboid,
    prediction: f64,
) -> BoxPair {
    let (b1, b2) = (WorldBox::new(pose1, c1), WorldBox::new(pose2, c2));
    let d = b2.center - b1.center;
    // The largest separation so far, along which unit axis, of which kind.
    let mut best = (f64::NEG_INFINITY, Vector3::x(), Axis::FaceOfFirst);
    let mut consider = |n: Vector3<f64>, kind: Axis| {
        let along = d.dot(&n);
        let sep = along.abs() - b1.reach(&n) - b2.reach(&n);
        if sep > best.0 {
            // Oriented from the first box towards the second.
            let n = if along < 0.0 { -n } else { n };
            best = (sep, n, kind);
        }
    };
    for i in 0..3 {
        consider(b1.axes.column(i).into_owned(), Axis::FaceOfFirst);
    }
    for j in 0..3 {
        consider(b2.axes.column(j).into_owned(), Axis::FaceOfSecond);
    }
    for i in 0..3 {
        for j in 0..3 {
            let n = b1.axes.column(i).cross(&b2.axes.column(j));
            let length = n.norm();
            if length > PARALLEL {
                consider(n / length, Axis::Edges);
            }
        }
    }
    let (sep, n, kind) = best;
    if sep > prediction {
        return BoxPair::Beyond;
    }
    // Apart, or not a number (parry then answers as it can).
    if sep > 0.0 || sep.is_nan() {
        return BoxPair::Apart;
    }
    // `sep ≤ 0` is minus the depth. The witness: the deepest point of the
    // box whose face is not the axis, and where it leaves the other box
    // along the normal (for two edges, the closest points of the edges).
    let (p1, p2) = match kind {
        Axis::FaceOfFirst => {
            let p2 = b2.support(&-n);
            (p2 - n * sep, p2)
        }
        Axis::FaceOfSecond => {
            let p1 = b1.support(&n);
            (p1, p1 + n * sep)
        }
        Axis::Edges => edge_points(&b1, &b2, &n),
    };
    BoxPair::Overlap(Contact::new(
        glam_from_vec(&p1),
        glam_from_vec(&p2),
        glam_from_vec(&n),
        glam_from_vec(&-n),
        sep as f32,
    ))
}

/// The closest points of the edge of `b1` farthest along `n` and the edge
/// of `b2` farthest against it (the edges whose cross product is `n`).
fn edge_points(b1: &WorldBox, b2: &WorldBox, n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (s1, e1) = support_edge(b1, n);
    let (s2, e2) = support_edge(b2, &-n);
    let (t1, t2) = closest_on_segments(&s1, &e1, &s2, &e2);
    (s1 + e1 * t1, s2 + e2 * t2)
}

/// The edge of `b` farthest along `n` (square to it): its start and the
/// vector along it.
fn support_edge(b: &WorldBox, n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    // The box axis most square to `n` runs along the edge.
    let k = (0..3)
        .min_by(|&i, &j| {
            let (ai, aj) = (b.axes.column(i).dot(n).abs(), b.axes.column(j).dot(n).abs());
            ai.total_cmp(&aj)
        })
        .unwrap_or(0);
    let along = b.axes.column(k) * b.half[k];
    let mut middle = b.center;
    for i in (0..3).filter(|&i| i != k) {
        let a = b.axes.column(i);
        middle += a * (b.half[i] * a.dot(n).signum());
    }
    (middle - along, along * 2.0)
}

/// Parameters in `[0, 1]` of the closest points of the segments
/// `s1 + t1·e1` and `s2 + t2·e2` (not parallel: the edge axes exclude
/// those).
fn closest_on_segments(
    s1: &Vector3<f64>,
    e1: &Vector3<f64>,
    s2: &Vector3<f64>,
    e2: &Vector3<f64>,
) -> (f64, f64) {
    let r = s1 - s2;
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d, e) = (e1.dot(&r), e2.dot(&r));
    let denom = a * c - b * b;
    let mut t1 = if denom > 0.0 {
        ((b * e - c * d) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t2 = if c > 0.0 { (b * t1 + e) / c } else { 0.0 };
    if !(0.0..=1.0).contains(&t2) {
        t2 = t2.clamp(0.0, 1.0);
        t1 = if a > 0.0 {
            ((b * t2 - d) / a).clamp(0.0, 1.0)
        } else {
            0.0
        };
    }
    (t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use rapier3d::math::{Rotation, Vector};
    use rapier3d::parry::query::PointQuery;

    /// Where a point of the world is, seen from a pose.
    fn local(pose: &Pose, p: Vector) -> Point3<f64> {
        Point3::from(vec_from_glam(pose.inverse_transform_point(p)))
    }

    /// A small seeded generator (tests only).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 33) as f64 / (1u64 << 31) as f64) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
    }

    fn random_pose(rng: &mut Lcg, spread: f32) -> Pose {
        let axis = Vector::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(Vector::Z);
        Pose::from_parts(
            Vector::new(
                rng.range(-spread, spread),
                rng.range(-spread, spread),
                rng.range(-spread, spread),
            ),
            Rotation::from_axis_angle(axis, rng.range(-3.0, 3.0)),
        )
    }

    /// On random box pairs the 15 axes agree with parry's GJK/EPA: apart
    /// where parry says apart; where they overlap, never deeper than the
    /// overlap along parry's normal, parry's depth on most pairs (on the
    /// few where EPA stops early, a dense grid of directions' least
    /// overlap), and witness points on the boxes' surfaces.
    #[test]
    fn the_axes_agree_with_parrys_contact() {
        let mut rng = Lcg(7);
        let (mut overlaps, mut beyond, mut disagree) = (0, 0, 0);
        for case in 0..4000 {
            let c1 = Cuboid::new(Vector::new(
                rng.range(0.05, 2.0),
                rng.range(0.05, 2.0),
                rng.range(0.05, 2.0),
            ));
            let c2 = Cuboid::new(Vector::new(
                rng.range(0.05, 1.0),
                rng.range(0.05, 1.0),
                rng.range(0.05, 1.0),
            ));
            let (p1, p2) = (random_pose(&mut rng, 1.5), random_pose(&mut rng, 1.5));
            let prediction = 0.1;
            let parry = rapier3d::parry::query::contact(&p1, &c1, &p2, &c2, prediction as f32)
                .expect("parry answers box pairs");
            match box_pair(&p1, &c1, &p2, &c2, prediction) {
                BoxPair::Beyond => {
                    beyond += 1;
                    assert!(parry.is_none(), "case {case}: parry sees {parry:?}");
                }
                BoxPair::Apart => {
                    let c = parry.expect("apart within the prediction");
                    assert!(c.dist > -1.0e-4, "case {case}: parry depth {}", c.dist);
                }
                BoxPair::Overlap(ours) => {
                    overlaps += 1;
                    let c = parry.expect("parry sees the overlap");
                    let (b1, b2) = (WorldBox::new(&p1, &c1), WorldBox::new(&p2, &c2));
                    let d = b2.center - b1.center;
                    let overlap = |n: &Vector3<f64>| b1.reach(n) + b2.reach(n) - d.dot(n).abs();
                    // The depth is the least overlap over all directions,
                    // parry's normal among them.
                    let depth = -ours.dist as f64;
                    let along_parry = overlap(&vec_from_glam(c.normal1));
                    assert!(
                        depth <= along_parry + 1.0e-5,
                        "case {case}: depth {depth} beyond the overlap along parry's normal {along_parry}"
                    );
                    if (ours.dist - c.dist).abs() > 1.0e-4 * (1.0 + c.dist.abs()) {
                        // parry's EPA stops early on some deep overlaps:
                        // the least overlap over a dense grid of directions.
                        disagree += 1;
                        let m = 200;
                        let mut least = f64::INFINITY;
                        for a in 0..m {
                            for b in 0..2 * m {
                                let th = std::f64::consts::PI * (a as f64 + 0.5) / m as f64;
                                let ph = std::f64::consts::PI * b as f64 / m as f64;
                                let n = Vector3::new(
                                    th.sin() * ph.cos(),
                                    th.sin() * ph.sin(),
                                    th.cos(),
                                );
                                least = least.min(overlap(&n));
                            }
                        }
                        assert!(
                            depth <= least + 1.0e-6 && least - depth < 5.0e-3,
                            "case {case}: depth {depth}, grid {least}, parry {}",
                            -c.dist
                        );
                        continue;
                    }
                    for (pose, cuboid, point) in [(&p1, &c1, ours.point1), (&p2, &c2, ours.point2)]
                    {
                        let at = local(pose, point);
                        let on = cuboid.project_local_point(glam_from_vec(&at.coords), false);
                        let off = (vec_from_glam(on.point) - at.coords).norm();
                        assert!(off < 1.0e-4, "case {case}: witness {off} m off its box");
                    }
                }
            }
        }
        println!("{overlaps} overlaps ({disagree} off parry's depth), {beyond} beyond");
        assert!(
            disagree * 20 < overlaps,
            "{disagree} of {overlaps} overlaps off parry's depth"
        );
        assert!(
            overlaps > 500 && beyond > 500,
            "{overlaps} overlaps, {beyond} beyond"
        );
    }

    /// A box resting 2 mm deep on a floor: the floor's normal, 2 mm deep,
    /// the witness under the box's bottom face centre.
    #[test]
    fn a_box_sunk_into_a_floor() {
        let floor = Cuboid::new(Vector::new(20.0, 0.5, 20.0));
        let cube = Cuboid::new(Vector::splat(0.2));
        let floor_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
        let cube_pose = Pose::from_translation(Vector::new(3.0, 0.198, 1.0));
        let BoxPair::Overlap(c) = box_pair(&floor_pose, &floor, &cube_pose, &cube, 0.01) else {
            panic!("the cube is in the floor");
        };
        assert!((c.dist + 0.002).abs() < 1.0e-6, "depth {}", c.dist);
        assert!((c.normal1 - Vector::Y).length() < 1.0e-6, "{:?}", c.normal1);
        assert!(
            (c.point2 - Vector::new(3.0, -0.002, 1.0)).length() < 1.0e-5,
            "{:?}",
            c.point2
        );
        assert!(
            (c.point1 - Vector::new(3.0, 0.0, 1.0)).length() < 1.0e-5,
            "{:?}",
            c.point1
        );
    }
}
