//! A pair already touching at the start of the step: rapier's contacts own
//! it, unless the motion drives it deeper than allowed: proved from the
//! pair's travel along its contact normal or with one sound query where it
//! can be, sampled with parry's contact otherwise (see [`touching_pair`]).

use super::backoff::{
    BACKOFF, HandBack, back_off, mesh_points_within, overlap_along, pair_approaches_within,
    pair_relative_travel, pair_travel, roundings, stop_before_gap, stop_when_deep,
};
use super::mesh_planes::stays_within_planes;
use super::report::CcdReport;
use super::search;
use crate::InitialContact;
use crate::convert::{glam_from_vec, pose_from_iso, vec_from_glam};
use crate::enclosure::TimeSpan;
use crate::error::CcdError;
use crate::motion::{Motion, Trajectory};
use crate::query::{QueryOptions, Settle, ShapeMotion, Toi, Witness, contact_settled, lone_pair};
use crate::solve::RootStatus;
use nalgebra::Vector3;
use rapier3d::parry::query::{Contact, Unsupported};
use rapier3d::parry::shape::{Shape, SupportMap};

/// Signed gap at step fraction `tau` (negative: penetration depth), with
/// the contact there; `None` when parry cannot tell. Gaps beyond `reach`
/// come back as `reach` (and no contact). A caller that asks only whether
/// the gap is deeper than `settle.allowed`, within `settle.band`, or
/// beyond gets each answer as without it, for less (see
/// `query::contact_settled`).
pub(super) fn gap_at(
    s1: &dyn Shape,
    m1: &Motion,
    s2: &dyn Shape,
    m2: &Motion,
    tau: f64,
    reach: f64,
    settle: Option<Settle>,
) -> Option<(f64, Option<Contact>)> {
    let p1 = pose_from_iso(&m1.pose_at(tau));
    let p2 = pose_from_iso(&m2.pose_at(tau));
    read_gap(
        contact_settled(&p1, s1, &p2, s2, reach as f32, settle),
        reach,
    )
}

/// A gap as [`gap_at`] reads parry's contact asked within `reach`.
pub(super) fn read_gap(
    found: Result<Option<Contact>, Unsupported>,
    reach: f64,
) -> Option<(f64, Option<Contact>)> {
    match found {
        Ok(Some(c)) => Some((c.dist as f64, Some(c))),
        Ok(None) => Some((reach, None)),
        Err(_) => None,
    }
}

/// How far parry's contact looks for a pair that reads its gap only to
/// tell whether it is within `band` (metres): just past it, since a larger
/// prediction makes a mesh contact visit every part within it.
pub(super) fn past_band(band: f64) -> f64 {
    band + 1.0e-3
}

/// How much deeper than allowed a rounded touching pair is stopped at,
/// and every bound of [`touching_pair`] that proves a pair stays within
/// its allowed depth lets it go, metres (see [`proved_within`]): the
/// samples alone test the allowed depth itself. (With the margin on the
/// search's proof only, the bounds tried before it failed where it held:
/// a propeller mesh rubbing a wall was searched where its vertices' bound
/// would have done, `spinning_trimesh` 11.6 % of its instructions.)
const DEEPER: f64 = 1.0e-4;

/// Most samples a pair touching at the start takes over the step.
pub(super) const MAX_TOUCH_SAMPLES: usize = 64;

/// Halvings of the time between the last allowed sample and the first one
/// deeper than allowed ([`touching_pair`]), and the share of that time they
/// come down to (`2^HALVINGS`).
const HALVINGS: usize = 12;
const HALVING_SHARE: f64 = (1u64 << HALVINGS) as f64;

