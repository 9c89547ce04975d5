//! Half-space against any convex shape: one exact axis.
//!
//! parry's half-space is `{x : n·x ≤ 0}` in its frame (`n` the outward
//! normal). With `m = R_a·n` the normal in the world, the convex shape's
//! lowest point along `m` is `t_b·m − h_b(−R_bᵀm)`, so
//!
//! ```text
//! D = m·(t_b − t_a) − h_b(−R_bᵀm) − skin·|n|
//! ```
//!
//! is `|n|` times the shape's signed distance to the plane minus the skin:
//! exact, so it separates as soon as the shape is off by more than the skin.

use super::Side;
use super::support::{Convex, ORTHO_SLACK, mul, norm_up};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use nalgebra::Vector3;

/// A half-space (side `a`) against a convex shape (side `b`).
#[derive(Clone, Debug)]
pub(crate) struct HalfSpaceConvex {
    /// The outward normal in the half-space's frame (not necessarily unit).
    normal: Vector3<f64>,
    /// `≥ |normal|`.
    norm: f64,
    other: Convex,
    /// `(skin + pad)·|n|`, rounded up, metres.
    skin: f64,
}

impl HalfSpaceConvex {
    pub const AXES: usize = 1;

    pub fn new(normal: Vector3<f64>, other: Convex, skin: f64) -> HalfSpaceConvex {
        let norm = norm_up(&normal);
        let pad = up(ORTHO_SLACK * up(other.extent() + skin));
        HalfSpaceConvex {
            normal,
            norm,
            other,
            skin: up(up(skin + pad) * norm),
        }
    }

    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        _span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        _axes: u64,
        out: &mut [E],
    ) {
        let m = mul(&a.pose.rotation, &self.normal);
        let delta = b.pose.translation - a.pose.translation;
        let along = E::dot([m.x, m.y, m.z], [delta.x, delta.y, delta.z]);
        let down = -b.pose.inverse_rotate(&m);
        out[0] = along - self.other.support(&down, self.norm) - self.skin;
    }
}
