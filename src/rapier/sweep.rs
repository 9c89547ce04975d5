//! One fast body's earliest impact over the step, and the sensors it
//! crosses before it. Every call to the time-of-impact query is in
//! [`earliest`] and [`first_crossing`].

use super::backoff::{BACKOFF, back_off, pair_travel};
use super::candidates::{Candidate, Interaction, gather, interaction, swept_aabb};
use super::moved::Moved;
use super::report::CcdReport;
use super::touching::{gap_at, touching_pair};
use super::world::{StageWorld, StepMotions};
use crate::convert::pose_from_iso;
use crate::enclosure::TimeSpan;
use crate::error::CcdError;
use crate::motion::{Motion, Trajectory};
use crate::query::{QueryOptions, ShapeMotion, Toi, Witness, time_of_impact, time_of_impact_many};
use crate::solve::RootStatus;
use rapier3d::parry::bounding_volume::BoundingVolume;
use rapier3d::parry::query::{Contact, QueryDispatcher};
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
    /// The pair was already touching at the start (`touching_pair`).
    pub touching: bool,
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

/// What every sweep of one step reads: the world, its broad phase and
/// query dispatcher, and the step length (seconds).
pub(crate) struct Sweeper<'w, 's> {
    pub scene: &'w StageWorld<'s>,
    pub broad_phase: &'w BroadPhaseBvh,
    pub dispatcher: &'w dyn QueryDispatcher,
    pub dt: f64,
}

/// Reused buffers; `motions` caches target motions for one step (clear it
/// between steps).
#[derive(Default)]
pub(crate) struct Workspace {
    candidates: Vec<Candidate>,
    pub motions: HashMap<ColliderHandle, Motion>,
}

/// The earliest impact of one collider: when, against which target, and
/// whether that pair was touching at the start.
struct Earliest {
    toi: Toi,
    target: usize,
    touching: bool,
}