/// A pair already touching at the start (apart by no more than `band`,
/// `HandBack::touch_band`): rapier's contacts own it, unless it goes
/// deeper than `HandBack::allowed_depth` or separates and comes back. Walks
/// the step in samples fine enough that no point moves more than
/// `HandBack::sample_travel` between two (at most [`MAX_TOUCH_SAMPLES`]):
/// at the first sample deeper than allowed the time is bisected down to
/// the last allowed one and returned; at the first sample apart by more
/// than `band` the sound query takes over for the rest of the step. This is parry's sampled depth, not a proof: the stage
/// is sound for pairs apart at the start; for touching ones it only stops
/// the solver from pushing a fast body deep.
pub(super) fn touching_pair(
    moving: &ShapeMotion,
    target: &ShapeMotion,
    start: (f64, Option<Contact>),
    band: f64,
    rules: &HandBack,
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<Toi>, CcdError> {
    let (s1, m1, s2, m2) = (moving.shape, &moving.motion, target.shape, &target.motion);
    let (gap0, contact0) = start;
    let span = opts.time_range;
    let driven = contact0.as_ref().map_or(f64::INFINITY, |c| {
        contact_approach(m1, m2, c, span.lo) * span.width()
    });
    let allowed = rules.allowed_depth(gap0, driven, moving, target);
    let (lo, hi) = (span.lo, span.hi);
    // What the proofs below let the pair reach: a tenth of a millimetre
    // past the allowed depth (see `proved_within`); the samples test the
    // allowed depth itself.
    let proven = allowed + DEEPER;
    // The pair's points move too little relative to each other to get
    // deeper than that: nothing to do. (parry's depth of a convex pair,
    // or of each convex part of a composite one, is the distance of the
    // origin from the border of their Minkowski difference, whose points
    // `p − q` move no farther than this.)
    if pair_relative_travel(s1, m1, s2, m2) <= proven + gap0 {
        return Ok(None);
    }
    let travel = pair_travel(s1, m1, s2, m2);
    // Against a convex target parry's depth is one least translation, so
    // bounds along a fixed direction bound it.
    let convex = is_convex(s2);
    let convex_start = contact0.as_ref().filter(|_| convex);
    if let Some(c) = convex_start {
        // The depth is at most the overlap along the start normal, which
        // starts at `-gap0` and grows no faster than the pair approaches
        // along it. A body sliding or resting on it, or bouncing off it,
        // is done here, without a query.
        let normal = vec_from_glam(c.normal1).normalize();
        if pair_approaches_within(moving, target, &normal, proven + gap0) {
            return Ok(None);
        }
        // A small mesh, from its vertices (its start overlap along the
        // normal may exceed the depth of its deepest triangle).
        if s2.as_halfspace().is_none() && mesh_points_within(moving, target, &normal, proven) {
            return Ok(None);
        }
    }
    // A convex body on a still mesh or heightfield (a fast one: a slow
    // one meets it as triangle targets, each convex): within every plane
    // of the triangles it can reach.
    if !convex && s1.is_convex() && stays_within_planes(moving, target, proven) {
        return Ok(None);
    }
    // A ball or capsule (roundings beyond the allowed depth) against a
    // convex shape: it is deeper exactly when its core comes closer than
    // `r₁ + r₂ − allowed`, one sound query for the whole step instead of
    // samples that each run parry's EPA. The allowed depth may be the
    // start depth itself: the query asks for a tenth of a millimetre more,
    // so the start is not already there (parry's `f32` depth is good to far
    // less). Against a mesh parry's samples are cheap (no EPA), and a
    // search over the mesh for the whole step is not.
    if convex && roundings(moving, target) > allowed + DEEPER {
        // A pair whose contact point is being driven in most often gets
        // that deep soon (a capsule a clamp left at its allowed depth, still
        // headed into the wall): its stop is searched for first just after
        // the start, where the nodes are narrow from the outset.
        return stop_when_deep(
            moving,
            target,
            lo,
            hi,
            allowed + DEEPER,
            rules.sweep_tolerance(),
            driven > 0.0,
            opts,
            report,
        );
    }
    // A mesh or compound moving shape takes the proof after the first
    // sample, not before: its proof searches every part near the target,
    // a sample costs a small part of that, and a pair the motion drives
    // deep is most often deep there already (a blade spinning into a
    // wall). A convex one's proof costs about what a sample's EPA does.
    let (proof_first, proof_after_sample) = if s1.is_convex() {
        (convex_start, None)
    } else {
        (None, convex_start)
    };
    if let Some(c) = proof_first
        && proved_within(moving, target, c, allowed, opts, report)
    {
        return Ok(None);
    }
    let step = rules.sample_travel(s1);
    let samples = ((travel / step).ceil() as usize).clamp(4, MAX_TOUCH_SAMPLES);
    // A sample only tells deeper than allowed, within the band, or apart
    // by more: parry's contact needs to look no farther than just past the
    // band (a gap beyond comes back as `reach`, apart all the same), and a
    // larger prediction makes it visit every mesh part within it. A depth
    // needs none (overlapping parts are always found), so a pair allowed
    // deep (a blade jammed 17 cm into a wall) looks no farther than one
    // allowed 5 mm. A pair with no band (left to the contacts, only kept
    // from sinking) tells only depths: its samples look just past touching
    // (an unbounded prediction made each of them measure the distance,
    // however far). The witness of a stop looks as far as a sample can
    // move, so that it finds the contact near the last allowed time.
    let reach = past_band(if band.is_finite() { band } else { 0.0 });
    let witness_reach = past_band(band) + travel / samples as f64;
    // Nor does a sample need the deepest part of a mesh once one is
    // within the band: only whether some part is deeper than allowed.
    let settle = Some(Settle { band, allowed });
    // A small mesh against a convex target reads most samples from its
    // vertices (see `VertexReading`), parry's contact only the others.
    let vertices = proof_after_sample.and_then(|c| VertexReading::new(moving, target, c));
    let sample = |tau: f64| {
        if vertices
            .as_ref()
            .is_some_and(|v| v.surely_within(moving, target, tau, allowed, band))
        {
            return Some((0.0, None));
        }
        gap_at(s1, m1, s2, m2, tau, reach, settle)
    };
    let width = hi - lo;
    let mut prev = lo;
    for k in 1..=samples {
        let tau = lo + width * k as f64 / samples as f64;
        let Some((gap, _)) = sample(tau) else {
            return Ok(None);
        };
        if k == 1
            && -gap <= allowed
            && let Some(c) = proof_after_sample
            && proved_within(moving, target, c, allowed, opts, report)
        {
            return Ok(None);
        }
        if -gap > allowed {
            // Deeper than allowed: the last allowed time, by bisection
            // down to 2⁻¹² of the samples' spacing. A pair already too deep
            // at that resolution after the last allowed sample (a body
            // pressed into a wall at its allowed depth, sinking from the
            // start) stops at that sample: asked first, it spares the
            // bisection its twelve steps down to the same answer.
            let (mut ok, mut bad) = (prev, tau);
            let finest = prev + (tau - prev) / HALVING_SHARE;
            let sinks_at_once = finest > prev && sample(finest).is_none_or(|(g, _)| -g > allowed);
            for _ in 0..if sinks_at_once { 0 } else { HALVINGS } {
                let mid = 0.5 * (ok + bad);
                match sample(mid) {
                    Some((g, _)) if -g <= allowed => ok = mid,
                    _ => bad = mid,
                }
            }
            let (_, found) = gap_at(s1, m1, s2, m2, ok, witness_reach, None).unwrap_or((0.0, None));
            let witness = found.map_or_else(
                || Witness::origins(&m1.pose_at(ok), &m2.pose_at(ok)),
                |c| Witness::of(&c),
            );
            let dt = m1.dt().max(m2.dt());
            return Ok(Some(Toi::new(
                ok,
                dt,
                RootStatus::Hit,
                witness,
                Default::default(),
            )));
        }
        if gap > band {
            // Apart: the sound query for the rest of the step. Where the
            // pair meets again it stops where rapier's sweep stops any
            // pair (see `backoff`): a ball or capsule `slop` deep, if it
            // gets that deep; an unrounded pair `slop` before its true
            // contact (zero skin).
            if let Some(depth) = rules.deep_stop(gap, moving, target) {
                let tolerance = rules.sweep_tolerance();
                return stop_when_deep(
                    moving, target, tau, hi, depth, tolerance, false, opts, report,
                );
            }
            let rest = QueryOptions {
                time_range: TimeSpan::new(tau, hi),
                skin: 0.0,
                ..*opts
            };
            if let Some(toi) = search::one(s1, m1, s2, m2, &rest, report)? {
                if toi.status != RootStatus::InitiallyTouching {
                    let stop_gap = rules.stop_gap(moving, target);
                    let stop = (toi.status == RootStatus::Hit && stop_gap > 0.0)
                        .then(|| stop_before_gap(moving, target, toi, tau, stop_gap, rules.slop))
                        .flatten();
                    return Ok(Some(stop.unwrap_or_else(|| {
                        back_off(toi, travel, BACKOFF * opts.skin, tau)
                    })));
                }
                prev = tau;
                continue;
            }
            return Ok(None);
        }
        prev = tau;
    }
    Ok(None)
}

/// Most vertices a mesh may have for [`VertexReading`] (each sample reads
/// them all).
const MAX_READ_VERTICES: usize = 64;

/// A touching sample of a small moving mesh against a convex target, read
/// from the mesh's vertices instead of parry's contact where that is
/// sure: the pair is within the band and no deeper than allowed when
/// (1) the mesh's farthest vertex along the start normal `n` reaches past
/// the target's nearest support point by no more than the allowed depth
/// (each triangle's depth, a least translation, is at most its overlap
/// along `n`, which is at most that), and (2) some vertex is within the
/// band of the target (parry's gap, its closest triangle's, is at most
/// that vertex's distance). A blade rubbing a wall has most of its
/// samples there; the deep ones, and any the vertices cannot settle, go
/// to parry's contact as before.
struct VertexReading<'a> {
    /// The mesh's vertices, in its frame.
    points: Vec<Vector3<f64>>,
    /// Unit, from the mesh towards the target.
    n: Vector3<f64>,
    support: &'a dyn SupportMap,
}

