//! Two overlapping polytopes (boxes, triangles): their contact by the
//! separating axes, in `f64`, instead of parry's EPA.
//!
//! parry 0.31 sends a box–box or box–triangle contact query to GJK, and on
//! to EPA when the shapes overlap (its dispatcher's box–box path is
//! commented out, and the function behind it ends in `unreachable!()` on a
//! degenerate edge pair), and EPA was most of what the stage paid for a
//! box resting or sliding on a box or a mesh (written here, not borrowed,
//! for that reason). For two convex polytopes the least translation that
//! separates them is along one of the separating-axis candidates, the face
//! normals of each and the cross products of an edge of each (their
//! Minkowski difference has no other face normals), so minus the largest
//! separation over those axes is the penetration depth, exactly. Edge
//! pairs within [`PARALLEL`] of parallel are left out: their cross
//! product has no stable direction, and the thin face of the Minkowski
//! difference it stands for lies that close to others.
//!
//! When some axis separates, the axes only bound the distance from below:
//! beyond the prediction that settles it; within it the caller asks parry
//! (GJK alone, no EPA, for separated shapes).
//!
//! Like parry's dispatcher, this works in the first shape's frame: the
//! second is placed by `pos12`, and the contact comes back with each
//! point and normal in its own shape's frame.

use crate::convert::{glam_from_vec, iso_from_pose, vec_from_glam};
use crate::gap::segment_segment;
use nalgebra::{Isometry3, Matrix3, Point3, UnitQuaternion, Vector3};
use rapier3d::parry::math::Pose;
use rapier3d::parry::query::Contact;
use rapier3d::parry::shape::Shape;

/// Edge pairs closer to parallel than this (the sine of their angle) give
/// no axis of their own.
const PARALLEL: f64 = 1.0e-6;

/// What the separating axes say about two polytopes.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SatAnswer {
    /// Farther apart than the prediction along some axis: no contact.
    Beyond,
    /// Apart along some axis, by less than the prediction: the axes do not
    /// give the distance (ask parry; the unit axis that separates most, in
    /// the first shape's frame from the first towards the second, is a
    /// good first direction for its GJK), and by how much along it.
    Apart(Vector3<f64>, f64),
    /// Not a box or triangle pair, or not finite: parry answers as it can.
    Unknown,
    /// Overlapping or touching: the contact (points and normals each in
    /// its own shape's frame, `dist` minus the depth).
    Overlap(Contact),
}

/// A box or a triangle, placed in the first shape's frame.
#[derive(Clone, Copy, Debug)]
enum Solid {
    Box(PlacedBox),
    /// A box in its own frame (the first shape): a `Box` at the origin
    /// with the unit axes, its projections and supports read off the
    /// direction's coordinates, with the same results bit for bit.
    LocalBox(LocalBox),
    Triangle(Triangle3),
}

/// A box placed in the first shape's frame.
#[derive(Clone, Copy, Debug)]
struct PlacedBox {
    center: Vector3<f64>,
    /// Unit axes, as columns.
    axes: Matrix3<f64>,
    half: Vector3<f64>,
}

/// The first shape's box, in its own frame.
#[derive(Clone, Copy, Debug)]
struct LocalBox {
    half: Vector3<f64>,
}

/// A triangle's corners, placed in the first shape's frame.
#[derive(Clone, Copy, Debug)]
struct Triangle3([Vector3<f64>; 3]);

/// What the separating-axis search asks of a box or a triangle. Each kind
/// answers for itself, and the search is written once over the trait, so
/// each pair of kinds gets its own copy with the projections inlined
/// (through the enum each projection was a call and a match on the kind).
trait Polytope {
    /// Unit face normals (a box's three axes, a triangle's normal; none
    /// for a triangle without area).
    fn faces(&self) -> ([Vector3<f64>; 3], usize);

    /// Edge directions (a box's axes; a triangle's edges, not unit).
    fn edges(&self) -> [Vector3<f64>; 3];

    /// The shape's extent along the unit direction `n`: `[min, max]`.
    fn project(&self, n: &Vector3<f64>) -> (f64, f64);

