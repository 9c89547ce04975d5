//! Ball against triangle: the vertex–face axes with the radius as skin.
//!
//! The ball touches the triangle when its centre comes within `r + skin` of
//! it, so the pair takes the axes of the vertex–face primitive of
//! `primitives.rs` with the centre as the vertex and `r + skin` as the
//! skin: the triangle's plane (each side), its three edge planes, and the
//! adaptive closest-point direction at the node's middle time (6 axes).
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
//! the face and edge normals are constants and each axis is linear in the
//! enclosed centre. They are prepared once, in plain `f64` (any direction
//! is a sound axis; the triangle's extent along it and its length are
//! rounded up), so a node costs five enclosed dot products and the
//! adaptive axis, instead of the vertex–face primitive's cross products and
//! enclosed square roots (rain: -13 % instructions a run).

use super::Side;
use super::primitives::{
    VERTEX_FACE_AXES, closest_on_triangle, direction, dot_const, skin_norm_const,
    vertex_face_adaptive,
};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub(crate) struct BallTriangle {
    corners: [Vector3<f64>; 3],
    reach: f64,
    /// The five fixed axes (the face normal, its opposite, the three edge
    /// normals in the face's plane, pointing out), each with the
    /// triangle's extent along it plus `reach` times its length, rounded
    /// up: the centre is apart along `u` when `u·c` exceeds that.
    fixed: [(Vector3<f64>, f64); 5],
}

impl BallTriangle {
    pub const AXES: usize = VERTEX_FACE_AXES;

    pub fn new(radius: f64, corners: [Vector3<f64>; 3], skin: f64) -> BallTriangle {
        let reach = up(radius + skin);
        let [f0, f1, f2] = corners;
        let n = (f1 - f0).cross(&(f2 - f0));
        let e = [f1 - f0, f2 - f1, f0 - f2];
        let normals = [n, -n, e[0].cross(&n), e[1].cross(&n), e[2].cross(&n)];
        // Any direction is a sound axis, so these are computed in plain
        // `f64`: only the triangle's extent along each (three roundings per
        // product term) and the skin times its length are bounded from
        // above.
        let fixed = normals.map(|u| {
            let along = |f: &Vector3<f64>| {
                let sum = u.dot(f);
                let size = u.x.abs() * f.x.abs() + u.y.abs() * f.y.abs() + u.z.abs() * f.z.abs();
                up(sum + up(4.0 * f64::EPSILON * size))
            };
            let top = along(&f0).max(along(&f1)).max(along(&f2));
            (u, up(top + skin_norm_const(&u, reach)))
        });
        BallTriangle {
            corners,
            reach,
            fixed,
        }
    }

    #[inline(never)]
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
        for (k, (u, limit)) in self.fixed.iter().enumerate() {
            if axes >> k & 1 == 1 {
                out[k] = dot_const(u, &centre) - *limit;
            }
        }
        if axes >> 5 & 1 == 1 {
            // The adaptive direction `w`, from the triangle towards the
            // centre's closest point at the node's middle.
            // Written out: `array::map` here was left a loop over a
            // partly initialised array in some builds.
            let [c0, c1, c2] = &self.corners;
            let f = [
                c0.map(E::constant),
                c1.map(E::constant),
                c2.map(E::constant),
            ];
            let w = self.direction(span, a, b);
            out[5] = vertex_face_adaptive(&centre, &f, self.reach, w.as_ref());
        }
    }

    fn direction<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
    ) -> Option<Vector3<f64>> {
        let mid = span.lo + 0.5 * (span.hi - span.lo);
        let (pa, pb) = (a.pose_at(mid), b.pose_at(mid));
        let centre = pb.inverse_transform_point(&pa.translation.vector.into());
        let [c0, c1, c2] = &self.corners;
        let closest = closest_on_triangle(&centre.coords, c0, c1, c2);
        direction(&closest, &centre.coords)
    }
}
