//! Ball against ball: the write-up's equation (1).
//!
//! `D(τ) = |c_a(τ) − c_b(τ)|² − (r_a + r_b + skin)²`, one exact axis. The
//! squared form needs no square root, and the difference of the centres is
//! formed before squaring so that large, shared world coordinates cancel.

use super::Side;
use crate::enclosure::rounding::up;
use crate::enclosure::{Enclosure, TimeSpan};

/// Two balls centred on their frames' origins.
#[derive(Clone, Debug)]
pub(crate) struct BallBall {
    /// `(r_a + r_b + skin)²`, metres².
    reach_sq: f64,
}

impl BallBall {
    pub const AXES: usize = 1;

    pub fn new(radius_a: f64, radius_b: f64, skin: f64) -> BallBall {
        // Rounded up: a larger reach only makes the gap smaller (sound).
        let reach = up(up(radius_a + radius_b) + skin);
        BallBall {
            reach_sq: up(reach * reach),
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
        let d = a.pose.translation - b.pose.translation;
        out[0] = d.x.sqr() + d.y.sqr() + d.z.sqr() - self.reach_sq;
    }
}