    /// A point of the shape farthest along `n`: where several are (a face
    /// or an edge square to `n`), their middle.
    fn support(&self, n: &Vector3<f64>) -> Vector3<f64>;

    /// Edge `k` as a segment (its two ends): for a box, the edge along
    /// axis `k` farthest along `n`.
    fn edge(&self, k: usize, n: &Vector3<f64>) -> [Vector3<f64>; 2];
}

impl Solid {
    /// The shape as a polytope placed by `rotation` and `translation`;
    /// `None` for other shapes.
    fn of(shape: &dyn Shape, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Option<Solid> {
        if let Some(c) = shape.as_cuboid() {
            return Some(Solid::Box(PlacedBox {
                center: *translation,
                axes: *rotation,
                half: vec_from_glam(c.half_extents),
            }));
        }
        let t = shape.as_triangle()?;
        let place = |v| rotation * vec_from_glam(v) + translation;
        Some(Solid::Triangle(Triangle3([
            place(t.a),
            place(t.b),
            place(t.c),
        ])))
    }

    /// The first shape, in its own frame: what [`Solid::of`] gives with no
    /// rotation and no translation, for less (a triangle's zero
    /// coordinates come out `+0` there, as here).
    fn local(shape: &dyn Shape) -> Option<Solid> {
        if let Some(c) = shape.as_cuboid() {
            return Some(Solid::LocalBox(LocalBox {
                half: vec_from_glam(c.half_extents),
            }));
        }
        let t = shape.as_triangle()?;
        let place = |v| vec_from_glam(v).map(|x: f64| x + 0.0);
        Some(Solid::Triangle(Triangle3([
            place(t.a),
            place(t.b),
            place(t.c),
        ])))
    }

    fn is_finite(&self) -> bool {
        match self {
            Solid::LocalBox(b) => b.half.iter().all(|x| x.is_finite()),
            Solid::Box(b) => b
                .center
                .iter()
                .chain(b.axes.iter())
                .chain(b.half.iter())
                .all(|x| x.is_finite()),
            Solid::Triangle(t) => t.0.iter().flat_map(|p| p.iter()).all(|x| x.is_finite()),
        }
    }
}

impl LocalBox {
    /// The `Box` it stands for.
    fn as_box(&self) -> PlacedBox {
        PlacedBox {
            center: Vector3::zeros(),
            axes: Matrix3::identity(),
            half: self.half,
        }
    }
}

impl Polytope for PlacedBox {
    fn faces(&self) -> ([Vector3<f64>; 3], usize) {
        (columns(&self.axes), 3)
    }

    fn edges(&self) -> [Vector3<f64>; 3] {
        columns(&self.axes)
    }

    fn project(&self, n: &Vector3<f64>) -> (f64, f64) {
        let (center, axes, half) = (&self.center, &self.axes, &self.half);
        let reach: f64 = (0..3).map(|i| half[i] * axes.column(i).dot(n).abs()).sum();
        let at = center.dot(n);
        (at - reach, at + reach)
    }

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

    fn edge(&self, k: usize, n: &Vector3<f64>) -> [Vector3<f64>; 2] {
        let along = self.axes.column(k) * self.half[k];
        let mut middle = self.center;
        for i in (0..3).filter(|&i| i != k) {
            let a = self.axes.column(i);
            middle += a * (self.half[i] * a.dot(n).signum());
        }
        [middle - along, middle + along]
    }
}

impl Polytope for LocalBox {
    fn faces(&self) -> ([Vector3<f64>; 3], usize) {
        (columns(&Matrix3::identity()), 3)
    }

    fn edges(&self) -> [Vector3<f64>; 3] {
        columns(&Matrix3::identity())
    }

    fn project(&self, n: &Vector3<f64>) -> (f64, f64) {
        // A unit axis' dot product with `n` is `n`'s coordinate (or a zero
        // of either sign, which the absolute value clears), and the
        // origin's is a zero: computed as the `Box` computes it, for its
        // sign.
        let reach: f64 = (0..3).map(|i| self.half[i] * n[i].abs()).sum();
        let at = Vector3::<f64>::zeros().dot(n);
        (at - reach, at + reach)
    }

