//! Cuboid against triangle: the 13 separating axes (zero skin, no border).
//!
//! Everything is seen from the box's frame, where the triangle's corners are
//! `v_i = R·c_i + t` (`R`, `t` the triangle's pose relative to the box). For
//! an axis `L` the shapes are apart when the triangle's projection
//! `[min_i L·v_i, max_i L·v_i]` and the box's `[−r, r]`, `r = Σ_k h_k·|L_k|`,
//! do not meet. The axes: the box's 3 face normals, the triangle's normal
//! `n = (v1 − v0) × (v2 − v0)` and the 9 crosses `e_k × (v_{j+1} − v_j)`, all
//! unnormalised (docs/design.md §4): near-parallel edges give `L ≈ 0`, never a
//! false separation. (Against a turning box the offset along the normal is
//! read from the world poses, where the box's turn enters it once, and the
//! edges are the triangle's own turned, not differences of enclosed
//! corners.) This set is complete for touching, so with zero skin
//! every axis `≤ 0` means the shapes touch: the family is exact. With a skin
//! or a border, corners would count as close early (as for two boxes), so
//! those pairs use the adaptive family.

use super::support::{ORTHO_SLACK, box_reach, padded_extent};
use super::{Exact, Middle, Relative, Side};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan, least_greatest};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub(crate) struct CuboidTriangle {
    half: Vector3<f64>,
    corners: [Vector3<f64>; 3],
    /// The orthonormality pad (the start rotation matrices are orthonormal
    /// to about 1e-15), metres: added to every projection gap.
    pad: f64,
    /// `pad·|L|` needs `|L|`: bounded by the lengths of the triangle's
    /// edges (`|e_k × f| ≤ |f|`) and its doubled area, taken from the
    /// triangle's own coordinates (rotation keeps them), rounded up.
    edge_len: [f64; 3],
    normal_len: f64,
    /// `(c1 − c0) × (c2 − c0)` in the triangle's frame.
    normal: Vector3<f64>,
    /// The edges `c_{j+1} − c_j` in the triangle's frame.
    edges: [Vector3<f64>; 3],
}

impl CuboidTriangle {
    pub const AXES: usize = 13;

    pub fn new(half: Vector3<f64>, corners: [Vector3<f64>; 3]) -> CuboidTriangle {
        let reach = half.norm() + corners.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let edges = [0, 1, 2].map(|j| corners[(j + 1) % 3] - corners[j]);
        let normal = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
        CuboidTriangle {
            half,
            corners,
            pad: up(ORTHO_SLACK * up(reach + 1.0)),
            edge_len: edges.map(|e| up(up(e.norm()) * (1.0 + 1e-12))),
            normal_len: up(up(normal.norm()) * (1.0 + 1e-12)),
            normal,
            edges,
        }
    }

