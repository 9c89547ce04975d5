//! The sweep rounds of one step: the fast bodies first, then, while some
//! body was clamped, what the clamps changed (see [`sweep_rounds`]). Nothing
//! is written to the world here; the [`Plan`] is applied afterwards.

use super::candidates::rough_swept_box;
use super::clamp;
use super::moved::Moved;
use super::push;
use super::report::{CcdReport, SkipReason};
use super::sweep::{self, SensorPair, Sweeper, Workspace};
use super::world::{MotionCache, StageWorld, StepMotions};
use crate::hashing::FastSet;
use crate::query::QueryOptions;
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::prelude::{
    BroadPhaseBvh, Collider, ColliderHandle, NarrowPhase, RigidBodyHandle, Vector,
};

/// What the sweeps found, applied after all of them (so that the order of
/// the bodies does not matter).
pub(crate) struct Plan {
    /// The moved bodies, each with its motion as cut by the sweeps.
    pub moved: Vec<Moved>,
    /// Per moved body, the share of its motion it keeps (1: not clamped).
    pub scale: Vec<f64>,
    /// Per moved body, the velocity a pusher gave it.
    pub velocity: Vec<Option<Vector>>,
    /// Index into `moved` of each clamped body, and its last impact.
    pub hits: Vec<(usize, sweep::BodyHit)>,
    /// Per moved body, whether some round clamped it for a pair touching at
    /// the start (a later round's hit may be another pair's).
    pub held: Vec<bool>,
    pub sensors: Vec<SensorPair>,
}

/// Rounds of re-sweeping after clamps (the first sweep included).
const MAX_ROUNDS: usize = 8;

/// What one body is swept against in a round.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Against {
    /// Everything (a fast body's first sweep, a rerouted body).
    All,
    /// The moving bodies (a clamped body: its timing changed).
    Moving,
    /// The bodies changed in the last round.
    Changed,
    /// Everything but dynamic bodies and pushers (a carried body).
    Blockers,
}

/// Sweeps the fast bodies; then, while some body was clamped, sweeps again
/// what the clamps changed: a clamped body against the moving bodies (its
/// timing changed), and every dynamic body near a clamped one against it
/// (it was solved against the uncut motion). Re-sweeps use half the skin,
/// so a pair left a skin apart by an earlier clamp does not clamp again.
///
/// Fast kinematic bodies ("pushers") are swept against too: rapier never
/// sweeps them, so a fast paddle passes through resting boxes. A dynamic
/// body (awake or not, moving or not) that a pusher would pass is
/// *carried*: from its time of impact on it moves rigidly with the pusher,
/// ends a skin ahead of it and gets the pusher's velocity at its centre of
/// mass (an inelastic push; the next step's contacts go on from there).
/// What a carried body meets on the way is carried in turn; anything else
/// stops it (it is then squeezed, rapier's contacts' business).
#[allow(clippy::too_many_arguments)]
pub(crate) fn sweep_rounds(
    scene: &StageWorld,
    broad_phase: &BroadPhaseBvh,
    narrow_phase: &NarrowPhase,
    moved: Vec<Moved>,
    dt: f64,
    opts: &QueryOptions,
    ws: &mut Workspace,
    report: &mut CcdReport,
) -> Plan {
    let query = Sweeper {
        scene,
        broad_phase,
        dispatcher: narrow_phase.query_dispatcher(),
        dt,
    };
    ws.motions.clear();
    let mut rounds = Rounds::new(moved);
    let mut dirty = rounds.push_and_start(&query, opts, ws, report);
    let resweep = QueryOptions {
        skin: 0.5 * opts.skin,
        ..*opts
    };
    for round in 0..MAX_ROUNDS {
        if dirty.is_empty() {
            break;
        }
        let first = round == 0;
        let found = rounds.sweep(
            &query,
            &dirty,
            first,
            if first { opts } else { &resweep },
            ws,
            report,
        );
        rounds.cut(scene, found, dt, report);
        dirty = rounds.next_dirty(scene, dt, &mut ws.motions);
    }
    rounds.into_plan()
}

/// A hit body's motion as a round cuts it: carried by the pusher at index
/// `p` (with the velocity the push gives it), or truncated at its impact
/// (`true` when the cut motion leaves the old path).
enum Cut {
    Carried(Moved, usize, Vector),
    Truncated(Moved, bool),
}