    fn support(&self, n: &Vector3<f64>) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            if n[i].abs() > PARALLEL {
                self.half[i] * n[i].signum()
            } else {
                0.0
            }
        })
    }

    fn edge(&self, k: usize, n: &Vector3<f64>) -> [Vector3<f64>; 2] {
        // Which way each other axis faces `n` hangs on the sign of a zero
        // dot product, which the `Box` decides (a contact between two
        // edges, rare enough to pay for it).
        self.as_box().edge(k, n)
    }
}

impl Polytope for Triangle3 {
    fn faces(&self) -> ([Vector3<f64>; 3], usize) {
        let [a, b, c] = &self.0;
        let n = (b - a).cross(&(c - a));
        let length = n.norm();
        if length > 0.0 && length.is_finite() {
            ([n / length, Vector3::zeros(), Vector3::zeros()], 1)
        } else {
            ([Vector3::zeros(); 3], 0)
        }
    }

    fn edges(&self) -> [Vector3<f64>; 3] {
        let [a, b, c] = &self.0;
        [b - a, c - b, a - c]
    }

    fn project(&self, n: &Vector3<f64>) -> (f64, f64) {
        let v = &self.0;
        let (a, b, c) = (v[0].dot(n), v[1].dot(n), v[2].dot(n));
        (a.min(b).min(c), a.max(b).max(c))
    }

    fn support(&self, n: &Vector3<f64>) -> Vector3<f64> {
        let v = &self.0;
        let far = v.iter().map(|p| p.dot(n)).fold(f64::NEG_INFINITY, f64::max);
        let tied = v
            .iter()
            .filter(|p| far - p.dot(n) <= PARALLEL * (1.0 + far.abs()));
        let (sum, count) = tied.fold((Vector3::zeros(), 0.0), |(s, k), p| (s + p, k + 1.0));
        sum / count
    }

    fn edge(&self, k: usize, _n: &Vector3<f64>) -> [Vector3<f64>; 2] {
        [self.0[k], self.0[(k + 1) % 3]]
    }
}

/// The enum answers as its kind does (for the tests, which mix kinds).
#[cfg(test)]
impl Polytope for Solid {
    fn faces(&self) -> ([Vector3<f64>; 3], usize) {
        match self {
            Solid::Box(b) => b.faces(),
            Solid::LocalBox(b) => b.faces(),
            Solid::Triangle(t) => t.faces(),
        }
    }

    fn edges(&self) -> [Vector3<f64>; 3] {
        match self {
            Solid::Box(b) => b.edges(),
            Solid::LocalBox(b) => b.edges(),
            Solid::Triangle(t) => t.edges(),
        }
    }

    fn project(&self, n: &Vector3<f64>) -> (f64, f64) {
        match self {
            Solid::Box(b) => b.project(n),
            Solid::LocalBox(b) => b.project(n),
            Solid::Triangle(t) => t.project(n),
        }
    }

    fn support(&self, n: &Vector3<f64>) -> Vector3<f64> {
        match self {
            Solid::Box(b) => b.support(n),
            Solid::LocalBox(b) => b.support(n),
            Solid::Triangle(t) => t.support(n),
        }
    }

    fn edge(&self, k: usize, n: &Vector3<f64>) -> [Vector3<f64>; 2] {
        match self {
            Solid::Box(b) => b.edge(k, n),
            Solid::LocalBox(b) => b.edge(k, n),
            Solid::Triangle(t) => t.edge(k, n),
        }
    }
}

/// A box's unit axes, its face normals and edge directions alike.
fn columns(axes: &Matrix3<f64>) -> [Vector3<f64>; 3] {
    [0, 1, 2].map(|j| axes.column(j).into_owned())
}

/// Which axis separates least.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    FaceOfFirst,
    FaceOfSecond,
    /// Edge `i` of the first and edge `j` of the second.
    Edges(usize, usize),
}