impl<'a> VertexReading<'a> {
    fn new(moving: &ShapeMotion, target: &ShapeMotion<'a>, c: &Contact) -> Option<Self> {
        let mesh = moving.shape.as_trimesh()?;
        if mesh.vertices().len() > MAX_READ_VERTICES {
            return None;
        }
        Some(VertexReading {
            points: mesh.vertices().iter().map(|v| vec_from_glam(*v)).collect(),
            n: vec_from_glam(c.normal1).try_normalize(1.0e-6)?,
            support: target.shape.as_support_map()?,
        })
    }

    /// Whether parry's sample at `tau` is surely within `band` and no
    /// deeper than `allowed`, with room for its `f32` poses and depths.
    fn surely_within(
        &self,
        moving: &ShapeMotion,
        target: &ShapeMotion,
        tau: f64,
        allowed: f64,
        band: f64,
    ) -> bool {
        let (p, q) = (moving.motion.pose_at(tau), target.motion.pose_at(tau));
        let scale = p.translation.vector.amax().max(q.translation.vector.amax());
        let room = 1.0e-5 + 1.0e-6 * scale;
        // (A NaN overlap settles nothing.)
        let overlap = overlap_along(&self.points, &p, self.support, &q, &self.n);
        if overlap.is_nan() || overlap > allowed - room {
            return false;
        }
        let (p32, q32) = (pose_from_iso(&p), pose_from_iso(&q));
        self.points.iter().any(|v| {
            let at = p32 * glam_from_vec(v);
            f64::from(target.shape.distance_to_point(&q32, at, true)) <= band - room
        })
    }
}