/// The state carried from one round to the next.
struct Rounds {
    /// The moved bodies, each with its motion as cut so far.
    current: Vec<Moved>,
    scale: Vec<f64>,
    velocity: Vec<Option<Vector>>,
    last: Vec<Option<sweep::BodyHit>>,
    held: Vec<bool>,
    /// Fast kinematic bodies and what they carry.
    pushing: FastSet<RigidBodyHandle>,
    carried: FastSet<RigidBodyHandle>,
    /// Bodies cut in the last round, as indices and as handles.
    changed: Vec<usize>,
    changed_set: FastSet<RigidBodyHandle>,
    /// Clamped bodies whose cut motion is not part of the old path.
    rerouted: FastSet<RigidBodyHandle>,
    sensors: Vec<SensorPair>,
}

impl Rounds {
    fn new(moved: Vec<Moved>) -> Rounds {
        let n = moved.len();
        Rounds {
            scale: vec![1.0; n],
            velocity: vec![None; n],
            last: vec![None; n],
            held: vec![false; n],
            pushing: moved
                .iter()
                .filter(|m| m.pusher)
                .map(|m| m.handle)
                .collect(),
            current: moved,
            carried: FastSet::default(),
            changed: Vec::new(),
            changed_set: FastSet::default(),
            rerouted: FastSet::default(),
            sensors: Vec::new(),
        }
    }

    /// Lets the pushers carry what they meet, and returns the first round's
    /// sweeps: every fast body against everything, a carried body against
    /// what can stop it (not what carries it or what it carries).
    fn push_and_start(
        &mut self,
        q: &Sweeper,
        opts: &QueryOptions,
        ws: &mut Workspace,
        report: &mut CcdReport,
    ) -> Vec<(usize, Against)> {
        if !self.pushing.is_empty() {
            let pushed = push::push(q, &mut self.current, &mut self.pushing, opts, ws, report);
            // Pushing may add bodies that were at rest (not moved).
            let n = self.current.len();
            self.scale.resize(n, 1.0);
            self.velocity.resize(n, None);
            self.last.resize(n, None);
            self.held.resize(n, false);
            for (i, hit, v) in pushed {
                self.velocity[i] = Some(v);
                self.last[i] = Some(hit);
                self.carried.insert(self.current[i].handle);
            }
        }
        // Fast bodies first, then carried ones (the order cuts are made in).
        let carried = |m: &Moved| self.carried.contains(&m.handle);
        let (fast, pushed): (Vec<_>, Vec<_>) = self
            .current
            .iter()
            .enumerate()
            .filter(|(_, m)| m.fast || carried(m))
            .partition(|(_, m)| !carried(m));
        let mut dirty: Vec<_> = fast.into_iter().map(|(i, _)| (i, Against::All)).collect();
        dirty.extend(pushed.into_iter().map(|(i, _)| (i, Against::Blockers)));
        dirty
    }

    /// Sweeps each dirty body against its targets: the hits before the end
    /// of the step. The first round also gathers the sensor pairs.
    #[allow(clippy::too_many_arguments)]
    fn sweep(
        &mut self,
        q: &Sweeper,
        dirty: &[(usize, Against)],
        first: bool,
        opts: &QueryOptions,
        ws: &mut Workspace,
        report: &mut CcdReport,
    ) -> Vec<(usize, sweep::BodyHit)> {
        let motions = StepMotions::new(&self.current, q.dt);
        let mut found = Vec::new();
        for &(i, against) in dirty {
            let body = &self.current[i];
            let targets = match against {
                Against::All => sweep::Targets::All,
                Against::Moving => sweep::Targets::Moving,
                Against::Changed => sweep::Targets::Only(&self.changed_set),
                Against::Blockers => sweep::Targets::Blockers(&self.pushing),
            };
            report.bodies_swept += 1;
            let mut body_sensors = Vec::new();
            match sweep::sweep_body(
                q.scene,
                q.broad_phase,
                q.dispatcher,
                &motions,
                body,
                targets,
                opts,
                ws,
                report,
                &mut body_sensors,
            ) {
                Ok(hit) => {
                    if let Some(hit) = hit.filter(|h| h.toi.fraction < 1.0) {
                        found.push((i, hit));
                    }
                    if first {
                        self.sensors.append(&mut body_sensors);
                    }
                }
                Err(e) => report.skip(body.handle, SkipReason::Query(e.to_string())),
            }
        }
        found
    }

