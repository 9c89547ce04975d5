//! Vertex–face and edge–edge: the two primitives of mesh–mesh contact.
//!
//! Two triangle meshes first touch where a vertex of one meets a face of the
//! other or an edge of one meets an edge of the other. This file holds the
//! axis functions of both primitives, written over *enclosed points* so that
//! the same code serves
//! - the standard CCD queries for linearly moving vertices
//!   (`query::vertex_face_toi`, `query::edge_edge_toi`): each vertex is
//!   given at `t0` and `t1` and moves on the straight line between; and
//! - the leaf gaps of rigid meshes (`triangle_triangle.rs`, `ball_triangle.rs`),
//!   whose vertices follow their body's rotation.
//!
//! ## Axes
//!
//! Every axis is a separating-axis value: `> 0` proves the primitives farther
//! apart than `skin` at every time of the node. None is normalised (docs/design.md
//! §4): a direction that degenerates to zero gives an axis of zero, which
//! never separates falsely. The skin is scaled by the direction's length
//! (enclosed by its square root, or by its 1-norm when that fails).
//!
//! Vertex `p` against triangle `f0 f1 f2`, with `n = (f1 − f0) × (f2 − f0)`
//! (a quadratic in τ for linear vertices), 6 axes:
//! - `±n·(p − f0) − skin·|n|`: the triangle's plane, each side;
//! - `(e_i × n)·(p − f_i) − skin·|e_i × n|`, `e_i = f_{i+1} − f_i`: the three
//!   edge planes, perpendicular to the face through each edge, outward
//!   (a quartic in τ). With the plane axes they are complete for `skin = 0`:
//!   `p` lies on the triangle exactly when none is positive;
//! - an *adaptive* axis (docs/design.md §5): the direction `w` from the closest
//!   point of the triangle to `p` at the node's middle time, computed in
//!   `f64` and held constant on the node: `w·p − max_i w·f_i − skin·|w|`.
//!   It makes the set tight for `skin > 0` and for degenerate (sliver)
//!   triangles, whose `n` vanishes.
//!
//! Edge `a0 a1` against edge `b0 b1`, with `n = (a1 − a0) × (b1 − b0)`, 7 axes:
//! - `±n·(b0 − a0) − skin·|n|`: the plane through `a` parallel to `b`;
//! - for `m_a = (a1 − a0) × n` (perpendicular to `a` within that plane):
//!   `min(±m_a·(b0 − a0), ±m_a·(b1 − a0)) − skin·|m_a|`: both ends of `b` on
//!   one side of the plane through `a` normal to `m_a`; the same for `m_b`
//!   with the ends of `a`. Complete for `skin = 0` when the edges are not
//!   parallel;
//! - an adaptive axis along the closest-points direction at the node's
//!   middle, which also covers parallel edges (`n = 0`).
//!
//! Soundness needs only that each axis bounds a true separation from below;
//! which directions are chosen, and whether the set is complete, decides
//! only how tight the answer is.

use crate::enclosure::Enclosure;
use crate::enclosure::rounding::{bound, up};
use nalgebra::Vector3;

/// Axes of a vertex against a triangle.
pub(crate) const VERTEX_FACE_AXES: usize = 6;
/// Axes of an edge against an edge.
pub(crate) const EDGE_EDGE_AXES: usize = 7;

