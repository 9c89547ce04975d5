//! One fast body's earliest impact over the step, and the sensors it
//! crosses before it ([`earliest`], [`first_crossing`]).

use super::backoff::{
    DeepStop, HandBack, Stop, deep_stop_at_once, mesh_stays_apart, pair_approaches_within,
    pair_relative_travel, pair_travel, stop_after_contact, stop_when_deep,
};
use super::candidates::{
    Candidate, FEW_PIECES, Interaction, MAX_PIECES, MeshPiece, MovingBoxes, gather, gather_listed,
    interaction, is_moving, mesh_triangles, move_together, pose_path_box, swept_aabb,
};
use super::moved::Moved;
use super::report::CcdReport;
use super::search;
use super::select::thickness;
use super::touching::{gap_at, never_as_deep, past_band, read_gap, touching_pair};
use super::world::{MotionCache, StageWorld, StepMotions};
use crate::convert::{pose_from_iso, vec_from_glam};
use crate::enclosure::TimeSpan;
use crate::error::CcdError;
use crate::hashing::FastSet;
use crate::motion::{Motion, Trajectory};
use crate::query::{
    QueryOptions, ShapeMotion, StartContact, Toi, Witness, lone_pair, start_contact,
};
use crate::solve::RootStatus;
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::parry::query::{Contact, QueryDispatcher};
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::RigidBodyHandle;
use rapier3d::prelude::{BroadPhaseBvh, Collider, ColliderHandle, Vector};
use smallvec::SmallVec;

/// A list of one sweep's targets' small values (indices, travels,
/// flags), kept on the stack: most sweeps have a few targets, and each
/// sweep made several such lists; on the heap they cost about 1 % of the
/// demo scenes' whole runs (2-3 % of `kinematic_push`'s).
type Few<T> = SmallVec<[T; 8]>;

/// The targets' shapes and motions of one sweep, on the stack when few.
type FewMotions<'a> = SmallVec<[ShapeMotion<'a>; 4]>;

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
    Only(&'a FastSet<RigidBodyHandle>),
    /// Everything but dynamic bodies and these (a body carried by a
    /// kinematic one: what it meets on the way is pushed in turn, the
    /// pushers carry it, only the rest stops it).
    Blockers(&'a FastSet<RigidBodyHandle>),
}

impl Targets<'_> {
    /// Whether `co` is one of these targets.
    fn wants(&self, co: &Collider, motions: &StepMotions, scene: &StageWorld) -> bool {
        let parent = co.parent();
        match *self {
            Targets::All => true,
            Targets::Moving => parent.is_some_and(|b| motions.body(b).is_some()),
            Targets::Only(set) => parent.is_some_and(|b| set.contains(&b)),
            Targets::Blockers(set) => !parent.is_some_and(|b| {
                set.contains(&b) || scene.bodies.get(b).is_some_and(|rb| rb.is_dynamic())
            }),
        }
    }
}

/// What every sweep of one step reads: the world, its broad phase and
/// query dispatcher, and the step length (seconds).
pub(crate) struct Sweeper<'w, 's> {
    pub scene: &'w StageWorld<'s>,
    pub broad_phase: &'w BroadPhaseBvh,
    pub dispatcher: &'w dyn QueryDispatcher,
    pub dt: f64,
}

/// Reused buffers; `motions` caches collider motions for one step (clear
/// it between steps).
#[derive(Default)]
pub(crate) struct Workspace {
    candidates: Vec<Candidate>,
    /// The triangles a sweep splits meshes into (see [`earliest`]).
    triangles: Vec<MeshPiece>,
    pub motions: MotionCache,
    /// The moved colliders' rough boxes, when sweeps take them from a
    /// list (see [`MovingBoxes`]).
    moving: MovingBoxes,
    /// The collider pairs the last step's clamps held at their start
    /// (moving collider, target), either way round (see [`HELD`]).
    held: FastSet<(ColliderHandle, ColliderHandle)>,
    /// The pairs of moving colliders this round's sweeps proved apart.
    apart: ProvedApart,
}

/// The pairs of moving colliders (moving, target) a sweep proved to stay
/// out of contact over the whole span, on the motions and options it was
/// proved under: when the target's own sweep meets the moving collider
/// under the same ones, the pair is already settled (two fast bodies
/// flying past each other were searched once from each side: in the
/// bounce houses, most of the searches that found nothing). A pair that
/// never touches gives no event either way round: no stop, no touching
/// pair sinking deeper than allowed, no rounded pair getting as deep as
/// rapier's stop.
#[derive(Default)]
struct ProvedApart {
    /// `StepMotions::id`, and the span and skin's bits.
    under: Option<(u64, [u64; 3])>,
    pairs: FastSet<(ColliderHandle, ColliderHandle)>,
}

