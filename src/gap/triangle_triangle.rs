//! Triangle against triangle, each fixed in its own moving frame: the leaf
//! gap of a moving mesh against a mesh (or a heightfield).
//!
//! Two triangles first touch vertex-to-face or edge-to-edge. The separating
//! axes of those primitives are the faces' normals and the cross products of
//! an edge of each, which is the classical triangle–triangle separating-axis
//! set; each axis is a projection gap
//! `min_j d·q_j − max_i d·p_i − skin·|d|` (each sign), 23 axes:
//! - `0, 1`: the normal of triangle `a`, computed in `a`'s frame where it is
//!   a constant (`b`'s corners brought into `a`'s frame);
//! - `2, 3`: the normal of triangle `b`, likewise in `b`'s frame;
//! - `4..22`: `e_i × f_j` for the 3 × 3 edge pairs, each sign, in `b`'s frame
//!   (`e_i` turns with the relative rotation; unnormalised, docs/design.md §4, so
//!   parallel edges give a zero axis that never separates falsely);
//! - `22`: the adaptive direction between the triangles' closest points at
//!   the node's middle time (also covers coplanar neighbours, for which the
//!   other axes degenerate).
//!
//! The first 22 are complete for `skin = 0` between non-degenerate triangles
//! that are not coplanar; the adaptive axis makes the set tight elsewhere.
//! Constant directions computed in `f64` carry rounding, which is harmless:
//! any direction is a valid axis as long as every projection along it is
//! enclosed, and they are.

use super::primitives::{
    closest_on_triangle, closest_segment_segment, cross, dot, skin_norm, skin_norm_const,
};
use super::{Relative, Side};
use crate::enclosure::{Enclosure, TimeSpan, least_greatest};
use crate::motion::Pose;
use nalgebra::{Isometry3, Vector3};

/// Two triangles, each in its own frame.
#[derive(Clone, Debug)]
pub(crate) struct TriangleTriangle {
    a: [Vector3<f64>; 3],
    b: [Vector3<f64>; 3],
    /// The face normals in their own frames (rounded; any direction is valid).
    normal_a: Vector3<f64>,
    normal_b: Vector3<f64>,
    skin: f64,
}

/// The projection gap of `q` beyond `p` along `d`, each sign: `(min d·q −
/// max d·p, min −d·q − max −d·p)`.
fn gaps<E: Enclosure>(d: &Vector3<E>, p: &[Vector3<E>; 3], q: &[Vector3<E>; 3]) -> (E, E) {
    let dp = p.map(|x| dot(d, &x));
    let dq = q.map(|x| dot(d, &x));
    let (p_lo, p_hi) = least_greatest(&dp);
    let (q_lo, q_hi) = least_greatest(&dq);
    (q_lo - p_hi, p_lo - q_hi)
}

fn corners<E: Enclosure>(pose: &Pose<E>, v: &[Vector3<f64>; 3]) -> [Vector3<E>; 3] {
    v.map(|x| pose.transform_point(&x))
}

impl TriangleTriangle {
    pub const AXES: usize = 23;

    pub fn new(a: [Vector3<f64>; 3], b: [Vector3<f64>; 3], skin: f64) -> TriangleTriangle {
        let normal = |t: &[Vector3<f64>; 3]| (t[1] - t[0]).cross(&(t[2] - t[0]));
        TriangleTriangle {
            normal_a: normal(&a),
            normal_b: normal(&b),
            a,
            b,
            skin,
        }
    }

    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        relative: &Relative<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let constant = |t: &[Vector3<f64>; 3]| t.map(|x| x.map(E::constant));
        if axes & 0b11 != 0 {
            let b_in_a = corners(&relative.b_in_a(a, b), &self.b);
            let d = self.normal_a.map(E::constant);
            let (plus, minus) = gaps(&d, &constant(&self.a), &b_in_a);
            let s = E::constant(skin_norm_const(&self.normal_a, self.skin));
            out[0] = plus - s;
            out[1] = minus - s;
        }
        if super::apart_by(out, axes, 0b11) {
            return;
        }
        let a_in_b = if axes >> 2 != 0 {
            let rel = relative.a_in_b(a, b);
            Some((rel, corners(&rel, &self.a)))
        } else {
            None
        };
        let Some((rel, a_in_b)) = a_in_b else {
            return;
        };
        let b_const = constant(&self.b);
        if axes & 0b1100 != 0 {
            let d = self.normal_b.map(E::constant);
            let (plus, minus) = gaps(&d, &a_in_b, &b_const);
            let s = E::constant(skin_norm_const(&self.normal_b, self.skin));
            out[2] = plus - s;
            out[3] = minus - s;
        }
        if super::apart_by(out, axes, 0b1100) {
            return;
        }
        for i in 0..3 {
            let pick = 0b11u64 << (4 + 6 * i);
            if axes & (pick | pick << 2 | pick << 4) == 0 {
                continue;
            }
            let ea = rel.rotate(&(self.a[(i + 1) % 3] - self.a[i]));
            for j in 0..3 {
                let k = 4 + 6 * i + 2 * j;
                if axes >> k & 0b11 == 0 {
                    continue;
                }
                let fb = (self.b[(j + 1) % 3] - self.b[j]).map(E::constant);
                let d = cross(&ea, &fb);
                let (plus, minus) = gaps(&d, &a_in_b, &b_const);
                let s = skin_norm(&d, self.skin);
                out[k] = plus - s;
                out[k + 1] = minus - s;
            }
        }
        if axes >> 22 & 1 == 1 {
            out[22] = match self.direction(span, a, b) {
                Some(w) => {
                    let s = skin_norm_const(&w, self.skin);
                    let (plus, _) = gaps(&w.map(E::constant), &a_in_b, &b_const);
                    plus - s
                }
                None => E::zero(),
            };
        }
    }

    /// From `a`'s closest point towards `b`'s at the node's middle time, in
    /// `b`'s frame; `None` when they meet.
    fn direction<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
    ) -> Option<Vector3<f64>> {
        let mid = span.lo + 0.5 * (span.hi - span.lo);
        let rel: Isometry3<f64> = b.pose_at(mid).inverse() * a.pose_at(mid);
        let pa = self.a.map(|x| rel.transform_point(&x.into()).coords);
        let pb = self.b;
        let mut best: Option<(f64, Vector3<f64>, Vector3<f64>)> = None;
        let mut consider = |p: Vector3<f64>, q: Vector3<f64>| {
            let d = (q - p).norm_squared();
            if best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, p, q));
            }
        };
        for v in &pa {
            consider(*v, closest_on_triangle(v, &pb[0], &pb[1], &pb[2]));
        }
        for v in &pb {
            consider(closest_on_triangle(v, &pa[0], &pa[1], &pa[2]), *v);
        }
        for i in 0..3 {
            for j in 0..3 {
                let (p, q) =
                    closest_segment_segment(&pa[i], &pa[(i + 1) % 3], &pb[j], &pb[(j + 1) % 3]);
                consider(p, q);
            }
        }
        let (_, p, q) = best?;
        super::primitives::direction(&p, &q)
    }
}
