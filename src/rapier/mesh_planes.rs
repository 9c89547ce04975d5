//! A convex body touching a still triangle mesh or heightfield: proved no
//! deeper than allowed over the whole step from the planes of the
//! triangles it can reach, instead of sampled (see [`stays_within_planes`]).

use super::backoff::pair_approaches_within;
use super::candidates::swept_aabb;
use crate::convert::{glam_from_vec, pose_from_iso, vec_from_glam};
use crate::motion::Trajectory;
use crate::query::ShapeMotion;
use nalgebra::{Point3, Vector3};
use rapier3d::parry::bounding_volume::BoundingVolume;
use rapier3d::parry::shape::{Triangle, TypedShape};
use smallvec::SmallVec;

/// Most triangles the body's box over the step may meet: a body that
/// reaches more is sampled as before.
const MAX_TRIANGLES: usize = 64;

/// Most distinct directions the proof bounds the body's approach along
/// (each costs one [`pair_approaches_within`]): a flat floor has one.
const MAX_DIRECTIONS: usize = 8;

/// Whether convex `moving`, touching the still mesh or heightfield
/// `target` at the step's start, gets no deeper than `allowed` (metres)
/// into it over the whole step.
///
/// parry's depth of the pair is its deepest triangle's, and a triangle's
/// depth (the least translation apart) is at most the overlap of the pair's
/// projections on the triangle's normal: how far the body reaches past the
/// triangle's plane on the side it mostly lies on. That overlap starts at
/// what the body's support gives at the start and grows by no more than the
/// body approaches the plane ([`pair_approaches_within`]), so the body
/// stays within `allowed` of every plane of the triangles its box over the
/// step meets (no other triangle can touch it). Triangles that share a
/// direction (a flat floor's) share one bound, with the least budget.
/// `false` when it cannot tell: a turning or moving target, more than
/// [`MAX_TRIANGLES`] triangles or [`MAX_DIRECTIONS`] directions, a
/// degenerate triangle, or a plane the body may sink too far past (a body
/// in a valley, whose far slope's plane cuts through it).
///
/// This is what lets a fast body sliding on a mesh (too many triangles on
/// its path to split it into triangle targets) skip the samples of
/// parry's contact that a pair touching at the start otherwise takes.
pub(super) fn stays_within_planes(
    moving: &ShapeMotion,
    target: &ShapeMotion,
    allowed: f64,
) -> bool {
    if !moving.shape.is_convex() || !target.motion.is_fixed() {
        return false;
    }
    let Some(support) = moving.shape.as_support_map() else {
        return false;
    };
    let mesh_pose = target.motion.pose_at(0.0);
    // Only triangles that meet the body's box over the step can touch it;
    // the margin covers the `f32` rounding of the boxes.
    let swept = swept_aabb(moving.shape, &moving.motion).loosened(1.0e-4);
    let local = swept.transform_by(&pose_from_iso(&mesh_pose.inverse()));
    let mut triangles: SmallVec<[Triangle; 16]> = SmallVec::new();
    match target.shape.as_typed_shape() {
        TypedShape::TriMesh(mesh) => {
            for i in mesh.bvh().intersect_aabb(&local) {
                if triangles.len() == MAX_TRIANGLES {
                    return false;
                }
                triangles.push(mesh.triangle(i));
            }
        }
        TypedShape::HeightField(field) => {
            // Its cells under the box, two triangles each, counted before
            // they are visited (a large field's would all be).
            let extent = local.extents();
            let across = |length: f32, cell: f32| (length / cell).ceil() + 1.0;
            let cells =
                across(extent.x, field.cell_width()) * across(extent.z, field.cell_height());
            if cells.is_nan() || 2.0 * cells > MAX_TRIANGLES as f32 {
                return false;
            }
            field.map_elements_in_local_aabb(&local, &mut |_, t| triangles.push(*t));
        }
        _ => return false,
    }
    let start = moving.motion.pose_at(0.0);
    // Far more than the `f64` rounding of the overlaps, computed on `f32`
    // data at these coordinates.
    let scale = start
        .translation
        .vector
        .amax()
        .max(mesh_pose.translation.vector.amax());
    let rounding = 1.0e-6 * (1.0 + scale);
    // The body's extent along a world direction at the start.
    let extent = |n: &Vector3<f64>| {
        let local = glam_from_vec(&(start.rotation.inverse() * n));
        let far = vec_from_glam(support.local_support_point(local));
        n.dot(&(start * Point3::from(far)).coords)
    };
    // Per direction (from the body towards the plane), the least budget.
    let mut directions: SmallVec<[(Vector3<f64>, f64); MAX_DIRECTIONS]> = SmallVec::new();
    for t in &triangles {
        let [a, b, c] = [t.a, t.b, t.c].map(|v| mesh_pose * Point3::from(vec_from_glam(v)));
        let Some(n) = (b - a).cross(&(c - a)).try_normalize(1.0e-12) else {
            return false;
        };
        let plane = n.dot(&a.coords);
        // How far the body reaches past the plane below it (along `-n`) and
        // above it (along `n`); the lesser is the side it lies on.
        let below = plane + extent(&-n);
        let above = extent(&n) - plane;
        let (towards, overlap) = if below <= above {
            (-n, below)
        } else {
            (n, above)
        };
        let budget = allowed - overlap - rounding;
        if budget < 0.0 {
            return false;
        }
        if let Some((_, least)) = directions.iter_mut().find(|(d, _)| *d == towards) {
            *least = least.min(budget);
        } else if directions.len() == MAX_DIRECTIONS {
            return false;
        } else {
            directions.push((towards, budget));
        }
    }
    directions
        .iter()
        .all(|(n, budget)| pair_approaches_within(moving, target, n, *budget))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Motion;
    use crate::query::{floors, grid};
    use crate::rapier::testing::{Numbers, flying};
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use rapier3d::parry::math::Vector;
    use rapier3d::parry::query::contact;
    use rapier3d::parry::shape::{Ball, Capsule, Cuboid, Shape};

    /// parry's depth of the pair at step fraction `tau` (0 when apart).
    fn depth_at(moving: &ShapeMotion, target: &ShapeMotion, tau: f64) -> f64 {
        let (p1, p2) = (
            pose_from_iso(&moving.motion.pose_at(tau)),
            pose_from_iso(&target.motion.pose_at(tau)),
        );
        contact(&p1, moving.shape, &p2, target.shape, 0.0)
            .expect("supported")
            .map_or(0.0, |c| -c.dist as f64)
    }

    /// A box sliding fast along a flat floor mesh, resting 1 mm deep in it:
    /// proved within 5 mm over the step (a box driven down into the
    /// floor is not, nor is one allowed less than its start depth).
    #[test]
    fn a_box_sliding_on_a_flat_floor_stays_within_its_planes() {
        let floor = grid(11, 1.0, |_, _| 0.0);
        let fixed = Motion::fixed(Isometry3::identity()).unwrap();
        let target = ShapeMotion {
            shape: &floor,
            motion: fixed,
        };
        let block = Cuboid::new(Vector::new(0.2, 0.2, 0.2));
        let slide = |down: f64| ShapeMotion {
            shape: &block,
            motion: flying(
                Vector3::new(-2.0, 0.199, 0.3),
                UnitQuaternion::identity(),
                Vector3::new(5.0, -down, 1.0),
                Vector3::zeros(),
                0.25,
            ),
        };
        assert!(stays_within_planes(&slide(0.0), &target, 0.005));
        assert!(!stays_within_planes(&slide(1.0), &target, 0.005));
        assert!(!stays_within_planes(&slide(0.0), &target, 0.0005));
    }

    /// Where the planes' proof answers, parry's depth sampled at 201 times
    /// over the step stays within the allowed depth: 3,000 boxes, balls
    /// and capsules touching a wavy floor (mesh and heightfield) at the
    /// start, sliding, bouncing and turning every way. It answers for a
    /// good share of them, or it would spare nothing.
    #[test]
    fn stays_within_planes_agrees_with_sampled_depths() {
        let mut rng = Numbers(0x5851_f42d_4c95_7f2d);
        let (mesh, field) = floors();
        let floors: [&dyn Shape; 2] = [&mesh, &field];
        let movers: [Box<dyn Shape>; 3] = [
            Box::new(Cuboid::new(Vector::new(0.3, 0.05, 0.2))),
            Box::new(Ball::new(0.2)),
            Box::new(Capsule::new_y(0.3, 0.1)),
        ];
        let fixed = Motion::fixed(Isometry3::identity()).unwrap();
        let (mut touching, mut answered) = (0, 0);
        for case in 0..3000 {
            let target = ShapeMotion {
                shape: floors[case % 2],
                motion: fixed,
            };
            let shape = &*movers[(case / 2) % 3];
            let (x, z) = (rng.next(-3.0, 3.0), rng.next(-3.0, 3.0));
            let turn = rng.vector(3.0);
            // Dropped onto the floor from above: the height where it first
            // touches, then a little into it.
            let probe = |y: f64| {
                let at = Isometry3::from_parts(
                    Translation3::new(x, y, z),
                    UnitQuaternion::from_scaled_axis(turn),
                );
                contact(
                    &pose_from_iso(&at),
                    shape,
                    &Default::default(),
                    target.shape,
                    0.0,
                )
                .expect("supported")
                .is_some()
            };
            let (mut above, mut below) = (2.0, -2.0);
            for _ in 0..40 {
                let mid = 0.5 * (above + below);
                if probe(mid) { below = mid } else { above = mid }
            }
            let at = Vector3::new(x, above - rng.next(0.0, 0.01), z);
            let dt = [1.0 / 60.0, 0.1][case % 2];
            let mut v = rng.vector(8.0);
            v.y *= 0.2;
            let moving = ShapeMotion {
                shape,
                motion: flying(
                    at,
                    UnitQuaternion::from_scaled_axis(turn),
                    v,
                    rng.vector(4.0),
                    dt,
                ),
            };
            touching += 1;
            let allowed = depth_at(&moving, &target, 0.0).max(0.005) + rng.next(0.0, 0.02);
            if !stays_within_planes(&moving, &target, allowed) {
                continue;
            }
            answered += 1;
            for k in 0..=200 {
                let tau = k as f64 / 200.0;
                let depth = depth_at(&moving, &target, tau);
                assert!(
                    depth <= allowed + 1.0e-4,
                    "case {case}: {depth} deep at {tau}, allowed {allowed}"
                );
            }
        }
        assert!(
            answered * 5 >= touching,
            "only {answered} of {touching} touching pairs answered"
        );
    }
}
