//! Ball against segment (a polyline's pieces).
//!
//! Three axes, in the segment's frame where its ends are constants:
//! - the two end planes: with `u = b − a`, `u·a − u·c − R·|u|` (the centre
//!   beyond `a`) and `u·c − u·b − R·|u|` (beyond `b`), `R = r + skin`;
//! - the adaptive direction `w` from the segment's closest point to the
//!   centre at the node's middle time: `w·c − max(w·a, w·b) − R·|w|`.
//!
//! The adaptive axis is exact at the middle time; the end planes catch the
//! cap regions early. The axes are sound for any directions (each bounds a
//! true separation), so a degenerate segment costs only tightness.

use super::Side;
use super::primitives::{closest_segment_segment, direction, dot_const, skin_norm_const};
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use nalgebra::Vector3;

/// A ball centred on its frame's origin against a segment fixed in its
/// frame.
#[derive(Clone, Debug)]
pub(crate) struct BallSegment {
    ends: [Vector3<f64>; 2],
    /// `r + skin`, rounded up, metres.
    reach: f64,
}

impl BallSegment {
    pub const AXES: usize = 3;

    pub fn new(radius: f64, ends: [Vector3<f64>; 2], skin: f64) -> BallSegment {
        BallSegment {
            ends,
            reach: up(radius + skin),
        }
    }

    /// `a` is the ball, `b` the segment's frame.
    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let c = b
            .pose
            .inverse_rotate(&(a.pose.translation - b.pose.translation));
        let [p, q] = self.ends;
        let ends = [p.map(E::constant), q.map(E::constant)];
        if axes & 0b11 != 0 {
            // u is rounded, but any direction is a valid axis.
            let u = q - p;
            let s = skin_norm_const(&u, self.reach);
            let (ua, ub, uc) = (
                dot_const(&u, &ends[0]),
                dot_const(&u, &ends[1]),
                dot_const(&u, &c),
            );
            out[0] = ua - uc - s;
            out[1] = uc - ub - s;
        }
        if axes >> 2 & 1 == 1 {
            let mid = span.lo + 0.5 * (span.hi - span.lo);
            let (pa, pb) = (a.pose_at(mid), b.pose_at(mid));
            let centre = pb
                .inverse_transform_point(&pa.translation.vector.into())
                .coords;
            let (closest, _) = closest_segment_segment(&p, &q, &centre, &centre);
            out[2] = match direction(&closest, &centre) {
                Some(w) => {
                    let top = dot_const(&w, &ends[0]).max(dot_const(&w, &ends[1]));
                    dot_const(&w, &c) - top - skin_norm_const(&w, self.reach)
                }
                None => E::zero(),
            };
        }
    }
}
