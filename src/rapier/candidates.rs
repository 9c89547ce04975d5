//! What a fast collider may meet during the step: its swept box against the
//! broad phase, then rapier's own pair rules.
//!
//! The broad phase's leaves hold end-of-step boxes, so a target that moved
//! may have been elsewhere earlier in the step. When few colliders moved,
//! they are listed with their rough swept boxes once per set of motions
//! ([`MovingBoxes`]) and checked from that list, and the broad phase is
//! asked only for the others, with the fast collider's own box. Otherwise
//! the query box is enlarged by the largest travel of any moved body, and
//! each moving candidate is then checked against its own swept box.

use super::backoff::pair_relative_travel;
use super::moved::Moved;
use super::select::thickness;
use super::world::{MotionCache, StageWorld, StepMotions};
use crate::convert::pose_from_iso;
use crate::enclosure::TimeSpan;
use crate::motion::{Motion, Trajectory};
use rapier3d::parry::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::parry::query::QueryDispatcher;
use rapier3d::parry::shape::{Shape, Triangle, TypedShape};
use rapier3d::prelude::{
    ActiveEvents, ActiveHooks, BroadPhaseBvh, Collider, ColliderHandle, PairFilterContext,
    QueryFilter, RigidBodySet, RigidBodyType, SolverFlags, Vector,
};

/// A box holding `shape` over the whole `motion`: every point stays
/// within the travel bound of both its start and its end, and close to the
/// segment between them ([`path_box`]; a body flying straight sweeps the
/// box of its path, not one grown by its travel on every side).
pub(crate) fn swept_aabb(shape: &dyn Shape, motion: &Motion) -> Aabb {
    // The motion's own end: a motion cut by a clamp (possibly to a
    // standstill) ends before the collider's pose.
    let end_box = shape.compute_aabb(&pose_from_iso(&motion.pose_at(1.0)));
    if motion.is_fixed() {
        return end_box;
    }
    let start_box = shape.compute_aabb(&pose_from_iso(&motion.pose_at(0.0)));
    let radius = bounding_radius(shape);
    let travel = motion.travel_bound(radius);
    // f32 boxes: round the margin up, plus rounding of the poses themselves.
    let margin = ((travel * (1.0 + 1.0e-5)) as f32).next_up() + 1.0e-5;
    if !margin.is_finite() {
        return everywhere();
    }
    let a = start_box.loosened(margin);
    let b = end_box.loosened(margin);
    let by_travel = a.intersection(&b).unwrap_or_else(|| a.merged(&b));
    let stray = motion.stray_within(TimeSpan::new(0.0, 1.0), radius);
    let path = path_box(start_box.merged(&end_box), stray);
    // Both hold the shape at the start: they meet.
    by_travel.intersection(&path).unwrap_or(path)
}

/// A box holding `shape` over the times `span` of `motion` (fractions of
/// the step): [`path_box`] of its boxes at the two ends of `span`.
pub(crate) fn swept_aabb_within(shape: &dyn Shape, motion: &Motion, span: TimeSpan) -> Aabb {
    let at = |tau: f64| shape.compute_aabb(&pose_from_iso(&motion.pose_at(tau)));
    let ends = at(span.lo).merged(&at(span.hi));
    path_box(ends, motion.stray_within(span, bounding_radius(shape)))
}

/// The shape's boxes at the two ends of a span, merged (`ends`), grown by
/// `stray`, how far its points leave the segments between their end
/// positions ([`Motion::stray_within`]): a box holding it over the span.
fn path_box(ends: Aabb, stray: f64) -> Aabb {
    // f32 boxes: the stray rounded up, plus the rounding of the poses and
    // of the boxes, a few parts in 10⁷ of their coordinates.
    let coordinates = ends.mins.abs().max(ends.maxs.abs()).max_element() as f64;
    let margin = (((stray + 1.0e-6 * coordinates) * (1.0 + 1.0e-5)) as f32).next_up() + 1.0e-5;
    if !margin.is_finite() {
        return everywhere();
    }
    ends.loosened(margin)
}

/// How far the shape reaches from its frame's origin, metres.
fn bounding_radius(shape: &dyn Shape) -> f64 {
    let sphere = shape.compute_local_bounding_sphere();
    sphere.center.length() as f64 + sphere.radius as f64
}

/// The box of all space (a motion or pose beyond `f32`).
fn everywhere() -> Aabb {
    Aabb::new(Vector::splat(f32::MIN), Vector::splat(f32::MAX))
}

/// How a pair interacts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interaction {
    /// Contacts would push the shapes apart: a hit clamps.
    Solid,
    /// A sensor is involved: a crossing is reported, never clamped.
    Sensor,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub handle: ColliderHandle,
    pub interaction: Interaction,
    /// The box it was found with: a moving collider's `own_box`, any
    /// other's own box. A moving one's motion is built only if this box
    /// meets the sweeping collider's own swept box too.
    pub bounds: Aabb,
}

