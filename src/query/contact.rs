//! parry's contact query, asked the one way that is right, and the
//! [`Toi`] built from it: the witness points and normal at the reported
//! time.

use super::Toi;
use super::sat::{self, SatAnswer};
use crate::convert::{
    glam_from_vec, iso_from_pose, point_from_glam, pose_from_iso, pose64_from_iso, vec_from_glam,
};
use crate::gap;
use crate::motion::{Motion, Trajectory};
use crate::solve::{RootStatus, SolveOutcome, SolveStats};
use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::math::Vector as Vec64;
use parry3d_f64::query::gjk::{
    self as gjk64, CsoPoint as Cso64, GJKResult as Gjk64Result, VoronoiSimplex as Simplex64,
};
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::parry::math::{Pose, Real, Vector};
use rapier3d::parry::partitioning::BvhNode;
use rapier3d::parry::query::details::{self, ShapeCastOptions};
use rapier3d::parry::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use rapier3d::parry::query::{
    ClosestPoints, Contact, DefaultQueryDispatcher, NonlinearRigidMotion, QueryDispatcher,
    ShapeCastHit, ShapeDistance, ShapeIntersection, Unsupported,
};
use rapier3d::parry::shape::{
    CompositeShape, HeightField, Shape, ShapeType, SupportMap, TypedShape,
};

/// parry's contact between two posed shapes within `prediction` metres
/// (`Ok(None)`: farther apart; `Err`: parry has no answer for the pair).
///
/// parry 0.31.1 answers a convex shape against a *second* half-space
/// wrongly (it uses the relative pose where it needs its inverse, so the
/// depth grows with the distance from the plane's origin): the half-space
/// is asked first and the answer flipped back. Boxes and triangles that
/// overlap, alone or as parts of meshes, heightfields and compounds, are
/// answered by their separating axes instead of EPA ([`AxesFirst`]); a
/// capsule or rounded box against a polytope by their cores, as rapier's
/// contacts measure it ([`rounded_contact`]).
pub(crate) fn contact(
    pose1: &Pose,
    shape1: &dyn Shape,
    pose2: &Pose,
    shape2: &dyn Shape,
    prediction: f32,
) -> Result<Option<Contact>, Unsupported> {
    contact_settled(pose1, shape1, pose2, shape2, prediction, None)
}

/// What a caller asks of a contact that needs only to tell whether the
/// pair is deeper than `allowed` metres (`≥ 0`), within `band` metres, or
/// farther apart (a touching pair's sample, `rapier::touching`): once a
/// part of a composite shape is found within `band`, the other parts are
/// asked only whether they are deeper than `allowed`, and the first part
/// that is ends the walk.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Settle {
    pub band: f64,
    pub allowed: f64,
}

impl Settle {
    /// The least prediction, in `f32`, at or above minus `allowed`: a box
    /// or triangle part whose separating axes show it beyond that is not
    /// deeper than allowed (its `f32` distance rounds to no less).
    fn deeper_than_allowed(&self) -> Real {
        let reach = (-self.allowed) as Real;
        if f64::from(reach) < -self.allowed {
            reach.next_up()
        } else {
            reach
        }
    }
}

/// [`contact`], whose `dist` answers a [`Settle`] caller's questions as
/// `contact`'s would: deeper than `allowed` exactly when `contact`'s is
/// (then the distance of some part that is), within `band` exactly when
/// `contact`'s is (then of some part within it, not deeper than allowed,
/// and its other fields that part's), and otherwise `contact`'s answer
/// itself. `None` asks for `contact`'s answer.
pub(crate) fn contact_settled(
    pose1: &Pose,
    shape1: &dyn Shape,
    pose2: &Pose,
    shape2: &dyn Shape,
    prediction: f32,
    settle: Option<Settle>,
) -> Result<Option<Contact>, Unsupported> {
    let flip = shape2.as_halfspace().is_some() && shape1.as_halfspace().is_none();
    let (p1, s1, p2, s2) = if flip {
        (pose2, shape2, pose1, shape1)
    } else {
        (pose1, shape1, pose2, shape2)
    };
    let found = AxesFirst.contact_settled(&p1.inv_mul(p2), s1, s2, prediction, settle)?;
    Ok(found.map(|mut c| {
        c.transform_by_mut(p1, p2);
        if flip { c.flipped() } else { c }
    }))
}

/// A pair's contact at the start of a step, or only the direction that
/// shows it apart beyond its band (see [`start_contact`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum StartContact {
    /// [`contact`]'s answer.
    Found(Option<Contact>),
    /// Apart by more than the band along this unit world direction, from
    /// the first shape towards the second. `closest`: the direction of the
    /// shapes' closest points, along which no other is farther apart; else
    /// a separating axis, and parry's normal may show more.
    ApartAlong { direction: Vector, closest: bool },
}

/// [`contact`] of two posed shapes within `prediction`, except for a pair
/// beyond its band, which needs only a direction along which it stays
/// apart: two boxes or triangles whose separating axes show them apart by
/// more than `band` get that axis, and a capsule or cylinder apart from a
/// box by more (or beyond `prediction`) the direction of its closest
/// points in closed form, instead of parry's distance (GJK). parry's GJK
/// distance is never below the true one, so a pair the closed form puts
/// beyond the band or the prediction is there for parry too.
pub(crate) fn start_contact(
    pose1: &Pose,
    shape1: &dyn Shape,
    pose2: &Pose,
    shape2: &dyn Shape,
    band: f64,
    prediction: f32,
) -> Result<StartContact, Unsupported> {
    if !sat::handles(shape1, shape2) {
        // The closed form's distance is the true one to ~1e-5 m (two ways
        // of composing `f32` poses), where parry's may stop above it.
        if round_and_box(shape1, shape2)
            && let Some(Some(c)) = round_cuboid(pose1, shape1, pose2, shape2, f64::INFINITY)
        {
            let dist = c.dist as f64 - 1.0e-5;
            if dist > prediction as f64 {
                return Ok(StartContact::Found(None));
            }
            if dist > band {
                return Ok(StartContact::ApartAlong {
                    direction: c.normal1,
                    closest: true,
                });
            }
        }
        return contact(pose1, shape1, pose2, shape2, prediction).map(StartContact::Found);
    }
    let pos12 = pose1.inv_mul(pose2);
    let axes = sat::contact(&pos12, shape1, shape2, prediction as f64);
    if let SatAnswer::Apart(n, sep) = axes
        && sep > band
    {
        return Ok(StartContact::ApartAlong {
            direction: pose1.rotation * glam_from_vec(&n),
            closest: false,
        });
    }
    let found = AxesFirst.polytopes(&pos12, shape1, shape2, prediction, axes)?;
    Ok(StartContact::Found(found.map(|mut c| {
        c.transform_by_mut(pose1, pose2);
        c
    })))
}

/// Whether one shape is a capsule or a cylinder and the other a box, the
/// pairs [`round_cuboid`] may answer: two type tags, cheaper than its
/// downcasts for every other pair.
fn round_and_box(shape1: &dyn Shape, shape2: &dyn Shape) -> bool {
    use ShapeType::{Capsule, Cuboid, Cylinder};
    matches!(
        (shape1.shape_type(), shape2.shape_type()),
        (Capsule | Cylinder, Cuboid) | (Cuboid, Capsule | Cylinder)
    )
}