    /// A positive lower bound of the gap over `span`, from the exact poses
    /// at its middle and no enclosed pose (as
    /// `SupportMap::apart_from_middle`, for a fast spin's pieces): the
    /// shapes' gap there along the best of their 13 axes, in plain `f64`,
    /// less how fast the gap along that direction can close
    /// ([`crate::motion::SpeedAlong`]) times the half-width. `None` where
    /// that is not positive. `a` is the cuboid, `b` the triangle.
    pub fn apart_from_middle(&self, span: TimeSpan, a: Exact, b: Exact) -> Option<f64> {
        let corners = self.corners.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let extents = (padded_extent(self.half.norm()), padded_extent(corners));
        let middle = Middle::new(span, a, b, extents);
        let rel = middle.rel;
        // The triangle's corners and edges in the box's frame.
        let v = self
            .corners
            .map(|c| rel * nalgebra::Point3::from(c))
            .map(|p| p.coords);
        let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
        let half = self.half;
        // The gap along the unit axis `l / |l|`, on whichever side of the
        // box the triangle lies.
        let along = |l: Vector3<f64>| {
            let n = l.try_normalize(1.0e-6)?;
            let reach = box_reach(&half, &n);
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    let x = n.dot(p);
                    (lo.min(x), hi.max(x))
                });
            Some((lo - reach).max(-hi - reach))
        };
        let mut best: Option<(f64, Vector3<f64>)> = None;
        let mut consider = |l: Vector3<f64>| {
            if let Some(gap) = along(l)
                && best.is_none_or(|(g, _)| gap > g)
            {
                best = Some((gap, l));
            }
        };
        consider(edges[0].cross(&edges[1]));
        for i in 0..3 {
            let e = Vector3::<f64>::ith(i, 1.0);
            consider(e);
            for edge in &edges {
                consider(e.cross(edge));
            }
        }
        let (gap, l) = best?;
        middle.apart(gap, self.pad, &(middle.ia.rotation * l.normalize()))
    }

    /// `a` is the cuboid, `b` the triangle.
    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        a: &Side<E>,
        b: &Side<E>,
        relative: &Relative<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let rel = relative.b_in_a(a, b);
        // Written out: `corners.map` moved each corner's enclosures through
        // a closure that was not inlined, a tenth of the evaluation.
        let c = &self.corners;
        let v = [
            rel.transform_point(&c[0]),
            rel.transform_point(&c[1]),
            rel.transform_point(&c[2]),
        ];
        let h = &self.half;
        // The gap along L given the triangle's projection `[lo, hi]` and the
        // box's reach.
        let gap = |(lo, hi): (E, E), reach: E, pad: f64| (lo - reach).max(-hi - reach) - pad;
        for k in 0..3 {
            if axes >> k & 1 != 0 {
                let corners = least_greatest(&[v[0][k], v[1][k], v[2][k]]);
                out[k] = gap(corners, E::constant(h[k]), self.pad);
            }
        }
        if super::apart_by(out, axes, 0b111) {
            return;
        }
        // The triangle's normal, turned from its own frame (tighter than
        // the cross product of two enclosed edges, and shared by the edge
        // axes below).
        let n = rel.rotate(&self.normal);
        if axes >> 3 & 1 != 0 {
            let reach = E::dot_f64([n.x.abs(), n.y.abs(), n.z.abs()], [h.x, h.y, h.z]);
            // The offset along the normal, `n·v₀`, from the world poses
            // where the box turns: in its frame the normal and the corner
            // each carry its turn, and their product counts it twice (a
            // slab tumbling onto terrain: a fifth fewer evaluations). Where
            // it does not, its frame's product is as tight and cheaper.
            let d = if a.motion.turns() {
                let nw = b.pose.rotate(&self.normal);
                let p0 = b.pose.transform_point(&c[0]) - a.pose.translation;
                E::dot([nw.x, nw.y, nw.z], [p0.x, p0.y, p0.z])
            } else {
                n.dot(&v[0])
            };
            out[3] = d.abs() - reach - up(self.pad * self.normal_len);
        }
        if super::apart_by(out, axes, 0b1000) {
            return;
        }
        // The edges turned from the triangle's frame, as the normal is: the
        // differences of the enclosed corners would carry the error of the
        // relative translation twice (a tenth fewer evaluations on a slab
        // landing on terrain).
        let e = &self.edges;
        let f = [rel.rotate(&e[0]), rel.rotate(&e[1]), rel.rotate(&e[2])];
        let zero = E::zero();
        for k in 0..3 {
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            // Along `L = e_k × f_j` edge `j`'s two corners project alike and
            // the third corner `n_k` further: `L·(v_{j+2} − v_j) =
            // e_k·(f_j × (v_{j+2} − v_j)) = e_k·n`. One projection per axis
            // instead of three (the identity holds for a rotation; the
            // start matrices' distance from one is within `pad`).
            let (nk_lo, nk_hi) = (n[k].min(zero), n[k].max(zero));
            for (j, fj) in f.iter().enumerate() {
                let axis = 4 + 3 * k + j;
                if axes >> axis & 1 == 0 {
                    continue;
                }
                // L = e_k × f_j: component k is 0, k1 is −f[k2], k2 is f[k1].
                let (l1, l2) = (-fj[k2], fj[k1]);
                let p = E::dot([l1, l2], [v[j][k1], v[j][k2]]);
                let reach = E::dot_f64([l1.abs(), l2.abs()], [h[k1], h[k2]]);
                let pad = up(self.pad * self.edge_len[j]);
                out[axis] = gap((p + nk_lo, p + nk_hi), reach, pad);
            }
        }
    }
}