/// `a × b` over enclosures.
pub(crate) fn cross<E: Enclosure>(a: &Vector3<E>, b: &Vector3<E>) -> Vector3<E> {
    Vector3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

/// `a · b` over enclosures.
pub(crate) fn dot<E: Enclosure>(a: &Vector3<E>, b: &Vector3<E>) -> E {
    a.x * b.x + a.y * b.y + a.z * b.z
}

/// `w · a` for a constant direction `w`.
pub(crate) fn dot_const<E: Enclosure>(w: &Vector3<f64>, a: &Vector3<E>) -> E {
    a.x * w.x + a.y * w.y + a.z * w.z
}

/// `skin · |v|` enclosed (zero when the skin is): the square root of the
/// squared norm, or the 1-norm (an upper bound) when the root fails.
pub(crate) fn skin_norm<E: Enclosure>(v: &Vector3<E>, skin: f64) -> E {
    if skin == 0.0 {
        return E::zero();
    }
    let norm = (v.x.sqr() + v.y.sqr() + v.z.sqr())
        .sqrt()
        .unwrap_or_else(|_| v.x.abs() + v.y.abs() + v.z.abs());
    norm * skin
}

/// An upper bound on `skin · |w|` for a constant `w` and a skin `≥ 0` (the
/// queries take no other): the sum of squares bounded once ([`bound`], a
/// multiply and an add), the correctly rounded root rounded up, and the
/// product with the skin bounded once more, where a `next_up` after every
/// operation cost a ball–triangle pair's construction a third of its
/// instructions (`rain_dt10`).
pub(crate) fn skin_norm_const(w: &Vector3<f64>, skin: f64) -> f64 {
    if skin == 0.0 {
        return 0.0;
    }
    let sq = bound(w.x * w.x + w.y * w.y + w.z * w.z);
    bound(up(sq.sqrt()) * skin)
}

/// The vertex–face axes of `p` against `f`, for the axes set in `axes`.
/// `w` is the adaptive direction (from the triangle towards `p`), if any.
pub(crate) fn vertex_face_axes<E: Enclosure>(
    p: &Vector3<E>,
    f: &[Vector3<E>; 3],
    skin: f64,
    w: Option<&Vector3<f64>>,
    axes: u64,
    out: &mut [E],
) {
    if axes & 0b11_1111 == 0 {
        return;
    }
    let e = [f[1] - f[0], f[2] - f[1], f[0] - f[2]];
    let n = cross(&e[0], &(f[2] - f[0]));
    if axes & 0b11 != 0 {
        let side = dot(&n, &(p - f[0]));
        let s = skin_norm(&n, skin);
        out[0] = side - s;
        out[1] = -side - s;
    }
    for i in 0..3 {
        if axes >> (2 + i) & 1 == 1 {
            let m = cross(&e[i], &n);
            out[2 + i] = dot(&m, &(p - f[i])) - skin_norm(&m, skin);
        }
    }
    if axes >> 5 & 1 == 1 {
        out[5] = vertex_face_adaptive(p, f, skin, w);
    }
}

/// The vertex–face axis along the adaptive direction `w` (from the
/// triangle `f` towards `p`): `p`'s height over the triangle's farthest
/// corner along `w`, less the skin; zero (never apart) without one.
pub(crate) fn vertex_face_adaptive<E: Enclosure>(
    p: &Vector3<E>,
    f: &[Vector3<E>; 3],
    skin: f64,
    w: Option<&Vector3<f64>>,
) -> E {
    match w {
        Some(w) => {
            let top = dot_const(w, &f[0])
                .max(dot_const(w, &f[1]))
                .max(dot_const(w, &f[2]));
            dot_const(w, p) - top - skin_norm_const(w, skin)
        }
        None => E::zero(),
    }
}

/// The edge–edge axes of `a` against `b`, for the axes set in `axes`.
/// `w` is the adaptive direction (from edge `a` towards edge `b`), if any.
pub(crate) fn edge_edge_axes<E: Enclosure>(
    a: &[Vector3<E>; 2],
    b: &[Vector3<E>; 2],
    skin: f64,
    w: Option<&Vector3<f64>>,
    axes: u64,
    out: &mut [E],
) {
    if axes & 0b111_1111 == 0 {
        return;
    }
    let ea = a[1] - a[0];
    let eb = b[1] - b[0];
    let n = cross(&ea, &eb);
    let (b0, b1) = (b[0] - a[0], b[1] - a[0]);
    if axes & 0b11 != 0 {
        let side = dot(&n, &b0);
        let s = skin_norm(&n, skin);
        out[0] = side - s;
        out[1] = -side - s;
    }
    if axes & 0b1100 != 0 {
        let m = cross(&ea, &n);
        let (s0, s1) = (dot(&m, &b0), dot(&m, &b1));
        let s = skin_norm(&m, skin);
        out[2] = s0.min(s1) - s;
        out[3] = (-s0).min(-s1) - s;
    }
    if axes & 0b11_0000 != 0 {
        let m = cross(&eb, &n);
        let (a0, a1) = (a[0] - b[0], a[1] - b[0]);
        let (s0, s1) = (dot(&m, &a0), dot(&m, &a1));
        let s = skin_norm(&m, skin);
        out[4] = s0.min(s1) - s;
        out[5] = (-s0).min(-s1) - s;
    }
    if axes >> 6 & 1 == 1 {
        out[6] = match w {
            Some(w) => {
                let low_b = dot_const(w, &b[0]).min(dot_const(w, &b[1]));
                let top_a = dot_const(w, &a[0]).max(dot_const(w, &a[1]));
                low_b - top_a - skin_norm_const(w, skin)
            }
            None => E::zero(),
        };
    }
}

/// The point of triangle `a b c` closest to `p` (Ericson, *Real-Time
/// Collision Detection*, 5.1.5), in plain `f64`: used only to choose
/// adaptive directions.
pub(crate) fn closest_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> Vector3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 != 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 != 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 && (d4 - d3) + (d5 - d6) != 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 || !denom.is_finite() {
        // A degenerate triangle: fall back to its nearest vertex.
        return *[a, b, c]
            .into_iter()
            .min_by(|x, y| (p - *x).norm_squared().total_cmp(&(p - *y).norm_squared()))
            .unwrap_or(a);
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// The closest points of segments `p1 q1` and `p2 q2` (Ericson 5.1.9), in
/// plain `f64`, for adaptive directions.
pub(crate) fn closest_segment_segment(
    p1: &Vector3<f64>,
    q1: &Vector3<f64>,
    p2: &Vector3<f64>,
    q2: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    const TINY: f64 = 1.0e-300;
    let (s, t);
    if a <= TINY && e <= TINY {
        return (*p1, *p2);
    }
    if a <= TINY {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= TINY {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    (p1 + d1 * s, p2 + d2 * t)
}

/// A usable direction `to − from`, or `None` when it vanishes or is not
/// finite.
pub(crate) fn direction(from: &Vector3<f64>, to: &Vector3<f64>) -> Option<Vector3<f64>> {
    let w = to - from;
    let n = w.norm();
    (n > 0.0 && n.is_finite()).then(|| w / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `skin_norm_const` is an upper bound of `skin·|w|`, and a tight one:
    /// on vectors whose length is exact (integer quadruples `a² + b² + c² =
    /// d²`, scaled by powers of two) against skins of every size, it is at
    /// least the exact product and within a few parts in 10¹³ of it.
    #[test]
    fn skin_norm_const_bounds_the_exact_product_from_above() {
        let quadruples = [
            (1.0, 2.0, 2.0, 3.0),
            (2.0, 3.0, 6.0, 7.0),
            (1.0, 4.0, 8.0, 9.0),
        ];
        let mut checked = 0;
        for (a, b, c, d) in quadruples {
            for scale in [-40, -7, 0, 5, 30].map(|k| 2f64.powi(k)) {
                for skin in [1.0e-9, 3.0e-4, 0.1, 0.7, 5.0, 1.0e6] {
                    let w = Vector3::new(a, -b, c) * scale;
                    let exact = d * scale * skin;
                    let got = skin_norm_const(&w, skin);
                    assert!(got >= exact, "{w:?} {skin}: {got} below {exact}");
                    assert!(
                        got - exact <= 4.0e-13 * exact + 4.0 * f64::MIN_POSITIVE,
                        "{w:?} {skin}: {got} far above {exact}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 90);
        assert_eq!(skin_norm_const(&Vector3::new(1.0, 2.0, 3.0), 0.0), 0.0);
    }

    #[test]
    fn closest_point_on_triangle_regions() {
        let (a, b, c) = (
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        );
        let q = |x, y, z| closest_on_triangle(&Vector3::new(x, y, z), &a, &b, &c);
        assert!((q(0.2, 0.2, 1.0) - Vector3::new(0.2, 0.2, 0.0)).norm() < 1e-15);
        assert_eq!(q(-1.0, -1.0, 0.0), a);
        assert_eq!(q(0.5, -1.0, 0.0), Vector3::new(0.5, 0.0, 0.0));
        assert_eq!(q(2.0, 2.0, 0.0), Vector3::new(0.5, 0.5, 0.0));
    }
}