/// The contact of a posed capsule or cylinder and a box (either order)
/// from the closest points of its axis segment and the box, in closed form
/// (`crate::gap::segment_box`, in `f64`), where parry would run GJK (whose
/// distance stops up to millimetres above the true one): the witness of a
/// capsule query's reported time, an eighth of its cost (a cylinder's, a
/// fifth: 16 k instructions of parry's GJK on its curved side). `None` for
/// other pairs, when the segment meets the box (parry's EPA measures that
/// depth), and for a cylinder overlapping the box or whose closest points
/// are not beside its axis; `Some(None)` when they are farther apart than
/// `prediction`.
///
/// The stage's contact samples keep parry's contact (and, for a capsule,
/// its cores' contact, [`rounded_contact`]): rapier's contacts see those
/// numbers, and the stage's hand-back rules are written against them.
fn round_cuboid(
    pose1: &Pose,
    g1: &dyn Shape,
    pose2: &Pose,
    g2: &dyn Shape,
    prediction: f64,
) -> Option<Option<Contact>> {
    // The round shape's axis segment and radius, and whether it is a
    // cylinder (whose closest points are the capsule's only beside the
    // axis, see below).
    let round = |g: &dyn Shape| match (g.as_capsule(), g.as_cylinder()) {
        (Some(c), _) => Some(([c.segment.a, c.segment.b], c.radius, false)),
        (_, Some(c)) => Some((
            [-Vector::Y, Vector::Y].map(|y| y * c.half_height),
            c.radius,
            true,
        )),
        _ => None,
    };
    let ((ends, radius, cylinder), cuboid, capsule_first) = match (round(g1), g2.as_cuboid()) {
        (Some(r), Some(b)) => (r, b, true),
        _ => (round(g2)?, g1.as_cuboid()?, false),
    };
    let (capsule_pose, box_pose) = if capsule_first {
        (pose1, pose2)
    } else {
        (pose2, pose1)
    };
    // The segment in the box's frame, where the box is axis-aligned.
    let box_iso = iso_from_pose(box_pose);
    let capsule_in_box = box_iso.inv_mul(&iso_from_pose(capsule_pose));
    let segment = ends.map(|p| (capsule_in_box * point_from_glam(p)).coords);
    let (on_segment, on_box) = gap::segment_box(&segment, &vec_from_glam(cuboid.half_extents));
    let between = on_box - on_segment;
    let core = between.norm();
    let scale = 1.0 + segment[0].norm() + segment[1].norm();
    // (Or NaN: parry's answer then too.)
    if core.is_nan() || core <= 1.0e-9 * scale {
        return None;
    }
    let radius = f64::from(radius);
    let dist = core - radius;
    // A cylinder is the capsule's middle: where the box's point nearest its
    // axis lies beside the axis (not past an end), the segment between them
    // is square to the axis and leaves the cylinder through its side, so
    // shapes apart have the capsule's closest points. Elsewhere, or
    // overlapping, parry's.
    if cylinder && !(dist > 0.0 && gap::beside_axis(&segment, &on_segment)) {
        return None;
    }
    if dist > prediction {
        return Some(None);
    }
    // In the world: the normal from the capsule towards the box, and the
    // witness on each surface.
    let n = box_iso.rotation * (between / core);
    let on_capsule = box_iso * Point3::from(on_segment) + n * radius;
    let on_box = box_iso * Point3::from(on_box);
    let (on_capsule, on_box) = (
        glam_from_vec(&on_capsule.coords),
        glam_from_vec(&on_box.coords),
    );
    let (out_of_capsule, out_of_box) = (glam_from_vec(&n), glam_from_vec(&-n));
    Some(Some(if capsule_first {
        Contact::new(on_capsule, on_box, out_of_capsule, out_of_box, dist as Real)
    } else {
        Contact::new(on_box, on_capsule, out_of_box, out_of_capsule, dist as Real)
    }))
}

/// The deepest (or closest) contact of a composite shape's parts with
/// `g2`, placed by `pos12` in the composite's frame, within `prediction`:
/// parry's composite contact, except that once a part overlaps, a box or
/// triangle part is asked only within that (negative) distance. Its
/// separating axes then stop at the first face that shows it shallower (a
/// mesh jammed into a wall has most of its triangles in it, and only the
/// deepest counts). A part so left out could only tie or lose (an overlap
/// by its axes' depth, exactly; a part apart is at a distance of at least
/// 0), so the answer is parry's. Apart parts are never asked within less
/// than `prediction`: parry's GJK, which measures them, rounds its stop
/// differently with a smaller one, and other parts go to parry's own
/// contacts, which are not written for a negative one.
///
/// With `settle` (and `allowed ≥ 0`), once a part is within the band a box
/// or triangle part is asked within the lesser of that part's distance and
/// minus `allowed`, and the first part deeper than allowed ends the walk
/// (see [`contact_settled`]): a box resting on a flat mesh overlaps every
/// triangle under it by about the same depth, which sets no bound on the
/// others, while the allowed depth turns most of them away at their face.
fn composite_contact(
    dispatcher: &AxesFirst,
    pos12: &Pose,
    g1: &dyn CompositeShape,
    g2: &dyn Shape,
    prediction: Real,
    settle: Option<Settle>,
) -> Option<Contact> {
    let settle = settle.filter(|s| s.allowed >= 0.0);
    let near = g2.compute_aabb(pos12).loosened(prediction);
    let placed_box = PlacedBox::new(pos12, g2, prediction);
    let mut best: Option<(u32, Contact)> = None;
    let g2_polytope = sat::is_polytope(g2);
    let mut placed = None;
    // parry's own box test (`Bvh::intersect_aabb`), then, for a part,
    // `g2`'s own box (a subtree's box is larger, and there the test cost
    // more than it spared).
    let query = BvhNode::leaf(near, 0);
    let parts = g1.bvh().leaves(|node: &BvhNode| {
        node.intersects(&query)
            && (!node.is_leaf() || placed_box.is_none_or(|b| b.may_meet(&node.aabb())))
    });
    for part in parts {
        let best_dist = best.as_ref().map(|(_, b)| b.dist);
        if is_settled(best_dist, settle) {
            break;
        }
        g1.map_part_at(part, &mut |part_pose, shape, _| {
            let polytope = g2_polytope && sat::is_polytope(shape);
            let reach = part_reach(best_dist, settle, polytope, prediction);
            let found = match part_pose {
                None => part_in_frame(dispatcher, pos12, (shape, polytope), g2, reach, &mut placed),
                Some(p) => dispatcher.contact(&p.inv_mul(pos12), shape, g2, reach),
            };
            if let Ok(Some(mut c)) = found
                && best.as_ref().is_none_or(|(_, b)| c.dist < b.dist)
            {
                if let Some(p) = part_pose {
                    c.transform1_by_mut(p);
                }
                best = Some((part, c));
            }
        });
    }
    best.map(|(part, mut c)| {
        c.subshape1 = part;
        c
    })
}

/// `g2`'s own box placed in a composite's frame, loosened by a
/// prediction: a part whose box is apart from it along one of its three
/// axes is not within the prediction of `g2`. A box or slab turned in the
/// composite's frame has an axis-aligned box far larger than itself (a
/// wall beside a spinning mesh covers the whole mesh), which lets every
/// part through to its own test.
#[derive(Clone, Copy)]
struct PlacedBox {
    center: Vector,
    axes: [Vector; 3],
    /// Half extents, loosened by the prediction and the `f32` rounding.
    half: Vector,
}

impl PlacedBox {
    /// `None` for a shape without a finite box (a half-space).
    fn new(pos12: &Pose, g2: &dyn Shape, prediction: Real) -> Option<PlacedBox> {
        let local = g2.compute_local_aabb();
        let center = *pos12 * local.center();
        let half = local.half_extents();
        // A few parts in 10⁶ of the coordinates: far more than the
        // rounding of the projections below.
        let rounding = 1.0e-5 * (1.0 + center.abs().max_element() + half.max_element());
        let half = half + Vector::splat(prediction.max(0.0) + rounding);
        (center.is_finite() && half.is_finite()).then(|| PlacedBox {
            center,
            axes: [Vector::X, Vector::Y, Vector::Z].map(|a| pos12.rotation * a),
            half,
        })
    }

    /// Whether `part` (a box in the composite's frame) may meet this box:
    /// not apart along its axes.
    fn may_meet(&self, part: &Aabb) -> bool {
        let (mins, maxs) = (part.mins, part.maxs);
        let (center, extent) = ((mins + maxs) * 0.5, (maxs - mins) * 0.5);
        let offset = center - self.center;
        self.axes
            .iter()
            .zip(self.half.to_array())
            .all(|(a, h)| offset.dot(*a).abs() <= extent.dot(a.abs()) + h)
    }
}

/// parry's heightfield contact (the deepest or closest of its triangles
/// near `g2`, placed by `pos12` in the field's frame), with the pruning
/// of [`composite_contact`].
fn heightfield_contact(
    dispatcher: &AxesFirst,
    pos12: &Pose,
    field: &HeightField,
    g2: &dyn Shape,
    prediction: Real,
    settle: Option<Settle>,
) -> Option<Contact> {
    let settle = settle.filter(|s| s.allowed >= 0.0);
    let near = g2.compute_aabb(pos12).loosened(prediction.max(0.0));
    let placed_box = PlacedBox::new(pos12, g2, prediction);
    let mut best: Option<Contact> = None;
    let polytope = sat::is_polytope(g2);
    let mut placed = None;
    field.map_elements_in_local_aabb(&near, &mut |_, triangle| {
        let best_dist = best.as_ref().map(|b| b.dist);
        if is_settled(best_dist, settle)
            || placed_box.is_some_and(|b| !b.may_meet(&triangle.local_aabb()))
        {
            return;
        }
        let reach = part_reach(best_dist, settle, polytope, prediction);
        let part = (triangle as &dyn Shape, polytope);
        if let Ok(Some(c)) = part_in_frame(dispatcher, pos12, part, g2, reach, &mut placed)
            && best.as_ref().is_none_or(|b| c.dist < b.dist)
        {
            best = Some(c);
        }
    });
    best
}