fn body_type(scene: &StageWorld, co: &Collider) -> RigidBodyType {
    co.parent()
        .and_then(|h| scene.bodies.get(h))
        .map_or(RigidBodyType::Fixed, |rb| rb.body_type())
}

/// Rapier's rules for whether the fast collider `(h1, co1)` and `(h2, co2)`
/// interact, and how; `None` when they do not.
pub(crate) fn interaction(
    scene: &StageWorld,
    h1: ColliderHandle,
    co1: &Collider,
    h2: ColliderHandle,
    co2: &Collider,
) -> Option<Interaction> {
    if h1 == h2 || !co2.is_enabled() || (co2.parent().is_some() && co2.parent() == co1.parent()) {
        return None;
    }
    let (t1, t2) = (body_type(scene, co1), body_type(scene, co2));
    let targets = &scene.config.targets;
    let wanted = match t2 {
        RigidBodyType::Fixed => targets.fixed,
        RigidBodyType::Dynamic => targets.dynamic,
        _ => targets.kinematic,
    };
    if !wanted
        || !co1.collision_groups().test(co2.collision_groups())
        || !(co1.active_collision_types() | co2.active_collision_types()).test(t1, t2)
    {
        return None;
    }
    if let (Some(b1), Some(b2)) = (co1.parent(), co2.parent()) {
        if scene
            .joints
            .joints_between(b1, b2)
            .any(|(_, j)| !j.data.contacts_enabled)
        {
            return None;
        }
    }
    let context = || PairFilterContext {
        bodies: scene.bodies,
        colliders: scene.colliders,
        collider1: h1,
        collider2: h2,
        rigid_body1: co1.parent(),
        rigid_body2: co2.parent(),
    };
    let hooks = co1.active_hooks() | co2.active_hooks();
    if co1.is_sensor() || co2.is_sensor() {
        let reported =
            (co1.active_events() | co2.active_events()).contains(ActiveEvents::COLLISION_EVENTS);
        let allowed = !hooks.contains(ActiveHooks::FILTER_INTERSECTION_PAIR)
            || scene.hooks.filter_intersection_pair(&context());
        return (reported && allowed).then_some(Interaction::Sensor);
    }
    if !co1.solver_groups().test(co2.solver_groups()) {
        return None;
    }
    if hooks.contains(ActiveHooks::FILTER_CONTACT_PAIRS) {
        let flags = scene.hooks.filter_contact_pair(&context())?;
        if !flags.contains(SolverFlags::COMPUTE_RIGID_IMPULSES) {
            return None;
        }
    }
    Some(Interaction::Solid)
}

/// The most moving colliders [`MovingBoxes`] lists: past that, checking
/// each against every fast collider's box could cost more than the broad
/// phase's tree does.
const FEW_MOVING: usize = 128;

/// How many moving colliders a gather must find within its enlarged box,
/// on average over a set of motions, for the next set's gathers to take
/// them from a list (see [`MovingBoxes`]).
const LIST_FINDS: u64 = 8;

/// The enabled colliders of the moved bodies with their rough swept boxes
/// (`rough_swept_box`), listed for a set of motions when the gathers under
/// the last set found more than [`LIST_FINDS`] of them each within their
/// enlarged boxes (and at most [`FEW_MOVING`] moved): [`gather`] then
/// checks them from the list, a box test each, instead of finding them in
/// the broad phase with a box enlarged by the largest travel of all. 40
/// balls raining at 40 m/s in steps of 0.1 s: each query box grown by 4 m
/// found two dozen other balls, each a rough box lookup and a few tests,
/// to keep one in forty (3 % of that scene's instructions). Where moving
/// bodies are few or far apart, the enlarged box finds few of them, and
/// making every moving collider's rough box for a list cost more than it
/// spared (80 balls at 40 m/s in steps of 1/60 s: 4 % more).
#[derive(Default)]
pub(crate) struct MovingBoxes {
    /// The motion set (`StepMotions::id`) the list is for.
    of: Option<u64>,
    /// Whether the gathers under that set take the list.
    listed: bool,
    list: Vec<(ColliderHandle, Aabb)>,
    /// Moving colliders within the gathers' enlarged boxes under that set,
    /// and the gathers.
    finds: u64,
    gathers: u64,
}

impl MovingBoxes {
    /// The list for `motions` if its gathers take one (decided, and the
    /// list made, on the set's first gather), counting the gather.
    #[inline]
    pub fn of(
        &mut self,
        motions: &StepMotions,
        scene: &StageWorld,
        cache: &mut MotionCache,
    ) -> Option<&[(ColliderHandle, Aabb)]> {
        if self.of != Some(motions.id()) {
            self.of = Some(motions.id());
            let wanted = self.gathers > 0 && self.finds >= LIST_FINDS * self.gathers;
            (self.finds, self.gathers) = (0, 0);
            self.listed = wanted && self.make_list(motions, scene, cache);
        }
        self.gathers += 1;
        self.listed.then_some(&self.list[..])
    }

