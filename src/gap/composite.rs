//! Composite shapes: TriMesh, HeightField, Polyline and Compound, on either
//! side of a pair (a shape against a mesh, a moving mesh against anything).
//!
//! A composite pair stands for every pair of their pieces. Its one gap is a
//! *bounding* gap: the box of one side, carried into the other side's frame
//! by the enclosed relative pose (so it sweeps with the node), against the
//! other side's box; six axes, `lo_i − hi'_i − skin` and `lo'_i − hi_i −
//! skin` per coordinate `i`, any of which `> 0` proves the pieces apart.
//! When the pair survives a node, the query's gap set (`GapSet::expand`)
//! splits one side (the larger that can be split) into its children:
//! - TriMesh, Polyline, Compound: the two children of a node of parry's BVH
//!   ([`Bvh::traverse_indexed`] gives them lazily); a leaf is a triangle, a
//!   segment, or a compound's part in its own frame;
//! - HeightField (which has no BVH): an implicit binary tree over its grid
//!   of cells, each node's box from the heights it covers, computed in
//!   `f32` exactly as parry builds the triangles; a single cell splits into
//!   its two triangles.
//!
//! Only children whose box meets the swept box of the other side on the
//! node join. Pieces that cannot be split meet through [`super::build`],
//! the same families as whole shapes (ball–triangle, triangle–triangle, …).
//!
//! ## Boxes and rounding
//!
//! parry's boxes are `f32` and, for compound parts, computed with `f32`
//! rotations. Every box is therefore grown by [`GROWTH`] of its largest
//! coordinate before use, far more than the few `f32` ulps parry's
//! rounding can take; a box that is too large costs only tightness.

use super::CcdError;
use crate::convert::iso_from_pose;
use crate::enclosure::rounding::{down, up};
use crate::enclosure::{Enclosure, Interval};
use crate::motion::Pose;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::parry::partitioning::{Bvh, BvhNode, BvhNodeIndex, TraversalAction};
use rapier3d::parry::shape::{
    Compound, HeightField, Polyline, Segment, Shape, ShapeType, TriMesh, Triangle, TypedShape,
};

/// Boxes from parry are grown by this share of their largest coordinate
/// (2⁻¹⁸ ≈ 32 ulps of `f32`).
pub(crate) const GROWTH: f64 = 1.0 / 262_144.0;

/// The number of axes of a composite pair.
pub(crate) const AXES: usize = 6;

/// An axis-aligned box in one frame, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub lo: Vector3<f64>,
    pub hi: Vector3<f64>,
}

impl Bounds {
    /// Nothing: a box every test finds apart.
    fn empty() -> Bounds {
        Bounds {
            lo: Vector3::repeat(f64::INFINITY),
            hi: Vector3::repeat(f64::NEG_INFINITY),
        }
    }

    /// The box of some `f32` points, grown.
    fn of_points(points: &[Vector3<f64>]) -> Bounds {
        let mut b = Bounds::empty();
        for p in points {
            b.lo = b.lo.inf(p);
            b.hi = b.hi.sup(p);
        }
        b.grown()
    }

    /// A parry box, grown.
    fn of_aabb(aabb: &Aabb) -> Bounds {
        Bounds::of_points(&[
            crate::convert::vec_from_glam(aabb.mins),
            crate::convert::vec_from_glam(aabb.maxs),
        ])
    }

    /// True when the box holds no point (or is not finite).
    pub fn is_empty(&self) -> bool {
        (0..3)
            .any(|i| !self.lo[i].is_finite() || !self.hi[i].is_finite() || self.lo[i] > self.hi[i])
    }

    /// The box grown by [`GROWTH`] of its largest coordinate.
    fn grown(self) -> Bounds {
        if self.is_empty() {
            return Bounds::empty();
        }
        let big = self.lo.abs().max().max(self.hi.abs().max());
        let m = up(big * GROWTH) + f64::MIN_POSITIVE;
        Bounds {
            lo: self.lo.map(|x| down(x - m)),
            hi: self.hi.map(|x| up(x + m)),
        }
    }

    /// A centre and half-extents whose box holds this one.
    fn centre_half(&self) -> (Vector3<f64>, Vector3<f64>) {
        let c = self.lo + (self.hi - self.lo) * 0.5;
        let h = Vector3::from_fn(|i, _| up(self.hi[i] - c[i]).max(up(c[i] - self.lo[i])));
        (c, h)
    }