/// The contact of a composite's part that lies in the composite's own
/// frame (a mesh's or heightfield's triangle) with `g2`, placed by `pos12`
/// in that frame, within `reach`: a box or triangle pair (`polytope`) by
/// the separating axes, with `g2` placed once for all the parts
/// (`placed`, made on first need), any other through the dispatcher.
#[inline]
fn part_in_frame(
    dispatcher: &AxesFirst,
    pos12: &Pose,
    (part, polytope): (&dyn Shape, bool),
    g2: &dyn Shape,
    reach: Real,
    placed: &mut Option<sat::Placed>,
) -> Result<Option<Contact>, Unsupported> {
    if !polytope {
        return dispatcher.contact(pos12, part, g2, reach);
    }
    let placed = placed.get_or_insert_with(|| sat::Placed::new(pos12, g2));
    let axes = sat::contact_placed(part, placed, f64::from(reach));
    dispatcher.polytopes(pos12, part, g2, reach, axes)
}

/// Whether the best part so far, at `best` metres, answers a settling
/// caller: it is deeper than allowed.
fn is_settled(best: Option<Real>, settle: Option<Settle>) -> bool {
    matches!((best, settle), (Some(d), Some(s)) if f64::from(d) < -s.allowed)
}

/// How far a composite's part is asked, the best part so far at `best`
/// metres (see [`composite_contact`]): a box or triangle against a box or
/// triangle (`polytope`) within an overlap so far, or for a settling
/// caller once a part is within the band, within the lesser of that
/// part's distance and minus `allowed` (either bound shows a part beyond
/// it not deeper than allowed, and both are at most 0, so no part is then
/// measured by GJK); any other part within `prediction`.
fn part_reach(
    best: Option<Real>,
    settle: Option<Settle>,
    polytope: bool,
    prediction: Real,
) -> Real {
    let Some(d) = best.filter(|_| polytope) else {
        return prediction;
    };
    match settle {
        Some(s) if f64::from(d) <= s.band => d.min(s.deeper_than_allowed()),
        _ if d < 0.0 => d,
        _ => prediction,
    }
}

/// parry's query dispatcher, except for contacts: two boxes or triangles
/// by their separating axes (see `sat`), and composite shapes through this
/// dispatcher, so that their triangles and boxes get the axes too. parry's
/// own composite contacts recurse through parry's dispatcher.
struct AxesFirst;

impl AxesFirst {
    /// The contact of two boxes or triangles from what their separating
    /// axes said within `prediction` (`sat`): parry's GJK along the best
    /// axis when apart within it, parry's dispatcher when the axes cannot
    /// tell.
    #[inline]
    fn polytopes(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
        sat: SatAnswer,
    ) -> Result<Option<Contact>, Unsupported> {
        match sat {
            SatAnswer::Beyond => return Ok(None),
            SatAnswer::Overlap(c) => return Ok(Some(c)),
            SatAnswer::Apart(axis, _) => {
                // GJK over the concrete shapes (the axes answer only boxes
                // and triangles): through `dyn SupportMap` every support
                // point of its iterations was a virtual call.
                let found = match (g1.as_typed_shape(), g2.as_typed_shape()) {
                    (TypedShape::Cuboid(a), TypedShape::Cuboid(b)) => {
                        gjk_contact(pos12, a, b, prediction, axis)
                    }
                    (TypedShape::Cuboid(a), TypedShape::Triangle(b)) => {
                        gjk_contact(pos12, a, b, prediction, axis)
                    }
                    (TypedShape::Triangle(a), TypedShape::Cuboid(b)) => {
                        gjk_contact(pos12, a, b, prediction, axis)
                    }
                    (TypedShape::Triangle(a), TypedShape::Triangle(b)) => {
                        gjk_contact(pos12, a, b, prediction, axis)
                    }
                    _ => return DefaultQueryDispatcher.contact(pos12, g1, g2, prediction),
                };
                return Ok(found);
            }
            SatAnswer::Unknown => {}
        }
        DefaultQueryDispatcher.contact(pos12, g1, g2, prediction)
    }

    /// The dispatcher's contact, a composite shape's settled for `settle`
    /// (see [`contact_settled`]).
    fn contact_settled(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
        settle: Option<Settle>,
    ) -> Result<Option<Contact>, Unsupported> {
        if sat::handles(g1, g2) {
            let axes = sat::contact(pos12, g1, g2, prediction as f64);
            return self.polytopes(pos12, g1, g2, prediction, axes);
        } else if let Some(field) = g1.as_heightfield() {
            return Ok(heightfield_contact(
                self, pos12, field, g2, prediction, settle,
            ));
        } else if let Some(field) = g2.as_heightfield() {
            let flipped =
                heightfield_contact(self, &pos12.inverse(), field, g1, prediction, settle);
            return Ok(flipped.map(|c| c.flipped()));
        } else if let Some(c1) = g1.as_composite_shape() {
            return Ok(composite_contact(self, pos12, c1, g2, prediction, settle));
        } else if let Some(c2) = g2.as_composite_shape() {
            let flipped = composite_contact(self, &pos12.inverse(), c2, g1, prediction, settle);
            return Ok(flipped.map(|c| c.flipped()));
        } else if let Some(found) = rounded_contact(pos12, g1, g2, prediction) {
            return Ok(found);
        }
        DefaultQueryDispatcher.contact(pos12, g1, g2, prediction)
    }
}

/// The contact of a pair with a rounded side (a capsule, a rounded box)
/// as rapier's contacts measure it: parry's contact manifolds for such a
/// pair (`contact_manifold_pfm_pfm`) run GJK on the cores (a capsule's
/// axis segment) within the prediction plus the radii and move the
/// witnesses out by them. parry's `contact` runs GJK on the whole rounded
/// shapes instead, and EPA whenever they overlap (a capsule resting on a
/// floor: 17 k instructions a call). Only for cores that are polytopes,
/// where GJK ends on their closest features; on a cylinder's or cone's
/// curved side it stops early, millimetres above the true distance, and
/// parry's whole-shape answer is nearer. `None`: not such a pair (a ball
/// or a half-space, whose contacts rapier measures otherwise, a curved
/// core, or no rounding at all), or cores that overlap: EPA on the whole
/// shapes then, as before (on a segment and a triangle, whose difference
/// may be flat, EPA on the cores can fail and report nothing).
fn rounded_contact(
    pos12: &Pose,
    g1: &dyn Shape,
    g2: &dyn Shape,
    prediction: Real,
) -> Option<Option<Contact>> {
    if !polytope_core(g1.shape_type()) || !polytope_core(g2.shape_type()) {
        return None;
    }
    let (core1, r1) = g1.as_polygonal_feature_map()?;
    let (core2, r2) = g2.as_polygonal_feature_map()?;
    if r1 == 0.0 && r2 == 0.0 {
        return None;
    }
    let start = pos12.translation.try_normalize().unwrap_or(Vector::X);
    let mut simplex = VoronoiSimplex::new();
    simplex.reset(CsoPoint::from_shapes(pos12, core1, core2, start));
    let reach = prediction + r1 + r2;
    match gjk::closest_points(pos12, core1, core2, reach, true, &mut simplex) {
        GJKResult::ClosestPoints(point1, point2_1, normal1) => {
            let normal2 = pos12.rotation.inverse() * -normal1;
            Some(Some(Contact::new(
                point1 + normal1 * r1,
                pos12.inverse_transform_point(point2_1) + normal2 * r2,
                normal1,
                normal2,
                (point2_1 - point1).dot(normal1) - r1 - r2,
            )))
        }
        GJKResult::NoIntersection(_) => Some(None),
        _ => None,
    }
}

/// Whether a shape's core, as parry's contact manifolds see it, is a
/// polytope: a capsule's segment, a rounded box's box.
fn polytope_core(shape: ShapeType) -> bool {
    use ShapeType::*;
    matches!(
        shape,
        Capsule
            | Cuboid
            | Triangle
            | Segment
            | ConvexPolyhedron
            | RoundCuboid
            | RoundTriangle
            | RoundConvexPolyhedron
    )
}

impl QueryDispatcher for AxesFirst {
    fn contact(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        prediction: Real,
    ) -> Result<Option<Contact>, Unsupported> {
        self.contact_settled(pos12, g1, g2, prediction, None)
    }