    /// Lists the moved bodies' enabled colliders with their rough boxes;
    /// `false` when more than [`FEW_MOVING`] moved.
    #[inline(never)]
    fn make_list(
        &mut self,
        motions: &StepMotions,
        scene: &StageWorld,
        cache: &mut MotionCache,
    ) -> bool {
        self.list.clear();
        for m in motions.moved {
            let Some(rb) = scene.bodies.get(m.handle) else {
                continue;
            };
            for &h in rb.colliders() {
                let Some(co) = scene.colliders.get(h).filter(|c| c.is_enabled()) else {
                    continue;
                };
                if self.list.len() == FEW_MOVING {
                    return false;
                }
                self.list
                    .push((h, cache.rough(motions, h, co, scene.bodies)));
            }
        }
        true
    }

    /// Counts `finds` moving colliders within a gather's enlarged box.
    pub fn found(&mut self, finds: usize) {
        self.finds += finds as u64;
    }
}

/// The colliders the fast collider `(h1, co1)` with swept box `swept` may
/// meet, of those `wanted`, with how each pair is handled
/// ([`interaction`]) and the box each was found with: a moving one's from
/// `own_box`, any other's its own. Returns how many moving colliders of
/// those `wanted` the enlarged box found (for [`MovingBoxes::found`];
/// [`gather_listed`] counts the listed ones within it whether wanted or
/// not, which only steers the choice of the next set's way).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather(
    scene: &StageWorld,
    broad_phase: &BroadPhaseBvh,
    dispatcher: &dyn QueryDispatcher,
    motions: &StepMotions,
    h1: ColliderHandle,
    co1: &Collider,
    swept: &Aabb,
    wanted: impl Fn(&Collider) -> bool,
    mut own_box: impl FnMut(ColliderHandle, &Collider) -> Option<Aabb>,
    out: &mut Vec<Candidate>,
) -> usize {
    out.clear();
    let query = broad_phase.as_query_pipeline(
        dispatcher,
        scene.bodies,
        scene.colliders,
        QueryFilter::default(),
    );
    let wide = enlarged(swept, motions);
    let mut finds = 0;
    for (h2, co2) in query.intersect_aabb_conservative(wide) {
        // The boxes first: most colliders the widened box finds are
        // farther, and the pair rules (groups, joints, the user's hooks)
        // cost more than a box.
        if h2 == h1 || !wanted(co2) {
            continue;
        }
        let bounds = if is_moving(motions, co2) {
            finds += 1;
            own_box(h2, co2)
        } else {
            Some(co2.compute_aabb())
        };
        // `admit`, written out: through it this loop, the stage's commonest
        // broad-phase walk, took 13 % more instructions in one build.
        let Some(bounds) = bounds.filter(|b| b.intersects(swept)) else {
            continue;
        };
        let Some(interaction) = interaction(scene, h1, co1, h2, co2) else {
            continue;
        };
        out.push(Candidate {
            handle: h2,
            interaction,
            bounds,
        });
    }
    finds
}

/// [`gather`] with the moving colliders taken from `moving` (their rough
/// boxes, [`MovingBoxes`]) and the broad phase asked, with `swept` itself,
/// only for the others: a collider that did not move is where its leaf
/// is. Returns how many listed colliders lie within the box enlarged by
/// the largest travel (where [`gather`] would have found them).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gather_listed(
    scene: &StageWorld,
    broad_phase: &BroadPhaseBvh,
    dispatcher: &dyn QueryDispatcher,
    motions: &StepMotions,
    h1: ColliderHandle,
    co1: &Collider,
    swept: &Aabb,
    moving: &[(ColliderHandle, Aabb)],
    wanted: impl Fn(&Collider) -> bool,
    out: &mut Vec<Candidate>,
) -> usize {
    out.clear();
    let query = broad_phase.as_query_pipeline(
        dispatcher,
        scene.bodies,
        scene.colliders,
        QueryFilter::default(),
    );
    for (h2, co2) in query.intersect_aabb_conservative(*swept) {
        if h2 != h1 && wanted(co2) && !is_moving(motions, co2) {
            admit(scene, (h1, co1), (h2, co2), co2.compute_aabb(), swept, out);
        }
    }
    let wide = enlarged(swept, motions);
    let mut finds = 0;
    for &(h2, bounds) in moving {
        if h2 == h1 || !bounds.intersects(&wide) {
            continue;
        }
        finds += 1;
        if let Some(co2) = scene.colliders.get(h2).filter(|co2| wanted(co2)) {
            admit(scene, (h1, co1), (h2, co2), bounds, swept, out);
        }
    }
    finds
}