    /// Cuts (or carries) the motions of the bodies hit in this round, after
    /// all of its sweeps, so the order of the bodies does not matter.
    fn cut(
        &mut self,
        scene: &StageWorld,
        found: Vec<(usize, sweep::BodyHit)>,
        dt: f64,
        report: &mut CcdReport,
    ) {
        self.changed.clear();
        self.changed_set.clear();
        self.rerouted.clear();
        // Every cut from the motions as they were before this round (a
        // pusher's own motion may be cut in it too), then all of them
        // applied, in the same order.
        let cuts: Vec<_> = found
            .into_iter()
            .map(|(i, hit)| {
                let by = scene.colliders[hit.collider2]
                    .parent()
                    .filter(|h| self.pushing.contains(h))
                    .and_then(|h| self.current.iter().position(|m| m.handle == h));
                let f = hit.toi.fraction;
                let cut = match by {
                    Some(p) => {
                        clamp::carry(scene.bodies, &self.current[i], &self.current[p], f, dt)
                            .map(|(cut, v)| Cut::Carried(cut, p, v))
                    }
                    None => clamp::truncate(scene.bodies, &self.current[i], f, dt)
                        .map(|(cut, new_path)| Cut::Truncated(cut, new_path)),
                };
                (i, hit, cut)
            })
            .collect();
        for (i, hit, cut) in cuts {
            let handle = self.current[i].handle;
            let changed = match cut {
                Ok(Cut::Carried(cut, p, v)) => {
                    self.current[i] = cut;
                    self.velocity[i] = Some(self.velocity[p].unwrap_or(v));
                    self.carried.insert(handle);
                    self.rerouted.insert(handle);
                    true
                }
                Ok(Cut::Truncated(cut, new_path)) => {
                    // Cut to the motion it already has (a body held at its
                    // start and found there again): nothing changed for
                    // the next round to sweep, which would only find the
                    // same cut again, round after round.
                    let old = &self.current[i];
                    let changed =
                        cut.end != old.end || cut.angvel != old.angvel || cut.accel != old.accel;
                    if new_path && changed {
                        self.rerouted.insert(handle);
                    }
                    self.current[i] = cut;
                    self.scale[i] *= hit.toi.fraction;
                    changed
                }
                Err(e) => {
                    report.skip(handle, SkipReason::Query(e.to_string()));
                    continue;
                }
            };
            self.held[i] |= hit.touching;
            self.last[i] = Some(hit);
            if changed {
                self.changed.push(i);
                self.changed_set.insert(handle);
            }
        }
        self.pushing.extend(self.carried.iter().copied());
    }

    /// The next round's sweeps: the changed bodies, and the dynamic bodies
    /// one of whose colliders' swept boxes meets a changed body's, both
    /// over their motions as cut so far. A collider is first held to the
    /// box from its body's two poses, which needs no motion built; only
    /// one that meets a changed box gets its motion's own.
    fn next_dirty(
        &self,
        scene: &StageWorld,
        dt: f64,
        cache: &mut MotionCache,
    ) -> Vec<(usize, Against)> {
        let mut dirty = Vec::new();
        if self.changed.is_empty() {
            return dirty;
        }
        for &i in &self.changed {
            let h = self.current[i].handle;
            let against = if self.carried.contains(&h) {
                Against::Blockers
            } else if self.rerouted.contains(&h) {
                Against::All
            } else {
                Against::Moving
            };
            dirty.push((i, against));
        }
        let motions = StepMotions::new(&self.current, dt);
        // `None`: a motion that cannot be built, which meets everything.
        let mut swept =
            |h: ColliderHandle, co: &Collider| cache.swept(&motions, h, co, scene.bodies).ok();
        let mut changed: Vec<Option<Aabb>> = Vec::new();
        for &i in &self.changed {
            for (h, co) in scene.colliders_of(self.current[i].handle) {
                changed.push(swept(h, co));
            }
        }
        let meets = |b: &Aabb| changed.iter().any(|c| c.is_none_or(|c| c.intersects(b)));
        for (j, m) in self.current.iter().enumerate() {
            // A carried body rides with its pusher: what it meets is
            // carried in turn, it is not stopped by it.
            if self.changed_set.contains(&m.handle) || self.carried.contains(&m.handle) {
                continue;
            }
            let Some(rb) = scene.bodies.get(m.handle) else {
                continue;
            };
            if !rb.is_dynamic() || scene.config.opted_out(rb.user_data) {
                continue;
            }
            let hit = scene.colliders_of(m.handle).any(|(h, co)| {
                meets(&rough_swept_box(&motions, co, scene.bodies))
                    && swept(h, co).is_none_or(|b| meets(&b))
            });
            if hit {
                dirty.push((j, Against::Changed));
            }
        }
        dirty
    }

    fn into_plan(self) -> Plan {
        let hits = self
            .last
            .iter()
            .enumerate()
            .filter_map(|(i, h)| h.map(|h| (i, h)))
            .collect();
        Plan {
            moved: self.current,
            scale: self.scale,
            velocity: self.velocity,
            hits,
            held: self.held,
            sensors: self.sensors,
        }
    }
}