    fn intersection_test(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeIntersection, Unsupported> {
        DefaultQueryDispatcher.intersection_test(pos12, g1, g2)
    }

    fn distance(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        DefaultQueryDispatcher.distance(pos12, g1, g2)
    }

    fn closest_points(
        &self,
        pos12: &Pose,
        g1: &dyn Shape,
        g2: &dyn Shape,
        max_dist: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        DefaultQueryDispatcher.closest_points(pos12, g1, g2, max_dist)
    }

    fn cast_shapes(
        &self,
        pos12: &Pose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes(pos12, local_vel12, g1, g2, options)
    }

    fn cast_shapes_nonlinear(
        &self,
        motion1: &NonlinearRigidMotion,
        g1: &dyn Shape,
        motion2: &NonlinearRigidMotion,
        g2: &dyn Shape,
        start_time: Real,
        end_time: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        DefaultQueryDispatcher.cast_shapes_nonlinear(
            motion1,
            g1,
            motion2,
            g2,
            start_time,
            end_time,
            stop_at_penetration,
        )
    }
}

/// parry's contact of two convex shapes apart by less than `prediction`
/// (its GJK, started along `axis`: a separating direction of the first
/// shape's frame, pointing towards the second), in parry's form.
fn gjk_contact<G1: SupportMap, G2: SupportMap>(
    pos12: &Pose,
    g1: &G1,
    g2: &G2,
    prediction: Real,
    axis: Vector3<f64>,
) -> Option<Contact> {
    let mut simplex = VoronoiSimplex::new();
    let init = Some(glam_from_vec(&axis));
    match details::contact_support_map_support_map_with_params(
        pos12,
        g1,
        g2,
        prediction,
        &mut simplex,
        init,
    ) {
        GJKResult::ClosestPoints(point1, point2_1, normal1) => {
            let dist = (point2_1 - point1).dot(normal1);
            let point2 = pos12.inverse_transform_point(point2_1);
            let normal2 = pos12.rotation.inverse() * -normal1;
            Some(Contact::new(point1, point2, normal1, normal2, dist))
        }
        _ => None,
    }
}

/// Where two shapes meet at a reported time: a point on each (world,
/// metres) and the unit normal from shape 1 towards shape 2.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Witness {
    pub point1: Point3<f64>,
    pub point2: Point3<f64>,
    pub normal1: Vector3<f64>,
}

impl Witness {
    /// The points and normal of a parry contact.
    pub fn of(contact: &Contact) -> Witness {
        Witness {
            point1: Point3::from(vec_from_glam(contact.point1)),
            point2: Point3::from(vec_from_glam(contact.point2)),
            normal1: vec_from_glam(contact.normal1),
        }
    }

    /// When parry cannot say: the frames' origins and the direction between
    /// them (zero when they coincide).
    pub fn origins(iso1: &Isometry3<f64>, iso2: &Isometry3<f64>) -> Witness {
        let (o1, o2) = (iso1.translation.vector, iso2.translation.vector);
        Witness {
            point1: Point3::from(o1),
            point2: Point3::from(o2),
            normal1: (o2 - o1).try_normalize(0.0).unwrap_or_else(Vector3::zeros),
        }
    }
}

impl Toi {
    /// The time of impact at `fraction` of a step of `dt` seconds.
    pub(crate) fn new(
        fraction: f64,
        dt: f64,
        status: RootStatus,
        witness: Witness,
        stats: SolveStats,
    ) -> Toi {
        Toi {
            fraction,
            time: fraction * dt,
            status,
            witness1: witness.point1,
            witness2: witness.point2,
            normal1: witness.normal1,
            stats,
        }
    }
}

/// The [`Toi`] of a search outcome: the time, and the witness points and
/// normal from parry's contact query at the poses of that time.
pub(super) fn describe(
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
    // At the reported time the shapes are about `skin` apart. A bounded
    // prediction keeps parry's composite contact to the mesh parts nearby
    // (an unbounded one visits every triangle); widen it only if needed.
    let witness = round_cuboid(&pose1, shape1, &pose2, shape2, f64::INFINITY)
        .flatten()
        .map(|c| Witness::of(&c))
        .or_else(|| round_box_closest(&iso1, shape1, &iso2, shape2))
        .or_else(|| polytopes_closest(&iso1, shape1, &iso2, shape2))
        .or_else(|| {
            [1.0e-2f32, 1.0, 1.0e2, f32::MAX]
                .into_iter()
                .find_map(|extra| {
                    contact(&pose1, shape1, &pose2, shape2, skin as f32 + extra)
                        .ok()
                        .flatten()
                })
                .map(|c| Witness::of(&c))
        })
        .unwrap_or_else(|| Witness::origins(&iso1, &iso2));
    Toi::new(fraction, dt, outcome.status, witness, outcome.stats)
}

/// The witness of a cylinder or cone and a box apart at the reported
/// time, through the round shape's generators (`gap::round_box`), where
/// parry's contact runs its `f32` GJK, which creeps along a rim or a
/// cone's side (some 12 k instructions a cone query's witness). `None` for
/// other pairs and where `round_box` does not find the closest points.
fn round_box_closest(
    iso1: &Isometry3<f64>,
    g1: &dyn Shape,
    iso2: &Isometry3<f64>,
    g2: &dyn Shape,
) -> Option<Witness> {
    let round = |g: &dyn Shape| g.as_cylinder().is_some() || g.as_cone().is_some();
    let (round_first, round_iso, box_iso, round_shape, box_shape) = match (round(g1), round(g2)) {
        (true, false) if g2.as_cuboid().is_some() => (true, iso1, iso2, g1, g2),
        (false, true) if g1.as_cuboid().is_some() => (false, iso2, iso1, g2, g1),
        _ => return None,
    };
    let (round_convex, box_convex) = (
        gap::Convex::from_shape(round_shape).ok()??,
        gap::Convex::from_shape(box_shape).ok()??,
    );
    let gap::RoundBox::Apart {
        normal,
        on_round,
        on_box,
    } = gap::round_box(
        &round_convex,
        &box_iso.inv_mul(round_iso),
        &box_convex,
        None,
    )
    else {
        return None;
    };
    // In the world; `normal` points from the round shape towards the box.
    let (on_round, on_box) = (
        box_iso * Point3::from(on_round),
        box_iso * Point3::from(on_box),
    );
    let normal = box_iso.rotation * normal;
    Some(if round_first {
        Witness {
            point1: on_round,
            point2: on_box,
            normal1: normal,
        }
    } else {
        Witness {
            point1: on_box,
            point2: on_round,
            normal1: -normal,
        }
    })
}

/// The witness of two polytopes (boxes, triangles, convex hulls) apart at
/// the reported time, from GJK in `f64` over their vertices
/// ([`gap::Convex`]): it ends in a few steps on polytopes, where parry's
/// contact first tries the separating axes and then runs its `f32` GJK
/// (10 k instructions a box–triangle query's witness). `None` for other
/// pairs, when the shapes overlap (parry's contact measures that depth) or
/// GJK has no answer.
fn polytopes_closest(
    iso1: &Isometry3<f64>,
    g1: &dyn Shape,
    iso2: &Isometry3<f64>,
    g2: &dyn Shape,
) -> Option<Witness> {
    let polytope = |g: &dyn Shape| {
        g.as_cuboid().is_some() || g.as_triangle().is_some() || g.as_convex_polyhedron().is_some()
    };
    if !(polytope(g1) && polytope(g2)) {
        return None;
    }
    let (c1, c2) = (
        gap::Convex::from_shape(g1).ok()??,
        gap::Convex::from_shape(g2).ok()??,
    );
    let pos12 = pose64_from_iso(&iso1.inv_mul(iso2));
    let search = || {
        let start = pos12.translation.try_normalize().unwrap_or(Vec64::X);
        let mut simplex = Simplex64::new();
        simplex.reset(Cso64::from_shapes(&pos12, &c1, &c2, start));
        gjk64::closest_points(&pos12, &c1, &c2, 1.0e6, true, &mut simplex)
    };
    // A panic in parry only costs this shortcut.
    let Ok(Gjk64Result::ClosestPoints(p1, p2, n)) = std::panic::catch_unwind(search) else {
        return None;
    };
    // Both points and the normal are in shape 1's frame.
    let local = |p: Vec64| Point3::new(p.x, p.y, p.z);
    let normal = Vector3::new(n.x, n.y, n.z).try_normalize(1.0e-9)?;
    Some(Witness {
        point1: iso1 * local(p1),
        point2: iso1 * local(p2),
        normal1: iso1.rotation * normal,
    })
}

/// A plus-shaped triangle mesh of two crossed slabs, `long` by `wide` by
/// `thick` half extents and the same turned a right angle (a propeller),
/// for the tests.
#[cfg(test)]
pub(crate) fn cross_mesh(long: f32, wide: f32, thick: f32) -> rapier3d::parry::shape::TriMesh {
    let mut corners = Vec::new();
    for half in [
        Vector::new(long, wide, thick),
        Vector::new(wide, long, thick),
    ] {
        for k in 0..8 {
            let sign = |bit: i32| if k >> bit & 1 == 0 { -1.0 } else { 1.0 };
            corners.push(Vector::new(
                sign(0) * half.x,
                sign(1) * half.y,
                sign(2) * half.z,
            ));
        }
    }
    let faces = |b: u32| {
        [
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
        ]
        .map(|f: [u32; 3]| f.map(|i| i + b))
    };
    let indices: Vec<[u32; 3]> = faces(0).into_iter().chain(faces(8)).collect();
    rapier3d::parry::shape::TriMesh::new(corners, indices).expect("a closed mesh")
}

