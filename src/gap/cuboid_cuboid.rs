//! Cuboid against cuboid: the 15 separating axes. They are exact for
//! touching, not for distance, so `gap::build` sends here only borderless
//! boxes with zero skin; with a skin or a round border the corners would
//! count as close up to √3 times too early, and those pairs go to the
//! adaptive family (`support_map.rs`).
//!
//! Everything is seen from box `a`'s frame: `R = R_aᵀR_b` (columns are
//! `b`'s axes) and `t = R_aᵀ(t_b − t_a)`, except the centres' offset along
//! `b`'s own axes, `t·R_j`, read from the world poses as `(t_b − t_a)·b_j`
//! (`a`'s turn then enters it once, not twice). For an axis `L` the boxes are
//! apart by more than `s` when `|t·L| − r_a(L) − r_b(L) > s·|L|`, with
//! `r(L) = Σ e_i·|L·axis_i|` each box's reach. The axes are `a`'s 3 face
//! normals, `b`'s 3, and the 9 edge cross products `a_i × b_j`, kept
//! unnormalised (docs/design.md §4): for nearly parallel edges `|L| → 0` and the
//! axis tends to `−s ≤ 0`, which never separates falsely. Every `|L| ≤ 1`
//! (up to the orthonormality pad), so `s·1` stands for `s·|L|`.
//!
//! The edge axes use `R_j × R_k = R_l` for the columns of a rotation (the
//! classic OBB form); the true `R` is a rotation, and the enclosure of the
//! formula contains the formula at the true `R`.

use super::support::{ORTHO_SLACK, box_reach, padded_extent};
use super::{Exact, Middle, Relative, Side};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use crate::motion::{column, row};
use nalgebra::Vector3;

#[derive(Clone, Debug)]
pub(crate) struct CuboidCuboid {
    half_a: Vector3<f64>,
    half_b: Vector3<f64>,
    /// `skin + border_a + border_b` plus the orthonormality pad, metres.
    skin: f64,
    /// `half_a[i] + skin` and `half_b[j] + skin`, rounded up.
    face_a: [f64; 3],
    face_b: [f64; 3],
}

impl CuboidCuboid {
    pub const AXES: usize = 15;

    pub fn new(
        half_a: Vector3<f64>,
        border_a: f64,
        half_b: Vector3<f64>,
        border_b: f64,
        skin: f64,
    ) -> CuboidCuboid {
        let total = up(up(skin + border_a) + border_b);
        let lengths = up(up(half_a.norm() + half_b.norm()) + total);
        let skin = up(total + up(ORTHO_SLACK * lengths));
        CuboidCuboid {
            half_a,
            half_b,
            skin,
            face_a: [0, 1, 2].map(|i| up(half_a[i] + skin)),
            face_b: [0, 1, 2].map(|j| up(half_b[j] + skin)),
        }
    }

    /// A positive lower bound of the gap beyond the skin over `span`, from
    /// the exact poses at its middle and no enclosed pose (as
    /// `SupportMap::apart_from_middle`, for a fast spin's pieces): the
    /// boxes' gap there along the best of their 15 axes, in plain `f64`,
    /// less how fast the gap along that direction can close
    /// ([`crate::motion::SpeedAlong`]) times the half-width. `None` where
    /// that is not positive.
    pub fn apart_from_middle(&self, span: TimeSpan, a: Exact, b: Exact) -> Option<f64> {
        let (ha, hb) = (self.half_a, self.half_b);
        let extents = (padded_extent(ha.norm()), padded_extent(hb.norm()));
        let middle = Middle::new(span, a, b, extents);
        // `b`'s axes in `a`'s frame, and its centre.
        let r = middle.rel.rotation.to_rotation_matrix().into_inner();
        let t = middle.rel.translation.vector;
        // The gap along the unit axis `l / |l|`, from `a` towards `b`.
        let along = |l: Vector3<f64>| {
            let n = l.try_normalize(1.0e-6)?;
            let n = if n.dot(&t) < 0.0 { -n } else { n };
            let gap = n.dot(&t) - box_reach(&ha, &n) - box_reach(&hb, &(r.transpose() * n));
            Some((gap, n))
        };
        let mut best: Option<(f64, Vector3<f64>)> = None;
        let mut consider = |l: Vector3<f64>| {
            if let Some((gap, n)) = along(l)
                && best.is_none_or(|(g, _)| gap > g)
            {
                best = Some((gap, n));
            }
        };
        for i in 0..3 {
            consider(Vector3::ith(i, 1.0));
            consider(r.column(i).into_owned());
        }
        for i in 0..3 {
            for j in 0..3 {
                consider(Vector3::<f64>::ith(i, 1.0).cross(&r.column(j)));
            }
        }
        let (gap, n) = best?;
        middle.apart(gap, self.skin, &(middle.ia.rotation * n))
    }

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
        let (r, t) = (rel.rotation, rel.translation);
        let abs = r.map(|x| x.abs());
        let (ea, eb) = (&self.half_a, &self.half_b);
        // a's faces: L = e_i.
        for i in 0..3 {
            if axes >> i & 1 != 0 {
                let rb = E::dot_f64(row(&abs, i), [eb.x, eb.y, eb.z]);
                out[i] = t[i].abs() - rb - self.face_a[i];
            }
        }
        if super::apart_by(out, axes, 0b111) {
            return;
        }
        // b's faces: L = R_j. The centres' offset along it from the world
        // poses, `(t_b − t_a)·b_j`: `t·R_j` is the same product with `a`'s
        // turn entering twice, once in each factor.
        let d = b.pose.translation - a.pose.translation;
        for j in 0..3 {
            if axes >> (3 + j) & 1 != 0 {
                let tl = E::dot([d.x, d.y, d.z], column(&b.pose.rotation, j));
                let ra = E::dot_f64(column(&abs, j), [ea.x, ea.y, ea.z]);
                out[3 + j] = tl.abs() - ra - self.face_b[j];
            }
        }
        if super::apart_by(out, axes, 0b111_000) {
            return;
        }
        // Edges: L = e_i × R_j.
        for i in 0..3 {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            for j in 0..3 {
                let k = 6 + 3 * i + j;
                if axes >> k & 1 == 0 {
                    continue;
                }
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                let tl = E::dot([t[i2], -t[i1]], [r[(i1, j)], r[(i2, j)]]);
                let ra = E::dot_f64([abs[(i2, j)], abs[(i1, j)]], [ea[i1], ea[i2]]);
                let rb = E::dot_f64([abs[(i, j2)], abs[(i, j1)]], [eb[j1], eb[j2]]);
                out[k] = tl.abs() - ra - rb - self.skin;
            }
        }
    }
}