impl ProvedApart {
    /// Forgets the pairs proved under other motions or options.
    fn under(&mut self, motions: &StepMotions, opts: &QueryOptions) {
        let span = opts.time_range;
        let key = (
            motions.id(),
            [span.lo.to_bits(), span.hi.to_bits(), opts.skin.to_bits()],
        );
        if self.under != Some(key) {
            self.pairs.clear();
            self.under = Some(key);
        }
    }

    /// Whether `target`'s sweep proved it apart from `moving`.
    fn proved(&self, moving: ColliderHandle, target: ColliderHandle) -> bool {
        !self.pairs.is_empty() && self.pairs.contains(&(target, moving))
    }
}

/// A clamp at most this share into the step holds its body at its start.
/// A pair held there is rapier's contacts' in the next step, kept only
/// from sinking deeper than allowed (as a pair touching at the start is):
/// held again instead, step after step, its bodies do not move while the
/// contacts, which a clamp leaves the pair to, may see nothing to resolve
/// (a spinning gram-heavy brick whose corner the sweep saw reach a ball at
/// once, 2.6 mm apart: rapier's speculative contact gave no impulse, and
/// both were held for 1,650 steps of the long soak, gaining speed from
/// gravity alone).
const HELD: f64 = 1.0e-3;

impl Workspace {
    /// Keeps the pairs of `hits` held at their start, for the next step.
    pub fn remember_holds(&mut self, hits: &[super::report::CcdHitEvent]) {
        self.held.clear();
        self.held.extend(
            hits.iter()
                .filter(|h| h.fraction <= HELD)
                .map(|h| (h.collider1, h.collider2)),
        );
    }