/// `swept` enlarged by the largest travel of any moved body (padded for
/// `f32`): where a moving collider's end-of-step leaf may lie if its path
/// meets `swept`.
fn enlarged(swept: &Aabb, motions: &StepMotions) -> Aabb {
    swept.loosened(((motions.margin * (1.0 + 1.0e-5)) as f32).next_up())
}

/// Adds `(h2, co2)`, found with `bounds`, to `out` if its box meets the
/// fast collider's `swept` box and rapier's rules let the pair interact.
fn admit(
    scene: &StageWorld,
    (h1, co1): (ColliderHandle, &Collider),
    (h2, co2): (ColliderHandle, &Collider),
    bounds: Aabb,
    swept: &Aabb,
    out: &mut Vec<Candidate>,
) {
    if !bounds.intersects(swept) {
        return;
    }
    if let Some(interaction) = interaction(scene, h1, co1, h2, co2) {
        out.push(Candidate {
            handle: h2,
            interaction,
            bounds,
        });
    }
}

/// Whether collider `co` moves this step (its body is among the moved).
pub(crate) fn is_moving(motions: &StepMotions, co: &Collider) -> bool {
    co.parent().is_some_and(|b| motions.body(b).is_some())
}

/// Whether two moving shapes move together: no point of one comes nearer
/// to or farther from any point of the other over the step than
/// `fast_factor` times the thinner one's thickness (`select::thickness`;
/// `thickness1` is `s1`'s, taken once per sweep). Neither can pass
/// through the other then; such a pair is as slow as the stage's test for
/// fast bodies leaves to rapier's contacts (a row of boxes a paddle threw,
/// flying on together; two bodies stuck after a head-on hit, drifting on).
pub(crate) fn move_together(
    s1: &dyn Shape,
    m1: &Motion,
    thickness1: f64,
    s2: &dyn Shape,
    m2: &Motion,
    fast_factor: f64,
) -> bool {
    let thinner = thickness1.min(thickness(s2));
    thinner > 0.0 && pair_relative_travel(s1, m1, s2, m2) <= fast_factor * thinner
}

/// A box holding collider `co` over the step, from its body's two poses
/// alone, with no motion built for it: most fast colliders meet nothing,
/// and their motions cost more than the broad phase does, so the broad
/// phase is asked with this box first. However the body turns, the
/// collider stays within its bounding sphere about the centre of mass, and
/// the centre runs along the segment between its two positions (plus the
/// bend of an accelerated motion). Across a fast path this is tighter than
/// [`swept_aabb`] (whose margin is the whole travel), for a slow turn of a
/// long shape looser; the candidates meet both. A collider of a body that
/// did not move: its own box.
pub(crate) fn rough_swept_box(motions: &StepMotions, co: &Collider, bodies: &RigidBodySet) -> Aabb {
    let (Some(m), Some(local), Some(rb)) = (
        co.parent().and_then(|h| motions.body(h)),
        co.position_wrt_parent(),
        co.parent().and_then(|h| bodies.get(h)),
    ) else {
        return co.compute_aabb();
    };
    let com = rb.local_center_of_mass();
    let (c0, c1) = (m.start * com, m.end * com);
    let bend = 0.5 * m.accel.length() as f64 * motions.dt * motions.dt;
    let sphere = co.shape().compute_local_bounding_sphere();
    let radius = (local.translation - com).length() as f64
        + sphere.center.length() as f64
        + sphere.radius as f64;
    // `f32` poses and boxes round by a few parts in 10⁷ of the coordinates.
    let rounding = 1.0e-6 * c0.abs().max(c1.abs()).max_element() as f64;
    let margin = (((radius + bend) * (1.0 + 1.0e-3) + rounding + 1.0e-4) as f32).next_up();
    let path = Aabb::new(c0.min(c1), c0.max(c1)).loosened(margin);
    if path.mins.is_finite() && path.maxs.is_finite() {
        path
    } else {
        Aabb::new(Vector::splat(f32::MIN), Vector::splat(f32::MAX))
    }
}

/// Least turn over the step (radians, from the body's angular velocity) for
/// which [`pose_path_box`] is asked for a compact shape.
const MIN_POSE_BOX_TURN: f64 = 0.05;

