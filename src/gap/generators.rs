//! The closest points of a cylinder or a cone and a box, through the
//! shape's straight generators, in plain `f64` and with no GJK.
//!
//! A cylinder is the union of the segments that join its two rims at the
//! same angle `φ`, a cone the union of the segments from its apex to its
//! rim: so the shape's distance to a box is the least, over `φ`, of one
//! segment's distance to the box, which `segment_box` gives in closed form.
//! That leaves a search in one variable: from a starting angle, Newton's
//! method on the distance's derivative in `φ`, which is `(p − q)·∂p/∂φ`
//! for the closest points `p` (on the segment) and `q` (in the box), since
//! `p` is the segment's closest point (the envelope theorem).
//!
//! A flat cap's inside, which no generator reaches, is tested first: where
//! the box's point deepest towards a cap lies over it, that point and its
//! foot on the cap are the closest points (as `face_box` has it for a
//! box's face).
//!
//! What the search finds is checked, not trusted: the gap of the shapes
//! along the found direction (their supports, exact) must match the
//! distance of the found points, which no two points of the shapes
//! undercut. So the direction is the closest points' one wherever it is
//! returned; where the search stalls, or found a minimum that is not the
//! least, it answers `Unknown` and the caller asks GJK. (parry's `f32`
//! GJK creeps along a rim or the cone's side: about 11 k instructions a
//! call on the queries bench's cylinder cases, most of a query's direction
//! cost.)

use super::support::{Convex, Core, box_reach};
use super::support_map::segment_box;
use nalgebra::{Isometry3, Vector3};

/// The most Newton steps. Measured on the queries bench's cylinder and cone
/// cases: 6 and 8 steps cost 2–5 % more instructions (more searches given
/// up, each then asking GJK), 20 about 1 % more.
const MOST_STEPS: usize = 12;

/// The found points' distance may exceed the gap along their direction by
/// this share of itself (and rounding): the direction is then as good as
/// the closest points' own, far better than parry's `f32` GJK, whose
/// distance bounds stop 0.3 % apart.
const AGREEMENT: f64 = 1.0e-6;

/// What [`round_box`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum RoundBox {
    /// The closest points: their unit direction, the round shape's and
    /// the box's.
    Apart {
        normal: Vector3<f64>,
        on_round: Vector3<f64>,
        on_box: Vector3<f64>,
    },
    /// A generator meets the box, or comes within 1e-9 of the shapes'
    /// sizes of it (closer than `f32` resolves): the shapes overlap, or
    /// as good as touch.
    Overlap,
    /// The search did not find the closest points (or the shapes are not
    /// a cylinder or cone and a box, both without a border).
    Unknown,
}

