//! Fast kinematic bodies push the dynamic bodies they would pass.
//!
//! Rapier never sweeps kinematic bodies, so a fast paddle passes through
//! resting boxes. Here the pushers' contacts are resolved in time order:
//! the earliest impact is carried first, and a carried body joins the
//! pusher's front for the later ones.

use super::candidates::body_box;
use super::clamp;
use super::moved::Moved;
use super::report::{CcdReport, SkipReason};
use super::sweep::{self, Sweeper, Workspace};
use super::world::StepMotions;
use crate::query::QueryOptions;
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::prelude::{QueryFilter, RigidBodyHandle, Vector};
use std::collections::{HashMap, HashSet};

/// Most bodies one step's pushers carry.
const MAX_CARRIED: usize = 64;

/// One body a pusher may carry: its index in the moved bodies, its
/// earliest impact with the front so far.
struct Cand {
    i: usize,
    best: Option<sweep::BodyHit>,
    /// Swept against the whole front (a candidate found late is).
    swept: bool,
    done: bool,
}

/// The fast kinematic bodies push what they would pass, in time order: the
/// dynamic bodies whose box meets a pusher's swept box are swept against
/// the pushers, the earliest impact is carried (`clamp::carry`), the
/// carried body joins the front (what it meets is carried in turn, the
/// bodies near its swept box become candidates), and so on. A body
/// touching the front at the start that the front drives into is carried
/// from the start. Each candidate is swept once against each front member
/// (their motions are final once they join). Returns the carried bodies
/// (index into `current`), their impacts and velocities; `front` ends with
/// the pushers and the carried bodies.
pub(super) fn push(
    q: &Sweeper,
    current: &mut Vec<Moved>,
    front: &mut HashSet<RigidBodyHandle>,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
) -> Vec<(usize, sweep::BodyHit, Vector)> {
    let (scene, dt) = (q.scene, q.dt);
    let mut out = Vec::new();
    let mut cands: Vec<Cand> = Vec::new();
    let mut seen: HashSet<RigidBodyHandle> = front.clone();
    let mut fresh: HashSet<RigidBodyHandle> = front.clone();
    let mut velocities: HashMap<RigidBodyHandle, Vector> = HashMap::new();
    let boxes: Vec<_> = current
        .iter()
        .filter(|m| m.pusher)
        .filter_map(|m| body_box(scene, m))
        .collect();
    for b in boxes {
        gather_near(q, current, &mut seen, b, &mut cands);
    }
    while out.len() < MAX_CARRIED {
        sweep_candidates(q, opts, current, &mut cands, front, &fresh, ws, report);
        fresh.clear();
        // The earliest impact of any candidate is carried first.
        let Some(k) = (0..cands.len())
            .filter(|&k| !cands[k].done && cands[k].best.is_some())
            .min_by(|&a, &b| {
                let fa = cands[a].best.map_or(1.0, |h| h.toi.fraction);
                let fb = cands[b].best.map_or(1.0, |h| h.toi.fraction);
                fa.total_cmp(&fb)
            })
        else {
            break;
        };
        cands[k].done = true;
        let (i, hit) = (cands[k].i, cands[k].best.expect("filtered"));
        let Some(by) = scene.colliders[hit.collider2].parent() else {
            continue;
        };
        let Some(p) = current.iter().position(|m| m.handle == by) else {
            continue;
        };
        match clamp::carry(scene.bodies, &current[i], &current[p], hit.toi.fraction, dt) {
            Ok((cut, v)) => {
                let v = velocities.get(&by).copied().unwrap_or(v);
                let h = cut.handle;
                current[i] = cut;
                velocities.insert(h, v);
                front.insert(h);
                fresh.insert(h);
                out.push((i, hit, v));
                if let Some(b) = body_box(scene, &current[i]) {
                    gather_near(q, current, &mut seen, b, &mut cands);
                }
            }
            Err(e) => report.skip(current[i].handle, SkipReason::Query(e.to_string())),
        }
    }
    out
}

/// Adds as candidates the dynamic bodies not seen yet whose colliders
/// meet `b` (a body at rest joins `current` with a motion that stays).
fn gather_near(
    q: &Sweeper,
    current: &mut Vec<Moved>,
    seen: &mut HashSet<RigidBodyHandle>,
    b: Aabb,
    cands: &mut Vec<Cand>,
) {
    let scene = q.scene;
    let query = q.broad_phase.as_query_pipeline(
        q.dispatcher,
        scene.bodies,
        scene.colliders,
        QueryFilter::default(),
    );
    for (_, co) in query.intersect_aabb_conservative(b) {
        let Some(h) = co.parent() else { continue };
        if !seen.insert(h) {
            continue;
        }
        let Some(rb) = scene.bodies.get(h) else {
            continue;
        };
        if !rb.is_dynamic() || !rb.is_enabled() || scene.config.opted_out(rb.user_data) {
            continue;
        }
        let i = match current.iter().position(|m| m.handle == h) {
            Some(i) => i,
            None => {
                current.push(Moved {
                    handle: h,
                    start: *rb.position(),
                    end: *rb.position(),
                    angvel: Vector::ZERO,
                    accel: Vector::ZERO,
                    fast: false,
                    pusher: false,
                    travel: 0.0,
                });
                current.len() - 1
            }
        };
        cands.push(Cand {
            i,
            best: None,
            swept: false,
            done: false,
        });
    }
}

/// Sweeps each open candidate against the front (a candidate swept
/// before only against its new members, `fresh`), keeping its earliest
/// impact. A candidate the front drives into from the start is hit at 0.
#[allow(clippy::too_many_arguments)]
fn sweep_candidates(
    q: &Sweeper,
    opts: &QueryOptions,
    current: &[Moved],
    cands: &mut [Cand],
    front: &HashSet<RigidBodyHandle>,
    fresh: &HashSet<RigidBodyHandle>,
    ws: &mut Workspace,
    report: &mut CcdReport,
) {
    let scene = q.scene;
    let reach = 2.0 * opts.skin + 1.0e-4;
    let motions = StepMotions::new(current, q.dt);
    for c in cands.iter_mut().filter(|c| !c.done) {
        let set = if c.swept { fresh } else { front };
        c.swept = true;
        if set.is_empty() {
            continue;
        }
        let body = &current[c.i];
        let touching = set.iter().find_map(|h| {
            let p = motions.body(*h)?;
            sweep::pushed_at_start(scene, body, p, reach, scene.config.sink)
        });
        let hit = match touching {
            Some(hit) => Some(hit),
            None => {
                report.bodies_swept += 1;
                match sweep::sweep_body(
                    scene,
                    q.broad_phase,
                    q.dispatcher,
                    &motions,
                    body,
                    sweep::Targets::Only(set),
                    opts,
                    ws,
                    report,
                    &mut Vec::new(),
                ) {
                    Ok(hit) => hit.filter(|h| h.toi.fraction < 1.0),
                    Err(e) => {
                        report.skip(body.handle, SkipReason::Query(e.to_string()));
                        None
                    }
                }
            }
        };
        if let Some(hit) = hit
            && c.best.is_none_or(|b| hit.toi.fraction < b.toi.fraction)
        {
            c.best = Some(hit);
        }
    }
}