/// A box holding collider `co` over the step from its body's two poses,
/// with no motion built: its local box carried to the two poses, merged
/// and grown by how far its points stray from the segments between their
/// end positions ([`path_box`], as [`swept_aabb`] grows its boxes, here
/// with no trigonometry). Tighter than [`rough_swept_box`] for a long
/// shape turning in place (a spinning rod beside a wall), so candidates
/// that miss it need no motion. `None` for a collider whose body did not
/// move, for a predicted motion with an acceleration (whose `end` is not
/// where it ends), and where it would hardly be smaller than the rough box
/// (a compact shape that barely turns).
pub(crate) fn pose_path_box(
    motions: &StepMotions,
    co: &Collider,
    bodies: &RigidBodySet,
) -> Option<Aabb> {
    let (m, local, rb) = (
        co.parent().and_then(|h| motions.body(h))?,
        co.position_wrt_parent()?,
        co.parent().and_then(|h| bodies.get(h))?,
    );
    if m.accel != Vector::ZERO {
        return None;
    }
    let shape = co.shape();
    let own = shape.compute_local_aabb();
    let reach = ((local.translation - rb.local_center_of_mass()).length() as f64
        + bounding_radius(shape))
        * (1.0 + 1.0e-5);
    let spin = m.angvel.length() as f64 * motions.dt;
    // Worth its products only where it can be much smaller than the rough
    // box, whose margin is `reach` on every side: for a body that turns, or
    // for a flat or long shape (a cube or a ball gliding along fills its
    // rough box nearly as well; asked anyway, the pushed cubes of
    // kinematic_sweeper cost 1.7 % more instructions).
    if spin < MIN_POSE_BOX_TURN && (own.half_extents().min_element() as f64) >= 0.5 * reach {
        return None;
    }
    // The local box carried to the two poses: a few products, where the
    // exact box of a cone or cylinder asks six support points at each.
    let ends = own
        .transform_by(&(m.start * *local))
        .merged(&own.transform_by(&(m.end * *local)));
    // The motion turns through the short angle θ between the poses unless
    // its whole turns may add some, which needs θ + spin ≥ π
    // (`angle_bound`). `c = cos(θ/2)`; `θ + spin < π` holds where
    // `c > sin(spin/2)`, so where `c > spin/2`. A point then strays from
    // its chord by the sagitta `reach·(1 − c)` (padded for the `f32`
    // quaternions), otherwise by at most `2·reach`.
    let dq = m.end.rotation * m.start.rotation.inverse();
    let c = dq.w.abs() as f64 / dq.length() as f64;
    let stray = if c > 0.5 * spin + 1.0e-6 {
        reach * (1.0 - c + 1.0e-6)
    } else {
        2.0 * reach
    };
    Some(path_box(ends, stray))
}

/// A box holding the body's colliders over its whole (uncut) motion: their
/// end boxes grown by the body's travel bound.
pub(crate) fn body_box(scene: &StageWorld, m: &Moved) -> Option<Aabb> {
    let margin = ((m.travel * (1.0 + 1.0e-5)) as f32).next_up() + 1.0e-5;
    scene
        .colliders_of(m.handle)
        .map(|(_, co)| co.compute_aabb().loosened(margin))
        .reduce(|a, b| a.merged(&b))
}

/// A box holding the body's colliders at the start of its motion.
pub(crate) fn start_box(scene: &StageWorld, m: &Moved) -> Option<Aabb> {
    scene
        .colliders_of(m.handle)
        .filter_map(|(_, co)| {
            let local = co.position_wrt_parent()?;
            Some(co.shape().compute_aabb(&(m.start * *local)))
        })
        .reduce(|a, b| a.merged(&b))
}

/// Most triangles of a fixed mesh that a search takes one by one where it
/// need not ([`mesh_triangles`]: a fast shape's sweep, a landing ball's
/// deep stop); past it the search takes the whole mesh, whose tree prunes
/// the far ones. A ball landing on terrain meets one to four; a capsule
/// sliding across 8-12 triangles (slide_dt025) cost 2 % more searched one
/// by one than through the tree.
pub(crate) const FEW_PIECES: usize = 4;

/// Most triangles of one mesh a slow collider is swept against one by one
/// ([`mesh_triangles`]); past it the mesh stays whole.
pub(crate) const MAX_PIECES: usize = 63;

/// One triangle of a mesh target, swept on its own.
pub(crate) struct MeshPiece {
    pub triangle: Triangle,
    /// Rapier's CCD leaves this triangle to the contacts: a heightfield
    /// (one-sided in rapier) the moving shape's centre approaches by less
    /// than rapier's fallback radius and ends in front of by more (parry's
    /// `one_sided_early_out`).
    pub contacts_only: bool,
}

