//! Conservative advancement before the search, for pairs that turn fast.
//!
//! A pair whose sides turn by many radians in a step is searched in pieces
//! of half a radian each (`pairs::TURN_PER_NODE`): over a wider turn the
//! enclosures of the turned shapes are too loose to prove anything. Each
//! piece costs a full evaluation, so a miss at 1000 rad/s costs some
//! thirty of them, however far apart the shapes stay.
//!
//! At a single time the shapes' distance is cheap to bound from below:
//! along any unit direction `n` (here the closest points' normal then)
//! their projections are apart by at least
//! `n·t − h_a(n) − h_b(−Rᵀn)` (from their support points, less a pad for
//! rounding). And the distance shrinks no faster than the fastest relative
//! speed of two of their points ([`Motion::relative_speed_bound`]). So a
//! pair apart by `g` beyond the skin at `τ` stays so until `τ + g/speed`:
//! the search can start there. Repeated, this is conservative advancement
//! (parry's nonlinear cast); here it only moves the search's start,
//! stopping where its steps become short, near a contact, where the search
//! is better. Only pairs of polytopes with a triangle side that turn by
//! more than [`TURNING`] are advanced (see [`advances`]: where it was
//! measured to pay).
//!
//! [`Motion::relative_speed_bound`]: crate::motion::Motion::relative_speed_bound

use super::ShapeMotion;
use crate::convert::pose64_from_iso;
use crate::enclosure::TimeSpan;
use crate::enclosure::rounding::{down, up};
use crate::gap::{Convex, Core};
use crate::motion::Trajectory;
use nalgebra::{Isometry3, Vector3};
use parry3d_f64::math::{Pose as Pose64, Vector as Vec64};
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};

/// Pairs whose sides turn by less than this over the step, radians
/// together, are searched from the start. The search cuts a pair that
/// turns more into pieces of half a radian (`pairs::TURN_PER_NODE`), each
/// a full evaluation, which the advancement spares. Measured on the
/// queries bench's box–triangle cases at ordinary spins: 0.5 rad takes
/// 23 % fewer instructions than 3 rad (the gate until the advancement
/// took the speed along its direction and the search skipped its start
/// check), 1 rad 17 %; 0 (every pair) 24 %, but then boxes and slabs
/// resting on a mesh, which barely turn, stall at their first step and
/// pay for it (`slabs_on_terrain` 3 % more, `settle_flat` 2 %).
const TURNING: f64 = 0.5;

/// An advancement step shorter than this share of the step ends the
/// advancement; the search starts there. It also stays this far short of
/// where the pair is proved apart, so that at the search's start the pair
/// is clearly apart (by `STALL` times its relative speed beyond the
/// skin), not touching. Measured on the box–triangle cases at 200–1000
/// rad/s: 1/1024 of the step spares the most (1/256: two thirds as much,
/// 1/32: nothing).
const STALL: f64 = 1.0 / 1024.0;

/// A step along the last direction shorter than this share of the step
/// asks GJK for a better one. Measured on the box–triangle cases at
/// 200–1000 rad/s (with the speed along the direction): 4·`STALL` spares
/// the most (2·: 2 % more instructions and time; 8·: 1.5 % more
/// instructions).
const RETRY: f64 = 4.0 * STALL;

/// The most advancement steps for one pair.
const MOST_STEPS: u64 = 64;

/// How far GJK looks for the closest points, metres.
const PREDICTION: f64 = 1.0e6;

/// What the advancement found of a pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Advanced {
    /// A time at or after `span.lo` before which the pair provably stays
    /// farther apart than the skin: `span.lo` when the pair is not
    /// advanced (see [`advances`]) or it cannot tell, `span.hi` when the
    /// pair stays apart over the whole span.
    pub until: f64,
    /// Advancement steps taken.
    pub steps: u64,
    /// A later time at which the shapes overlap, if the guess made where
    /// the advancement stalled found one (see [`overlap_after`]): the
    /// pair's first impact is no later.
    pub overlap_at: Option<f64>,
}