    /// The length of the diagonal (to choose which side to split).
    fn diagonal(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            (self.hi - self.lo).norm()
        }
    }

    /// True when this box, grown by `skin`, meets the interval box `other`.
    pub(crate) fn meets(&self, other: &[Interval; 3], skin: f64) -> bool {
        !self.is_empty()
            && (0..3).all(|i| {
                other[i].lo <= up(self.hi[i] + skin) && down(self.lo[i] - skin) <= other[i].hi
            })
    }
}

/// A composite shape with a BVH.
#[derive(Clone, Copy)]
pub(crate) enum Tree<'s> {
    Mesh(&'s TriMesh),
    Line(&'s Polyline),
    Parts(&'s Compound),
}

impl<'s> Tree<'s> {
    fn bvh(&self) -> &'s Bvh {
        match self {
            Tree::Mesh(m) => m.bvh(),
            Tree::Line(l) => l.bvh(),
            Tree::Parts(c) => c.bvh(),
        }
    }
}

/// What one side of a pair stands for.
#[derive(Clone, Copy)]
pub(crate) enum Region<'s> {
    /// A whole shape: convex, or a composite's root.
    Shape(&'s dyn Shape),
    /// A node of a composite's BVH.
    Node(Tree<'s>, BvhNodeIndex),
    /// The heightfield cells of rows `rows.0..rows.1`, columns `cols.0..cols.1`.
    Cells {
        field: &'s HeightField,
        rows: (usize, usize),
        cols: (usize, usize),
    },
    /// One triangle of a mesh or heightfield (parry's `f32` corners).
    Triangle(Triangle),
    /// One segment of a polyline.
    Segment(Segment),
}

impl<'s> Region<'s> {
    /// True when the part splits into children.
    pub fn is_composite(&self) -> bool {
        match self {
            Region::Shape(s) => is_composite(*s),
            Region::Node(..) | Region::Cells { .. } => true,
            Region::Triangle(_) | Region::Segment(_) => false,
        }
    }

    /// The part as a shape, when it is one piece.
    pub fn shape(&self) -> Option<&dyn Shape> {
        match self {
            Region::Shape(s) if !is_composite(*s) => Some(*s),
            Region::Triangle(t) => Some(t),
            Region::Segment(s) => Some(s),
            _ => None,
        }
    }
}

/// One side of a pair: a part in a frame, with its box in that frame.
#[derive(Clone, Copy)]
pub(crate) struct PairSide<'s> {
    pub part: Region<'s>,
    pub frame: u32,
    pub bounds: Bounds,
}

impl<'s> PairSide<'s> {
    /// A whole shape in `frame`.
    pub fn whole(shape: &'s dyn Shape, frame: u32) -> PairSide<'s> {
        let bounds = match shape.as_typed_shape() {
            // The heightfield's own box (parry's `local_aabb` agrees).
            TypedShape::HeightField(hf) => cells_bounds(hf, (0, hf.nrows()), (0, hf.ncols())),
            _ => Bounds::of_aabb(&shape.compute_local_aabb()),
        };
        PairSide {
            part: Region::Shape(shape),
            frame,
            bounds,
        }
    }
}

/// A child of a split part: what it is, its box in the parent's frame, and
/// for a compound's part its index and pose in the parent's frame.
#[derive(Clone, Copy)]
pub(crate) struct SubRegion<'s> {
    pub part: Region<'s>,
    pub bounds: Bounds,
    pub local: Option<(u32, Isometry3<f64>)>,
}

/// True for the shapes this module splits.
pub(crate) fn is_composite(shape: &dyn Shape) -> bool {
    matches!(
        shape.shape_type(),
        ShapeType::TriMesh | ShapeType::Polyline | ShapeType::HeightField | ShapeType::Compound
    )
}

/// The children of `part` (at most two) into `out`.
pub(crate) fn children<'s>(part: &Region<'s>, out: &mut Vec<SubRegion<'s>>) {
    match *part {
        Region::Shape(shape) => match shape.as_typed_shape() {
            TypedShape::TriMesh(m) => tree_children(Tree::Mesh(m), None, out),
            TypedShape::Polyline(l) => tree_children(Tree::Line(l), None, out),
            TypedShape::Compound(c) => tree_children(Tree::Parts(c), None, out),
            TypedShape::HeightField(hf) => cell_children(hf, (0, hf.nrows()), (0, hf.ncols()), out),
            _ => {}
        },
        Region::Node(tree, node) => tree_children(tree, Some(node), out),
        Region::Cells { field, rows, cols } => cell_children(field, rows, cols, out),
        Region::Triangle(_) | Region::Segment(_) => {}
    }
}

