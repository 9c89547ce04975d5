//! Fast kinematic bodies push the dynamic bodies they would pass.
//!
//! Rapier never sweeps kinematic bodies, so a fast paddle passes through
//! resting boxes. Here the pushers' contacts are resolved in time order:
//! the earliest impact is carried first, and a carried body joins the
//! pusher's front for the later ones.

use super::candidates::{body_box, start_box};
use super::clamp;
use super::moved::{Moved, relative_travel};
use super::report::{CcdReport, SkipReason};
use super::sweep::{self, Sweeper, Workspace};
use super::world::{StageWorld, StepMotions};
use crate::hashing::{FastMap, FastSet};
use crate::query::QueryOptions;
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::prelude::{QueryFilter, RigidBodyHandle, Vector};
use smallvec::SmallVec;

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
    front: &mut FastSet<RigidBodyHandle>,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
) -> Vec<(usize, sweep::BodyHit, Vector)> {
    let (scene, dt) = (q.scene, q.dt);
    let mut out = Vec::new();
    let mut cands: Vec<Cand> = Vec::new();
    let mut seen: FastSet<RigidBodyHandle> = front.clone();
    let mut fresh: FastSet<RigidBodyHandle> = front.clone();
    let mut velocities: FastMap<RigidBodyHandle, Vector> = FastMap::default();
    let mut start_boxes = StartBoxes::default();
    let boxes: Vec<_> = current
        .iter()
        .filter(|m| m.pusher)
        .filter_map(|m| body_box(scene, m))
        .collect();
    for b in boxes {
        gather_near(q, current, &mut seen, b, &mut cands);
    }
    while out.len() < MAX_CARRIED {
        sweep_candidates(
            q,
            opts,
            current,
            &mut cands,
            front,
            &fresh,
            &mut start_boxes,
            ws,
            report,
        );
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

/// The bodies' boxes at the start of their motions, each made once per
/// push: a carry changes where a body ends, never where it starts, and
/// every candidate is held against every front member again after each
/// carry (a paddle pushing six boxes in a row: 1.4 % of that scene's
/// instructions).
///
/// A short list, looked up in turn: a push meets a handful of bodies,
/// where a hash map's set-up cost more than the boxes it saved (pinball's
/// flippers).
#[derive(Default)]
struct StartBoxes(SmallVec<[(RigidBodyHandle, Option<Aabb>); 8]>);

impl StartBoxes {
    fn of(&mut self, scene: &StageWorld, m: &Moved) -> Option<Aabb> {
        if let Some((_, b)) = self.0.iter().find(|(h, _)| *h == m.handle) {
            return *b;
        }
        let b = start_box(scene, m);
        self.0.push((m.handle, b));
        b
    }
}

/// Adds as candidates the dynamic bodies not seen yet whose colliders
/// meet `b` (a body at rest joins `current` with a motion that stays).
fn gather_near(
    q: &Sweeper,
    current: &mut Vec<Moved>,
    seen: &mut FastSet<RigidBodyHandle>,
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
/// impact. A candidate the front drives into from the start is hit at 0;
/// one that cannot come near any of those members ([`may_meet`]) is not
/// swept.
#[allow(clippy::too_many_arguments)]
fn sweep_candidates(
    q: &Sweeper,
    opts: &QueryOptions,
    current: &[Moved],
    cands: &mut [Cand],
    front: &FastSet<RigidBodyHandle>,
    fresh: &FastSet<RigidBodyHandle>,
    start_boxes: &mut StartBoxes,
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
        let at_start = start_boxes.of(scene, body);
        if !set.iter().any(|h| {
            motions.body(*h).is_none_or(|m| {
                let member = start_boxes.of(scene, m);
                may_meet(
                    scene,
                    body,
                    at_start.as_ref(),
                    m,
                    member.as_ref(),
                    reach,
                    q.dt,
                )
            })
        }) {
            continue;
        }
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

/// Whether `body` (its start box `at_start`) may come within `reach` of
/// front member `member` (its start box `member_box`) during the step:
/// their start boxes are apart by no more than the two can move
/// relative to each other ([`relative_travel`]), with a millimetre to
/// spare for parry's `f32` gaps. A body farther than that can neither
/// touch the member at the start nor meet it later, so its sweep against
/// the member would find nothing. In a row of boxes a paddle pushes, each
/// carried box joins the front, and every box still ahead, moving along
/// with it, was swept against it: O(n²) sweeps a step, most of them this
/// far apart.
fn may_meet(
    scene: &StageWorld,
    body: &Moved,
    at_start: Option<&Aabb>,
    member: &Moved,
    member_box: Option<&Aabb>,
    reach: f64,
    dt: f64,
) -> bool {
    let (Some(a), Some(b), Some(ra), Some(rb)) = (
        at_start,
        member_box,
        scene.bodies.get(body.handle),
        scene.bodies.get(member.handle),
    ) else {
        return true;
    };
    let bound = relative_travel(body, ra, member, rb, dt) + reach + 1.0e-3;
    let gap = sweep::box_gap(a, b);
    // A gap or bound that came out NaN proves nothing.
    gap <= bound || gap.is_nan() || bound.is_nan()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InitialContact;
    use crate::rapier::config::CcdConfig;
    use crate::rapier::search;
    use crate::rapier::testing::Numbers;
    use rapier3d::prelude::{
        ColliderBuilder, ColliderSet, ImpulseJointSet, Pose, RigidBodyBuilder, RigidBodySet,
        Rotation,
    };

    /// A unit vector drawn from `n`.
    fn direction(n: &mut Numbers) -> Vector {
        let v = n.vector(1.0);
        Vector::new(v.x as f32, v.y as f32, v.z as f32).normalize_or(Vector::X)
    }

    /// Two bodies (a box with a ball off its centre of mass, and a box)
    /// and their records for one step of `dt`: both carried by a common
    /// `drift`, each shifted by up to `own` metres more and turned by up
    /// to `turn` radians, with spin hints of up to 40 rad/s; the second
    /// starts `apart` metres from the first along a random direction.
    fn pair(n: &mut Numbers, apart: f64, drift: f64, own: f64, turn: f64, dt: f64) -> Case {
        let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
        let mut records = Vec::new();
        let common = direction(n) * drift as f32;
        for k in 0..2 {
            let at = if k == 0 {
                Vector::ZERO
            } else {
                direction(n) * apart as f32
            };
            let start = Pose::from_parts(at, Rotation::from_scaled_axis(direction(n) * 3.0));
            let handle = bodies.insert(RigidBodyBuilder::dynamic().pose(start));
            let mut parts = vec![ColliderBuilder::cuboid(0.3, 0.1, 0.15)];
            if k == 0 {
                parts.push(ColliderBuilder::ball(0.1).translation(Vector::new(0.45, 0.0, 0.0)));
            }
            for part in parts {
                colliders.insert_with_parent(part.build(), handle, &mut bodies);
            }
            // What rapier's step does for a body whose colliders changed
            // (`max_extent` among it); the pushes run after the step.
            bodies[handle].recompute_mass_properties_from_colliders(&colliders);
            let shift = common + direction(n) * n.next(0.0, own) as f32;
            let rotation = Rotation::from_scaled_axis(direction(n) * n.next(0.0, turn) as f32);
            let end = Pose::from_parts(start.translation + shift, rotation * start.rotation);
            records.push(Moved {
                handle,
                start,
                end,
                angvel: direction(n) * n.next(0.0, 40.0) as f32,
                accel: Vector::ZERO,
                fast: true,
                pusher: false,
                travel: 0.0,
            });
        }
        Case {
            bodies,
            colliders,
            records,
            dt,
        }
    }

    struct Case {
        bodies: RigidBodySet,
        colliders: ColliderSet,
        records: Vec<Moved>,
        dt: f64,
    }

    impl Case {
        fn may_meet(&self, reach: f64) -> bool {
            let config = CcdConfig::default();
            let scene = StageWorld {
                bodies: &self.bodies,
                colliders: &self.colliders,
                joints: &ImpulseJointSet::new(),
                hooks: &(),
                config: &config,
                slop: 0.0,
            };
            let (body, member) = (&self.records[0], &self.records[1]);
            let (at_start, member_box) = (start_box(&scene, body), start_box(&scene, member));
            may_meet(
                &scene,
                body,
                at_start.as_ref(),
                member,
                member_box.as_ref(),
                reach,
                self.dt,
            )
        }

        /// Whether any collider of the first body comes within `reach` of
        /// the second's at some time of the step, on the motions the stage
        /// builds from the records, by the sound search.
        fn meet_within(&self, reach: f64) -> bool {
            let motions = StepMotions::new(&self.records, self.dt);
            let colliders = |m: &Moved| self.bodies[m.handle].colliders().to_vec();
            let opts = QueryOptions {
                skin: reach,
                initial_contact: InitialContact::Report,
                ..QueryOptions::default()
            };
            let mut report = CcdReport::default();
            colliders(&self.records[0]).iter().any(|&h1| {
                colliders(&self.records[1]).iter().any(|&h2| {
                    let (c1, c2) = (&self.colliders[h1], &self.colliders[h2]);
                    let m1 = motions.collider(c1, &self.bodies).expect("finite");
                    let m2 = motions.collider(c2, &self.bodies).expect("finite");
                    search::one(c1.shape(), &m1, c2.shape(), &m2, &opts, &mut report)
                        .expect("a search")
                        .is_some()
                })
            })
        }
    }

    /// Where `may_meet` answers that two bodies cannot meet, the sound
    /// search finds them nowhere within the reach over the step: bodies
    /// carried together, drifting apart or together, turning up to two
    /// radians and spun by their hints, their origins 0.4 to 1.6 m apart
    /// (overlapping to a metre apart). It answers so for a good share of
    /// them, or the sweeps it spares would be none; with the turning
    /// chords left out of the bound it lets pairs that meet through.
    #[test]
    fn bodies_that_cannot_meet_do_not() {
        let mut n = Numbers(0x005e_ed0f_9a5e);
        let (reach, dt) = (2.0e-3 + 1.0e-4, 1.0 / 60.0);
        let mut spared = 0;
        for case in 0..600 {
            let own = [0.0, 0.05, 0.3][case % 3];
            let turn = [0.0, 0.5, 2.0][(case / 3) % 3];
            let (apart, drift) = (n.next(0.4, 1.6), n.next(0.0, 0.7));
            let c = pair(&mut n, apart, drift, own, turn, dt);
            if !c.may_meet(reach) {
                spared += 1;
                assert!(!c.meet_within(reach), "case {case}: they meet");
            }
        }
        assert!(spared >= 180, "only {spared} of 600 pairs spared");
    }

    /// A record whose bound comes out NaN (a non-finite end pose) proves
    /// nothing: the bodies may meet, however far apart they start.
    #[test]
    fn a_bound_that_is_nan_proves_nothing() {
        let mut n = Numbers(11);
        let mut c = pair(&mut n, 1.9, 0.0, 0.0, 0.0, 1.0 / 60.0);
        assert!(!c.may_meet(2.1e-3), "far apart and still");
        c.records[1].end.translation.x = f32::NAN;
        assert!(c.may_meet(2.1e-3));
    }

    /// Two bodies a paddle carries in a row, apart at the start and
    /// moving together at 40 m/s without turning, cannot meet, however far
    /// they go (the pushes of such a row were O(n²) sweeps a step).
    #[test]
    fn boxes_carried_together_cannot_meet() {
        let mut n = Numbers(7);
        let c = pair(&mut n, 0.65, 40.0 / 60.0, 0.0, 0.0, 1.0 / 60.0);
        assert!(!c.may_meet(2.1e-3));
    }
}