/// How far the pair of `a` and `b` is proved apart from `span.lo` on, and
/// where they are found overlapping after that (see [`Advanced`]).
pub(super) fn apart_until(a: &ShapeMotion, b: &ShapeMotion, span: TimeSpan, skin: f64) -> Advanced {
    let mut advanced = Advanced {
        until: span.lo,
        steps: 0,
        overlap_at: None,
    };
    let Some((ca, cb)) = advances(a, b) else {
        return advanced;
    };
    // A hull's extent is a walk over its vertices: taken once.
    let (reach_a, reach_b) = (ca.extent(), cb.extent());
    let speed = a.motion.relative_speed_bound(reach_a, &b.motion, reach_b);
    let speed_along = a.motion.relative_speed_along(reach_a, &b.motion, reach_b);
    if !(speed > 0.0 && speed.is_finite()) {
        return advanced;
    }
    let mut tau = span.lo;
    // The last step's direction (`a`'s frame), tried first: GJK, which
    // finds a better one, costs far more than the projections.
    let mut last = None;
    let mut closest = Closest::default();
    while advanced.steps < MOST_STEPS {
        advanced.steps += 1;
        let (pa, pb) = (a.motion.pose_at(tau), b.motion.pose_at(tau));
        let at = At::new(&pa, &pb, reach_a + reach_b);
        // How far the pair may advance from `tau` along `n`: apart beyond
        // the skin until `tau + clear/speed`, less `STALL`.
        let step_along = |n: &Vector3<f64>| {
            let clear = down(at.gap_along(n, &ca, &cb) - skin);
            let along = pa.rotation * n;
            let speed = speed_along.at(&along).min(speed);
            down(down(clear / speed) * (1.0 - 1.0e-12)) - STALL
        };
        let mut step = last.as_ref().map_or(f64::NEG_INFINITY, step_along);
        if step < RETRY || step.is_nan() {
            let Some(n) = closest.normal(&at.rel, &ca, &cb) else {
                break;
            };
            step = step.max(step_along(&n));
            last = Some(n);
        }
        if step < STALL || step.is_nan() {
            if let Some(n) = last {
                let stalled = Stalled {
                    tau,
                    gap: at.gap_along(&n, &ca, &cb) - skin,
                    direction: pa.rotation * n,
                };
                advanced.overlap_at =
                    overlap_after(&stalled, a, b, (&ca, &cb), span.hi, &mut closest);
            }
            break;
        }
        tau += step;
        if tau >= span.hi {
            tau = span.hi;
            break;
        }
    }
    advanced.until = tau;
    advanced
}

/// The pair where its advancement stalled: at `tau`, apart by `gap`
/// beyond the skin along the world `direction`.
struct Stalled {
    tau: f64,
    gap: f64,
    direction: Vector3<f64>,
}

/// Over how long a share of the step [`overlap_after`] measures how fast
/// the gap closes. 1/64 and 1/1024 did as well on the queries bench's
/// box–triangle cases.
const CLOSING_SPAN: f64 = 1.0 / 256.0;

/// How many times the time the gap would take to close at its present
/// rate [`overlap_after`] looks ahead. Measured on the queries bench's
/// box–triangle cases, instructions against no guess (ordinary spins /
/// 200–1000 rad/s): 1.1 −5 % / −1 %, 1.3 −12 % / −6 %, 2 −27 % / −15 %,
/// 3 −29 % / −15 %, 5 −27 % / −12 %.
const OVERSHOOT: f64 = 3.0;

/// A time after the stall at which the shapes overlap, if a guess finds
/// one (GJK in `f64` at a single time), else `None`.
///
/// Where the advancement stalls, its speed bound, which holds for every
/// point and direction, runs far ahead of how fast the gap truly closes,
/// and each step gains little: near a contact the search is better. It
/// starts at the stall, and it may stop wherever the shapes are found
/// overlapping, since the first impact is no later: a search over a span
/// that ends just past the contact takes one or two evaluations where one
/// over the rest of the step took four to six. The guess is unsound (the
/// gap along a fixed direction, its rate measured over a short span, run
/// on for `OVERSHOOT` times as long) but only the overlap it finds is used,
/// and that is checked.
fn overlap_after(
    stalled: &Stalled,
    a: &ShapeMotion,
    b: &ShapeMotion,
    (ca, cb): (&Convex, &Convex),
    hi: f64,
    closest: &mut Closest,
) -> Option<f64> {
    let later = (stalled.tau + CLOSING_SPAN).min(hi);
    if later <= stalled.tau {
        return None;
    }
    let (pa, pb) = (a.motion.pose_at(later), b.motion.pose_at(later));
    // No rounding slack: the guess needs none, and the overlap it leads
    // to is checked.
    let at = At::new(&pa, &pb, 0.0);
    let n = pa.rotation.inverse() * stalled.direction;
    let closing = (stalled.gap - at.gap_along(&n, ca, cb)) / (later - stalled.tau);
    // Not closing (or NaN from a degenerate motion): no guess.
    if closing.is_nan() || closing <= 0.0 {
        return None;
    }
    let guess = stalled.tau + OVERSHOOT * stalled.gap.max(0.0) / closing;
    if guess.is_nan() || guess >= hi {
        return None;
    }
    let (pa, pb) = (a.motion.pose_at(guess), b.motion.pose_at(guess));
    closest.overlap(&pa.inv_mul(&pb), ca, cb).then_some(guess)
}