/// How fast the contact `c` (parry's, in world coordinates, at step
/// fraction `tau`) closes along its normal, metres per step: the two
/// bodies' velocities at the contact point (the centre's mean one over the
/// step plus the turn's about where the centre is at `tau`), the moving
/// one's less the target's, along the normal from the moving shape towards
/// the target. About 0 for a body rolling on the target.
fn contact_approach(moving: &Motion, target: &Motion, c: &Contact, tau: f64) -> f64 {
    let at = (vec_from_glam(c.point1) + vec_from_glam(c.point2)) * 0.5;
    let normal = vec_from_glam(c.normal1);
    normal.dot(&(moving.point_velocity(&at, tau) - target.point_velocity(&at, tau)))
}

/// Whether parry's depth against `shape` is one least translation (a
/// convex shape or a half-space), not one per mesh triangle along its own
/// normal: only then do a fixed direction's bounds bound it.
fn is_convex(shape: &dyn Shape) -> bool {
    shape.is_convex() || shape.as_halfspace().is_some()
}

/// Whether a ball or capsule close to a convex target at the start (gap
/// `start.0`, parry's contact `start.1`) can be seen never to get `depth`
/// deep over the step without a search: the depth of two convex shapes is
/// at most the overlap of their projections on any direction, which
/// starts at `-gap0` along the start normal and grows no faster than the
/// pair approaches along it (the bounds [`touching_pair`] tries first). A
/// body leaving a wall it bounced off, or rolling along the floor, is done
/// here instead of by [`stop_when_deep`]'s search over the whole step. The
/// budget is kept short of parry's `f32` error on the gap (1e-5 m, and
/// 1e-6 of the coordinates).
pub(super) fn never_as_deep(
    moving: &ShapeMotion,
    target: &ShapeMotion,
    start: &(f64, Option<Contact>),
    depth: f64,
) -> bool {
    let (gap0, Some(c)) = (start.0, start.1.as_ref()) else {
        return false;
    };
    if !moving.shape.is_convex() || !is_convex(target.shape) {
        return false;
    }
    let Some(normal) = vec_from_glam(c.normal1).try_normalize(1.0e-6) else {
        return false;
    };
    let scale = c.point1.abs().max(c.point2.abs()).max_element() as f64;
    let budget = depth + gap0 - (1.0e-5 + 1.0e-6 * scale);
    budget > 0.0 && pair_approaches_within(moving, target, &normal, budget)
}

