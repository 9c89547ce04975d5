//! Ball against cuboid (and against a round cuboid: its border joins the
//! ball's radius).
//!
//! In the box's frame the ball's centre is `p = R_bᵀ(c_a − t_b)`, and its
//! squared distance to the box is exactly `Σ max(|p_i| − e_i, 0)²`. Axis 0
//! is that minus `reach²` (`reach = r + border + skin`): exact, so it
//! separates as soon as the shapes are apart by more than the skin. Axes
//! 1–3 are the box's face slabs `|p_i| − e_i − reach`, cheaper and linear in
//! `p`, which clip nodes well while the ball is far off one face.

use super::Side;
use super::support::ORTHO_SLACK;
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};
use nalgebra::Vector3;

/// A ball (side `a`) against a box (side `b`).
#[derive(Clone, Debug)]
pub(crate) struct BallCuboid {
    /// The box's half-extents, metres.
    half: Vector3<f64>,
    /// `r + border + skin` plus the orthonormality pad, metres.
    reach: f64,
    /// `reach²`, rounded up, metres².
    reach_sq: f64,
}

impl BallCuboid {
    pub const AXES: usize = 4;

    pub fn new(radius: f64, half: Vector3<f64>, border: f64, skin: f64) -> BallCuboid {
        // The box frame's rotation is orthonormal only to ~1e-15: pad the
        // reach by a thousandfold of that share of the lengths involved.
        let lengths = up(up(radius + border) + up(skin + half.norm()));
        let reach = up(up(up(radius + border) + skin) + up(ORTHO_SLACK * lengths));
        BallCuboid {
            half,
            reach,
            reach_sq: up(reach * reach),
        }
    }

    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        _span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let p = b
            .pose
            .inverse_rotate(&(a.pose.translation - b.pose.translation));
        let outside = [
            p.x.abs() - self.half.x,
            p.y.abs() - self.half.y,
            p.z.abs() - self.half.z,
        ];
        if axes & 1 != 0 {
            let zero = E::zero();
            out[0] = outside[0].max(zero).sqr()
                + outside[1].max(zero).sqr()
                + outside[2].max(zero).sqr()
                - self.reach_sq;
        }
        for (k, o) in outside.iter().enumerate() {
            if axes >> (k + 1) & 1 != 0 {
                out[k + 1] = *o - self.reach;
            }
        }
    }
}