/// Two shapes at their poses at one time, in `a`'s frame.
struct At {
    rel: Isometry3<f64>,
    /// How much the gap along a direction may be off by rounding, metres.
    slack: f64,
}

impl At {
    /// `extents`: how far the two shapes reach from their frames' origins
    /// together, metres.
    fn new(pa: &Isometry3<f64>, pb: &Isometry3<f64>, extents: f64) -> At {
        // The poses, the relative pose and the projections are each
        // rounded a few times in terms no larger than these sizes (and a
        // direction is unit to within as much): 1e-12 of them covers that
        // many times over.
        let sizes = pa.translation.vector.norm() + pb.translation.vector.norm() + extents;
        At {
            rel: pa.inv_mul(pb),
            slack: up(1.0e-12 * sizes),
        }
    }

    /// A lower bound of the shapes' distance from their projections on
    /// the unit direction `n` (`a`'s frame, from `a` towards `b`), metres.
    fn gap_along(&self, n: &Vector3<f64>, ca: &Convex, cb: &Convex) -> f64 {
        let back = -(self.rel.rotation.inverse() * n);
        let reach_a = n.dot(&ca.support_point(n));
        let reach_b = back.dot(&cb.support_point(&back));
        down(n.dot(&self.rel.translation.vector) - reach_a - reach_b - self.slack)
    }
}

/// The closest points' normal of two convex shapes, by GJK in `f64` over
/// their support points, each search started from the last one's simplex
/// (carried to the new relative pose): a nearby time's answer, from which
/// GJK converges in a step or two.
#[derive(Default)]
struct Closest {
    /// The last simplex and the relative pose it was at.
    warm: Option<(VoronoiSimplex, Pose64)>,
}

impl Closest {
    /// The unit normal (from `a` towards `b`, `a`'s frame) of the closest
    /// points of `ca` and `cb` at the relative pose `rel`; `None` when they
    /// overlap or GJK has no answer.
    fn normal(&mut self, rel: &Isometry3<f64>, ca: &Convex, cb: &Convex) -> Option<Vector3<f64>> {
        let pos12 = pose64_from_iso(rel);
        let mut simplex = self.start(&pos12, ca, cb);
        // A panic in parry would only cost the advance.
        let found = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            gjk::closest_points(&pos12, ca, cb, PREDICTION, true, &mut simplex)
        }));
        // A simplex that ended holding the origin would answer `Intersection`
        // at once next time: kept only after closest points.
        let Ok(GJKResult::ClosestPoints(_, _, n)) = found else {
            return None;
        };
        self.warm = Some((simplex, pos12));
        Vector3::new(n.x, n.y, n.z).try_normalize(1.0e-9)
    }

    /// Whether `ca` and `cb` overlap at the relative pose `rel`: GJK found
    /// the origin inside a simplex of points of their difference.
    fn overlap(&mut self, rel: &Isometry3<f64>, ca: &Convex, cb: &Convex) -> bool {
        let pos12 = pose64_from_iso(rel);
        let mut simplex = self.start(&pos12, ca, cb);
        let found = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            gjk::closest_points(&pos12, ca, cb, 0.0, false, &mut simplex)
        }));
        matches!(found, Ok(GJKResult::Intersection))
    }

    /// GJK's first simplex at `pos12`: the last one carried there (its
    /// `b` points, kept in `a`'s frame, moved with `b`'s pose), else the
    /// difference's support point along the frames' offset.
    fn start(&mut self, pos12: &Pose64, ca: &Convex, cb: &Convex) -> VoronoiSimplex {
        match self.warm.take() {
            Some((mut simplex, old12)) => {
                let shift = *pos12 * old12.inverse();
                simplex.modify_pnts(&|p| *p = CsoPoint::new(p.orig1, shift * p.orig2));
                simplex
            }
            None => {
                let start = pos12.translation.try_normalize().unwrap_or(Vec64::X);
                let mut simplex = VoronoiSimplex::new();
                simplex.reset(CsoPoint::from_shapes(pos12, ca, cb, start));
                simplex
            }
        }
    }
}