/// A wavy 8 × 8 m floor as a triangle mesh, and as a heightfield.
#[cfg(test)]
pub(crate) fn floors() -> (
    rapier3d::parry::shape::TriMesh,
    rapier3d::parry::shape::HeightField,
) {
    let n = 9;
    let height = |i: usize, j: usize| 0.3 * ((i as f32 * 0.9).sin() + (j as f32 * 0.7).cos());
    let mesh = grid(n, 1.0, height);
    let heights = rapier3d::parry::utils::Array2::from_fn(n, n, height);
    let field = rapier3d::parry::shape::HeightField::new(heights, Vector::new(8.0, 1.0, 8.0));
    (mesh, field)
}

/// A square grid of `n × n` vertices `spacing` apart about the origin,
/// at `height(i, j)`, two triangles a cell.
#[cfg(test)]
pub(crate) fn grid(
    n: usize,
    spacing: f32,
    height: impl Fn(usize, usize) -> f32,
) -> rapier3d::parry::shape::TriMesh {
    let half = spacing * (n - 1) as f32 / 2.0;
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (spacing * i as f32 - half, spacing * j as f32 - half);
            vertices.push(Vector::new(x, height(i, j), z));
        }
    }
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let k = (i * n + j) as u32;
            indices.push([k, k + 1, k + n as u32]);
            indices.push([k + 1, k + n as u32 + 1, k + n as u32]);
        }
    }
    rapier3d::parry::shape::TriMesh::new(vertices, indices).expect("a valid mesh")
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::math::Rotation;
    use rapier3d::parry::shape::{Ball, Capsule, Cuboid, Cylinder, Triangle};

    /// Seeded numbers in `[0, 1)` (a linear congruential generator).
    fn uniform(mut seed: u64) -> impl FnMut() -> f32 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// A rotation by up to 6 rad about an axis, from `next`'s numbers.
    fn turn(next: &mut dyn FnMut() -> f32) -> Rotation {
        let axis = Vector::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vector::Y);
        Rotation::from_axis_angle(axis, 6.0 * next())
    }

    /// A parry vector in parry3d-f64's (exact: every `f32` is an `f64`).
    fn wide(v: Vector) -> Vec64 {
        Vec64::new(v.x.into(), v.y.into(), v.z.into())
    }

    /// Boxes and balls dropped onto both floors at random: the contact
    /// asked through [`AxesFirst`] is parry's own (its composite contacts
    /// run EPA per triangle) on nearly every pose, both argument orders.
    /// A capsule and a box at random poses, apart and shallowly
    /// overlapping, both argument orders: the closed form's distance is the
    /// least over 4001 points of the segment of their exact distance to the
    /// box (less the radius), within the samples' spacing, and never above
    /// parry's (GJK stops above the true distance, here by up to 2 mm); its
    /// normal is parry's, and its witness points lie that far apart along
    /// it.
    #[test]
    fn capsule_box_contacts_match_parrys() {
        let mut next = uniform(9u64);
        let mut compared = 0;
        for case in 0..2000 {
            let capsule = Capsule::new_y(0.05 + 0.5 * next(), 0.02 + 0.3 * next());
            let cuboid = Cuboid::new(Vector::new(0.05 + next(), 0.05 + next(), 0.05 + next()));
            let at = Vector::new(3.0 * next() - 1.5, 3.0 * next() - 1.5, 3.0 * next() - 1.5);
            let capsule_pose = Pose::from_parts(at, turn(&mut next));
            let box_pose = Pose::from_parts(Vector::ZERO, turn(&mut next));
            let prediction = 0.5;
            for flip in [false, true] {
                let (p1, s1, p2, s2): (_, &dyn Shape, _, &dyn Shape) = if flip {
                    (&box_pose, &cuboid, &capsule_pose, &capsule)
                } else {
                    (&capsule_pose, &capsule, &box_pose, &cuboid)
                };
                // Segments meeting the box are left to parry.
                let Some(ours) = round_cuboid(p1, s1, p2, s2, f64::from(prediction)) else {
                    continue;
                };
                let parry =
                    rapier3d::parry::query::contact(p1, s1, p2, s2, prediction).expect("supported");
                let (Some(a), Some(b)) = (ours, parry) else {
                    assert_eq!(ours.is_some(), parry.is_some(), "case {case} flip {flip}");
                    continue;
                };
                compared += 1;
                // The truth: the segment sampled in the box's frame, in f64.
                let to_box = iso_from_pose(&box_pose).inverse() * iso_from_pose(&capsule_pose);
                let ends = [capsule.segment.a, capsule.segment.b]
                    .map(|p| (to_box * point_from_glam(p)).coords);
                let half = vec_from_glam(cuboid.half_extents);
                let samples = 4000;
                let sampled = (0..=samples)
                    .map(|k| {
                        let p = ends[0] + (ends[1] - ends[0]) * (k as f64 / samples as f64);
                        Vector3::from_fn(|i, _| (p[i].abs() - half[i]).max(0.0)).norm()
                    })
                    .fold(f64::INFINITY, f64::min);
                let spacing = (ends[1] - ends[0]).norm() / samples as f64;
                let truth = sampled - f64::from(capsule.radius);
                // The poses are f32 (their quaternions unit to ~1e-7),
                // so two ways of composing them differ by ~1e-6 m here.
                if sampled > 0.0 {
                    let ours = f64::from(a.dist);
                    assert!(
                        ours <= truth + 1.0e-5 && ours >= truth - spacing - 1.0e-5,
                        "case {case} flip {flip}: {ours} vs sampled {truth}"
                    );
                }
                assert!(
                    a.dist <= b.dist + 1.0e-5,
                    "case {case} flip {flip}: {} vs parry {}",
                    a.dist,
                    b.dist
                );
                assert!(
                    a.normal1.dot(b.normal1) > 0.99 || a.dist.abs() < 1.0e-3,
                    "case {case} flip {flip}: normal {:?} vs parry {:?}",
                    a.normal1,
                    b.normal1
                );
                let along = (a.point2 - a.point1).dot(a.normal1);
                assert!(
                    (along - a.dist).abs() < 1.0e-4,
                    "case {case}: {along} vs {}",
                    a.dist
                );
            }
        }
        assert!(compared > 500, "only {compared} contacts compared");
    }

    /// A capsule or a cylinder and a box at random poses, either order, a
    /// band and a prediction: where `start_contact` puts the pair beyond
    /// the band along the closest points' direction, parry's contact puts
    /// it there too, with nearly that normal, and where it finds nothing
    /// within the prediction, parry finds nothing; elsewhere its answer is
    /// [`contact`]'s.
    #[test]
    fn start_contacts_of_round_shapes_and_boxes_agree_with_parrys() {
        let mut next = uniform(23u64);
        let (mut apart, mut beyond, mut asked_whole) = (0, 0, 0);
        for case in 0..3000 {
            let round: Box<dyn Shape> = if case % 2 == 0 {
                Box::new(Capsule::new_y(0.05 + 0.5 * next(), 0.02 + 0.3 * next()))
            } else {
                Box::new(Cylinder::new(0.05 + 0.5 * next(), 0.02 + 0.3 * next()))
            };
            let cuboid = Cuboid::new(Vector::new(0.05 + next(), 0.05 + next(), 0.05 + next()));
            let at = Vector::new(3.0 * next() - 1.5, 3.0 * next() - 1.5, 3.0 * next() - 1.5);
            let round_pose = Pose::from_parts(at, turn(&mut next));
            let box_pose = Pose::from_parts(Vector::ZERO, turn(&mut next));
            let band = 0.2 * next() as f64;
            let prediction = band as f32 + 0.6 * next();
            for flip in [false, true] {
                let (p1, s1, p2, s2): (_, &dyn Shape, _, &dyn Shape) = if flip {
                    (&box_pose, &cuboid, &round_pose, &*round)
                } else {
                    (&round_pose, &*round, &box_pose, &cuboid)
                };
                let ours = start_contact(p1, s1, p2, s2, band, prediction).expect("supported");
                let parry = rapier3d::parry::query::contact(p1, s1, p2, s2, 100.0)
                    .expect("supported")
                    .expect("within 100 m");
                match ours {
                    StartContact::ApartAlong { direction, closest } => {
                        apart += 1;
                        assert!(closest, "case {case}: only closest points here");
                        assert!(
                            parry.dist as f64 > band,
                            "case {case}: parry {}",
                            parry.dist
                        );
                        assert!(
                            direction.dot(parry.normal1) > 0.99,
                            "case {case} flip {flip}: {direction:?} vs parry {:?}",
                            parry.normal1
                        );
                    }
                    StartContact::Found(None) => {
                        beyond += 1;
                        assert!(parry.dist > prediction, "case {case}: parry {}", parry.dist);
                    }
                    StartContact::Found(Some(c)) => {
                        asked_whole += 1;
                        let asked = contact(p1, s1, p2, s2, prediction).expect("supported");
                        assert_eq!(
                            Some(c.dist),
                            asked.map(|a| a.dist),
                            "case {case} flip {flip}"
                        );
                    }
                }
            }
        }
        assert!(
            apart > 500 && beyond > 500 && asked_whole > 500,
            "{apart} apart, {beyond} beyond, {asked_whole} asked as contact"
        );
    }

    /// A rounded shape (capsules, a rounded box) against boxes, triangles,
    /// capsules, cylinders and cones at random poses, apart and
    /// overlapping, both orders. Against the polytope cores [`contact`]
    /// measures the pair as rapier's contacts do: its distance and normal
    /// are those of the closest-points contact in parry's contact manifold
    /// for the pair (the cores' GJK, which the manifold carries beside its
    /// features' clipped points), and within 0.1 mm of the truth
    /// (parry3d-f64's on the cores). Where the cores themselves overlap,
    /// and against a cylinder or a cone, it is parry's whole-shape answer
    /// itself.
    #[test]
    fn rounded_contacts_are_rapiers_manifolds() {
        use rapier3d::parry::query::{ContactManifold, PersistentQueryDispatcher};
        use rapier3d::parry::shape::{Cone, RoundCuboid};
        let mut next = uniform(31u64);
        let (mut overlapping, mut apart, mut curved, mut cores_overlap) = (0, 0, 0, 0);
        for case in 0..3000 {
            let rounded: Box<dyn Shape> = if case % 3 == 2 {
                let half = Vector::new(
                    0.05 + 0.3 * next(),
                    0.05 + 0.3 * next(),
                    0.05 + 0.3 * next(),
                );
                Box::new(RoundCuboid {
                    inner_shape: Cuboid::new(half),
                    border_radius: 0.02 + 0.1 * next(),
                })
            } else {
                Box::new(Capsule::new_y(0.05 + 0.5 * next(), 0.02 + 0.3 * next()))
            };
            let (a, b) = (0.05 + 0.5 * next(), 0.05 + 0.5 * next());
            let other: Box<dyn Shape> = match case % 5 {
                0 => Box::new(Cuboid::new(Vector::new(a, b, 0.05 + next()))),
                1 => Box::new(Triangle::new(
                    Vector::new(-a, 0.0, -b),
                    Vector::new(a, 0.1, -b),
                    Vector::new(0.0, -0.1, b),
                )),
                2 => Box::new(Capsule::new_x(a, 0.02 + 0.2 * b)),
                3 => Box::new(Cylinder::new(a, b)),
                _ => Box::new(Cone::new(a, b)),
            };
            let at = Vector::new(next() - 0.5, next() - 0.5, next() - 0.5) * 1.5;
            let rounded_pose = Pose::from_parts(at, turn(&mut next));
            let other_pose = Pose::from_parts(Vector::ZERO, turn(&mut next));
            let prediction = 0.3 * next();
            for flip in [false, true] {
                let (p1, s1, p2, s2): (_, &dyn Shape, _, &dyn Shape) = if flip {
                    (&other_pose, &*other, &rounded_pose, &*rounded)
                } else {
                    (&rounded_pose, &*rounded, &other_pose, &*other)
                };
                let ours = contact(p1, s1, p2, s2, prediction).expect("supported");
                let whole =
                    rapier3d::parry::query::contact(p1, s1, p2, s2, prediction).expect("supported");
                // The truth: parry3d-f64's contact of the cores (polytopes,
                // on which its GJK and EPA end on the closest features).
                // Against a curved shape, and where the cores themselves
                // overlap, the answer is parry's on the whole shapes.
                let cores = (case % 5 < 3).then(|| {
                    let ((c1, r1), (c2, r2)) = (core64(s1), core64(s2));
                    let found = parry3d_f64::query::contact(
                        &pose64_from_iso(&iso_from_pose(p1)),
                        &*c1,
                        &pose64_from_iso(&iso_from_pose(p2)),
                        &*c2,
                        10.0,
                    );
                    let dist = found.expect("supported").expect("within 10 m").dist;
                    (dist, r1 + r2)
                });
                let truth = match cores {
                    // Touching, either way within the rounding.
                    Some((dist, _)) if dist.abs() < 1.0e-4 => continue,
                    Some((dist, radii)) if dist > 0.0 => dist - radii,
                    _ => {
                        if cores.is_some() {
                            cores_overlap += 1;
                        } else {
                            curved += 1;
                        }
                        assert_eq!(
                            ours.map(|c| c.dist),
                            whole.map(|w| w.dist),
                            "case {case} flip {flip}"
                        );
                        continue;
                    }
                };
                let mut manifolds: Vec<ContactManifold<(), ()>> = Vec::new();
                DefaultQueryDispatcher
                    .contact_manifolds(
                        &p1.inv_mul(p2),
                        s1,
                        s2,
                        prediction,
                        &mut manifolds,
                        &mut None,
                    )
                    .expect("supported");
                // The manifold's point nearest ours in distance: the
                // cores' GJK point, beside the features' clipped points.
                let points = || {
                    manifolds
                        .iter()
                        .flat_map(|m| m.points.iter().map(move |p| (p.dist, m.local_n1)))
                };
                let (Some(c), Some(_)) = (ours, points().next()) else {
                    assert!(
                        ours.is_none() && points().all(|p| p.0 > prediction - 1.0e-5),
                        "case {case} flip {flip}: {ours:?} vs the manifold's {:?}",
                        points().collect::<Vec<_>>()
                    );
                    continue;
                };
                let (dist, local_n1) = points()
                    .min_by(|x, y| (x.0 - c.dist).abs().total_cmp(&(y.0 - c.dist).abs()))
                    .expect("a point");
                if c.dist < 0.0 {
                    overlapping += 1;
                } else {
                    apart += 1;
                }
                assert!(
                    (c.dist - dist).abs() < 1.0e-5,
                    "case {case} flip {flip}: {} vs the manifold's {dist}",
                    c.dist
                );
                assert!(
                    c.normal1.dot(p1.rotation * local_n1) > 0.9999,
                    "case {case} flip {flip}: normal {:?} vs the manifold's {:?}",
                    c.normal1,
                    p1.rotation * local_n1
                );
                assert!(
                    (f64::from(c.dist) - truth).abs() < 1.0e-4,
                    "case {case} flip {flip}: {} vs the truth {truth}",
                    c.dist
                );
                if let Some(w) = whole
                    && w.dist >= 0.0
                {
                    assert!(
                        f64::from(w.dist) > truth - 1.0e-4,
                        "case {case}: {}",
                        w.dist
                    );
                }
            }
        }
        assert!(
            overlapping > 500 && apart > 500 && curved > 1000 && cores_overlap > 100,
            "{overlapping} overlapping, {apart} apart, {curved} curved, \
             {cores_overlap} with their cores overlapping"
        );
    }

    /// A polytope core of a shape in parry3d-f64 and its radius: a
    /// capsule's segment, a rounded box's box, a box or a triangle itself.
    fn core64(shape: &dyn Shape) -> (Box<dyn parry3d_f64::shape::Shape>, f64) {
        use parry3d_f64::shape::{
            Cuboid as Cuboid64, Segment as Segment64, Triangle as Triangle64,
        };
        match shape.as_typed_shape() {
            TypedShape::Capsule(c) => (
                Box::new(Segment64::new(wide(c.segment.a), wide(c.segment.b))),
                c.radius.into(),
            ),
            TypedShape::RoundCuboid(r) => (
                Box::new(Cuboid64::new(wide(r.inner_shape.half_extents))),
                r.border_radius.into(),
            ),
            TypedShape::Cuboid(c) => (Box::new(Cuboid64::new(wide(c.half_extents))), 0.0),
            TypedShape::Triangle(t) => (
                Box::new(Triangle64::new(wide(t.a), wide(t.b), wide(t.c))),
                0.0,
            ),
            _ => panic!("not a polytope core"),
        }
    }

    /// A cylinder and a box: where the closed form answers (apart, the
    /// box's point nearest the axis beside it), its distance is
    /// parry3d-f64's, its points lie on the two surfaces with the
    /// normal between them, and the normal is parry3d-f64's closest-points
    /// normal; on 3,000 random poses, either order, about a fifth of those
    /// apart are answered (the rest are seen past an end).
    #[test]
    fn cylinder_box_contacts_beside_the_axis_are_exact() {
        use parry3d_f64::shape::{Cuboid as Cuboid64, Cylinder as Cylinder64};
        let mut next = uniform(11u64);
        let (mut apart, mut answered) = (0, 0);
        for case in 0..3000 {
            let cylinder = Cylinder::new(0.05 + 0.5 * next(), 0.02 + 0.3 * next());
            let cuboid = Cuboid::new(Vector::new(0.05 + next(), 0.05 + next(), 0.05 + next()));
            let cylinder64 = Cylinder64::new(cylinder.half_height.into(), cylinder.radius.into());
            let h = cuboid.half_extents;
            let cuboid64 = Cuboid64::new(wide(h));
            let at = Vector::new(3.0 * next() - 1.5, 3.0 * next() - 1.5, 3.0 * next() - 1.5);
            let cylinder_pose = Pose::from_parts(at, turn(&mut next));
            let box_pose = Pose::from_parts(Vector::ZERO, turn(&mut next));
            let (c64, b64) = (
                crate::convert::pose64_from_iso(&iso_from_pose(&cylinder_pose)),
                crate::convert::pose64_from_iso(&iso_from_pose(&box_pose)),
            );
            let truth = parry3d_f64::query::contact(&c64, &cylinder64, &b64, &cuboid64, 10.0)
                .unwrap()
                .unwrap();
            if truth.dist > 1.0e-6 {
                apart += 1;
            }
            for flip in [false, true] {
                let (p1, s1, p2, s2): (_, &dyn Shape, _, &dyn Shape) = if flip {
                    (&box_pose, &cuboid, &cylinder_pose, &cylinder)
                } else {
                    (&cylinder_pose, &cylinder, &box_pose, &cuboid)
                };
                let Some(ours) = round_cuboid(p1, s1, p2, s2, f64::INFINITY) else {
                    continue;
                };
                let ours = ours.expect("within an infinite prediction");
                if !flip {
                    answered += 1;
                }
                assert!(
                    truth.dist > 0.0,
                    "case {case}: answered overlapping, {}",
                    truth.dist
                );
                let dist = f64::from(ours.dist);
                // The poses are f32 (their quaternions unit to ~1e-7).
                assert!(
                    (dist - truth.dist).abs() < 1.0e-5,
                    "case {case}: {dist} vs {}",
                    truth.dist
                );
                let (on_cylinder, on_box, n) = if flip {
                    (ours.point2, ours.point1, -ours.normal1)
                } else {
                    (ours.point1, ours.point2, ours.normal1)
                };
                let n64 = truth.normal1;
                let agree =
                    f64::from(n.x) * n64.x + f64::from(n.y) * n64.y + f64::from(n.z) * n64.z;
                assert!(
                    agree > 1.0 - 1.0e-6,
                    "case {case} flip {flip}: normal {n:?} vs {n64:?}"
                );
                let gap = (on_box - on_cylinder).dot(n);
                assert!(
                    (f64::from(gap) - dist).abs() < 1.0e-4,
                    "case {case}: {gap} vs {dist}"
                );
                // On the box's surface, and on the cylinder's side.
                let in_box = box_pose.inverse_transform_point(on_box);
                let out = (in_box.abs() - h).max_element();
                assert!(out.abs() < 1.0e-4, "case {case}: {out} off the box");
                let in_cylinder = cylinder_pose.inverse_transform_point(on_cylinder);
                let off_axis = in_cylinder.x.hypot(in_cylinder.z) - cylinder.radius;
                assert!(
                    off_axis.abs() < 1.0e-4,
                    "case {case}: {off_axis} off the side"
                );
                assert!(
                    in_cylinder.y.abs() <= cylinder.half_height + 1.0e-4,
                    "case {case}"
                );
            }
        }
        assert!(
            apart > 1000 && answered > 300,
            "{answered} of {apart} apart answered"
        );
    }

    /// Two boxes, or a box and a triangle, apart: the witness from GJK in
    /// `f64` has parry3d-f64's distance, its points on the two shapes
    /// (within 1e-5 m, as parry's `f32` witness) that far apart (to 1e-5
    /// m, along its normal to 1e-5); shapes that
    /// overlap get none (parry's contact measures them). 2,000 random
    /// poses, either order.
    #[test]
    fn polytope_witnesses_are_the_closest_points() {
        use parry3d_f64::query::PointQuery;
        use parry3d_f64::shape::{Cuboid as Cuboid64, Triangle as Triangle64};
        use rapier3d::parry::shape::Triangle;
        let mut next = uniform(5u64);
        let (mut apart, mut answered) = (0, 0);
        let mut worst = [0.0f64; 2];
        for case in 0..2000 {
            let half = Vector::new(0.05 + next(), 0.05 + next(), 0.05 + next());
            let corners =
                [(); 3].map(|_| Vector::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.0);
            let cuboid = Cuboid::new(half);
            let other: (Box<dyn Shape>, Box<dyn parry3d_f64::shape::Shape>) = if case % 2 == 0 {
                (
                    Box::new(Triangle::new(corners[0], corners[1], corners[2])),
                    Box::new(Triangle64::new(
                        wide(corners[0]),
                        wide(corners[1]),
                        wide(corners[2]),
                    )),
                )
            } else {
                let h = corners[0].abs() + Vector::splat(0.05);
                (Box::new(Cuboid::new(h)), Box::new(Cuboid64::new(wide(h))))
            };
            let cuboid64 = Cuboid64::new(wide(half));
            let at = Vector::new(4.0 * next() - 2.0, 4.0 * next() - 2.0, 4.0 * next() - 2.0);
            let (iso1, iso2) = (
                iso_from_pose(&Pose::from_parts(Vector::ZERO, turn(&mut next))),
                iso_from_pose(&Pose::from_parts(at, turn(&mut next))),
            );
            let (p1, p2) = (pose64_from_iso(&iso1), pose64_from_iso(&iso2));
            let truth = parry3d_f64::query::distance(&p1, &cuboid64, &p2, other.1.as_ref())
                .unwrap()
                .distance;
            if truth > 1.0e-6 {
                apart += 1;
            }
            for flip in [false, true] {
                let witness = if flip {
                    polytopes_closest(&iso2, other.0.as_ref(), &iso1, &cuboid)
                } else {
                    polytopes_closest(&iso1, &cuboid, &iso2, other.0.as_ref())
                };
                let Some(w) = witness else {
                    assert!(
                        truth < 1.0e-6,
                        "case {case} flip {flip}: none, {truth} apart"
                    );
                    continue;
                };
                answered += 1;
                let (on_box, on_other, n) = if flip {
                    (w.point2, w.point1, -w.normal1)
                } else {
                    (w.point1, w.point2, w.normal1)
                };
                let between = on_other - on_box;
                worst[0] = worst[0].max((between.norm() - truth).abs());
                assert!(
                    (between.norm() - truth).abs() < 1.0e-5,
                    "case {case}: {between:?} vs {truth}"
                );
                assert!(
                    // GJK stops at 1e-7 of the distance: its normal is
                    // that close to the points' direction, not exact.
                    (between.dot(&n) - truth).abs() < 1.0e-5 * (1.0 + truth),
                    "case {case} flip {flip}: {} along the normal, {truth} apart",
                    between.dot(&n)
                );
                let point = |p: Point3<f64>| parry3d_f64::math::Vector::new(p.x, p.y, p.z);
                let off_box = cuboid64.distance_to_point(&p1, point(on_box), true);
                let off_other = other.1.distance_to_point(&p2, point(on_other), true);
                worst[1] = worst[1].max(off_box.max(off_other));
                assert!(
                    off_box < 1.0e-5 && off_other < 1.0e-5,
                    "case {case}: {off_box} {off_other}"
                );
            }
        }
        println!(
            "worst distance error {:e} m, worst point off its shape {:e} m",
            worst[0], worst[1]
        );
        assert!(
            apart > 1000 && answered >= 2 * apart,
            "{answered} answers, {apart} apart"
        );
    }

    /// A cross of two boxes as one mesh, jammed into a wall box at random
    /// poses, either side first: the composite contact that asks the later
    /// triangles only within the deepest overlap so far answers exactly as
    /// parry's own composite loop over the same dispatcher (every field
    /// bit for bit), and the cases are mostly overlaps.
    /// A contact settled for a touching pair's sample tells deeper than
    /// allowed, within the band, or beyond exactly as the full contact
    /// does (beyond: the same distance), for boxes and capsules resting on
    /// a fine flat mesh, boxes on a wavy heightfield and a cross mesh jammed
    /// into a wall, either order.
    #[test]
    fn settled_contacts_answer_as_the_full_contact() {
        let flat = grid(17, 0.25, |_, _| 0.0);
        let (_, field) = floors();
        let cross = cross_mesh(0.85, 0.05, 0.02);
        let wall = Cuboid::new(Vector::new(0.02, 2.0, 2.0));
        let slab = Cuboid::new(Vector::new(0.6, 0.05, 0.4));
        let capsule = Capsule::new_x(0.5, 0.05);
        let mut next = uniform(29u64);
        let mut classes = [0usize; 3];
        for case in 0..1200 {
            let (mesh, body, pose): (&dyn Shape, &dyn Shape, Pose) = if case % 4 == 3 {
                let at = Vector::new(6.0 * next() - 3.0, 0.6 * next() - 0.3, 6.0 * next() - 3.0);
                let tilt = Rotation::from_axis_angle(Vector::Z, 0.6 * next() - 0.3);
                (&field, &slab, Pose::from_parts(at, tilt))
            } else if case % 3 == 0 {
                let at = Vector::new(1.2 * next() - 0.6, 0.4 * next() - 0.2, 0.4 * next() - 0.2);
                let axis =
                    Vector::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vector::Z);
                let turn = Rotation::from_axis_angle(axis, 6.0 * next());
                (&cross, &wall, Pose::from_parts(at, turn))
            } else {
                let body: &dyn Shape = if case % 3 == 1 { &slab } else { &capsule };
                let at = Vector::new(
                    2.0 * next() - 1.0,
                    0.035 + 0.03 * next(),
                    2.0 * next() - 1.0,
                );
                let tilt = Rotation::from_axis_angle(Vector::X, 0.1 * next() - 0.05);
                (&flat, body, Pose::from_parts(at, tilt))
            };
            let band = f64::from(0.01 * next());
            let allowed = f64::from(0.02 * next());
            let prediction = (band + 1.0e-3) as f32;
            let settle = Some(Settle { band, allowed });
            let class = |d: Option<f32>| match d.map_or(f64::from(prediction), f64::from) {
                g if -g > allowed => 0,
                g if g <= band => 1,
                _ => 2,
            };
            for flip in [false, true] {
                let ground = Pose::IDENTITY;
                let (p1, s1, p2, s2) = if flip {
                    (&pose, body, &ground, mesh)
                } else {
                    (&ground, mesh, &pose, body)
                };
                let full = contact(p1, s1, p2, s2, prediction).unwrap().map(|c| c.dist);
                let settled = contact_settled(p1, s1, p2, s2, prediction, settle)
                    .unwrap()
                    .map(|c| c.dist);
                assert_eq!(
                    class(settled),
                    class(full),
                    "case {case}: {settled:?} vs {full:?}"
                );
                if class(full) == 2 {
                    assert_eq!(settled, full, "case {case}");
                }
                classes[class(full)] += 1;
            }
        }
        println!("deeper, within, beyond: {classes:?}");
        assert!(classes.iter().all(|&k| k > 300), "classes {classes:?}");
    }

    /// Every field of two contacts (or none) equal, bit for bit.
    fn same_answer(ours: Option<Contact>, loop_of_parry: Option<Contact>, case: usize) {
        assert_eq!(
            format!("{ours:?}"),
            format!("{loop_of_parry:?}"),
            "case {case}"
        );
    }

    /// Our contact of `a` with `b` at `pose`, and of `b` with `a` at its
    /// inverse, each the same as parry's loop over the same dispatcher
    /// (`forward`, `backward`, given the pose); returns the second.
    fn same_both_ways(
        case: usize,
        pose: &Pose,
        (a, b): (&dyn Shape, &dyn Shape),
        prediction: f32,
        forward: impl Fn(&Pose) -> Option<Contact>,
        backward: impl Fn(&Pose) -> Option<Contact>,
    ) -> Option<Contact> {
        let ours = AxesFirst.contact(pose, a, b, prediction).unwrap();
        same_answer(ours, forward(pose), case);
        let inverse = pose.inverse();
        let ours = AxesFirst.contact(&inverse, b, a, prediction).unwrap();
        same_answer(ours, backward(&inverse), case);
        ours
    }

    /// The same for a heightfield: boxes and triangles sunk into the wavy
    /// field at random, either side first, every field equal to parry's
    /// loop over the same dispatcher.
    #[test]
    fn heightfield_contacts_are_parrys_loop_exactly() {
        let (_, field) = floors();
        let slab = Cuboid::new(Vector::new(0.7, 0.1, 0.5));
        let triangle = Triangle::new(
            Vector::new(-0.6, 0.0, -0.4),
            Vector::new(0.7, 0.05, -0.3),
            Vector::new(0.0, -0.05, 0.8),
        );
        let mut next = uniform(13u64);
        let (mut overlaps, mut compared) = (0, 0);
        for case in 0..600 {
            let body: &dyn Shape = if case % 4 == 0 { &triangle } else { &slab };
            let at = Vector::new(6.0 * next() - 3.0, 0.8 * next() - 0.4, 6.0 * next() - 3.0);
            let axis =
                Vector::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vector::Y);
            let pose = Pose::from_parts(at, Rotation::from_axis_angle(axis, 6.0 * next()));
            let prediction = 0.01 * next();
            let ours = same_both_ways(
                case,
                &pose,
                (body, &field),
                prediction,
                |p| details::contact_shape_heightfield(&AxesFirst, p, body, &field, prediction),
                |p| details::contact_heightfield_shape(&AxesFirst, p, &field, body, prediction),
            );
            compared += 1;
            overlaps += usize::from(ours.is_some_and(|c| c.dist < 0.0));
        }
        assert!(
            overlaps * 4 > compared,
            "only {overlaps} of {compared} overlap"
        );
    }

    #[test]
    fn composite_contacts_are_parrys_loop_exactly() {
        let cross = cross_mesh(0.85, 0.05, 0.02);
        let wall = Cuboid::new(Vector::new(0.02, 2.0, 2.0));
        let mut next = uniform(11u64);
        let (mut overlaps, mut compared) = (0, 0);
        for case in 0..600 {
            let at = Vector::new(1.2 * next() - 0.6, 0.4 * next() - 0.2, 0.4 * next() - 0.2);
            let axis =
                Vector::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vector::Z);
            let pose = Pose::from_parts(at, Rotation::from_axis_angle(axis, 6.0 * next()));
            let prediction = 0.01 * next();
            let ours = same_both_ways(
                case,
                &pose,
                (&wall, &cross),
                prediction,
                |p| {
                    details::contact_shape_composite_shape(&AxesFirst, p, &wall, &cross, prediction)
                },
                |p| {
                    details::contact_composite_shape_shape(&AxesFirst, p, &cross, &wall, prediction)
                },
            );
            compared += 1;
            overlaps += usize::from(ours.is_some_and(|c| c.dist < 0.0));
        }
        assert!(
            overlaps * 2 > compared,
            "only {overlaps} of {compared} overlap"
        );
    }

    #[test]
    fn composite_contacts_match_parrys() {
        let (mesh, field) = floors();
        let floors: [&dyn Shape; 2] = [&mesh, &field];
        let mut next = uniform(5u64);
        let (mut touching, mut differ) = (0, 0);
        for case in 0..1500 {
            let floor = floors[case % 2];
            let body: Box<dyn Shape> = if case % 5 == 0 {
                Box::new(Ball::new(0.3))
            } else {
                Box::new(Cuboid::new(Vector::new(0.4, 0.2, 0.3)))
            };
            let at = Vector::new(6.0 * next() - 3.0, 0.9 * next() - 0.4, 6.0 * next() - 3.0);
            let axis =
                Vector::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vector::Y);
            let pose = Pose::from_parts(at, Rotation::from_axis_angle(axis, 6.0 * next()));
            let ground = Pose::IDENTITY;
            let prediction = 0.05;
            for flip in [false, true] {
                let (p1, s1, p2, s2) = if flip {
                    (&pose, body.as_ref(), &ground, floor)
                } else {
                    (&ground, floor, &pose, body.as_ref())
                };
                let ours = contact(p1, s1, p2, s2, prediction).expect("supported");
                let parry =
                    rapier3d::parry::query::contact(p1, s1, p2, s2, prediction).expect("supported");
                match (ours, parry) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        touching += 1;
                        if (a.dist - b.dist).abs() > 1.0e-4 {
                            differ += 1;
                            // Only where parry's EPA stopped short of the depth.
                            assert!(
                                a.dist < b.dist,
                                "case {case}: {} vs parry {}",
                                a.dist,
                                b.dist
                            );
                        } else {
                            assert!(
                                a.normal1.dot(b.normal1) > 0.99 || a.dist.abs() < 1.0e-3,
                                "case {case}: normal {:?} vs parry {:?}",
                                a.normal1,
                                b.normal1
                            );
                        }
                    }
                    (a, b) => panic!("case {case}: ours {a:?}, parry {b:?}"),
                }
            }
        }
        println!("{touching} touching pairs, {differ} off parry's depth");
        assert!(
            touching > 500 && differ * 20 < touching,
            "{touching} touching, {differ} differ"
        );
    }
}
