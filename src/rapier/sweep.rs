//! One fast body's earliest impact over the step, and the sensors it
//! crosses before it. Every call to the time-of-impact query is in
//! [`earliest`] and [`first_crossing`].

use super::candidates::{Candidate, Motions, PairKind, Scene, gather, pair_kind, swept_aabb};
use super::convert::pose_from_iso;
use super::query::{QueryOptions, ShapeMotion, Toi, time_of_impact, time_of_impact_many};
use super::report::CcdReport;
use super::select::Moved;
use crate::enclosure::TimeSpan;
use crate::error::CcdError;
use crate::motion::{Motion, Trajectory};
use crate::solve::RootStatus;
use rapier3d::parry::query::QueryDispatcher;
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::RigidBodyHandle;
use rapier3d::prelude::{BroadPhaseBvh, ColliderHandle};
use std::collections::{HashMap, HashSet};

/// The earliest solid impact of one fast body.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BodyHit {
    pub toi: Toi,
    pub collider1: ColliderHandle,
    pub collider2: ColliderHandle,
}

/// A sensor pair the body's sweep may cross, checked once the body's own
/// stop is known.
pub(crate) struct SensorPair {
    pub collider1: ColliderHandle,
    pub collider2: ColliderHandle,
    pub motion1: Motion,
    pub motion2: Motion,
}