/// The pair as two polytopes, if it is advanced: a pair that turns by
/// more than [`TURNING`], of polytopes (GJK in `f64` converges on those in
/// a few steps; on a curved or rounded shape it creeps towards the closest
/// points, and advancing cylinders, cones, capsules and balls cost more
/// than the search it spared), one of them a triangle (a mesh's piece: the
/// case the stage sweeps triangle by triangle). Between two boxes, where
/// an evaluation is cheaper, it spared 6 % of the instructions at
/// 200–1000 rad/s but cost 8 % more time.
fn advances(a: &ShapeMotion, b: &ShapeMotion) -> Option<(Convex, Convex)> {
    if a.shape.as_triangle().is_none() && b.shape.as_triangle().is_none() {
        return None;
    }
    let turn = a.motion.rotation().norm() + b.motion.rotation().norm();
    if turn <= TURNING || turn.is_nan() {
        return None;
    }
    let (Ok(Some(ca)), Ok(Some(cb))) = (Convex::from_shape(a.shape), Convex::from_shape(b.shape))
    else {
        return None;
    };
    (polytope(&ca) && polytope(&cb)).then_some((ca, cb))
}

/// Whether `c` is a polytope (no border; a box, triangle or hull).
fn polytope(c: &Convex) -> bool {
    c.border == 0.0
        && matches!(
            c.core,
            Core::Cuboid(_) | Core::Triangle(_) | Core::Polyhedron(_)
        )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convert::pose_from_iso;
    use crate::motion::Motion;
    use nalgebra::{Point3, UnitQuaternion};
    use proptest::prelude::*;
    use rapier3d::parry::math::Vector;
    use rapier3d::parry::shape::{Cuboid, Triangle};

    const DT: f64 = 1.0 / 60.0;

    fn v32(v: [f64; 3]) -> Vector {
        Vector::new(v[0] as f32, v[1] as f32, v[2] as f32)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Ground truth for the advanced start: a box spinning at 200–1000
        /// rad/s and flown at a fixed or drifting triangle (most of them
        /// hit it) never touches it, by parry's distance at 2,000 sampled
        /// times, before the time `apart_until` returns.
        #[test]
        fn nothing_touches_before_the_advanced_start(
            half in prop::array::uniform3(0.05f64..0.5),
            corners in prop::array::uniform3(prop::array::uniform3(-1.0f64..1.0)),
            at in prop::array::uniform3(-2.0f64..2.0),
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in 0.0f64..6.3,
            share in 0.3f64..1.2,
            jitter in prop::array::uniform3(-20.0f64..20.0),
            spin in prop::array::uniform3(-1.0f64..1.0),
            rate in 200.0f64..1000.0,
            drift in prop::array::uniform3(prop_oneof![Just(0.0f64), -5.0f64..5.0]),
            skin in prop_oneof![Just(0.0f64), 0.0f64..0.01],
        ) {
            let cuboid = Cuboid::new(v32(half));
            let triangle = Triangle::new(v32(corners[0]), v32(corners[1]), v32(corners[2]));
            prop_assume!(triangle.normal().is_some());
            let axis = Vector3::from(axis).try_normalize(1.0e-6).unwrap_or(Vector3::x());
            let start = Isometry3::from_parts(
                Vector3::from(at).into(),
                UnitQuaternion::from_scaled_axis(axis * angle),
            );
            let spin = Vector3::from(spin).try_normalize(1.0e-6).unwrap_or(Vector3::y()) * rate;
            // Aimed at the triangle's side of the origin, most of the way.
            let linvel = -Vector3::from(at) / DT * share + Vector3::from(jitter);
            let boxed = Motion::from_velocities(start, Point3::from(at), linvel, spin, DT)
                .unwrap();
            let fixed = Motion::from_velocities(
                Isometry3::identity(), Point3::origin(), drift.into(), Vector3::zeros(), DT,
            )
            .unwrap();
            let a = ShapeMotion { shape: &cuboid, motion: boxed };
            let b = ShapeMotion { shape: &triangle, motion: fixed };
            let Advanced { until, steps, overlap_at } = apart_until(&a, &b, TimeSpan::STEP, skin);
            prop_assert!((0.0..=1.0).contains(&until));
            prop_assert!(steps <= MOST_STEPS);
            // An overlap is claimed only where the shapes do overlap (by
            // parry3d-f64 on the same shapes), and after the advanced start.
            if let Some(t) = overlap_at {
                prop_assert!(t > until && t <= 1.0, "overlap at {t}, advanced to {until}");
                let (pa, pb) = (a.motion.pose_at(t), b.motion.pose_at(t));
                let wide = |p: Vector| {
                    parry3d_f64::math::Vector::new(f64::from(p.x), f64::from(p.y), f64::from(p.z))
                };
                let triangle64 =
                    parry3d_f64::shape::Triangle::new(wide(triangle.a), wide(triangle.b), wide(triangle.c));
                let cuboid64 = parry3d_f64::shape::Cuboid::new(wide(cuboid.half_extents));
                let touching = parry3d_f64::query::intersection_test(
                    &pose64_from_iso(&pa), &cuboid64, &pose64_from_iso(&pb), &triangle64,
                )
                .unwrap();
                prop_assert!(touching.intersecting, "no overlap at {t}");
            }
            // Not advanced (touching at the start, or no time gained):
            // nothing claimed.
            if until == 0.0 {
                return Ok(());
            }
            for i in 0..=2000 {
                let tau = until * i as f64 / 2000.0;
                let (pa, pb) = (a.motion.pose_at(tau), b.motion.pose_at(tau));
                let gap = rapier3d::parry::query::distance(
                    &pose_from_iso(&pa), &cuboid, &pose_from_iso(&pb), &triangle,
                )
                .unwrap()
                .distance;
                prop_assert!(
                    f64::from(gap) > skin,
                    "at {tau} (advanced to {until} in {steps} steps) the gap is {gap}"
                );
            }
        }
    }

    /// The advance is not vacuous: a box spinning at 600 rad/s that passes
    /// 30 cm beside a triangle is advanced over the whole step, and one
    /// that hits it is advanced part of the way, not past the hit.
    #[test]
    fn a_spinning_box_is_advanced_past_a_miss_and_up_to_a_hit() {
        let cuboid = Cuboid::new(Vector::new(0.2, 0.05, 0.1));
        let triangle = Triangle::new(
            Vector::new(-1.0, 0.0, -1.0),
            Vector::new(1.0, 0.0, -1.0),
            Vector::new(0.0, 0.0, 1.0),
        );
        let floor = Motion::fixed(Isometry3::identity()).unwrap();
        let flying = |height: f64, down: f64| {
            let start = Isometry3::translation(0.0, height, 0.0);
            Motion::from_velocities(
                start,
                Point3::new(0.0, height, 0.0),
                Vector3::new(0.0, -down, 0.0),
                Vector3::new(0.0, 0.0, 600.0),
                DT,
            )
            .unwrap()
        };
        let b = ShapeMotion {
            shape: &triangle,
            motion: floor,
        };
        // Drops from 1.0 m to 0.5 m: its corners (0.21 m from its centre)
        // stay 29 cm up.
        let miss = ShapeMotion {
            shape: &cuboid,
            motion: flying(1.0, 30.0),
        };
        let passed = apart_until(&miss, &b, TimeSpan::STEP, 0.0);
        assert_eq!((passed.until, passed.overlap_at), (1.0, None));
        // Drops from 0.6 m to 0.0 through the triangle: its first contact,
        // by parry's distance at 10,000 sampled times.
        let hit = ShapeMotion {
            shape: &cuboid,
            motion: flying(0.6, 36.0),
        };
        let contact = (0..=10_000)
            .map(|i| i as f64 / 10_000.0)
            .find(|&tau| {
                let (pa, pb) = (hit.motion.pose_at(tau), b.motion.pose_at(tau));
                let (pa, pb) = (pose_from_iso(&pa), pose_from_iso(&pb));
                rapier3d::parry::query::distance(&pa, &cuboid, &pb, &triangle)
                    .unwrap()
                    .distance
                    == 0.0
            })
            .expect("it hits");
        let Advanced {
            until,
            steps,
            overlap_at,
        } = apart_until(&hit, &b, TimeSpan::STEP, 0.0);
        assert!(
            until < contact && until > 0.5 * contact,
            "advanced to {until} in {steps} steps, contact at {contact}"
        );
        // The guess past the stall finds the box through the triangle,
        // after the contact and soon after it (the box closes at 36 m/s).
        let overlap_at = overlap_at.expect("an overlap past the stall");
        assert!(
            overlap_at >= contact && overlap_at < contact + 0.05,
            "overlap at {overlap_at}, contact at {contact}"
        );
    }
}