/// Cheap proof that a touching pair never gets more than [`DEEPER`] deeper
/// than `allowed`: shifted that far back along the normal of its contact
/// at the start, `start`, the moving shape never touches the target (one
/// sound query); the shift then separates them at every time, so the depth
/// (parry's: the least translation apart) stays within it. Where the start
/// depth is what is allowed (a pair already deeper than the sink), the
/// shifted shape starts apart by only the margin; without one it started
/// a rounding apart, and the search halved its way down to a
/// five-thousandth of the step before it could prove the start apart (a
/// spinning mesh against a wall: 316 evaluations; with the margin
/// `spinning_trimesh` 4.2 % fewer instructions, `ccd_pair_pass` 7.9 %,
/// `fan_propellers` 3.1 %). `false` when the shifted shape does touch (the
/// normal may just have turned: the caller samples) or nothing could be
/// proved. Only for a convex target: against a mesh parry measures the
/// depth along each triangle's own normal, which no single shift bounds (a
/// slab resting across terrain triangles was proved within 5 mm while
/// parry, and the solver, saw 12 mm along a neighbouring triangle's normal).
fn proved_within(
    moving: &ShapeMotion,
    target: &ShapeMotion,
    start: &Contact,
    allowed: f64,
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> bool {
    let (s1, m1, s2, m2) = (moving.shape, &moving.motion, target.shape, &target.motion);
    let c = start;
    let back = -vec_from_glam(c.normal1) * ((allowed + DEEPER) * (1.0 + 1.0e-6));
    let apart = QueryOptions {
        skin: 0.0,
        initial_contact: InitialContact::Report,
        ..*opts
    };
    // Only whether the shifted pair meets: the hit's witness is not read.
    let (shifted, target) = lone_pair(s1, &m1.shifted(back), s2, m2);
    match search::found(&shifted, &target, &apart, report) {
        Ok(None) => true,
        Ok(Some(_)) => false,
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rapier::testing::{Numbers, flying, propeller_and_wall};
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
    use proptest::prelude::*;
    use rapier3d::parry::shape::{Ball, Capsule, Cuboid};
    use rapier3d::prelude::Vector;

    proptest! {
        /// Where `never_as_deep` answers without a search, the search
        /// agrees: a ball or capsule starting within millimetres of a wall
        /// (just apart, or a little into it), moving and spinning every
        /// way, is never found 5 mm deep by `stop_when_deep`. And the bound
        /// answers for a good share of them (those leaving the wall or
        /// running along it), or it would spare nothing.
        #[test]
        fn never_as_deep_agrees_with_the_search(
            capsule in any::<bool>(),
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in -3.0f64..3.0,
            gap in -0.004f64..0.003,
            at in prop::array::uniform2(-0.5f64..0.5),
            linvel in prop::array::uniform3(-8.0f64..8.0),
            angvel in prop::array::uniform3(-40.0f64..40.0),
        ) {
            let (ball, rod) = (Ball::new(0.1), Capsule::new_y(0.2, 0.06));
            let wall = Cuboid::new(Vector::new(0.05, 1.0, 1.0));
            let rotation = UnitQuaternion::from_scaled_axis(
                Vector3::from(axis).try_normalize(1.0e-9).unwrap_or(Vector3::y()) * angle,
            );
            // How far the shape reaches towards the wall (−x) from its centre.
            let reach = if capsule {
                0.06 + 0.2 * (rotation * Vector3::y()).x.abs()
            } else {
                0.1
            };
            let centre = Vector3::new(0.05 + reach + gap, at[0], at[1]);
            let start = Isometry3::from_parts(Translation3::from(centre), rotation);
            let motion = Motion::from_velocities(
                start,
                Point3::from(centre),
                Vector3::from(linvel),
                Vector3::from(angvel),
                1.0 / 60.0,
            )
            .unwrap();
            let shape: &dyn Shape = if capsule { &rod } else { &ball };
            let moving = ShapeMotion { shape, motion };
            let target = ShapeMotion {
                shape: &wall,
                motion: Motion::fixed(Isometry3::identity()).unwrap(),
            };
            let depth = 0.005;
            let first = gap_at(shape, &moving.motion, &wall, &target.motion, 0.0, 0.01, None);
            let Some(first) = first else {
                return Err(TestCaseError::reject("parry has no start gap"));
            };
            prop_assume!(first.1.is_some() && first.0 > -depth + 1.0e-4);
            if never_as_deep(&moving, &target, &first, depth) {
                let mut report = CcdReport::default();
                let opts = QueryOptions::default();
                let deep = stop_when_deep(&moving, &target, 0.0, 1.0, depth, 0.0, false, &opts, &mut report);
                prop_assert!(
                    matches!(deep, Ok(None)),
                    "start gap {}: the search finds it {} deep at {:?}",
                    first.0,
                    depth,
                    deep
                );
            }
        }
    }

    /// The bound answers for a ball leaving the wall it touches, and not
    /// for one driven into it.
    #[test]
    fn never_as_deep_answers_for_a_ball_leaving_a_wall() {
        let ball = Ball::new(0.1);
        let wall = Cuboid::new(Vector::new(0.05, 1.0, 1.0));
        let target = ShapeMotion {
            shape: &wall,
            motion: Motion::fixed(Isometry3::identity()).unwrap(),
        };
        for (vx, expected) in [(3.0, true), (0.0, true), (-3.0, false)] {
            let centre = Point3::new(0.15 + 0.001, 0.0, 0.0);
            let motion = Motion::from_velocities(
                Isometry3::translation(centre.x, 0.0, 0.0),
                centre,
                Vector3::new(vx, 1.0, 0.0),
                Vector3::new(0.0, 0.0, 30.0),
                1.0 / 60.0,
            )
            .unwrap();
            let moving = ShapeMotion {
                shape: &ball,
                motion,
            };
            let first = gap_at(&ball, &motion, &wall, &target.motion, 0.0, 0.01, None).unwrap();
            assert_eq!(
                never_as_deep(&moving, &target, &first, 0.005),
                expected,
                "ball at {vx} m/s along the wall's normal"
            );
        }
    }

    /// Where a propeller's vertices settle a sample (`VertexReading`),
    /// parry's contact agrees that the pair is within the band and no
    /// deeper than allowed: 2,000 propellers near a wall, from 5 cm into
    /// it to 5 cm beside it, turned every way and moving, read at three
    /// times of the step along the normal of their contact at the start.
    /// The reading settles a good share of those parry finds within the
    /// band, or it would spare nothing.
    #[test]
    fn vertex_readings_agree_with_parrys_contact() {
        let mut rng = Numbers(0x6a09_e667_f3bc_c909);
        let (mesh, wall) = propeller_and_wall();
        let fixed = Motion::fixed(Isometry3::identity()).unwrap();
        let target = ShapeMotion {
            shape: &wall,
            motion: fixed,
        };
        let (mut within, mut settled) = (0, 0);
        for case in 0..2000 {
            let turn = UnitQuaternion::from_scaled_axis(rng.vector(3.0));
            // The mesh's reach towards the wall (−x) from its centre.
            let reach = mesh
                .vertices()
                .iter()
                .map(|v| -(turn * vec_from_glam(*v)).x)
                .fold(f64::NEG_INFINITY, f64::max);
            let at = Vector3::new(
                0.1 + reach + rng.next(-0.05, 0.05),
                rng.next(-0.5, 0.5),
                0.0,
            );
            let motion = flying(at, turn, rng.vector(1.0), rng.vector(3.0), 1.0 / 60.0);
            let moving = ShapeMotion {
                shape: &mesh,
                motion,
            };
            let Some((_, Some(start))) = gap_at(&mesh, &motion, &wall, &fixed, 0.0, 0.06, None)
            else {
                continue;
            };
            let reading = VertexReading::new(&moving, &target, &start).expect("a small mesh");
            let (allowed, band) = (rng.next(0.0, 0.03), rng.next(0.001, 0.02));
            for tau in [0.0, 0.5, 1.0] {
                let (gap, _) =
                    gap_at(&mesh, &motion, &wall, &fixed, tau, band + 1.0e-3, None).unwrap();
                within += usize::from(-gap <= allowed && gap <= band);
                if reading.surely_within(&moving, &target, tau, allowed, band) {
                    settled += 1;
                    assert!(
                        -gap <= allowed && gap <= band,
                        "case {case} at {tau}: gap {gap}, allowed {allowed}, band {band}"
                    );
                }
            }
        }
        assert!(
            settled * 3 >= within && within > 500,
            "{settled} settled of {within} within"
        );
    }
}