/// Whether both shapes are boxes or triangles (the pairs [`contact`]
/// answers).
pub(crate) fn handles(shape1: &dyn Shape, shape2: &dyn Shape) -> bool {
    is_polytope(shape1) && is_polytope(shape2)
}

/// Whether `shape` is a box or a triangle.
pub(crate) fn is_polytope(shape: &dyn Shape) -> bool {
    shape.as_cuboid().is_some() || shape.as_triangle().is_some()
}

/// Two boxes or triangles by their separating axes, the second placed by
/// `pos12` in the first's frame, with `prediction` metres as in parry's
/// contact query. `Unknown` for other shapes and for non-finite input.
pub(crate) fn contact(
    pos12: &Pose,
    shape1: &dyn Shape,
    shape2: &dyn Shape,
    prediction: f64,
) -> SatAnswer {
    contact_placed(shape1, &Placed::new(pos12, shape2), prediction)
}

/// The second shape of [`contact`] placed in the first's frame, made once
/// for the many parts of a mesh or heightfield that meet it (each part is
/// in the composite's own frame, so they all see it at the same pose).
pub(crate) struct Placed {
    iso12: Isometry3<f64>,
    /// `None`: not a box or triangle, or not finite.
    solid: Option<Solid>,
}

impl Placed {
    pub fn new(pos12: &Pose, shape2: &dyn Shape) -> Placed {
        let raw = iso_from_pose(pos12);
        let iso12 = Isometry3::from_parts(
            raw.translation,
            UnitQuaternion::new_normalize(raw.rotation.into_inner()),
        );
        let rotation12 = *iso12.rotation.to_rotation_matrix().matrix();
        let solid =
            Solid::of(shape2, &rotation12, &iso12.translation.vector).filter(|s| s.is_finite());
        Placed { iso12, solid }
    }
}

/// [`contact`] with its second shape placed already.
pub(crate) fn contact_placed(shape1: &dyn Shape, placed: &Placed, prediction: f64) -> SatAnswer {
    let (Some(s1), Some(s2)) = (Solid::local(shape1), placed.solid) else {
        return SatAnswer::Unknown;
    };
    if !s1.is_finite() {
        return SatAnswer::Unknown;
    }
    let iso12 = &placed.iso12;
    // The first shape is in its own frame (a local box or a triangle), the
    // second placed in it (a box or a triangle).
    match (s1, s2) {
        (Solid::LocalBox(a), Solid::Box(b)) => separating_axes(&a, &b, iso12, prediction),
        (Solid::LocalBox(a), Solid::Triangle(b)) => separating_axes(&a, &b, iso12, prediction),
        (Solid::Triangle(a), Solid::Box(b)) => separating_axes(&a, &b, iso12, prediction),
        (Solid::Triangle(a), Solid::Triangle(b)) => separating_axes(&a, &b, iso12, prediction),
        // Only the first shape is ever local, and it always is.
        _ => SatAnswer::Unknown,
    }
}