/// The children of a BVH node (`None`: the root).
fn tree_children<'s>(tree: Tree<'s>, node: Option<BvhNodeIndex>, out: &mut Vec<SubRegion<'s>>) {
    let mut at_subtree_root = node.is_some();
    tree.bvh()
        .traverse_indexed(node, |n: &BvhNode, id: BvhNodeIndex| {
            if at_subtree_root {
                at_subtree_root = false;
                return TraversalAction::Continue;
            }
            out.push(tree_child(tree, n, id));
            TraversalAction::Prune
        });
}

fn tree_child<'s>(tree: Tree<'s>, n: &BvhNode, id: BvhNodeIndex) -> SubRegion<'s> {
    let bounds = Bounds::of_aabb(&n.aabb());
    let Some(leaf) = n.leaf_data() else {
        return SubRegion {
            part: Region::Node(tree, id),
            bounds,
            local: None,
        };
    };
    match tree {
        Tree::Mesh(m) => SubRegion {
            part: Region::Triangle(m.triangle(leaf)),
            bounds,
            local: None,
        },
        Tree::Line(l) => SubRegion {
            part: Region::Segment(l.segment(leaf)),
            bounds,
            local: None,
        },
        Tree::Parts(c) => {
            let (pose, shape) = &c.shapes()[leaf as usize];
            let iso = iso_from_pose(pose);
            let iso = Isometry3::from_parts(
                iso.translation,
                UnitQuaternion::new_normalize(iso.rotation.into_inner()),
            );
            SubRegion {
                part: Region::Shape(shape.as_ref()),
                bounds,
                local: Some((leaf, iso)),
            }
        }
    }
}

/// The x (column `j`) or z (row `i`) coordinate of a grid line, in `f32`
/// exactly as parry's `HeightField::triangles_at` computes it.
fn grid_line(unit: f32, index: usize, scale: f32) -> f64 {
    f64::from((-0.5 + unit * (index as f32)) * scale)
}

/// The box of heightfield cells `rows × cols` (half-open), grown.
fn cells_bounds(hf: &HeightField, rows: (usize, usize), cols: (usize, usize)) -> Bounds {
    if rows.0 >= rows.1 || cols.0 >= cols.1 {
        return Bounds::empty();
    }
    let scale = hf.scale();
    let heights = hf.heights();
    let (mut y_lo, mut y_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in rows.0..=rows.1 {
        for j in cols.0..=cols.1 {
            let y = f64::from(heights[(i, j)] * scale.y);
            y_lo = y_lo.min(y);
            y_hi = y_hi.max(y);
        }
    }
    let (cw, ch) = (hf.unit_cell_width(), hf.unit_cell_height());
    let x = [
        grid_line(cw, cols.0, scale.x),
        grid_line(cw, cols.1, scale.x),
    ];
    let z = [
        grid_line(ch, rows.0, scale.z),
        grid_line(ch, rows.1, scale.z),
    ];
    Bounds::of_points(&[
        Vector3::new(x[0], y_lo, z[0]),
        Vector3::new(x[1], y_hi, z[1]),
    ])
}

fn cell_children<'s>(
    hf: &'s HeightField,
    rows: (usize, usize),
    cols: (usize, usize),
    out: &mut Vec<SubRegion<'s>>,
) {
    let (nr, nc) = (rows.1.saturating_sub(rows.0), cols.1.saturating_sub(cols.0));
    if nr == 0 || nc == 0 {
        return;
    }
    if nr == 1 && nc == 1 {
        let (left, right) = hf.triangles_at(rows.0, cols.0);
        for t in [left, right].into_iter().flatten() {
            let corners = [t.a, t.b, t.c].map(crate::convert::vec_from_glam);
            out.push(SubRegion {
                part: Region::Triangle(t),
                bounds: Bounds::of_points(&corners),
                local: None,
            });
        }
        return;
    }
    let halves = if nr >= nc {
        let m = rows.0 + nr / 2;
        [((rows.0, m), cols), ((m, rows.1), cols)]
    } else {
        let m = cols.0 + nc / 2;
        [(rows, (cols.0, m)), (rows, (m, cols.1))]
    };
    for (rows, cols) in halves {
        out.push(SubRegion {
            part: Region::Cells {
                field: hf,
                rows,
                cols,
            },
            bounds: cells_bounds(hf, rows, cols),
            local: None,
        });
    }
}