/// The triangles of a fixed triangle mesh or heightfield that `moving` may
/// meet (those whose boxes meet the world box `swept` gives, holding it
/// over the times that matter, grown by the reach that counts), for
/// sweeping each on its own as rapier's CCD does: it stops a body at each
/// triangle of a mesh apart, and leaves to the contacts only the
/// triangles touching at the start, not the whole mesh. `false` (and
/// nothing pushed) for other shapes, moving meshes, or more than `most`
/// triangles (at most [`MAX_PIECES`]; the walk stops at the first one
/// past it). `slop`: rapier's allowed linear error.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mesh_triangles(
    moving: &dyn Shape,
    moving_motion: &Motion,
    swept: impl FnOnce() -> Aabb,
    target: &dyn Shape,
    target_motion: &Motion,
    slop: f64,
    most: usize,
    out: &mut Vec<MeshPiece>,
) -> bool {
    if !target_motion.is_fixed() {
        return false;
    }
    // The box is asked for only when the target has triangles.
    if !matches!(
        target.as_typed_shape(),
        TypedShape::TriMesh(_) | TypedShape::HeightField(_)
    ) {
        return false;
    }
    let pose = pose_from_iso(&target_motion.pose_at(0.0));
    let local = swept().transform_by(&pose.inverse());
    let start = out.len();
    let most = most.min(MAX_PIECES);
    match target.as_typed_shape() {
        TypedShape::TriMesh(mesh) => {
            for i in mesh.bvh().intersect_aabb(&local) {
                if out.len() - start > most {
                    break;
                }
                out.push(MeshPiece {
                    triangle: mesh.triangle(i),
                    contacts_only: false,
                });
            }
        }
        TypedShape::HeightField(field) => {
            // The moving shape's centre at both ends, in the field's frame.
            let centre = moving.mass_properties(1.0).local_com;
            let at = |tau: f64| {
                let p = pose_from_iso(&moving_motion.pose_at(tau)) * centre;
                pose.inverse_transform_point(p)
            };
            let (c1, c2) = (at(0.0), at(1.0));
            let fallback = (0.5 * moving.ccd_thickness()).max(slop as f32);
            field.map_elements_in_local_aabb(&local, &mut |_, t| {
                if out.len() - start <= most {
                    let n = (t.b - t.a).cross(t.c - t.a).normalize_or_zero();
                    let (o1, o2) = (n.dot(c1 - t.a), n.dot(c2 - t.a));
                    out.push(MeshPiece {
                        triangle: *t,
                        contacts_only: o1 >= 0.0 && o1 - o2 < fallback && o2 > fallback,
                    });
                }
            });
        }
        _ => return false,
    }
    if out.len() - start > most {
        out.truncate(start);
        return false;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rapier3d::prelude::{
        ColliderBuilder, ColliderSet, Pose, RigidBodyBuilder, RigidBodyHandle, Rotation,
    };

    fn pose(at: [f32; 3], axis: [f32; 3], angle: f32) -> Pose {
        let axis = Vector::from(axis).normalize_or(Vector::Z);
        Pose::from_parts(Vector::from(at), Rotation::from_axis_angle(axis, angle))
    }

    fn within(inner: &Aabb, outer: &Aabb) -> bool {
        inner.mins.cmpge(outer.mins).all() && inner.maxs.cmple(outer.maxs).all()
    }

    /// Two 20 cm cubes flying on together at 60 m/s move together; one
    /// catching up at 10 m/s (17 cm a step, where half its thickness, a
    /// half extent, allows 5 cm), or turning at 40 rad/s (its corners
    /// swing 11 cm), does not; nor does anything with a triangle, which
    /// has no thickness.
    #[test]
    fn moving_together_is_a_small_relative_travel() {
        use crate::rapier::testing::flying;
        use nalgebra::{UnitQuaternion, Vector3};
        use rapier3d::parry::shape::{Cuboid, Triangle};
        let cube = Cuboid::new(Vector::splat(0.1));
        let dt = 1.0 / 60.0;
        let at = |x: f64, v: f64, w: f64| {
            flying(
                Vector3::new(x, 0.0, 0.0),
                UnitQuaternion::identity(),
                Vector3::new(v, 0.0, 0.0),
                Vector3::new(0.0, 0.0, w),
                dt,
            )
        };
        let together = |a: &Motion, b: &dyn Shape, mb: &Motion| {
            move_together(&cube, a, thickness(&cube), b, mb, 0.5)
        };
        let lead = at(0.0, 60.0, 0.0);
        assert!(together(&lead, &cube, &at(0.201, 60.0, 0.0)));
        assert!(!together(&lead, &cube, &at(0.201, 70.0, 0.0)));
        assert!(!together(&lead, &cube, &at(0.201, 60.0, 40.0)));
        let triangle = Triangle::new(Vector::ZERO, Vector::X, Vector::Y);
        assert!(!together(&lead, &triangle, &at(0.201, 60.0, 0.0)));
    }

    /// A ball thrown up and falling back over a part of the step: its path
    /// rises above both its ends (the top at 0.75 of the step, 12 cm above
    /// the higher end), which the part's box takes in.
    #[test]
    fn the_part_box_holds_a_falling_ball() {
        use nalgebra::{Isometry3, Point3, Vector3};
        let ball = rapier3d::parry::shape::Ball::new(0.05);
        let start = Isometry3::translation(1.0, 2.0, 3.0);
        let motion = Motion::from_velocities(
            start,
            Point3::new(1.0, 2.0, 3.0),
            Vector3::new(30.0, 30.0, 0.0),
            Vector3::zeros(),
            1.0 / 10.0,
        )
        .unwrap()
        .with_acceleration(Vector3::new(0.0, -400.0, 0.0))
        .unwrap();
        let span = TimeSpan::new(0.3, 1.0);
        let partial = swept_aabb_within(&ball, &motion, span);
        for k in 0..=64 {
            let tau = span.lo + span.width() * k as f64 / 64.0;
            let b = ball.compute_aabb(&pose_from_iso(&motion.pose_at(tau)));
            assert!(within(&b, &partial), "τ = {tau}: {b:?} not in {partial:?}");
        }
    }

    /// [`gather_listed`], which takes the moving colliders from their list
    /// and asks the broad phase only for the others, with the fast
    /// collider's own box, finds the same candidates, with the same boxes,
    /// as [`gather`], which asks the broad phase with the box enlarged by
    /// the largest travel: 40 balls flying at
    /// 5–45 m/s across a 6 m cube among fixed boxes, each one swept, over
    /// three steps of 0.05 s (26 moving candidates found, which the test
    /// fails on when a third of the listed ones are left out).
    #[test]
    fn listed_moving_colliders_are_found_as_the_enlarged_box_finds_them() {
        use super::super::config::CcdConfig;
        use super::super::moved::travel_between;
        use rapier3d::parry::query::DefaultQueryDispatcher;
        use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, Pose, RigidBodyBuilder};
        let mut seed = 11u64;
        let mut uniform = |lo: f32, hi: f32| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((seed >> 40) as f32 / (1u64 << 24) as f32)
        };
        let mut world = PhysicsWorld {
            gravity: Vector::ZERO,
            ..PhysicsWorld::default()
        };
        world.integration_parameters.dt = 0.05;
        world.integration_parameters.max_ccd_substeps = 0;
        for _ in 0..6 {
            let at = Vector::new(uniform(-6.0, 6.0), uniform(-6.0, 6.0), uniform(-6.0, 6.0));
            world.insert_collider(ColliderBuilder::cuboid(1.0, 0.2, 2.0).translation(at), None);
        }
        let balls: Vec<_> = (0..40)
            .map(|_| {
                let at = Vector::new(uniform(-8.0, 8.0), uniform(-8.0, 8.0), uniform(-8.0, 8.0));
                let v = Vector::new(
                    uniform(-60.0, 60.0),
                    uniform(-60.0, 60.0),
                    uniform(-60.0, 60.0),
                );
                let body = RigidBodyBuilder::dynamic().translation(at).linvel(v);
                world.insert(body, ColliderBuilder::ball(0.2)).0
            })
            .collect();
        let (mut listed_moving, mut cache, mut moving) =
            (0, MotionCache::default(), MovingBoxes::default());
        for _ in 0..3 {
            let starts: Vec<Pose> = balls.iter().map(|&b| *world.bodies[b].position()).collect();
            world.step();
            let moved: Vec<Moved> = balls
                .iter()
                .zip(&starts)
                .map(|(&handle, start)| {
                    let rb = &world.bodies[handle];
                    Moved {
                        handle,
                        start: *start,
                        end: *rb.position(),
                        angvel: Vector::ZERO,
                        accel: Vector::ZERO,
                        fast: true,
                        pusher: false,
                        travel: travel_between(rb, start, rb.position()),
                    }
                })
                .collect();
            let motions = StepMotions::new(&moved, 0.05);
            let config = CcdConfig::default();
            let scene = StageWorld {
                bodies: &world.bodies,
                colliders: &world.colliders,
                joints: &world.impulse_joints,
                hooks: &(),
                config: &config,
                slop: 0.0,
            };
            cache.clear();
            assert!(
                moving.make_list(&motions, &scene, &mut cache),
                "40 balls are few"
            );
            let list = moving.list.clone();
            let found = |cache: &mut MotionCache,
                         h1: ColliderHandle,
                         listed: Option<&[(ColliderHandle, Aabb)]>| {
                let co1 = &world.colliders[h1];
                let rough = cache.rough(&motions, h1, co1, &world.bodies);
                let mut out = Vec::new();
                let (bp, dispatcher) = (&world.broad_phase, &DefaultQueryDispatcher);
                match listed {
                    Some(list) => gather_listed(
                        &scene,
                        bp,
                        dispatcher,
                        &motions,
                        h1,
                        co1,
                        &rough,
                        list,
                        |_| true,
                        &mut out,
                    ),
                    None => gather(
                        &scene,
                        bp,
                        dispatcher,
                        &motions,
                        h1,
                        co1,
                        &rough,
                        |_| true,
                        |h2, co2| Some(cache.rough(&motions, h2, co2, &world.bodies)),
                        &mut out,
                    ),
                };
                let mut found: Vec<_> = out
                    .iter()
                    .map(|c| {
                        (
                            c.handle.into_raw_parts(),
                            c.bounds.mins.to_array(),
                            c.bounds.maxs.to_array(),
                        )
                    })
                    .collect();
                found.sort_by(|a, b| a.partial_cmp(b).expect("finite boxes"));
                found
            };
            for &ball in &balls {
                let h1 = world.bodies[ball].colliders()[0];
                let from_list = found(&mut cache, h1, Some(&list));
                let enlarged = found(&mut cache, h1, None);
                assert_eq!(from_list, enlarged, "ball {h1:?}");
                listed_moving += from_list
                    .iter()
                    .filter(|(h, _, _)| list.iter().any(|(l, _)| l.into_raw_parts() == *h))
                    .count();
            }
        }
        assert!(listed_moving > 0, "no moving candidate was found at all");
    }

    proptest! {
        /// A collider off its body's centre of mass, on a body that moves,
        /// turns (whole turns too) and accelerates, near the origin or far
        /// from it: at every sampled time of the motion the stage builds,
        /// its box lies in the rough box, in the box from the two poses and
        /// in the tight one, and at every sampled time of a part of the
        /// step in that part's box.
        #[test]
        fn the_rough_and_tight_boxes_hold_the_collider(
            start in (prop::array::uniform3(-5.0f32..5.0), prop::array::uniform3(-1.0f32..1.0), -3.0f32..3.0),
            shift in prop::array::uniform3(-4.0f32..4.0),
            turn in (prop::array::uniform3(-1.0f32..1.0), -3.0f32..3.0),
            spin in prop::array::uniform3(-400.0f32..400.0),
            accel in prop_oneof![Just([0.0f32; 3]), prop::array::uniform3(-3000.0f32..3000.0)],
            local in (prop::array::uniform3(-1.0f32..1.0), prop::array::uniform3(-1.0f32..1.0), -3.0f32..3.0),
            half in prop::array::uniform3(0.01f32..1.0),
            far in prop::sample::select(vec![0.0f32, 1.0e3, 2.0e4, 3.0e5]),
            part in (0.0f64..1.0, 0.0f64..1.0),
        ) {
            let dt = 1.0 / 60.0;
            let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
            // Far from the origin too, where `f32` poses round by millimetres.
            let mut start = pose(start.0, start.1, start.2);
            start.translation += Vector::new(far, -0.5 * far, far);
            let handle: RigidBodyHandle = bodies.insert(RigidBodyBuilder::dynamic().pose(start));
            let tested = ColliderBuilder::cuboid(half[0], half[1], half[2])
                .position(pose(local.0, local.1, local.2))
                .build();
            let h = colliders.insert_with_parent(tested, handle, &mut bodies);
            // A heavy ball elsewhere moves the centre of mass off the cuboid.
            let ball = ColliderBuilder::ball(0.3)
                .translation(Vector::new(0.7, -0.4, 0.2))
                .density(5.0)
                .build();
            colliders.insert_with_parent(ball, handle, &mut bodies);
            let end = Pose::from_parts(
                start.translation + Vector::from(shift),
                Rotation::from_axis_angle(Vector::from(turn.0).normalize_or(Vector::X), turn.1)
                    * start.rotation,
            );
            let moved = [Moved {
                handle,
                start,
                end,
                angvel: Vector::from(spin),
                accel: Vector::from(accel),
                fast: true,
                pusher: false,
                travel: 0.0,
            }];
            let motions = StepMotions::new(&moved, dt);
            let co = &colliders[h];
            let rough = rough_swept_box(&motions, co, &bodies);
            let motion = motions.collider(co, &bodies).unwrap();
            let tight = swept_aabb(co.shape(), &motion);
            // None with an acceleration, or for a compact shape barely
            // turning (rare here: the spin is mostly hundreds of rad/s).
            let posed = pose_path_box(&motions, co, &bodies);
            prop_assert!(posed.is_none() || accel == [0.0; 3]);
            let posed = posed.unwrap_or(rough);
            for k in 0..=64 {
                let at = pose_from_iso(&motion.pose_at(k as f64 / 64.0));
                let b = co.shape().compute_aabb(&at);
                prop_assert!(within(&b, &rough), "τ = {}/64: {:?} not in rough {:?}", k, b, rough);
                prop_assert!(within(&b, &posed), "τ = {}/64: {:?} not in posed {:?}", k, b, posed);
                prop_assert!(within(&b, &tight), "τ = {}/64: {:?} not in tight {:?}", k, b, tight);
            }
            // And over a part of the step, the box of its path there.
            let span = TimeSpan::new(part.0.min(part.1), part.0.max(part.1));
            let partial = swept_aabb_within(co.shape(), &motion, span);
            for k in 0..=64 {
                let tau = span.lo + span.width() * k as f64 / 64.0;
                let b = co.shape().compute_aabb(&pose_from_iso(&motion.pose_at(tau)));
                prop_assert!(within(&b, &partial), "τ = {}: {:?} not in {:?}", tau, b, partial);
            }
        }
    }
}
