//! Ball against triangle: the vertex–face axes with the radius as skin.
//!
//! The ball touches the triangle when its centre comes within `r + skin` of
//! it, so the pair is the vertex–face primitive of `primitives.rs` with the
//! centre as the vertex and `r + skin` as the skin: the triangle's plane
//! (each side), its three edge planes, and the adaptive closest-point
//! direction at the node's middle time (6 axes).
//!
//! Why not the exact squared point–triangle distance: it is a minimum over
//! seven Voronoi regions, and enclosing a region switch over a node loses
//! the linear part that clipping needs. The separating axes are each smooth,
//! exact where they decide (the face axis in the face region, the adaptive
//! axis near the closest feature), and false positives can only occur
//! within the vertex/edge regions at near contact, where the adaptive axis
//! closes them as the node shrinks.
//!
//! Everything is computed in the triangle's frame: its corners are
//! constants there and only the centre moves, `c = R_tᵀ·(c_ball − t_t)`, so
//! the face and edge normals are exact constants and each axis is linear in
//! the enclosed centre.

use super::Side;
use super::primitives::{VERTEX_FACE_AXES, closest_on_triangle, direction, vertex_face_axes};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use crate::motion::Trajectory;
use nalgebra::Vector3;

/// A ball centred on its frame's origin against a triangle fixed in its
/// frame.
#[derive(Clone, Debug)]
pub(crate) struct BallTriangle {
    /// The triangle's corners in its frame, metres.
    corners: [Vector3<f64>; 3],
    /// `r + skin`, rounded up, metres.
    reach: f64,
}

impl BallTriangle {
    pub const AXES: usize = VERTEX_FACE_AXES;

    pub fn new(radius: f64, corners: [Vector3<f64>; 3], skin: f64) -> BallTriangle {
        BallTriangle {
            corners,
            reach: up(radius + skin),
        }
    }

    /// `a` is the ball, `b` the triangle's frame.
    pub fn eval<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let centre = b
            .pose
            .inverse_rotate(&(a.pose.translation - b.pose.translation));
        let f = self.corners.map(|v| v.map(E::constant));
        let w = self.direction(span, a, b);
        vertex_face_axes(&centre, &f, self.reach, w.as_ref(), axes, out);
    }

    /// From the triangle's closest point towards the centre at the node's
    /// middle time, in the triangle's frame.
    fn direction<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
    ) -> Option<Vector3<f64>> {
        let mid = span.lo + 0.5 * (span.hi - span.lo);
        let (pa, pb) = (a.motion.pose_at(mid), b.motion.pose_at(mid));
        let centre = pb.inverse_transform_point(&pa.translation.vector.into());
        let [c0, c1, c2] = &self.corners;
        let closest = closest_on_triangle(&centre.coords, c0, c1, c2);
        direction(&closest, &centre.coords)
    }
}