/// The closest-points direction (in the box's frame, from `round` towards
/// the box) of the cylinder or cone `round`, at `pose` in the box's frame,
/// and the box `box_convex`; `start`, if given, a nearby direction (the
/// same way) to start from.
pub(crate) fn round_box(
    round: &Convex,
    pose: &Isometry3<f64>,
    box_convex: &Convex,
    start: Option<&Vector3<f64>>,
) -> RoundBox {
    let Core::Cuboid(half) = &box_convex.core else {
        return RoundBox::Unknown;
    };
    if round.border != 0.0 || box_convex.border != 0.0 {
        return RoundBox::Unknown;
    }
    let (half_height, radius, cone) = match round.core {
        Core::Cylinder {
            half_height,
            radius,
        } => (half_height, radius, false),
        Core::Cone {
            half_height,
            radius,
        } => (half_height, radius, true),
        _ => return RoundBox::Unknown,
    };
    let r = pose.rotation.to_rotation_matrix();
    let (u, axis, v) = (
        r.matrix().column(0).into_owned(),
        r.matrix().column(1).into_owned(),
        r.matrix().column(2).into_owned(),
    );
    let centre = pose.translation.vector;
    // A flat cap facing the box over which the box's deepest point lies
    // (no generator reaches a cap's inside): that point and its foot on
    // the cap are exactly the gap along the cap's normal apart.
    let caps: &[f64] = if cone { &[-1.0] } else { &[-1.0, 1.0] };
    for &side in caps {
        let n = axis * side;
        let cap = centre + n * half_height;
        let deepest = Vector3::new(
            -half.x.copysign(n.x),
            -half.y.copysign(n.y),
            -half.z.copysign(n.z),
        );
        let height = (deepest - cap).dot(&n);
        let foot = deepest - n * height;
        if height > 0.0 && (foot - cap).norm_squared() <= radius * radius {
            return RoundBox::Apart {
                normal: n,
                on_round: foot,
                on_box: deepest,
            };
        }
    }
    // The generator at the angle `φ` whose cosine and sine are `(c, s)`
    // (its ends), how its points move with `φ` at a fixed segment
    // parameter `t` (`turn`, times `t` for a cone, whose apex stays) and
    // how that motion turns (`-out`, likewise).
    let generator = |(c, s): (f64, f64)| {
        let out = u * (radius * c) + v * (radius * s);
        let turn = v * (radius * c) - u * (radius * s);
        let rim = centre - axis * half_height + out;
        let ends = if cone {
            [centre + axis * half_height, rim]
        } else {
            [rim, rim + axis * (2.0 * half_height)]
        };
        (ends, out, turn)
    };
    // At `φ`: the closest points `p` (on the generator) and `q` (in the
    // box), and the first two derivatives in `φ` of half their squared
    // distance `f`. With `t` the segment parameter of `p` and `C` the
    // coordinates where `p` lies outside the box, `f = ½ Σ_C (s_i − q_i)²`
    // around `φ`; `f' = (p − q)·s_φ` (the envelope theorem), and `f''` is
    // `f_φφ`, less `f_tφ²/f_tt` where `t` is free to follow (inside the
    // segment).
    let at = |angle: (f64, f64)| {
        let (ends, out, turn) = generator(angle);
        let (p, q) = segment_box(&ends, half);
        let along = ends[1] - ends[0];
        let t = ((p - ends[0]).dot(&along) / along.norm_squared()).clamp(0.0, 1.0);
        // `s_φ`, `s_φφ` and `s_tφ` at `(t, φ)`.
        let (s_phi, s_phiphi, s_tphi) = if cone {
            (turn * t, -out * t, turn)
        } else {
            (turn, -out, Vector3::zeros())
        };
        let (mut f_pp, mut f_tp, mut f_tt) = (0.0, 0.0, 0.0);
        for i in 0..3 {
            let off = p[i] - q[i];
            if off != 0.0 {
                f_pp += s_phi[i] * s_phi[i] + off * s_phiphi[i];
                f_tp += s_phi[i] * along[i] + off * s_tphi[i];
                f_tt += along[i] * along[i];
            }
        }
        let free = t > 0.0 && t < 1.0 && f_tt > 0.0;
        let curvature = if free {
            f_pp - f_tp * f_tp / f_tt
        } else {
            f_pp
        };
        (p, q, (p - q).dot(&s_phi), curvature)
    };
    // The starting angle: the rim's point deepest along the start
    // direction, else towards the box's centre.
    let toward = start.copied().unwrap_or(-centre);
    let (x, z) = (toward.dot(&u), toward.dot(&v));
    let mut angle = match (x * x + z * z).sqrt() {
        0.0 => (1.0, 0.0),
        r => (x / r, z / r),
    };
    let scale = radius + half_height + half.norm() + centre.norm();
    let (mut p, mut q, mut slope, mut curvature) = at(angle);
    let mut converged = false;
    let (mut last_step, mut last_slope) = (0.0f64, 0.0f64);
    for _ in 0..MOST_STEPS {
        let d2 = (p - q).norm_squared();
        if d2 <= (1.0e-9 * scale).powi(2) {
            return RoundBox::Overlap;
        }
        // Flat in `φ`: a cone's apex nearest the box, or a minimum met.
        if slope == 0.0 {
            converged = true;
            break;
        }
        // Newton's step where `f` curves up, else a fixed one downhill; at
        // most about a quarter turn. A step too short to matter is not
        // taken: the points are then the closest ones to well within
        // rounding of the direction (Newton's steps shrink quadratically).
        let mut step = if curvature > 0.0 {
            -slope / curvature
        } else if last_step * slope < 0.0 {
            // Still downhill where `f` curves down: twice the last step.
            2.0 * last_step
        } else {
            -0.2f64.copysign(slope)
        };
        // The slope changed sign since the last point: the minimum lies
        // between the two, and a step that leaves that span (Newton's
        // overshooting at a kink, and then swinging back and forth) is
        // the secant's instead.
        if slope * last_slope < 0.0 && !(step * last_step < 0.0 && step.abs() < last_step.abs()) {
            step = -last_step * slope / (slope - last_slope);
        }
        // Steps that shrink only linearly: the distance nears zero at a
        // smooth minimum (a rim lying against a face), where its square
        // is flat to fourth order. Newton's step on the distance itself,
        // `-d'/d''` with `d' = f'/d` and `d'' = (f'' − d'²)/d`, is exact
        // there.
        if curvature > 0.0
            && step * last_step > 0.0
            && step.abs() > 0.3 * last_step.abs()
            && d2 < (0.01 * radius).powi(2)
        {
            let den = curvature * d2 - slope * slope;
            if den > 0.0 {
                step = -slope * d2 / den;
            }
        }
        let step = step.clamp(-0.8, 0.8);
        (last_step, last_slope) = (step, slope);
        if (step * radius).abs() <= 1.0e-9 * scale {
            converged = true;
            break;
        }
        // Turned by `atan(step)` rather than `step` (no sine or cosine):
        // the same to second order, which keeps Newton's convergence.
        let (c, s) = angle;
        let norm = (1.0 + step * step).sqrt();
        angle = ((c - s * step) / norm, (s + c * step) / norm);
        (p, q, slope, curvature) = at(angle);
    }
    let between = q - p;
    let distance = between.norm();
    if !converged || distance.is_nan() || distance <= 1.0e-9 * scale {
        return RoundBox::Unknown;
    }
    let n = between / distance;
    // The gap along `n`: the box's nearest reach less the round shape's
    // farthest, both exact.
    let gap = -box_reach(half, &n)
        - n.dot(&centre)
        - round.support_f64(&pose.rotation.inverse_transform_vector(&n));
    if gap >= distance * (1.0 - AGREEMENT) - 1.0e-12 * scale {
        RoundBox::Apart {
            normal: n,
            on_round: p,
            on_box: q,
        }
    } else {
        RoundBox::Unknown
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convert::pose64_from_iso;
    use parry3d_f64::math::{Pose as Pose64, Vector as Vec64};
    use parry3d_f64::shape::{Cone, Cuboid, Cylinder, Shape};
    use proptest::prelude::*;

    fn iso(at: [f64; 3], turn: [f64; 3]) -> Isometry3<f64> {
        Isometry3::new(Vector3::from(at), Vector3::from(turn))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// At random poses of a cylinder or cone about a box: a direction
        /// found is the closest points' one, and an overlap found is one.
        /// The gap along the direction (a lower bound of the distance) and
        /// the distance of the points found (an upper bound) agree, so both
        /// are the distance. parry3d-f64's distance, itself the distance of
        /// two of the shapes' points, is no smaller, and larger by at most
        /// 1e-3 of it: its GJK on a curved shape stops above the distance,
        /// by 1.1e-4 of it in the worst case seen (a cone; in another, a
        /// sweep of 2,000,000 generators matched the gap found here to
        /// 1e-12).
        #[test]
        fn round_box_finds_the_closest_points_or_says_it_did_not(
            cone in any::<bool>(),
            half_height in 0.05f64..1.0,
            radius in 0.05f64..1.0,
            half in prop::array::uniform3(0.05f64..1.0),
            at in prop::array::uniform3(-2.5f64..2.5),
            turn in prop::array::uniform3(-3.2f64..3.2),
            start in prop::option::of(prop::array::uniform3(-1.0f64..1.0)),
        ) {
            let core = if cone {
                Core::Cone { half_height, radius }
            } else {
                Core::Cylinder { half_height, radius }
            };
            let round = Convex { core, border: 0.0 };
            let cuboid = Convex { core: Core::Cuboid(Vector3::from(half)), border: 0.0 };
            let shape: Box<dyn Shape> = if cone {
                Box::new(Cone::new(half_height, radius))
            } else {
                Box::new(Cylinder::new(half_height, radius))
            };
            let box64 = Cuboid::new(Vec64::new(half[0], half[1], half[2]));
            let pose = iso(at, turn);
            let start = start.map(Vector3::from);
            let found = round_box(&round, &pose, &cuboid, start.as_ref());
            let distance = parry3d_f64::query::distance(
                &pose64_from_iso(&pose), shape.as_ref(), &Pose64::IDENTITY, &box64,
            )
            .unwrap()
            .distance;
            match found {
                RoundBox::Apart { normal: n, on_round, on_box } => {
                    prop_assert!((n.norm() - 1.0).abs() < 1.0e-12);
                    // The points are the shapes' (the box's within it, the
                    // round one's on a generator), `distance` apart.
                    prop_assert!((0..3).all(|i| on_box[i].abs() <= half[i]));
                    let local = pose.inverse_transform_vector(&(on_round - pose.translation.vector));
                    prop_assert!(local.y.abs() <= half_height * (1.0 + 1.0e-12));
                    let apart = (on_box - on_round).norm();
                    let gap = -box_reach(&Vector3::from(half), &n) - n.dot(&pose.translation.vector)
                        - round.support_f64(&pose.rotation.inverse_transform_vector(&n));
                    prop_assert!(
                        (gap - apart).abs() <= 1.0e-9 * (1.0 + apart),
                        "gap {gap} along the direction, points {apart} apart"
                    );
                    prop_assert!(
                        apart <= distance + 1.0e-9 && distance <= apart * (1.0 + 1.0e-3) + 1.0e-9,
                        "points {apart} apart, parry's distance {distance}"
                    );
                }
                RoundBox::Overlap => prop_assert!(distance <= 1.0e-6, "apart by {distance}"),
                RoundBox::Unknown => {}
            }
        }
    }

    /// Not vacuous: of 2,000 poses of a cone or a cylinder apart from a
    /// box, spread evenly (an additive recurrence in six dimensions), most
    /// get their direction here.
    #[test]
    fn most_poses_apart_are_answered() {
        // Steps of the recurrence: fractional parts of irrational numbers.
        let steps = [
            2f64.sqrt(),
            3f64.sqrt(),
            5f64.sqrt(),
            7f64.sqrt(),
            11f64.sqrt(),
            13f64.sqrt(),
        ];
        let spread = |case: usize, i: usize| (case as f64 * steps[i]).fract() * 2.0 - 1.0;
        let cuboid = Convex {
            core: Core::Cuboid(Vector3::new(0.6, 0.3, 0.9)),
            border: 0.0,
        };
        let (mut apart, mut answered) = (0, 0);
        for case in 0..2000 {
            let (half_height, radius) = (0.5, 0.3);
            let core = if case % 2 == 0 {
                Core::Cone {
                    half_height,
                    radius,
                }
            } else {
                Core::Cylinder {
                    half_height,
                    radius,
                }
            };
            let round = Convex { core, border: 0.0 };
            let at = [0, 1, 2].map(|i| spread(case, i) * 2.5);
            let turn = [3, 4, 5].map(|i| spread(case, i) * 3.2);
            let pose = iso(at, turn);
            match round_box(&round, &pose, &cuboid, None) {
                RoundBox::Apart { .. } => {
                    apart += 1;
                    answered += 1;
                }
                RoundBox::Unknown => apart += 1,
                RoundBox::Overlap => {}
            }
        }
        assert!(
            apart > 1000 && answered * 10 > apart * 8,
            "{answered} of {apart} answered"
        );
    }
}