/// Which side of a composite pair to split: `true` for `b`.
pub(crate) fn split_b(a: &PairSide, b: &PairSide) -> bool {
    match (a.part.is_composite(), b.part.is_composite()) {
        (true, false) => false,
        (false, true) => true,
        _ => b.bounds.diagonal() >= a.bounds.diagonal(),
    }
}

/// A box carried into another frame: its low and high ends along each
/// of that frame's axes, enclosed over the node (`None`: an empty box).
pub(crate) type Carried<E> = Option<[[E; 3]; 2]>;

/// The box `small` (in its own frame) carried into another frame by `rel`.
/// The same for every part of the other side met on a node (a hull's box
/// against each box of a mesh's tree): the search keeps it for the node.
pub(crate) fn carried<E: Enclosure>(rel: &Pose<E>, small: &Bounds) -> Carried<E> {
    if small.is_empty() {
        return None;
    }
    let (c, h) = small.centre_half();
    let centre = rel.transform_point(&c);
    let half = Vector3::from_fn(|i, _| {
        rel.rotation[(i, 0)].abs() * h.x
            + rel.rotation[(i, 1)].abs() * h.y
            + rel.rotation[(i, 2)].abs() * h.z
    });
    Some([
        std::array::from_fn(|i| centre[i] - half[i]),
        std::array::from_fn(|i| centre[i] + half[i]),
    ])
}

/// The six bounding axes of a carried box against `big`.
pub(crate) fn bounding_axes<E: Enclosure>(
    small: &Carried<E>,
    big: &Bounds,
    skin: f64,
    out: &mut [E],
) {
    let Some([low, high]) = small.filter(|_| !big.is_empty()) else {
        // Nothing to touch: every axis far positive.
        out[..AXES].fill(E::constant(f64::MAX));
        return;
    };
    for i in 0..3 {
        out[i] = -high[i] + big.lo[i] - skin;
        out[3 + i] = low[i] - big.hi[i] - skin;
    }
}

/// The swept box of `small` carried by `rel`, as intervals over the node.
pub(crate) fn swept<E: Enclosure>(rel: &Pose<E>, small: &Bounds) -> [Interval; 3] {
    if small.is_empty() {
        return [Interval::new(f64::INFINITY, f64::INFINITY); 3];
    }
    // Only the box's range is wanted: its half-extents bounded from the
    // rotation's ranges, `Σⱼ max|R_ij|·h_j` (a few plain products, where
    // `carried`'s enclosed absolute values cost an affine operation each).
    let (c, h) = small.centre_half();
    let centre = rel.transform_point(&c);
    // The box turned any way stays within its circumscribed sphere: a
    // spinning box's bound `Σⱼ max|R_ij|·h_j` (up to √3 times that
    // sphere's radius over a wide node) is capped by it.
    let sphere = up(h.norm() * (1.0 + 4.0 * f64::EPSILON));
    std::array::from_fn(|i| {
        let reach = (0..3)
            .map(|j| up(rel.rotation[(i, j)].range().mag() * h[j]))
            .fold(0.0, |sum, x| up(sum + x))
            .min(sphere);
        let range = centre[i].range();
        Interval::new(down(range.lo - reach), up(range.hi + reach))
    })
}

/// True when the child's box meets the swept box.
pub(crate) fn child_meets(child: &SubRegion, sweep: &[Interval; 3], skin: f64) -> bool {
    child.bounds.meets(sweep, skin)
}