/// Earliest impact of `moving` against `targets`, all pairs in one search.
///
/// A pair within the skin at the start (parry's gap) belongs to rapier's
/// contacts, whose speculative contacts see it: it is left out of the
/// joint search and handed to [`touching_pair`], which steps in only when
/// the motion drives it deeper than `max(start depth, sink)` or it
/// separates and comes back (rapier's `stop_at_penetration = false`). An
/// impact at τ = 0 for every touching pair would freeze a body resting or
/// sliding on the ground.
///
/// The others are searched together at **zero skin**: an impact is the
/// true contact, backed off along the motion (see `backoff`). A near miss
/// (a ball passing an edge within the skin) is no impact, and neither is a
/// contact that cannot get deeper than `sink` before the step ends (the
/// pair's travel after it is smaller): rapier's contacts resolve it next
/// step exactly as they would without CCD.
fn earliest(
    moving: &ShapeMotion,
    targets: &[ShapeMotion],
    opts: &QueryOptions,
    sink: f64,
    report: &mut CcdReport,
) -> Result<Option<Earliest>, CcdError> {
    let mut best: Option<Earliest> = None;
    let mut keep = |found: Earliest| {
        if best
            .as_ref()
            .is_none_or(|b| found.toi.fraction < b.toi.fraction)
        {
            best = Some(found);
        }
    };
    let lo = opts.time_range.lo;
    // A small prediction finds the contact of a pair within the skin, or
    // within the allowed sinking (which `touching_pair` reads it for).
    let reach = opts.skin.max(sink) + 1.0e-2;
    let touching = |j: usize, start: (f64, Option<Contact>), report: &mut CcdReport| {
        report.pairs_touching_at_start += 1;
        touching_pair(moving, &targets[j], start, sink, opts, report)
    };
    let mut alive: Vec<usize> = Vec::with_capacity(targets.len());
    // parry's contact costs GJK (and EPA when touching): ask it only for
    // pairs whose boxes at the start come within the skin.
    let start_box = |s: &dyn Shape, m: &Motion| s.compute_aabb(&pose_from_iso(&m.pose_at(lo)));
    let moving_box =
        start_box(moving.shape, &moving.motion).loosened(opts.skin as f32 * 1.01 + 1.0e-6);
    for (j, t) in targets.iter().enumerate() {
        if !moving_box.intersects(&start_box(t.shape, &t.motion)) {
            alive.push(j);
            continue;
        }
        match gap_at(moving.shape, &moving.motion, t.shape, &t.motion, lo, reach) {
            Some(start) if start.0 <= opts.skin => {
                if let Some(toi) = touching(j, start, report)? {
                    keep(Earliest {
                        toi,
                        target: j,
                        touching: true,
                    });
                }
            }
            _ => alive.push(j),
        }
    }
    let contact = QueryOptions { skin: 0.0, ..*opts };
    while !alive.is_empty() {
        let set: Vec<ShapeMotion> = alive
            .iter()
            .map(|&j| ShapeMotion {
                shape: targets[j].shape,
                motion: targets[j].motion,
            })
            .collect();
        let found = time_of_impact_many(std::slice::from_ref(moving), &set, &contact)?;
        let Some(many) = found else { break };
        report.evaluations += many.toi.stats.pair_evaluations;
        let j = alive[many.target];
        let t = &targets[j];
        if many.toi.status != RootStatus::InitiallyTouching {
            let travel = pair_travel(moving.shape, &moving.motion, t.shape, &t.motion);
            // No point of the pair moves farther than this after the
            // contact, so it gets no deeper: rapier's contacts take it
            // next step as they would without CCD (a slow landing).
            let after = travel * (opts.time_range.hi - many.toi.fraction).max(0.0);
            if after <= sink && many.toi.status == RootStatus::Hit {
                report.shallow_contacts += 1;
                alive.remove(many.target);
                continue;
            }
            keep(Earliest {
                toi: back_off(many.toi, travel, BACKOFF * opts.skin, lo),
                target: j,
                touching: false,
            });
            break;
        }
        // The pair touches at the start after all (parry saw it apart).
        alive.remove(many.target);
        let Some(start) = gap_at(moving.shape, &moving.motion, t.shape, &t.motion, lo, reach)
        else {
            continue;
        };
        if let Some(toi) = touching(j, start, report)? {
            keep(Earliest {
                toi,
                target: j,
                touching: true,
            });
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
    scene: &StageWorld,
    broad_phase: &BroadPhaseBvh,
    dispatcher: &dyn QueryDispatcher,
    motions: &StepMotions,
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
            match c.interaction {
                Interaction::Solid => {
                    solid.push(ShapeMotion {
                        shape: co2.shape(),
                        motion: motion2,
                    });
                    handles.push(c.handle);
                }
                Interaction::Sensor => sensors.push(SensorPair {
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
        if let Some(e) = earliest(&moving, &solid, opts, scene.config.sink, report)? {
            if best.is_none_or(|b| e.toi.fraction < b.toi.fraction) {
                best = Some(BodyHit {
                    toi: e.toi,
                    collider1: h1,
                    collider2: handles[e.target],
                    touching: e.touching,
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
    scene: &StageWorld,
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
            if !matches!(
                interaction(scene, h1, co1, h2, co2),
                Some(Interaction::Solid)
            ) {
                continue;
            }
            let Some(local2) = co2.position_wrt_parent() else {
                continue;
            };
            let p1 = body.start * *local1;
            let p2 = pusher.start * *local2;
            let Ok(Some(c)) =
                crate::query::contact(&p2, co2.shape(), &p1, co1.shape(), reach as f32)
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
                // The contact was asked pusher first: flip it to the body's side.
                return Some(BodyHit {
                    toi: Toi::new(
                        0.0,
                        0.0,
                        RootStatus::InitiallyTouching,
                        Witness::of(&c.flipped()),
                        Default::default(),
                    ),
                    collider1: h1,
                    collider2: h2,
                    touching: false,
                });
            }
        }
    }
    None
}