/// [`contact_placed`] for one pair of kinds: `s1` in its own frame, `s2`
/// placed in it by `iso12`.
fn separating_axes<A: Polytope, B: Polytope>(
    s1: &A,
    s2: &B,
    iso12: &Isometry3<f64>,
    prediction: f64,
) -> SatAnswer {
    // The largest separation so far, along which unit axis (oriented from
    // the first shape towards the second), of which kind.
    let mut best = (f64::NEG_INFINITY, Vector3::x(), Axis::FaceOfFirst);
    let consider = |best: &mut (f64, Vector3<f64>, Axis), n: Vector3<f64>, kind: Axis| {
        let ((lo1, hi1), (lo2, hi2)) = (s1.project(&n), s2.project(&n));
        let (ahead, behind) = (lo2 - hi1, lo1 - hi2);
        let sep = ahead.max(behind);
        if sep > best.0 {
            *best = (sep, if ahead >= behind { n } else { -n }, kind);
        }
    };
    // A face that separates by more than the prediction settles it at
    // once (the largest separation can only be larger): most of a mesh's
    // triangles near a box, in a contact query, end here.
    let (faces1, count1) = s1.faces();
    for n in &faces1[..count1] {
        consider(&mut best, *n, Axis::FaceOfFirst);
        if best.0 > prediction {
            return SatAnswer::Beyond;
        }
    }
    let (faces2, count2) = s2.faces();
    for n in &faces2[..count2] {
        consider(&mut best, *n, Axis::FaceOfSecond);
        if best.0 > prediction {
            return SatAnswer::Beyond;
        }
    }
    // A face that separates settles it (the edges could only separate
    // more): apart, or beyond the prediction, and in either case parry
    // needs nothing more than a direction to start from. Only overlapping
    // faces ask the edges, for the depth or for an edge that separates.
    let faces_apart = best.0 > 0.0;
    if !faces_apart {
        let (edges1, edges2) = (s1.edges(), s2.edges());
        let lengths2 = edges2.map(|e| e.norm());
        for (i, e1) in edges1.iter().enumerate() {
            let length1 = PARALLEL * e1.norm();
            for (j, e2) in edges2.iter().enumerate() {
                let n = e1.cross(e2);
                let length = n.norm();
                if length > length1 * lengths2[j] {
                    consider(&mut best, n / length, Axis::Edges(i, j));
                }
            }
        }
    }
    let (sep, n, kind) = best;
    if sep > prediction {
        return SatAnswer::Beyond;
    }
    // No number, or a depth beyond `f32` (a contact must carry it).
    if !(sep as f32).is_finite() {
        return SatAnswer::Unknown;
    }
    if sep > 0.0 {
        return SatAnswer::Apart(n, sep);
    }
    // `sep ≤ 0` is minus the depth. The witness: the deepest point of the
    // shape whose face is not the axis, and where it leaves the other
    // along the normal; for two edges, the closest points of the edges.
    let (p1, p2) = match kind {
        Axis::FaceOfFirst => {
            let p2 = s2.support(&-n);
            (p2 - n * sep, p2)
        }
        Axis::FaceOfSecond => {
            let p1 = s1.support(&n);
            (p1, p1 + n * sep)
        }
        Axis::Edges(i, j) => segment_segment(&s1.edge(i, &n), &s2.edge(j, &-n)),
    };
    // The second shape's point and normal back in its own frame.
    let inverse = iso12.inverse();
    let p2_local = inverse * Point3::from(p2);
    let n2_local = inverse.rotation * -n;
    SatAnswer::Overlap(Contact::new(
        glam_from_vec(&p1),
        glam_from_vec(&p2_local.coords),
        glam_from_vec(&n),
        glam_from_vec(&n2_local),
        sep as f32,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::math::{Rotation, Vector};
    use rapier3d::parry::query::QueryDispatcher;
    use rapier3d::parry::shape::{Cuboid, Triangle};

    fn cuboid(x: f32, y: f32, z: f32) -> Cuboid {
        Cuboid::new(Vector::new(x, y, z))
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
        fn vector(&mut self, spread: f32) -> Vector {
            Vector::new(
                self.range(-spread, spread),
                self.range(-spread, spread),
                self.range(-spread, spread),
            )
        }
        fn pose(&mut self, spread: f32) -> Pose {
            let axis = self.vector(1.0).normalize_or(Vector::Z);
            Pose::from_parts(
                self.vector(spread),
                Rotation::from_axis_angle(axis, self.range(-3.0, 3.0)),
            )
        }
        fn cuboid(&mut self, size: f32) -> Cuboid {
            cuboid(
                self.range(0.05, size),
                self.range(0.05, size),
                self.range(0.05, size),
            )
        }
        fn triangle(&mut self, size: f32) -> Triangle {
            Triangle::new(self.vector(size), self.vector(size), self.vector(size))
        }
    }

    /// The least overlap of two shapes over a dense grid of directions: an
    /// upper bound of the depth within the grid's resolution.
    fn least_overlap(s1: &Solid, s2: &Solid) -> f64 {
        let m = 200;
        let mut least = f64::INFINITY;
        for a in 0..m {
            for b in 0..2 * m {
                let th = std::f64::consts::PI * (a as f64 + 0.5) / m as f64;
                let ph = std::f64::consts::PI * b as f64 / m as f64;
                let n = Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                let ((lo1, hi1), (lo2, hi2)) = (s1.project(&n), s2.project(&n));
                least = least.min((hi1 - lo2).min(hi2 - lo1));
            }
        }
        least
    }

    /// Random pairs against parry's GJK/EPA: apart where parry says apart;
    /// where they overlap, never deeper than the overlap along parry's
    /// normal, parry's depth on most pairs (where EPA stops early, a dense
    /// grid of directions' least overlap), and the witness points on the
    /// shapes. Returns (overlaps, beyond, off parry's depth).
    fn agree_with_parry(
        cases: usize,
        seed: u64,
        make: impl Fn(&mut Lcg) -> (Box<dyn Shape>, Box<dyn Shape>),
    ) -> (usize, usize, usize) {
        let mut rng = Lcg(seed);
        let (mut overlaps, mut beyond, mut disagree) = (0, 0, 0);
        for case in 0..cases {
            let (shape1, shape2) = make(&mut rng);
            let (p1, p2) = (rng.pose(1.0), rng.pose(1.0));
            let pos12 = p1.inv_mul(&p2);
            let prediction = 0.1;
            let parry = rapier3d::parry::query::DefaultQueryDispatcher
                .contact(&pos12, shape1.as_ref(), shape2.as_ref(), prediction as f32)
                .expect("parry answers these pairs");
            match contact(&pos12, shape1.as_ref(), shape2.as_ref(), prediction) {
                SatAnswer::Beyond => {
                    beyond += 1;
                    assert!(parry.is_none(), "case {case}: parry sees {parry:?}");
                }
                SatAnswer::Unknown => panic!("case {case}: no answer"),
                SatAnswer::Apart(..) => {
                    // Apart by at least the largest separation: parry's
                    // distance may still be beyond the prediction.
                    if let Some(c) = parry {
                        assert!(c.dist > -1.0e-4, "case {case}: parry depth {}", c.dist);
                    }
                }
                SatAnswer::Overlap(ours) => {
                    overlaps += 1;
                    let c = parry.expect("parry sees the overlap");
                    let iso12 = iso_from_pose(&pos12);
                    let r12 = *iso12.rotation.to_rotation_matrix().matrix();
                    let s1 = Solid::of(shape1.as_ref(), &Matrix3::identity(), &Vector3::zeros())
                        .unwrap();
                    let s2 = Solid::of(shape2.as_ref(), &r12, &iso12.translation.vector).unwrap();
                    let overlap = |n: &Vector3<f64>| {
                        let ((lo1, hi1), (lo2, hi2)) = (s1.project(n), s2.project(n));
                        (hi1 - lo2).min(hi2 - lo1)
                    };
                    let depth = -ours.dist as f64;
                    let along_parry = overlap(&vec_from_glam(c.normal1));
                    assert!(
                        depth <= along_parry + 1.0e-5,
                        "case {case}: depth {depth} beyond the overlap along parry's normal {along_parry}"
                    );
                    if (ours.dist - c.dist).abs() > 1.0e-4 * (1.0 + c.dist.abs()) {
                        disagree += 1;
                        let least = least_overlap(&s1, &s2);
                        assert!(
                            depth <= least + 1.0e-6 && least - depth < 5.0e-3,
                            "case {case}: depth {depth}, grid {least}, parry {}",
                            -c.dist
                        );
                        continue;
                    }
                    let on = |shape: &dyn Shape, p: Vector| {
                        let proj = shape.project_local_point(p, false);
                        (proj.point - p).length()
                    };
                    let (off1, off2) = (
                        on(shape1.as_ref(), ours.point1),
                        on(shape2.as_ref(), ours.point2),
                    );
                    assert!(
                        off1 < 1.0e-4 && off2 < 1.0e-4,
                        "case {case}: witnesses {off1} and {off2} m off their shapes"
                    );
                    // The normals are opposite in the world.
                    let n2 = pos12.rotation * ours.normal2;
                    assert!((n2 + ours.normal1).length() < 1.0e-5, "case {case}");
                }
            }
        }
        (overlaps, beyond, disagree)
    }

    /// The first shape in its own frame answers as the same shape placed
    /// at the origin with no turn, bit for bit: a box's projections,
    /// supports and edges along directions with zero coordinates of
    /// either sign among them, and a triangle's corners with zero
    /// coordinates of either sign.
    #[test]
    fn local_solids_are_the_placed_ones() {
        let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
        let mut rng = Lcg(5);
        let (origin, identity) = (Vector3::zeros(), Matrix3::identity());
        let zero = |x: f64, k: f32| {
            if k < 0.2 {
                0.0
            } else if k < 0.4 {
                -0.0
            } else {
                x
            }
        };
        for case in 0..2000 {
            let half = rng.vector(1.0).abs() + Vector::splat(0.01);
            let cube = Cuboid::new(half);
            let (local, placed) = (
                Solid::local(&cube).unwrap(),
                Solid::of(&cube, &identity, &origin).unwrap(),
            );
            let raw = vec_from_glam(rng.vector(1.0));
            let n = Vector3::new(
                zero(raw.x, rng.next()),
                zero(raw.y, rng.next()),
                zero(raw.z, rng.next()),
            );
            let (a, b) = (local.project(&n), placed.project(&n));
            assert_eq!(
                (a.0.to_bits(), a.1.to_bits()),
                (b.0.to_bits(), b.1.to_bits())
            );
            assert_eq!(
                bits(&local.support(&n)),
                bits(&placed.support(&n)),
                "case {case}"
            );
            for k in 0..3 {
                let (a, b) = (local.edge(k, &n), placed.edge(k, &n));
                assert_eq!([bits(&a[0]), bits(&a[1])], [bits(&b[0]), bits(&b[1])]);
            }
            let corner = |rng: &mut Lcg| {
                let v = rng.vector(2.0);
                Vector::new(
                    zero(v.x as f64, rng.next()) as f32,
                    zero(v.y as f64, rng.next()) as f32,
                    zero(v.z as f64, rng.next()) as f32,
                )
            };
            let triangle = Triangle::new(corner(&mut rng), corner(&mut rng), corner(&mut rng));
            let (Solid::Triangle(a), Solid::Triangle(b)) = (
                Solid::local(&triangle).unwrap(),
                Solid::of(&triangle, &identity, &origin).unwrap(),
            ) else {
                panic!("case {case}: not triangles");
            };
            assert_eq!(a.0.map(|v| bits(&v)), b.0.map(|v| bits(&v)), "case {case}");
        }
    }

    #[test]
    fn box_pairs_agree_with_parrys_contact() {
        let (overlaps, beyond, disagree) = agree_with_parry(4000, 7, |rng| {
            (Box::new(rng.cuboid(2.0)), Box::new(rng.cuboid(1.0)))
        });
        println!("boxes: {overlaps} overlaps ({disagree} off parry's depth), {beyond} beyond");
        assert!(overlaps > 500 && beyond > 500 && disagree * 20 < overlaps);
    }

    #[test]
    fn box_triangle_pairs_agree_with_parrys_contact() {
        let (overlaps, beyond, disagree) = agree_with_parry(4000, 11, |rng| {
            let (b, t) = (rng.cuboid(1.0), rng.triangle(1.5));
            if rng.next() < 0.5 {
                (Box::new(b), Box::new(t))
            } else {
                (Box::new(t), Box::new(b))
            }
        });
        println!(
            "box-triangle: {overlaps} overlaps ({disagree} off parry's depth), {beyond} beyond"
        );
        assert!(overlaps > 500 && beyond > 500 && disagree * 20 < overlaps);
    }

    #[test]
    fn triangle_pairs_agree_with_parrys_contact() {
        let (overlaps, beyond, disagree) = agree_with_parry(4000, 13, |rng| {
            (Box::new(rng.triangle(1.0)), Box::new(rng.triangle(1.0)))
        });
        println!("triangles: {overlaps} overlaps ({disagree} off parry's depth), {beyond} beyond");
        assert!(overlaps > 200 && beyond > 500 && disagree * 20 < overlaps);
    }

    /// A box resting 2 mm deep on a floor: the floor's normal, 2 mm deep,
    /// the witness under the box's bottom face centre.
    #[test]
    fn a_box_sunk_into_a_floor() {
        let floor = cuboid(20.0, 0.5, 20.0);
        let cube = cuboid(0.2, 0.2, 0.2);
        let pos12 = Pose::from_translation(Vector::new(3.0, 0.698, 1.0));
        let SatAnswer::Overlap(c) = contact(&pos12, &floor, &cube, 0.01) else {
            panic!("the cube is in the floor");
        };
        assert!((c.dist + 0.002).abs() < 1.0e-6, "depth {}", c.dist);
        assert!((c.normal1 - Vector::Y).length() < 1.0e-6, "{:?}", c.normal1);
        assert!((c.normal2 + Vector::Y).length() < 1.0e-6, "{:?}", c.normal2);
        // In the floor's frame, and in the cube's.
        assert!(
            (c.point1 - Vector::new(3.0, 0.5, 1.0)).length() < 1.0e-5,
            "{:?}",
            c.point1
        );
        assert!(
            (c.point2 - Vector::new(0.0, -0.2, 0.0)).length() < 1.0e-5,
            "{:?}",
            c.point2
        );
    }

    /// Degenerate boxes and triangles (no size, no area, a point) and far
    /// or huge poses give an answer, never a panic, and an overlap only
    /// with a finite depth.
    #[test]
    fn degenerate_shapes_are_answered() {
        let p = Vector::new(0.1, 0.0, 0.0);
        let shapes: Vec<Box<dyn Shape>> = vec![
            Box::new(cuboid(0.0, 0.0, 0.0)),
            Box::new(cuboid(1.0, 0.0, 1.0)),
            Box::new(Triangle::new(p, p, p)),
            Box::new(Triangle::new(Vector::ZERO, p, p * 2.0)),
            Box::new(Triangle::new(Vector::ZERO, Vector::X, Vector::Z)),
            Box::new(cuboid(1.0e20, 1.0, 1.0)),
        ];
        let poses = [
            Pose::IDENTITY,
            Pose::from_translation(Vector::new(0.05, 0.0, 0.0)),
            Pose::from_parts(Vector::new(3.0e7, 0.0, 0.0), Rotation::from_rotation_y(0.3)),
            Pose::from_translation(Vector::splat(f32::MAX)),
        ];
        for (i, a) in shapes.iter().enumerate() {
            for (j, b) in shapes.iter().enumerate() {
                for (k, pose) in poses.iter().enumerate() {
                    if let SatAnswer::Overlap(c) = contact(pose, a.as_ref(), b.as_ref(), 0.1) {
                        assert!(c.dist.is_finite(), "shapes {i}, {j}, pose {k}: {c:?}");
                    }
                }
            }
        }
    }

    /// Shapes it does not know, and non-finite poses, go to parry.
    #[test]
    fn other_shapes_and_bad_poses_go_to_parry() {
        let ball = rapier3d::parry::shape::Ball::new(0.5);
        let cube = cuboid(0.2, 0.2, 0.2);
        let here = Pose::from_translation(Vector::new(0.1, 0.0, 0.0));
        assert!(matches!(
            contact(&here, &ball, &cube, 0.1),
            SatAnswer::Unknown
        ));
        let nowhere = Pose::from_translation(Vector::new(f32::NAN, 0.0, 0.0));
        assert!(matches!(
            contact(&nowhere, &cube, &cube, 0.1),
            SatAnswer::Unknown
        ));
        assert!(handles(&cube, &cube) && !handles(&ball, &cube));
    }
}