/// Which of a body's candidates a sweep looks at.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Targets<'a> {
    /// Everything it may collide with (the first sweep of a fast body).
    All,
    /// Only colliders of bodies that moved during the step (a body whose
    /// own motion was cut short: against fixed targets it only covers part
    /// of the path already cleared, against moving ones its timing changed).
    Moving,
    /// Only colliders of these bodies (whose motion was cut short, or
    /// fast kinematic bodies and what they carry).
    Only(&'a HashSet<RigidBodyHandle>),
    /// Everything but dynamic bodies and these (a body carried by a
    /// kinematic one: what it meets on the way is pushed in turn, the
    /// pushers carry it, only the rest stops it).
    Blockers(&'a HashSet<RigidBodyHandle>),
}

/// Reused buffers; `motions` caches target motions for one step (clear it
/// between steps).
#[derive(Default)]
pub(crate) struct Workspace {
    candidates: Vec<Candidate>,
    pub motions: HashMap<ColliderHandle, Motion>,
}

/// Signed gap at step fraction `tau` (negative: penetration depth), with
/// the contact there; `None` when parry cannot tell. Gaps beyond `reach`
/// come back as `reach` (and no contact).
fn gap_at(
    s1: &dyn Shape,
    m1: &Motion,
    s2: &dyn Shape,
    m2: &Motion,
    tau: f64,
    reach: f64,
) -> Option<(f64, Option<rapier3d::parry::query::Contact>)> {
    let p1 = pose_from_iso(&m1.pose_at(tau));
    let p2 = pose_from_iso(&m2.pose_at(tau));
    // parry 0.31.1 answers a convex shape against a half-space wrongly
    // (the depth grows with the distance from the plane's origin); the
    // half-space first is right.
    let flip = s2.as_halfspace().is_some() && s1.as_halfspace().is_none();
    let found = if flip {
        rapier3d::parry::query::contact(&p2, s2, &p1, s1, reach as f32)
            .map(|c| c.map(|c| c.flipped()))
    } else {
        rapier3d::parry::query::contact(&p1, s1, &p2, s2, reach as f32)
    };
    match found {
        Ok(Some(c)) => Some((c.dist as f64, Some(c))),
        Ok(None) => Some((reach, None)),
        Err(_) => None,
    }
}

/// Most samples a pair touching at the start takes over the step.
const MAX_TOUCH_SAMPLES: usize = 64;

/// A pair already touching (within the skin) at the start: rapier's
/// contacts own it, unless it goes deeper than `max(start depth, sink)` or
/// separates and comes back. Walks the step in samples fine enough that no
/// point moves more than the sink between two (at most
/// [`MAX_TOUCH_SAMPLES`]): at the first sample deeper than allowed the time
/// is bisected down to the last allowed one and returned; at the first
/// sample apart by more than the skin the sound query takes over for the
/// rest of the step. This is parry's sampled depth, not a proof: the stage
/// is sound for pairs apart at the start; for touching ones it only stops
/// the solver from pushing a fast body deep.
fn touching_pair(
    moving: &ShapeMotion,
    target: &ShapeMotion,
    gap0: f64,
    sink: f64,
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<Toi>, CcdError> {
    let (s1, m1, s2, m2) = (moving.shape, &moving.motion, target.shape, &target.motion);
    let allowed = (-gap0).max(sink);
    let radius = |s: &dyn Shape| {
        let b = s.compute_local_bounding_sphere();
        b.center.length() as f64 + b.radius as f64
    };
    let travel = m1.travel_bound(radius(s1)) + m2.travel_bound(radius(s2));
    let samples = ((travel / sink).ceil() as usize).clamp(4, MAX_TOUCH_SAMPLES);
    // parry's contact only needs to look as far as a sample can move: a
    // larger prediction makes it visit every mesh part within it.
    let reach = opts.skin.max(allowed) + travel / samples as f64 + 1.0e-3;
    let lo = opts.time_range.lo;
    let width = opts.time_range.hi - lo;
    let mut prev = lo;
    for k in 1..=samples {
        let tau = lo + width * k as f64 / samples as f64;
        let Some((gap, _)) = gap_at(s1, m1, s2, m2, tau, reach) else {
            return Ok(None);
        };
        if -gap > allowed {
            // Deeper than allowed: the last allowed time, by bisection.
            let (mut ok, mut bad) = (prev, tau);
            for _ in 0..12 {
                let mid = 0.5 * (ok + bad);
                match gap_at(s1, m1, s2, m2, mid, reach) {
                    Some((g, _)) if -g <= allowed => ok = mid,
                    _ => bad = mid,
                }
            }
            let (_, contact) = gap_at(s1, m1, s2, m2, ok, reach).unwrap_or((0.0, None));
            let (w1, w2, n) = contact.map_or(
                (
                    m1.pose_at(ok).translation.vector,
                    m2.pose_at(ok).translation.vector,
                    nalgebra::Vector3::zeros(),
                ),
                |c| {
                    (
                        super::convert::vec_from_glam(c.point1),
                        super::convert::vec_from_glam(c.point2),
                        super::convert::vec_from_glam(c.normal1),
                    )
                },
            );
            return Ok(Some(Toi {
                fraction: ok,
                time: ok * m1.dt().max(m2.dt()),
                status: RootStatus::Hit,
                witness1: w1.into(),
                witness2: w2.into(),
                normal1: n,
                stats: Default::default(),
            }));
        }
        if gap > opts.skin {
            // Apart: the sound query for the rest of the step.
            let rest = QueryOptions {
                time_range: TimeSpan::new(tau, opts.time_range.hi),
                ..*opts
            };
            if let Some(toi) = time_of_impact(s1, m1, s2, m2, &rest)? {
                report.evaluations += toi.stats.pair_evaluations;
                if toi.status != RootStatus::InitiallyTouching {
                    return Ok(Some(toi));
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

/// Earliest impact of `moving` against `targets`, all pairs in one search.
///
/// A pair already within the skin at the start is taken out of the joint
/// search and handed to [`touching_pair`]: rapier's contacts own it unless
/// it goes deeper than `max(start depth, sink)` or separates and comes
/// back (rapier's `stop_at_penetration = false`: a touching pair counts
/// only when the motion makes it deeper). An impact at τ = 0 for every
/// touching pair would freeze a body resting or sliding on the ground.
fn earliest(
    moving: &ShapeMotion,
    targets: &[ShapeMotion],
    opts: &QueryOptions,
    sink: f64,
    report: &mut CcdReport,
) -> Result<Option<(Toi, usize)>, CcdError> {
    let mut alive: Vec<usize> = (0..targets.len()).collect();
    let mut best: Option<(Toi, usize)> = None;
    let keep = |toi: Toi, j: usize, best: &mut Option<(Toi, usize)>| {
        if best.is_none_or(|(b, _)| toi.fraction < b.fraction) {
            *best = Some((toi, j));
        }
    };
    while !alive.is_empty() {
        let set: Vec<ShapeMotion> = alive
            .iter()
            .map(|&j| ShapeMotion {
                shape: targets[j].shape,
                motion: targets[j].motion,
            })
            .collect();
        let found = time_of_impact_many(std::slice::from_ref(moving), &set, opts)?;
        let Some(many) = found else { break };
        report.evaluations += many.toi.stats.pair_evaluations;
        let j = alive[many.target];
        if many.toi.status != RootStatus::InitiallyTouching {
            keep(many.toi, j, &mut best);
            break;
        }
        report.pairs_touching_at_start += 1;
        alive.remove(many.target);
        let t = &targets[j];
        // The pair is within the skin at the start: a small prediction
        // finds its contact.
        let reach = opts.skin + 1.0e-2;
        let lo = opts.time_range.lo;
        let Some((gap, _)) = gap_at(moving.shape, &moving.motion, t.shape, &t.motion, lo, reach)
        else {
            continue;
        };
        if let Some(toi) = touching_pair(moving, t, gap, sink, opts, report)? {
            keep(toi, j, &mut best);
        }
    }
    Ok(best)
}

/// When a sensor pair first touches before `until` (a fraction of the
/// step), if it is apart at the start.
pub(crate) fn first_crossing(
    s1: &dyn Shape,
    pair: &SensorPair,
    s2: &dyn Shape,
    until: f64,
    opts: &QueryOptions,
) -> Result<Option<f64>, CcdError> {
    let opts = QueryOptions {
        skin: 0.0,
        time_range: TimeSpan::new(0.0, until),
        ..*opts
    };
    Ok(time_of_impact(s1, &pair.motion1, s2, &pair.motion2, &opts)?
        .filter(|t| t.status != RootStatus::InitiallyTouching)
        .map(|t| t.fraction))
}

/// Sweeps every enabled collider of `body`: the earliest solid impact, and
/// the sensor pairs to check afterwards (pushed to `sensors`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn sweep_body(
    scene: &Scene,
    broad_phase: &BroadPhaseBvh,
    dispatcher: &dyn QueryDispatcher,
    motions: &Motions,
    body: &Moved,
    targets: Targets,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
    sensors: &mut Vec<SensorPair>,
) -> Result<Option<BodyHit>, CcdError> {
    let Some(rb) = scene.bodies.get(body.handle) else {
        return Ok(None);
    };
    let mut best: Option<BodyHit> = None;
    for &h1 in rb.colliders() {
        let Some(co1) = scene.colliders.get(h1).filter(|c| c.is_enabled()) else {
            continue;
        };
        let motion1 = motions.collider(co1, scene.bodies)?;
        let swept = swept_aabb(co1.shape(), &motion1);
        let mut failure = None;
        let cache = &mut ws.motions;
        gather(
            scene,
            broad_phase,
            dispatcher,
            motions,
            h1,
            co1,
            &swept,
            |h2, co2| match cache
                .get(&h2)
                .copied()
                .map(Ok)
                .unwrap_or_else(|| motions.collider(co2, scene.bodies))
            {
                Ok(m) => {
                    cache.insert(h2, m);
                    Some(swept_aabb(co2.shape(), &m))
                }
                Err(e) => {
                    failure = Some(e);
                    None
                }
            },
            &mut ws.candidates,
        );
        if let Some(e) = failure {
            return Err(e);
        }
        let mut solid = Vec::new();
        let mut handles = Vec::new();
        for c in &ws.candidates {
            let co2 = &scene.colliders[c.handle];
            let parent = co2.parent();
            let wanted = match targets {
                Targets::All => true,
                Targets::Moving => parent.is_some_and(|b| motions.body(b).is_some()),
                Targets::Only(set) => parent.is_some_and(|b| set.contains(&b)),
                Targets::Blockers(set) => !parent.is_some_and(|b| {
                    set.contains(&b) || scene.bodies.get(b).is_some_and(|rb| rb.is_dynamic())
                }),
            };
            if !wanted {
                continue;
            }
            let motion2 = match ws.motions.get(&c.handle) {
                Some(m) => *m,
                None => motions.collider(co2, scene.bodies)?,
            };
            match c.kind {
                PairKind::Solid => {
                    solid.push(ShapeMotion {
                        shape: co2.shape(),
                        motion: motion2,
                    });
                    handles.push(c.handle);
                }
                PairKind::Sensor => sensors.push(SensorPair {
                    collider1: h1,
                    collider2: c.handle,
                    motion1,
                    motion2,
                }),
            }
        }
        report.pairs += ws.candidates.len();
        if solid.is_empty() {
            continue;
        }
        let moving = ShapeMotion {
            shape: co1.shape(),
            motion: motion1,
        };
        if let Some((toi, j)) = earliest(&moving, &solid, opts, scene.config.sink, report)? {
            if best.is_none_or(|b| toi.fraction < b.toi.fraction) {
                best = Some(BodyHit {
                    toi,
                    collider1: h1,
                    collider2: handles[j],
                });
            }
        }
    }
    Ok(best)
}

/// A contact at the start of the step between `body` and `pusher` (a fast
/// kinematic body, or a body it carries) that the pusher's motion drives
/// into the body by more than `sink` over the step: the body is pushed from
/// the start. `reach`: how far apart counts as touching.
pub(crate) fn pushed_at_start(
    scene: &Scene,
    body: &Moved,
    pusher: &Moved,
    reach: f64,
    sink: f64,
) -> Option<BodyHit> {
    let rb = scene.bodies.get(body.handle)?;
    let pb = scene.bodies.get(pusher.handle)?;
    for &h1 in rb.colliders() {
        let Some(co1) = scene.colliders.get(h1).filter(|c| c.is_enabled()) else {
            continue;
        };
        let Some(local1) = co1.position_wrt_parent() else {
            continue;
        };
        for &h2 in pb.colliders() {
            let Some(co2) = scene.colliders.get(h2) else {
                continue;
            };
            if !matches!(pair_kind(scene, h1, co1, h2, co2), Some(PairKind::Solid)) {
                continue;
            }
            let Some(local2) = co2.position_wrt_parent() else {
                continue;
            };
            let p1 = body.start * *local1;
            let p2 = pusher.start * *local2;
            let Ok(Some(c)) =
                rapier3d::parry::query::contact(&p2, co2.shape(), &p1, co1.shape(), reach as f32)
            else {
                continue;
            };
            if c.dist as f64 > reach {
                continue;
            }
            let w = c.point1;
            let moved = pusher.end * pusher.start.inverse_transform_point(w);
            let drive = (moved - w).dot(c.normal1) as f64;
            if drive > sink {
                let point = |p: rapier3d::prelude::Vector| {
                    nalgebra::Point3::new(p.x as f64, p.y as f64, p.z as f64)
                };
                return Some(BodyHit {
                    toi: Toi {
                        fraction: 0.0,
                        time: 0.0,
                        status: RootStatus::InitiallyTouching,
                        witness1: point(c.point2),
                        witness2: point(c.point1),
                        normal1: nalgebra::Vector3::new(
                            -c.normal1.x as f64,
                            -c.normal1.y as f64,
                            -c.normal1.z as f64,
                        ),
                        stats: Default::default(),
                    },
                    collider1: h1,
                    collider2: h2,
                });
            }
        }
    }
    None
}