/// Representative pieces of a shape: the kinds of leaf a split reaches,
/// one of each type (a compound's parts recursively, a mesh's first
/// triangle, …), for checking up front that every leaf pair has a family.
fn leaf_kinds<'s>(shape: &'s dyn Shape, out: &mut Vec<LeafSample<'s>>) {
    let mut push = |p: LeafSample<'s>| {
        if !out
            .iter()
            .any(|q| q.shape().shape_type() == p.shape().shape_type())
        {
            out.push(p);
        }
    };
    match shape.as_typed_shape() {
        TypedShape::TriMesh(m) => {
            if m.num_triangles() > 0 {
                push(LeafSample::Triangle(m.triangle(0)));
            }
        }
        TypedShape::HeightField(hf) => {
            if let Some(t) = hf.triangles().next() {
                push(LeafSample::Triangle(t));
            }
        }
        TypedShape::Polyline(l) => {
            if l.num_segments() > 0 {
                push(LeafSample::Segment(l.segment(0)));
            }
        }
        TypedShape::Compound(c) => {
            for (_, part) in c.shapes() {
                let mut inner = Vec::new();
                leaf_kinds(part.as_ref(), &mut inner);
                for p in inner {
                    push(p);
                }
            }
        }
        _ => push(LeafSample::Shape(shape)),
    }
}

/// A leaf piece, owned or borrowed.
enum LeafSample<'s> {
    Shape(&'s dyn Shape),
    Triangle(Triangle),
    Segment(Segment),
}

impl LeafSample<'_> {
    fn shape(&self) -> &dyn Shape {
        match self {
            LeafSample::Shape(s) => *s,
            LeafSample::Triangle(t) => t,
            LeafSample::Segment(s) => s,
        }
    }
}

/// `Ok` when every kind of leaf pair that splitting `shape1` against
/// `shape2` can reach has a gap family; the `Unsupported` error of the
/// first that has none otherwise.
pub(crate) fn check_leaves(
    shape1: &dyn Shape,
    shape2: &dyn Shape,
    skin: f64,
) -> Result<(), CcdError> {
    let (mut k1, mut k2) = (Vec::new(), Vec::new());
    leaf_kinds(shape1, &mut k1);
    leaf_kinds(shape2, &mut k2);
    for p in &k1 {
        for q in &k2 {
            super::build(p.shape(), q.shape(), skin)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosure::{Affine, TimeSpan};
    use crate::motion::{Motion, Trajectory};
    use nalgebra::{Point3, Translation3};
    use proptest::prelude::*;

    proptest! {
        /// The swept box holds the small side's box at every sampled time
        /// of the node, however fast the small side spins relative to the
        /// other (the circumscribed sphere caps its turned box).
        #[test]
        fn the_swept_box_holds_the_turning_box(
            half in prop::array::uniform3(0.01f64..2.0),
            offset in prop::array::uniform3(-1.0f64..1.0),
            spin in prop::array::uniform3(-600.0f64..600.0),
            other_spin in prop::array::uniform3(-50.0f64..50.0),
            linvel in prop::array::uniform3(-30.0f64..30.0),
            node in (0.0f64..1.0, 0.0f64..1.0),
        ) {
            let dt = 1.0 / 60.0;
            let small = Bounds::of_points(&[
                Vector3::from(offset) - Vector3::from(half),
                Vector3::from(offset) + Vector3::from(half),
            ]);
            let start = Isometry3::from_parts(
                Translation3::new(0.3, -0.2, 0.5),
                UnitQuaternion::from_scaled_axis(Vector3::new(0.4, 1.0, -0.7)),
            );
            let m_small = Motion::from_velocities(start, Point3::new(0.1, 0.0, 0.2), Vector3::from(linvel), Vector3::from(spin), dt).unwrap();
            let m_big = Motion::from_velocities(Isometry3::identity(), Point3::origin(), Vector3::zeros(), Vector3::from(other_spin), dt).unwrap();
            let span = TimeSpan::new(node.0.min(node.1), node.0.max(node.1));
            let (pb, ps) = (m_big.pose::<Affine>(span), m_small.pose::<Affine>(span));
            let rel = pb.relative(&ps);
            let sweep = swept(&rel, &small);
            for k in 0..=32 {
                let tau = span.lo + (span.hi - span.lo) * k as f64 / 32.0;
                let rel_at = m_big.pose_at(tau).inv_mul(&m_small.pose_at(tau));
                for corner in 0..8 {
                    let p = Vector3::from_fn(|i, _| if corner >> i & 1 == 1 { small.hi[i] } else { small.lo[i] });
                    let q = rel_at * Point3::from(p);
                    for i in 0..3 {
                        let slack = 1.0e-9 * (1.0 + q[i].abs());
                        prop_assert!(sweep[i].lo - slack <= q[i] && q[i] <= sweep[i].hi + slack,
                            "tau {tau} axis {i}: {} outside [{}, {}]", q[i], sweep[i].lo, sweep[i].hi);
                    }
                }
            }
        }
    }
}