    /// Whether the last step held the pair of `a` and `b` at its start.
    fn was_held(&self, a: ColliderHandle, b: ColliderHandle) -> bool {
        !self.held.is_empty() && (self.held.contains(&(a, b)) || self.held.contains(&(b, a)))
    }
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
/// A fixed mesh or heightfield near a slow shape, or one whose triangles
/// a fast shape's path meets at most [`FEW_PIECES`] of, is split into
/// those triangles first, each a target of its own, as rapier's CCD sweeps
/// them.
///
/// A pair close at the start (within [`HandBack::touch_band`] by parry's
/// gap: the skin, or about rapier's stop for a slow pair) belongs to
/// rapier's contacts, whose speculative contacts see it: it is left out of
/// the joint search and handed to [`touching_pair`], which steps in only
/// when the motion drives it deeper than [`HandBack::allowed_depth`] or it
/// separates and comes back (rapier's `stop_at_penetration = false`). An
/// impact at τ = 0 for every touching pair would freeze a body resting or
/// sliding on the ground. A ball or capsule close but shallower than
/// rapier's stop gets that stop instead (`stop_when_deep`).
///
/// The others are searched together at **zero skin**: an impact is the
/// true contact, so a near miss (a ball passing an edge within the skin)
/// is no impact. The body then stops where rapier's own CCD would stop it
/// (see `backoff`): an unrounded pair `slop` before the contact, a rounded
/// one `slop` deep after it, if it gets that deep before the step ends (or
/// before another pair's stop); pairs rapier casts to the contact, at the
/// contact, unless they cannot get deeper than `sink` before the step ends
/// (the pair's travel after it is smaller): rapier's contacts resolve
/// those next step exactly as they would without CCD.
///
/// `held` marks the targets whose pair the last step held at its start
/// (see [`HELD`]): they are the contacts', as touching pairs are. `apart`
/// gets the targets proved to stay out of contact over the whole span
/// (see [`ProvedApart`]).
#[allow(clippy::too_many_arguments)]
fn earliest(
    moving: &ShapeMotion,
    targets: &[ShapeMotion],
    held: &[bool],
    opts: &QueryOptions,
    rules: &HandBack,
    triangles: &mut Vec<MeshPiece>,
    apart: &mut Few<usize>,
    report: &mut CcdReport,
) -> Result<Option<Earliest>, CcdError> {
    // Fixed meshes near a slow shape, or a fast one whose path meets only
    // a few of their triangles: one target per triangle (see
    // `mesh_triangles`), each known by the target it came from.
    let margin = 2.0 * rules.slop + opts.skin;
    triangles.clear();
    let mut origin: Few<usize> = Few::with_capacity(targets.len());
    let mut split: Few<usize> = Few::new();
    let mut travels: Few<f64> = Few::with_capacity(targets.len());
    for (j, t) in targets.iter().enumerate() {
        let travel = pair_travel(moving.shape, &moving.motion, t.shape, &t.motion);
        travels.push(travel);
        let before = triangles.len();
        let most = if rules.is_slow(moving.shape, travel) {
            MAX_PIECES
        } else {
            FEW_PIECES
        };
        if mesh_triangles(
            moving.shape,
            &moving.motion,
            || swept_aabb(moving.shape, &moving.motion).loosened(margin as f32),
            t.shape,
            &t.motion,
            rules.slop,
            most,
            triangles,
        ) {
            split.extend(std::iter::repeat_n(j, triangles.len() - before));
        } else {
            origin.push(j);
        }
    }
    let unsplit = origin.len();
    // Unsplit targets go as they are (a motion is 240 bytes); `origin` is
    // then the identity.
    let (mut pieces, mut piece_travels, mut piece_contacts) =
        (Vec::new(), Few::<f64>::new(), Few::<bool>::new());
    let (pieces, travels, contacts_only): (&[ShapeMotion], &[f64], &[bool]) =
        if origin.len() == targets.len() {
            (targets, &travels, held)
        } else {
            let n = origin.len() + triangles.len();
            pieces.reserve_exact(n);
            piece_travels.reserve_exact(n);
            piece_contacts.reserve_exact(n);
            pieces.extend(origin.iter().map(|&j| targets[j]));
            piece_travels.extend(origin.iter().map(|&j| travels[j]));
            piece_contacts.extend(origin.iter().map(|&j| held[j]));
            for (piece, &j) in triangles.iter().zip(&split) {
                let motion = targets[j].motion;
                piece_travels.push(pair_travel(
                    moving.shape,
                    &moving.motion,
                    &piece.triangle,
                    &motion,
                ));
                pieces.push(ShapeMotion {
                    shape: &piece.triangle,
                    motion,
                });
                piece_contacts.push(piece.contacts_only || held[j]);
            }
            origin.extend(split);
            (&pieces, &piece_travels, &piece_contacts)
        };
    // The targets proved to stay out of contact over the span: an unsplit
    // one as its piece was (the unsplit ones come first, in order); a
    // split one never (each triangle is asked on its own).
    let mut pieces_apart = Few::new();
    let found = earliest_piece(
        moving,
        pieces,
        travels,
        contacts_only,
        opts,
        rules,
        &mut pieces_apart,
        report,
    )?;
    apart.extend(
        pieces_apart
            .iter()
            .filter(|&&p| p < unsplit)
            .map(|&p| origin[p]),
    );
    Ok(found.map(|e| Earliest {
        target: origin[e.target],
        ..e
    }))
}

/// [`earliest`] over targets none of which is split further, with each
/// pair's travel (`pair_travel`); `contacts_only` marks those rapier's CCD
/// leaves to its contacts, and those the last step held at their start
/// (only `touching_pair`'s check that they do not sink deep applies).
/// The targets proved apart over the whole span are pushed to `apart`.
#[allow(clippy::too_many_arguments)]
fn earliest_piece(
    moving: &ShapeMotion,
    targets: &[ShapeMotion],
    travels: &[f64],
    contacts_only: &[bool],
    opts: &QueryOptions,
    rules: &HandBack,
    apart: &mut Few<usize>,
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
    let sink = rules.sink;
    let lo = opts.time_range.lo;
    let bands: Few<f64> = targets
        .iter()
        .zip(travels)
        .map(|(t, &travel)| rules.touch_band(moving, t, opts.skin, travel))
        .collect();
    let widest = bands.iter().copied().fold(opts.skin, f64::max);
    // For the pairs whose start gap is read beyond their band (those left
    // to the contacts, and a pair found touching after all): a small
    // prediction finds the contact of a pair within the widest band, or
    // within the allowed sinking (which `touching_pair` reads it for).
    let reach = widest.max(sink) + 1.0e-2;
    // A pair rapier's contacts own, within `band` at the start.
    let touching = |j: usize, start, band, report: &mut CcdReport| {
        report.pairs_touching_at_start += 1;
        let toi = touching_pair(moving, &targets[j], start, band, rules, opts, report)?;
        Ok::<_, CcdError>(toi.map(|toi| Earliest {
            toi,
            target: j,
            touching: true,
        }))
    };
    // A pair close at the start: a ball or capsule shallower than
    // rapier's stop gets that stop from the sound query on its cores (as
    // rapier's sweep gives it, rather than leaving it to the contacts);
    // any other is rapier's contacts'.
    let close = |j: usize, start: (f64, Option<Contact>), report: &mut CcdReport| {
        let t = &targets[j];
        if let Some(depth) = rules.deep_stop(start.0, moving, t) {
            if never_as_deep(moving, t, &start, depth) {
                return Ok(None);
            }
            let toi = stop_when_deep(
                moving,
                t,
                lo,
                opts.time_range.hi,
                depth,
                rules.sweep_tolerance(),
                false,
                opts,
                report,
            )?;
            return Ok(toi.map(|toi| Earliest {
                toi,
                target: j,
                touching: false,
            }));
        }
        touching(j, start, bands[j], report)
    };
    // The pair's gap at the start, read within `reach`.
    let start_gap = |t: &ShapeMotion, reach: f64| {
        gap_at(
            moving.shape,
            &moving.motion,
            t.shape,
            &t.motion,
            lo,
            reach,
            None,
        )
    };
    let mut alive: Few<usize> = Few::with_capacity(targets.len());
    // parry's contact costs GJK (and EPA when touching): ask it only for
    // pairs whose boxes at the start come within the band.
    let start_box = |s: &dyn Shape, m: &Motion| s.compute_aabb(&pose_from_iso(&m.pose_at(lo)));
    let moving_box =
        start_box(moving.shape, &moving.motion).loosened(widest as f32 * 1.01 + 1.0e-6);
    // A convex pair (or a small mesh against a convex target) apart at the
    // start beyond its band that provably stays apart needs no search
    // (most searches that find nothing): the direction of parry's contact
    // at the start (`known`, else read as far as the pair's relative
    // travel, padded for `f32` poses by a few parts in 10⁷ of the moving
    // shape's box, near which any closer point of the target lies, and of
    // the target's origin (not its box: a half-space's is unbounded):
    // farther than that, it is apart),
    // along which the pair cannot close its start separation
    // (`apart_along`, or from the mesh's vertices, `mesh_stays_apart`).
    let far = |t: &ShapeMotion| {
        let travel = pair_relative_travel(moving.shape, &moving.motion, t.shape, &t.motion);
        let origin = t.motion.pose_at(lo).translation.vector.amax() as f32;
        let origin = Aabb::new(Vector::splat(-origin), Vector::splat(origin));
        travel * (1.0 + 1.0e-3) + 1.0e-4 + box_rounding(&moving_box, &origin)
    };
    let stays_apart = |t: &ShapeMotion, known: Option<&Contact>| {
        let convex = moving.shape.is_convex() && t.shape.is_convex();
        if !convex && (moving.shape.as_trimesh().is_none() || !t.shape.is_convex()) {
            return false;
        }
        let normal = match known {
            Some(c) => c.normal1,
            None => match start_gap(t, far(t)) {
                Some((_, None)) => return true,
                Some((_, Some(c))) => c.normal1,
                None => return false,
            },
        };
        if convex {
            apart_along(moving, t, normal)
        } else {
            normal
                .try_normalize()
                .is_some_and(|n| mesh_stays_apart(moving, t, &vec_from_glam(n)))
        }
    };
    for (j, t) in targets.iter().enumerate() {
        if contacts_only[j] {
            let start = start_gap(t, reach).unwrap_or((reach, None));
            if let Some(found) = touching(j, start, f64::INFINITY, report)? {
                keep(found);
            }
            continue;
        }
        let target_box = start_box(t.shape, &t.motion);
        if !moving_box.intersects(&target_box) {
            // Farther apart at the start than their points can move
            // relative to each other: they cannot meet (two bodies flying
            // side by side, a body far from a fixed one). Or, for a turning
            // shape (whose travel counts its whole reach turning), not
            // closing along the axis the boxes are farthest apart along (a
            // blade spinning beside a wall). A ball's or a straight
            // flyer's travel says as much, and the test would only cost.
            let gap = box_gap(&moving_box, &target_box);
            if gap > pair_relative_travel(moving.shape, &moving.motion, t.shape, &t.motion)
                || (moving.motion.turns()
                    && moving.shape.as_ball().is_none()
                    && moving.shape.is_convex()
                    && t.shape.is_convex()
                    && apart_along(moving, t, box_axis(&moving_box, &target_box)))
            {
                apart.push(j);
                continue;
            }
            alive.push(j);
            continue;
        }
        // Only a pair within its band reads its start gap here. A convex
        // pair reads it as far as `stays_apart` would (GJK costs the same
        // whatever the reach), so that a pair beyond its band is not asked
        // twice; a mesh's contact visits every part within the reach, and
        // reads only the band first.
        let band_reach = past_band(bands[j]);
        let convex = moving.shape.is_convex() && t.shape.is_convex();
        let ask = if convex {
            band_reach.max(far(t))
        } else {
            band_reach
        };
        // Two polytopes whose separating axes show them apart beyond the
        // band need no distance from parry (GJK) if they stay apart along
        // the axis that shows it; else their start gap as any pair's. A
        // capsule or cylinder and a box apart beyond the band, from their
        // closest points in closed form, need none at all.
        let start = if convex {
            let found = start_contact(
                &pose_from_iso(&moving.motion.pose_at(lo)),
                moving.shape,
                &pose_from_iso(&t.motion.pose_at(lo)),
                t.shape,
                band_reach,
                ask as f32,
            );
            match found {
                Ok(StartContact::ApartAlong { direction, .. })
                    if apart_along(moving, t, direction) =>
                {
                    apart.push(j);
                    continue;
                }
                // Beyond the band and not shown to stay apart along the
                // closest points' direction: no other does better.
                Ok(StartContact::ApartAlong { closest: true, .. }) => {
                    alive.push(j);
                    continue;
                }
                Ok(StartContact::ApartAlong { .. }) => start_gap(t, ask),
                Ok(StartContact::Found(c)) => read_gap(Ok(c), ask),
                Err(e) => read_gap(Err(e), ask),
            }
        } else {
            start_gap(t, ask)
        };
        match start {
            Some(start) if start.0 <= bands[j] => {
                if let Some(found) = close(j, start, report)? {
                    keep(found);
                }
            }
            // Nothing within `far` either: apart, as `stays_apart` finds.
            Some((_, None)) if convex => apart.push(j),
            Some((_, contact)) if stays_apart(t, contact.as_ref()) => apart.push(j),
            _ => alive.push(j),
        }
    }
    // The search ends at the earliest stop found so far: a rounded pair
    // stops after its contact, and another pair may stop before that.
    let mut until = opts.time_range.hi;
    while !alive.is_empty() && until > lo {
        // A lone ball or capsule that rapier stops a little deep after its
        // contact with a mesh: one search for that depth, not the
        // contact's and then the depth's (see `deep_stop_at_once`).
        if let [j] = alive[..] {
            match deep_stop_at_once(moving, &targets[j], lo, until, rules, opts, report)? {
                Some(DeepStop::Never) => break,
                Some(DeepStop::At(toi)) => {
                    keep(Earliest {
                        toi,
                        target: j,
                        touching: false,
                    });
                    break;
                }
                Some(DeepStop::NeedsContact) | None => {}
            }
        }
        let contact = QueryOptions {
            skin: 0.0,
            time_range: TimeSpan::new(lo, until),
            ..*opts
        };
        let set: FewMotions = alive
            .iter()
            .map(|&j| ShapeMotion {
                shape: targets[j].shape,
                motion: targets[j].motion,
            })
            .collect();
        let found = search::found(std::slice::from_ref(moving), &set, &contact, report)?;
        let Some(hit) = found else {
            // No contact over the whole span: apart.
            if until == opts.time_range.hi {
                apart.extend_from_slice(&alive);
            }
            break;
        };
        let j = alive[hit.target];
        let t = &targets[j];
        let status = hit.outcome.status;
        if status == RootStatus::InitiallyTouching {
            // The pair touches at the start after all (parry saw it apart).
            alive.remove(hit.target);
            let Some(start) = start_gap(t, reach) else {
                continue;
            };
            if let Some(found) = close(j, start, report)? {
                keep(found);
            }
            continue;
        }
        let found = |toi| Earliest {
            toi,
            target: j,
            touching: false,
        };
        let contact = (hit.outcome.time, status);
        let described = || hit.toi(moving, &set[hit.target]);
        match stop_after_contact(moving, t, contact, described, until, rules, opts, report)? {
            // At or before the contact: the earliest stop of all.
            Stop::Before(toi) => {
                keep(found(toi));
                break;
            }
            // After it: other pairs may still meet before.
            Stop::After(toi) => {
                alive.remove(hit.target);
                until = toi.fraction;
                keep(found(toi));
            }
            Stop::Contacts => {
                report.shallow_contacts += 1;
                alive.remove(hit.target);
            }
        }
    }
    Ok(best)
}

/// Whether convex `moving` and `target` stay apart over the whole step
/// along the direction `n` (from `moving` towards `target`): their
/// projections on `n` are apart at the step's start by `sep` (from their
/// support points, less the `f32` rounding of those), more than the pair
/// can approach along `n` from there ([`pair_approaches_within`]: its
/// bounds, the chord one and point by point, both bound the growth from
/// the step's start, so the separation is taken there, whatever part of
/// the step is searched). A plane across `n` then separates them at every
/// time: a body leaving a wall it bounced off, a box sliding past a
/// triangle's edge, two bodies passing each other. `false` for a shape
/// without support points (a half-space) or when it cannot tell.
fn apart_along(moving: &ShapeMotion, target: &ShapeMotion, n: Vector) -> bool {
    let (Some(g1), Some(g2)) = (moving.shape.as_support_map(), target.shape.as_support_map())
    else {
        return false;
    };
    let Some(n) = n.try_normalize() else {
        return false;
    };
    let (p1, p2) = (
        pose_from_iso(&moving.motion.pose_at(0.0)),
        pose_from_iso(&target.motion.pose_at(0.0)),
    );
    let (a, b) = (g1.support_point(&p1, n), g2.support_point(&p2, -n));
    let sep = (b.dot(n) - a.dot(n)) as f64;
    // A few ulps of the points' coordinates, padded.
    let rounding = 1.0e-6 * a.abs().max(b.abs()).max_element() as f64 + 1.0e-7;
    let budget = sep - 2.0 * rounding;
    budget > 0.0 && pair_approaches_within(moving, target, &vec_from_glam(n), budget)
}

/// The world axis, pointing from `a` towards `b`, along which boxes `a`
/// and `b` are farthest apart.
fn box_axis(a: &Aabb, b: &Aabb) -> Vector {
    let ahead = b.mins - a.maxs;
    let behind = a.mins - b.maxs;
    let gaps = ahead.max(behind);
    let i = if gaps.x >= gaps.y && gaps.x >= gaps.z {
        0
    } else if gaps.y >= gaps.z {
        1
    } else {
        2
    };
    let mut n = Vector::ZERO;
    n[i] = if ahead[i] >= behind[i] { 1.0 } else { -1.0 };
    n
}

/// A lower bound of the distance between anything inside two boxes,
/// metres (0 when they meet), less the rounding of `f32` boxes (a few
/// parts in 10⁷ of the coordinates).
pub(crate) fn box_gap(a: &Aabb, b: &Aabb) -> f64 {
    let below = (b.mins - a.maxs).max(Vector::ZERO);
    let above = (a.mins - b.maxs).max(Vector::ZERO);
    ((below + above).length() as f64 - box_rounding(a, b)).max(0.0)
}

/// How far `f32` boxes `a` and `b`, and parry's distances between shapes
/// at poses of that size, may be off, metres: a few parts in 10⁷ of the
/// coordinates, padded.
fn box_rounding(a: &Aabb, b: &Aabb) -> f64 {
    let scale = a
        .mins
        .abs()
        .max(a.maxs.abs())
        .max(b.mins.abs().max(b.maxs.abs()));
    1.0e-6 * scale.max_element() as f64 + 1.0e-6
}

/// When a sensor pair first touches before `until` (a fraction of the
/// step), if it is apart at the start.
pub(crate) fn first_crossing(
    s1: &dyn Shape,
    pair: &SensorPair,
    s2: &dyn Shape,
    until: f64,
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<f64>, CcdError> {
    let opts = QueryOptions {
        skin: 0.0,
        time_range: TimeSpan::new(0.0, until),
        ..*opts
    };
    // Only when: the hit's witness is not read.
    let (moving, target) = lone_pair(s1, &pair.motion1, s2, &pair.motion2);
    Ok(search::found(&moving, &target, &opts, report)?
        .map(|hit| hit.outcome)
        .filter(|hit| hit.status != RootStatus::InitiallyTouching)
        .map(|hit| hit.time))
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
    ws.apart.under(motions, opts);
    let mut best: Option<BodyHit> = None;
    for &h1 in rb.colliders() {
        let Some(co1) = scene.colliders.get(h1).filter(|c| c.is_enabled()) else {
            continue;
        };
        // The broad phase with a rough box first: a collider that meets
        // nothing needs no motion (building one costs more than the query).
        let rough = ws.motions.rough(motions, h1, co1, scene.bodies);
        let cache = &mut ws.motions;
        let wants = |co2: &Collider| targets.wants(co2, motions, scene);
        let finds = match ws.moving.of(motions, scene, cache) {
            Some(moving) => gather_listed(
                scene,
                broad_phase,
                dispatcher,
                motions,
                h1,
                co1,
                &rough,
                moving,
                wants,
                &mut ws.candidates,
            ),
            None => gather(
                scene,
                broad_phase,
                dispatcher,
                motions,
                h1,
                co1,
                &rough,
                wants,
                |h2, co2| Some(cache.rough(motions, h2, co2, scene.bodies)),
                &mut ws.candidates,
            ),
        };
        ws.moving.found(finds);
        if ws.candidates.is_empty() {
            continue;
        }
        // A box from the two poses, still without the motion: a long shape
        // turning in place meets most of its rough box's finds only here.
        // (A candidate whose box holds the rough one, a floor's or a
        // half-space's, meets it: both hold the collider at the start.)
        if ws.candidates.iter().any(|c| !c.bounds.contains(&rough))
            && let Some(path) = pose_path_box(motions, co1, scene.bodies)
        {
            ws.candidates.retain(|c| c.bounds.intersects(&path));
            if ws.candidates.is_empty() {
                continue;
            }
        }
        // Then the motion and its own swept box, which the candidates must
        // meet too: first by the box they were found with (most are dropped
        // here), a moving one then by its own swept box, its motion built
        // only now. In a sweep against everything (a fast body's first, a
        // rerouted one's), a solid one that moves together with this
        // collider is rapier's contacts' (see `move_together`); a re-sweep
        // of what a clamp changed keeps it.
        let (swept, motion1) = ws.motions.swept_motion(motions, h1, co1, scene.bodies)?;
        let motion1 = *motion1;
        let mut failure = None;
        let cache = &mut ws.motions;
        let against_all = matches!(targets, Targets::All);
        let fast_factor = scene.config.fast_factor;
        // Read on first need (a compound's walks its parts).
        let mut thickness1 = None;
        let mut together = 0;
        ws.candidates.retain(|c| {
            if !c.bounds.intersects(&swept) {
                return false;
            }
            let co2 = &scene.colliders[c.handle];
            if !is_moving(motions, co2) {
                return true;
            }
            let (own, motion2) = match cache.swept_motion(motions, c.handle, co2, scene.bodies) {
                Ok(found) => found,
                Err(e) => {
                    failure = Some(e);
                    return false;
                }
            };
            if !own.intersects(&swept) {
                return false;
            }
            if !against_all || !matches!(c.interaction, Interaction::Solid) {
                return true;
            }
            let with = move_together(
                co1.shape(),
                &motion1,
                *thickness1.get_or_insert_with(|| thickness(co1.shape())),
                co2.shape(),
                motion2,
                fast_factor,
            );
            together += usize::from(with);
            !with
        });
        if let Some(e) = failure {
            return Err(e);
        }
        report.pairs_moving_together += together;
        let mut solid: FewMotions = FewMotions::with_capacity(ws.candidates.len());
        let mut handles: Few<ColliderHandle> = Few::with_capacity(ws.candidates.len());
        let mut held: Few<bool> = Few::with_capacity(ws.candidates.len());
        let mut settled = 0;
        for c in &ws.candidates {
            let solid_pair = matches!(c.interaction, Interaction::Solid);
            if solid_pair && ws.apart.proved(h1, c.handle) {
                settled += 1;
                continue;
            }
            let co2 = &scene.colliders[c.handle];
            let motion2 = ws.motions.get(motions, c.handle, co2, scene.bodies)?;
            match c.interaction {
                Interaction::Solid => {
                    solid.push(ShapeMotion {
                        shape: co2.shape(),
                        motion: motion2,
                    });
                    handles.push(c.handle);
                    held.push(ws.was_held(h1, c.handle));
                }
                Interaction::Sensor => sensors.push(SensorPair {
                    collider1: h1,
                    collider2: c.handle,
                    motion1,
                    motion2,
                }),
            }
        }
        report.pairs += ws.candidates.len() - settled;
        if solid.is_empty() {
            continue;
        }
        let moving = ShapeMotion {
            shape: co1.shape(),
            motion: motion1,
        };
        let mut apart = Few::new();
        let found = earliest(
            &moving,
            &solid,
            &held,
            opts,
            &scene.hand_back(),
            &mut ws.triangles,
            &mut apart,
            report,
        )?;
        // Kept for the targets that are swept themselves (fast bodies).
        for &h2 in apart.iter().map(|&j| &handles[j]) {
            let swept = scene.colliders[h2]
                .parent()
                .and_then(|b| motions.body(b))
                .is_some_and(|m| m.fast);
            if swept {
                ws.apart.pairs.insert((h1, h2));
            }
        }
        if let Some(e) = found {
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
            // Bounding spheres farther apart than `reach` cannot touch (a
            // contact query costs far more; the pad covers `f32` poses).
            let (s1, s2) = (
                co1.shape().compute_bounding_sphere(&p1),
                co2.shape().compute_bounding_sphere(&p2),
            );
            let apart =
                (s1.center - s2.center).length() as f64 - (s1.radius as f64 + s2.radius as f64);
            let scale = s1.center.abs().max(s2.center.abs()).max_element() as f64;
            if apart > reach + 1.0e-5 + 1.0e-6 * scale {
                continue;
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rapier::testing::{Numbers, flying, propeller_and_wall};
    use nalgebra::{Isometry3, UnitQuaternion, Vector3};
    use rapier3d::parry::shape::{Ball, Capsule, Cuboid, Triangle};

    /// The sound search over the whole step finds no contact between
    /// the pair (case `case`, `gap` apart at the start), as a bound said.
    fn assert_no_contact(case: usize, gap: f64, moving: &ShapeMotion, target: &ShapeMotion) {
        let opts = QueryOptions {
            skin: 0.0,
            ..QueryOptions::default()
        };
        let mut report = CcdReport::default();
        let found = search::one(
            moving.shape,
            &moving.motion,
            target.shape,
            &target.motion,
            &opts,
            &mut report,
        );
        assert!(
            matches!(found, Ok(None)),
            "case {case}: start gap {gap}, the search finds {found:?}"
        );
    }

    /// A bound answers for at least a fifth of the pairs apart at the
    /// start, or it would spare nothing.
    fn assert_answers_a_share(answered: usize, apart: usize) {
        assert!(
            answered * 5 >= apart,
            "only {answered} of {apart} apart pairs answered"
        );
    }

    /// Where `mesh_stays_apart` answers for a small moving mesh (by parry's
    /// start normal, as the sweep asks it), the sound search finds no
    /// contact over the whole step: 1,500 propellers spinning up to 150
    /// rad/s and flying beside a fixed box, from 5 cm into it to 80 cm
    /// away (829 of the 1,158 apart at the start answered). It answers
    /// for a good share, or it would spare nothing.
    #[test]
    fn mesh_stays_apart_agrees_with_the_search() {
        let mut rng = Numbers(0x2545_f491_4f6c_dd1d);
        let (mesh, wall) = propeller_and_wall();
        let fixed = Motion::fixed(Isometry3::identity()).unwrap();
        let (mut answered, mut apart) = (0, 0);
        for case in 0..1500 {
            let at = Vector3::new(rng.next(0.5, 1.6), rng.next(-0.5, 0.5), rng.next(-0.5, 0.5));
            let motion = flying(
                at,
                UnitQuaternion::from_scaled_axis(rng.vector(3.0)),
                rng.vector(15.0),
                rng.vector(150.0),
                1.0 / 60.0,
            );
            let moving = ShapeMotion {
                shape: &mesh,
                motion,
            };
            let target = ShapeMotion {
                shape: &wall,
                motion: fixed,
            };
            let start = gap_at(&mesh, &motion, &wall, &fixed, 0.0, 10.0, None);
            let Some((gap, Some(contact))) = start else {
                continue;
            };
            if gap <= 0.0 {
                continue;
            }
            apart += 1;
            let n = vec_from_glam(contact.normal1).normalize();
            if mesh_stays_apart(&moving, &target, &n) {
                answered += 1;
                assert_no_contact(case, gap, &moving, &target);
            }
        }
        assert_answers_a_share(answered, apart);
    }

    /// Where `apart_along` answers (by parry's start normal, or the axis
    /// the start boxes are farthest apart along, as the sweep asks it),
    /// the sound search finds no contact over the whole step:
    /// 3,000 pairs of boxes, balls and capsules against a fixed box, a fixed
    /// triangle and a moving box, apart at the start and moving and
    /// spinning every way. The bound answers for a good share of them, or
    /// it would spare nothing.
    #[test]
    fn apart_along_agrees_with_the_search() {
        let mut rng = Numbers(0x9e37_79b9_7f4a_7c15);
        let movers: [Box<dyn Shape>; 3] = [
            Box::new(Cuboid::new(Vector::new(0.3, 0.1, 0.2))),
            Box::new(Ball::new(0.2)),
            Box::new(Capsule::new_y(0.3, 0.1)),
        ];
        let targets: [Box<dyn Shape>; 2] = [
            Box::new(Cuboid::new(Vector::new(1.0, 0.1, 1.0))),
            Box::new(Triangle::new(
                Vector::new(-1.0, 0.0, -1.0),
                Vector::new(1.5, 0.0, -0.5),
                Vector::new(0.0, 0.2, 1.2),
            )),
        ];
        let motion = |rng: &mut Numbers, at: Vector3<f64>, speed: f64, spin: f64| {
            let turn = UnitQuaternion::from_scaled_axis(rng.vector(3.0));
            flying(at, turn, rng.vector(speed), rng.vector(spin), 1.0 / 60.0)
        };
        let (mut answered, mut apart) = (0, 0);
        for case in 0..3000 {
            let mover = &*movers[case % 3];
            let target = &*targets[(case / 3) % 2];
            let at = rng.vector(1.0).normalize() * rng.next(0.3, 1.5);
            let moving = ShapeMotion {
                shape: mover,
                motion: motion(&mut rng, at, 20.0, 30.0),
            };
            // Every third target moves too.
            let target_motion = if case % 3 == 2 {
                motion(&mut rng, Vector3::zeros(), 10.0, 10.0)
            } else {
                Motion::fixed(Isometry3::identity()).unwrap()
            };
            let target = ShapeMotion {
                shape: target,
                motion: target_motion,
            };
            let start = gap_at(
                mover,
                &moving.motion,
                target.shape,
                &target.motion,
                0.0,
                10.0,
                None,
            );
            let Some((gap, Some(contact))) = start else {
                continue;
            };
            if gap <= 0.0 {
                continue;
            }
            apart += 1;
            // The direction the sweep takes for boxes apart at the start:
            // the axis they are farthest apart along.
            let start_box =
                |s: &dyn Shape, m: &Motion| s.compute_aabb(&pose_from_iso(&m.pose_at(0.0)));
            let axis = box_axis(
                &start_box(mover, &moving.motion),
                &start_box(target.shape, &target.motion),
            );
            if apart_along(&moving, &target, contact.normal1) || apart_along(&moving, &target, axis)
            {
                answered += 1;
                assert_no_contact(case, gap, &moving, &target);
            }
        }
        assert_answers_a_share(answered, apart);
    }
}
