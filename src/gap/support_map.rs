//! Any two convex shapes: adaptive separating axes (docs/design.md §5).
//!
//! Capsules, cylinders, cones, convex hulls, segments, triangles and the
//! rounded shapes have no finite complete set of separating axes. But *any*
//! direction `n` gives a lower bound of the distance: the shapes are apart
//! by at least `n·(t_b − t_a) − h_a(R_aᵀn) − h_b(−R_bᵀn)` (over `|n|`),
//! with `h` each shape's support function ([`super::support`]). So the
//! axes here are sound whatever direction they use; only their tightness
//! depends on the choice.
//!
//! On each node the direction comes from the shapes' closest points at the
//! exact poses of the node's middle time (in closed form when both cores
//! are points, segments or boxes, a capsule pair needing no GJK, and for a
//! cylinder and a box whose closest points lie beside the cylinder's axis;
//! for a cylinder or cone and a box, by Newton's method over the round
//! shape's generators (`super::generators`);
//! parry's contact query otherwise, and on a node narrower than 1e-3 of
//! the step a pair with a curved shape first asks GJK in `f64` over our
//! own support points, whose normal is precise where parry's `f32` one is
//! not, near a graze): the closest-points normal when
//! the shapes are apart there (the best single separating direction), the
//! penetration normal when they overlap (no direction separates then, but
//! the approach direction still clips the node well; on a node wider than
//! 1 % of the step, the shapes' own box or cylinder axis, or a triangle's
//! normal against a hull, along which they overlap least stands in for
//! it, see `SupportMap::shallowest_axis`, and
//! on a narrower one of a pair with a curved shape, the last node's
//! direction, see `SupportMap::direction`). As
//! nodes shrink the direction becomes right for the whole node, and the
//! axis positive wherever the shapes are truly apart. The same direction
//! is used three
//! ways, because the best separating direction turns with the bodies:
//!
//! 0. fixed in the world: `n`;
//! 1. fixed in `a`'s frame: `n(τ) = R_a(τ)·m`, `m = R_a(mid)ᵀn` — exact
//!    for `a`'s own support, right when `a` spins and `b` does not;
//! 2. fixed in `b`'s frame: `n(τ) = R_b(τ)·k`, `k = R_b(mid)ᵀn`.
//!
//! (A side that does not turn, a floor or a wall, holds its direction
//! fixed in the world: its axis is axis 0's, not evaluated again.)
//!
//! Cost: one closest-points computation per node (parry's GJK, and EPA
//! when overlapping on a node narrower than 1 % of the step, unless the
//! closed form applies) plus some 60
//! enclosure products and the support functions; a node that axis 0
//! proves apart skips the other two. Where the direction is parry's, the
//! last node's direction (as it was in the world) is tried first, and a
//! node it proves apart needs no query.

use super::support::{Convex, Core, ORTHO_SLACK, dot, norm_up, tr_mul};
use super::{Exact, Middle, Side, rounding_slack};
use super::{RoundBox, round_box};
use crate::convert::{glam_from_vec, pose_from_iso, pose64_from_iso, vec_from_glam};
use crate::enclosure::rounding::{down, up};
use crate::enclosure::{Enclosure, Interval, TimeSpan};
use crate::motion::Trajectory;
use nalgebra::{Isometry3, Vector3};
use parry3d_f64::math::{Pose as Pose64, Vector as Vec64};
use parry3d_f64::query::gjk::{
    self as gjk64, CsoPoint as Cso64, GJKResult as Gjk64Result, VoronoiSimplex as Simplex64,
};
use rapier3d::parry::math::{Pose as ParryPose, Vector};
use rapier3d::parry::query::epa::EPA;
use rapier3d::parry::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use rapier3d::parry::shape::Shape;
use std::cell::{Cell, RefCell};
use std::fmt;
use std::sync::Arc;

/// How far apart (metres) parry's contact query still reports the closest
/// points; farther pairs take the direction of their frames' origins, good
/// enough at such distances. (`f32::MAX` overflows in some of parry's
/// paths, which then answer nothing.)
const PREDICTION: f32 = 1.0e6;

/// Nodes wider than this (a fraction of the step) whose middle overlaps
/// take the shapes' shallowest own axis for a direction, not parry's
/// penetration normal (see `SupportMap::shallowest_axis`).
const COARSE_NODE: f64 = 0.01;

/// Nodes narrower than this (a fraction of the step) take the direction
/// of a pair with a curved shape from GJK in `f64` when the shapes are
/// apart at their middle (see `SupportMap::closest_f64`). Measured on the
/// accuracy cases (100 a kind, seed 7): 1e-3 is the least work; 1e-2 and
/// 1e-4 cost 2-12 % more.
const NARROW_NODE: f64 = 1.0e-3;

/// Shapes closer than this share of their sizes count as touching at a
/// single time (see `SupportMap::eval_at_a_time`).
const TOUCHING: f64 = 1.0e-7;

/// What parry's GJK (and EPA) said of the shapes at one pose.
enum Found {
    /// A direction from `a` towards `b` (`a`'s frame): the closest points'
    /// normal, with their distance, or the penetration normal.
    Apart(Vector, Option<f32>),
    /// The shapes overlap; no penetration normal was asked for.
    Overlap,
    Nothing,
}

/// What the generators of a cylinder or cone told of it and a box
/// ([`SupportMap::round_box_direction`]), in `a`'s frame.
enum Generators {
    /// The closest points' direction from `a` towards `b`, and their
    /// distance.
    Apart {
        normal: Vector3<f64>,
        distance: f64,
    },
    Overlap,
    Unknown,
}

/// GJK simplices kept from the last queries of a pair, each with the
/// relative pose it was at (see `SupportMap::first_simplex`): parry's `f32`
/// one and the `f64` one of narrow nodes.
#[derive(Clone, Default)]
struct Warm {
    f32: Option<(VoronoiSimplex, ParryPose)>,
    /// With the closest points' normal GJK found from it, if any.
    f64: Option<(Simplex64, Pose64, Option<Vector3<f64>>)>,
}

/// Two convex shapes, each a core plus a border.
#[derive(Clone)]
pub(crate) struct SupportMap {
    a: Convex,
    b: Convex,
    /// parry's own shapes, for the direction query.
    shape_a: Arc<dyn Shape>,
    shape_b: Arc<dyn Shape>,
    /// `skin` plus the orthonormality pad, metres.
    skin: f64,
    /// The unit face normal of a triangle side, in its own frame: a fourth
    /// axis, exact for a flat piece. parry's `f32` direction is off by up
    /// to ~1e-4 rad, which across a 14 m floor triangle costs about a
    /// millimetre of bound, so a capsule resting 0.5 mm above such a floor
    /// could not be proved apart from it.
    face_a: Option<Vector3<f64>>,
    face_b: Option<Vector3<f64>>,
    /// The direction (in `a`'s frame) of the last node evaluated.
    last: Cell<Option<Vector3<f64>>>,
    /// The same direction in the world, as it was at that node's middle:
    /// the next node's first try (see `SupportMap::eval`).
    last_world: Cell<Option<Vector3<f64>>>,
    /// `last` was found for the node `eval` is asked next, by
    /// [`SupportMap::apart_from_middle`]: `eval` takes it instead of
    /// asking again.
    directed: Cell<bool>,
    /// The GJK simplices of the last closest-points queries: the next
    /// ones' start. Kept only when `curved`; boxed so that the other pairs
    /// stay small to move, the box made once and then written over.
    warm: RefCell<Option<Box<Warm>>>,
    /// Some shape is curved: GJK takes many steps to converge on it, and
    /// starting from the last simplex saves most of them. (Between two
    /// polyhedra it converges in a few steps from the last direction, and
    /// a stale simplex costs more than it saves: 2 % more instructions on
    /// the hull–mesh benchmark.)
    curved: bool,
    /// The cores' closest points have a closed form (`core_direction`).
    closed_form: bool,
    /// A cylinder or cone against a box ([`round_box`]): `Some(true)`
    /// when `a` is the cylinder or cone.
    round_box: Option<bool>,
    /// Some shape has its own axes for [`SupportMap::shallowest_axis`].
    own_axes: bool,
    /// A triangle's normal is one of them: against a hull (which has no
    /// axes of its own, and whose EPA visits every vertex).
    face_axes: bool,
    /// Some shape has a point test ([`Convex::contains`]): a touch check
    /// may find a point in both (`SupportMap::overlap_witnessed`).
    witnesses: bool,
}

impl fmt::Debug for SupportMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SupportMap")
            .field("a", &self.a)
            .field("b", &self.b)
            .field("skin", &self.skin)
            .finish_non_exhaustive()
    }
}

impl SupportMap {
    /// The adaptive axes; a triangle side adds its face normal.
    pub const AXES: usize = 3;

    pub fn axis_count(&self) -> usize {
        Self::AXES + usize::from(self.face_a.is_some()) + usize::from(self.face_b.is_some())
    }

    pub fn new(
        a: Convex,
        shape_a: Arc<dyn Shape>,
        b: Convex,
        shape_b: Arc<dyn Shape>,
        skin: f64,
    ) -> SupportMap {
        let pad = up(ORTHO_SLACK * up(up(a.extent() + b.extent()) + skin));
        let closed_form = has_closed_form(&a.core, &b.core);
        let (face_a, face_b) = (face_normal(&a), face_normal(&b));
        let axes = |c: &Core| {
            matches!(
                c,
                Core::Cuboid(_) | Core::Cylinder { .. } | Core::Cone { .. }
            )
        };
        // A triangle against a hull: the triangle's normal is an own axis.
        let hull = |c: &Core| matches!(c, Core::Polyhedron(_));
        let face_axes = (face_a.is_some() && hull(&b.core)) || (face_b.is_some() && hull(&a.core));
        let own_axes = axes(&a.core) || axes(&b.core) || face_axes;
        let curved = |c: &Convex| {
            c.border > 0.0
                || matches!(
                    c.core,
                    Core::Point | Core::Cylinder { .. } | Core::Cone { .. }
                )
        };
        let curved = curved(&a) || curved(&b);
        let witnesses = a.tests_points() || b.tests_points();
        let round = |c: &Convex| {
            c.border == 0.0 && matches!(c.core, Core::Cylinder { .. } | Core::Cone { .. })
        };
        let cuboid = |c: &Convex| c.border == 0.0 && matches!(c.core, Core::Cuboid(_));
        let round_box = if round(&a) && cuboid(&b) {
            Some(true)
        } else if cuboid(&a) && round(&b) {
            Some(false)
        } else {
            None
        };
        SupportMap {
            round_box,
            face_a,
            face_b,
            own_axes,
            face_axes,
            a,
            b,
            shape_a,
            shape_b,
            skin: up(skin + pad),
            last: Cell::new(None),
            last_world: Cell::new(None),
            directed: Cell::new(false),
            warm: RefCell::new(None),
            curved,
            closed_form,
            witnesses,
        }
    }

    /// GJK's starting simplex at the relative pose `pos12`: the last
    /// query's simplex `kept` (with its pose) carried to it, else the
    /// shapes' difference's support point along `start`.
    ///
    /// A simplex's vertices are differences of points of the two shapes,
    /// kept in each shape's frame, so at any relative pose they are points
    /// of the shapes' difference; a nearby time's simplex is close to the
    /// answer, and GJK stops after a step or two instead of rebuilding it.
    fn first_simplex(
        pos12: &ParryPose,
        g1: &dyn rapier3d::parry::shape::SupportMap,
        g2: &dyn rapier3d::parry::shape::SupportMap,
        start: Vector,
        kept: Option<&(VoronoiSimplex, ParryPose)>,
    ) -> VoronoiSimplex {
        match kept {
            Some((simplex, old12)) => {
                let mut simplex = simplex.clone();
                let shift = *pos12 * old12.inverse();
                simplex.modify_pnts(&|p| *p = CsoPoint::new(p.orig1, shift * p.orig2));
                simplex
            }
            None => {
                let mut simplex = VoronoiSimplex::new();
                simplex.reset(CsoPoint::from_shapes(pos12, g1, g2, start));
                simplex
            }
        }
    }

    /// A unit direction from `a` towards `b`, in `a`'s frame, at the poses
    /// `ia`, `ib` of the middle of a node `width` wide (0: a single time),
    /// and the shapes' distance when parry measured it. Never fails: when
    /// parry has no answer, the direction of the frames' origins, or any
    /// axis.
    ///
    /// At a single time (where the search only asks whether the shapes
    /// touch) overlapping shapes take the last direction instead of parry's
    /// penetration normal: along every direction overlapping shapes show as
    /// touching (the penetration normal is the one along which they overlap
    /// *least*), and that normal's EPA was most of the cost of a cylinder
    /// query. On a node wider than [`COARSE_NODE`] (only its clipping needs
    /// the direction) they take [`Self::shallowest_axis`]. On a narrower
    /// one a pair with a curved shape takes the last direction as well
    /// (parry's EPA there cost a cylinder 17 k instructions a call; cone
    /// queries at 200–1000 rad/s 6.5 % fewer instructions, cylinder
    /// queries 3 % fewer at ordinary spins and 1 % more at fast ones;
    /// between polytopes EPA's normal clips better and stays). On one
    /// narrower than [`NARROW_NODE`] a pair with a curved shape asks
    /// [`Self::closest_f64`] first. Any of these within a milliradian of a
    /// box's face normal becomes that normal ([`Self::snap_to_face`]).
    fn direction(
        &self,
        ia: &Isometry3<f64>,
        ib: &Isometry3<f64>,
        width: f64,
    ) -> (Vector3<f64>, Option<f64>) {
        let rel = ia.inv_mul(ib);
        if let Some(n) = core_direction(&self.a.core, &self.b.core, &rel) {
            return (n, None);
        }
        // (A cylinder or cone against a box finds a face's normal through
        // its generators, in `parry_direction`, where it is the closest
        // points' direction.)
        if self.round_box.is_none()
            && let Some(n) = self.face_direction(&rel)
        {
            return (n, None);
        }
        let (n, distance) = self.parry_direction(rel, width);
        (self.snap_to_face(n, &rel), distance)
    }

    /// The closest points' direction (in `a`'s frame, from `a` towards
    /// `b`) where a box side's face holds them: see [`face_box`].
    fn face_direction(&self, rel: &Isometry3<f64>) -> Option<Vector3<f64>> {
        if let Core::Cuboid(half) = &self.a.core
            && self.a.border == 0.0
            && let Some(n) = face_box(half, &self.b, rel)
        {
            return Some(n);
        }
        if let Core::Cuboid(half) = &self.b.core
            && self.b.border == 0.0
        {
            return face_box(half, &self.a, &rel.inverse()).map(|n| -(rel.rotation * n));
        }
        None
    }

    /// What [`round_box`] finds of a cylinder or cone and a box (`None`
    /// for other pairs), started from the last node's direction.
    fn round_box_direction(&self, rel: &Isometry3<f64>) -> Option<Generators> {
        let last = self.last.get();
        // `round_box` works in the box's frame, from the round shape
        // towards the box: carried to `a`'s frame, from `a` towards `b`.
        let a_is_round = self.round_box?;
        let found = if a_is_round {
            let start = last.map(|n| rel.rotation.inverse() * n);
            round_box(&self.a, &rel.inverse(), &self.b, start.as_ref())
        } else {
            round_box(&self.b, rel, &self.a, last.map(|n| -n).as_ref())
        };
        Some(match found {
            RoundBox::Apart {
                normal,
                on_round,
                on_box,
            } => Generators::Apart {
                normal: if a_is_round {
                    rel.rotation * normal
                } else {
                    -normal
                },
                distance: (on_box - on_round).norm(),
            },
            RoundBox::Overlap => Generators::Overlap,
            RoundBox::Unknown => Generators::Unknown,
        })
    }

    /// [`Self::direction`] where it has no closed form: GJK in `f64` on
    /// narrow nodes of a curved pair, else parry's `f32` GJK (or EPA, or
    /// the shapes' own least-overlap axis, or parry's contact).
    fn parry_direction(&self, rel: Isometry3<f64>, width: f64) -> (Vector3<f64>, Option<f64>) {
        let (depth, coarse) = (width > 0.0, width > COARSE_NODE);
        // A narrow node of a curved pair that overlaps at its middle takes
        // the last direction (below): a point in both shapes tells that
        // without GJK.
        if depth
            && !coarse
            && self.curved
            && self.witnesses
            && let Some(last) = self.last.get()
            && self.overlap_witnessed(&rel)
        {
            return (last, None);
        }
        // A cylinder and a box whose closest points the closed form did
        // not find (a cap's rim near the box): on a wide node, the best of
        // their own axes where it separates them at the middle. Between a
        // cap and a box it mostly is the closest points' direction, which
        // parry's GJK creeps towards over the flat cap (5.9 k instructions
        // a call). (Cylinder queries 7 % fewer instructions, at ordinary
        // spins and at 200-1000 rad/s; a cone's, which has no closed form,
        // took 1-3 % more with it and is not offered it.)
        if coarse
            && self.closed_form
            && let Some((gap, n)) = self.shallowest_axis(&rel)
            && gap > 0.0
        {
            return (n, None);
        }
        // A cylinder or cone and a box: their closest points through the
        // round shape's generators, where parry's GJK creeps along a rim
        // or a cone's side. Found overlapping, they take what GJK's
        // `Intersection` leads to below, without it: the last direction,
        // or on a wide node their shallowest own axis.
        match self.round_box_direction(&rel) {
            Some(Generators::Apart { normal, .. }) => return (normal, None),
            Some(Generators::Overlap) => {
                if depth && coarse {
                    if let Some((_, n)) = self.shallowest_axis(&rel) {
                        return (n, None);
                    }
                } else if let Some(last) = self.last.get() {
                    return (last, None);
                }
            }
            _ => {}
        }
        if width > 0.0
            && width < NARROW_NODE
            && self.curved
            && let Some(n) = self.closest_f64(&rel)
        {
            return (n, None);
        }
        let pos12 = pose_from_iso(&rel);
        if let (Some(g1), Some(g2)) = (self.shape_a.as_support_map(), self.shape_b.as_support_map())
        {
            // GJK starts from the last node's direction (a nearby time's
            // answer, so it converges in fewer steps), else the origins'.
            // On overlap with a `depth` wanted, parry's EPA takes GJK's last
            // simplex, as its own contact query would after running GJK anew.
            let start = match self.last.get() {
                Some(last) => glam_from_vec(&last),
                None => pos12.translation.try_normalize().unwrap_or(Vector::X),
            };
            let search = || {
                let mut kept = self.warm.borrow_mut().take();
                let last = kept.as_ref().and_then(|w| w.f32.as_ref());
                let mut simplex = Self::first_simplex(&pos12, g1, g2, start, last);
                let found =
                    match gjk::closest_points(&pos12, g1, g2, PREDICTION, true, &mut simplex) {
                        GJKResult::ClosestPoints(p1, p2, n) => {
                            Found::Apart(n, Some((p2 - p1).length()))
                        }
                        GJKResult::Intersection
                            if depth && !coarse && self.curved && self.last.get().is_some() =>
                        {
                            Found::Overlap
                        }
                        GJKResult::Intersection if depth && (!coarse || !self.own_axes) => {
                            match EPA::new().closest_points(&pos12, g1, g2, &simplex) {
                                Some((_, _, n)) => Found::Apart(n, None),
                                None => Found::Nothing,
                            }
                        }
                        GJKResult::Intersection => Found::Overlap,
                        _ => Found::Nothing,
                    };
                if self.curved {
                    kept.get_or_insert_with(Box::default).f32 = Some((simplex, pos12));
                }
                self.warm.replace(kept);
                found
            };
            // As below: a panic in parry only costs the hint.
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(search)) {
                Ok(Found::Apart(n, distance)) => {
                    if let Some(n) = vec_from_glam(n).try_normalize(1.0e-6) {
                        return (n, distance.map(f64::from));
                    }
                }
                Ok(Found::Overlap) if !depth || !coarse => {
                    if let Some(last) = self.last.get() {
                        return (last, None);
                    }
                }
                Ok(Found::Overlap) => {
                    if let Some((_, n)) = self.shallowest_axis(&rel) {
                        return (n, None);
                    }
                }
                _ => {}
            }
        }
        // Shapes that are no support maps, or parry found nothing: its
        // contact query. It is not written to be total on degenerate
        // shapes; a panic there only costs us the hint, not the answer.
        let query = || {
            rapier3d::parry::query::contact(
                &ParryPose::IDENTITY,
                &*self.shape_a,
                &pos12,
                &*self.shape_b,
                PREDICTION,
            )
        };
        let contact = std::panic::catch_unwind(std::panic::AssertUnwindSafe(query));
        if let Ok(Ok(Some(c))) = contact
            && let Some(n) = vec_from_glam(c.normal1).try_normalize(1.0e-6)
        {
            return (n, Some(f64::from(c.dist)));
        }
        let n = rel.translation.vector.try_normalize(1.0e-300);
        (n.unwrap_or_else(Vector3::x), None)
    }

    /// The closest points' unit normal (from `a` towards `b`, in `a`'s
    /// frame) at the relative pose `rel`, by [`Self::closest_at`]; `None`
    /// when the shapes overlap (the caller's `f32` query then runs EPA) or
    /// GJK has no answer.
    ///
    /// parry's `f32` GJK stops once its distance bounds agree to about
    /// 0.3 % (and rounds in `f32`): its normal can be milliradians off,
    /// which near a graze leaves the axis negative over nodes where the
    /// shapes are a tenth of a millimetre apart, and the search stalls
    /// there. In `f64` GJK converges to about 1e-7, but on a curved shape
    /// that takes many more steps, so only narrow nodes, where a precise
    /// direction pays, ask for it (cylinder queries: 18 % fewer
    /// evaluations, 9 % fewer instructions).
    fn closest_f64(&self, rel: &Isometry3<f64>) -> Option<Vector3<f64>> {
        self.closest_at(rel, None).flatten().map(|(n, _)| n)
    }

    /// For shapes at the poses `rel` (`b`'s in `a`'s frame): of their own
    /// face and axis directions (a box's faces, a cylinder's or cone's
    /// axis, a triangle's normal against a hull), the one along which they
    /// overlap least (or are farthest apart), in `a`'s frame, pointing
    /// from `a` towards `b`, with their gap along it (negative: overlap).
    /// parry's penetration normal is that direction over *all* directions
    /// (its EPA, most of a cylinder query's cost); where a box face or a
    /// cylinder's axis meets the other shape, as it mostly does, the two
    /// agree; a hull sunk into a mesh's triangle mostly overlaps it least
    /// along the triangle's normal (hull–mesh queries at 200–1000 rad/s:
    /// 1.3 % fewer instructions, the slowest one 7 %; a capsule's on a
    /// flat mesh cost more with it, and it is not offered there). `None`
    /// when neither shape has such a direction (`own_axes` is false).
    fn shallowest_axis(&self, rel: &Isometry3<f64>) -> Option<(f64, Vector3<f64>)> {
        const AXES: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let own = |core: &Core| -> &'static [[f64; 3]] {
            match core {
                Core::Cuboid(_) => &AXES,
                Core::Cylinder { .. } | Core::Cone { .. } => &AXES[1..2],
                _ => &[],
            }
        };
        let offset = rel.translation.vector;
        let mut best: Option<(f64, Vector3<f64>)> = None;
        let candidates = own(&self.a.core)
            .iter()
            .map(|u| Vector3::from(*u))
            .chain(self.face_a.filter(|_| self.face_axes))
            .chain(
                own(&self.b.core)
                    .iter()
                    .map(|u| rel.rotation * Vector3::from(*u)),
            )
            .chain(
                self.face_b
                    .filter(|_| self.face_axes)
                    .map(|f| rel.rotation * f),
            );
        for u in candidates {
            let n = if u.dot(&offset) >= 0.0 { u } else { -u };
            // The gap along `n` (negative: the overlap).
            let gap = n.dot(&offset)
                - self.a.support_f64(&n)
                - self.b.support_f64(&-(rel.rotation.inverse() * n));
            if best.is_none_or(|(g, _)| gap > g) {
                best = Some((gap, n));
            }
        }
        best
    }

    /// `n` (a unit direction in `a`'s frame, `rel` being `b`'s pose in it)
    /// replaced by a box's face normal within a milliradian of it. Along a
    /// direction tilted by `δ` from a face normal a box reaches out by `δ`
    /// times its size, and parry's directions are a tenth of a milliradian
    /// to a milliradian off: a cone skimming a 40 m floor box 1.4 mm above
    /// it could not be proved apart within a millimetre's skin (2,211
    /// evaluations), and along the face normal itself it is in 6. Where the
    /// box's nearest feature is that face, the face normal is the exact
    /// closest direction; near one of its edges, a direction as good.
    fn snap_to_face(&self, n: Vector3<f64>, rel: &Isometry3<f64>) -> Vector3<f64> {
        const AXES: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        // cos of a milliradian.
        const NEAR: f64 = 1.0 - 5.0e-7;
        let faces_a = matches!(self.a.core, Core::Cuboid(_)).then(|| AXES.map(Vector3::from));
        let faces_b = matches!(self.b.core, Core::Cuboid(_))
            .then(|| AXES.map(|u| rel.rotation * Vector3::from(u)));
        for u in faces_a.into_iter().chain(faces_b).flatten() {
            let c = n.dot(&u);
            if c.abs() > NEAR {
                return u * c.signum();
            }
        }
        n
    }

    /// The axes at the single time `t` (a touch check, or the check of
    /// the span's start), from the exact poses in `f64`, without enclosing
    /// the poses: overlapping where a point lies in both shapes
    /// ([`Self::overlap_witnessed`]), else for a cylinder or cone and a
    /// box from their closest points through the round shape's generators
    /// ([`round_box`]; cylinder queries 4 % fewer instructions at ordinary
    /// spins, cone queries 3 %), else from GJK in `f64`, stopped as
    /// soon as it knows on which side of the touching distance the shapes
    /// are. `false` (and `out` untouched) where no point in both was found
    /// and GJK is not asked here (a rounded shape, or no curved one: see
    /// below), or when GJK has no answer.
    ///
    /// Every axis is the gap along some direction, less the skin: along
    /// any unit direction it is at least `-(|d| + extents)` (`d` the
    /// origins' offset) and at most the shapes' distance, which GJK's
    /// simplex (points of the shapes' difference) bounds from above;
    /// overlapping shapes have no positive gap along any direction. Axis 0
    /// takes GJK's last direction, whose gap the supports bound from below.
    pub fn eval_at_a_time<E: Enclosure>(
        &self,
        t: f64,
        ma: &crate::motion::Motion,
        mb: &crate::motion::Motion,
        axes: u64,
        out: &mut [E],
    ) -> bool {
        // GJK only where the enclosed axes' GJK (or closed form and
        // enclosed poses) is the slow part and GJK in `f64` is not: a
        // cylinder or a cone against a shape with corners (cylinder
        // queries: 3-4 % fewer instructions than their closed form and
        // enclosed path). A rounded border makes the shapes' difference
        // smooth near the closest points, where `f64` GJK creeps (a
        // capsule against a triangle: 23 k instructions a call, measured);
        // polyhedra need no GJK at all when the last direction still
        // separates them. The point in both is looked for wherever a shape
        // has a point test (cylinder, capsule, cone queries: 2-10 % fewer
        // instructions).
        let gjk_here = self.curved && self.a.border == 0.0 && self.b.border == 0.0;
        if !gjk_here && !self.witnesses {
            return false;
        }
        let (ia, ib) = (ma.pose_at(t), mb.pose_at(t));
        let rel = ia.inv_mul(&ib);
        let extents = self.a.extent() + self.b.extent();
        let (sizes, slack) = rounding_slack(&ia, &ib, extents);
        // No two points of the shapes are farther apart than this.
        let farthest = up(rel.translation.vector.norm() + extents);
        let least = -up(farthest + self.skin + slack);
        // A distance under this reads as touching below; GJK stops as soon
        // as it knows on which side of it the shapes are.
        let enough = self.skin + TOUCHING * sizes - 2.0 * slack;
        // A cylinder or cone and a box: through the generators first (an
        // overlap found there is as close as `f32` resolves, which reads
        // as touching below anyway).
        let generators = || match self.round_box_direction(&rel)? {
            Generators::Apart { normal, distance } => Some(Some((normal, distance))),
            Generators::Overlap => Some(None),
            Generators::Unknown => None,
        };
        let closest = if self.overlap_witnessed(&rel) {
            Some(None)
        } else if let Some(found) = generators() {
            Some(found)
        } else if gjk_here {
            self.closest_at(&rel, Some(enough))
        } else {
            return false;
        };
        let Some(closest) = closest else {
            return false;
        };
        let (along_n, any) = match closest {
            Some((m, d)) => {
                let d = d.min(farthest);
                // Shapes closer than `f32` resolves (1e-7 of the sizes)
                // count as touching, as parry's `f32` GJK, which the
                // enclosed path asks, sees them: only a touch check reads
                // this upper bound, and a search that cannot confirm a
                // touch 2e-8 m away bisects down to its floor width
                // instead (cone queries: 3x the evaluations).
                let most = up(up(d + slack) - self.skin - TOUCHING * sizes).max(least);
                self.last.set(Some(m));
                self.last_world.set(Some(ia.rotation * m));
                let gap = self.gap_along(&m, &rel);
                let lo = down(gap - slack - self.skin);
                (
                    Interval::new(lo.clamp(least, most), most),
                    Interval::new(least, most),
                )
            }
            // Overlapping: along no direction is the gap positive, so
            // every axis is at most `-skin`.
            None => {
                let overlap = Interval::new(least, (-self.skin).max(least));
                (overlap, overlap)
            }
        };
        let (along_n, any) = (E::from_interval(along_n), E::from_interval(any));
        let mut bits = axes;
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if k < out.len() {
                out[k] = if k == 0 { along_n } else { any };
            }
        }
        // Axis 0 proves them apart alone: the others take its value, as a
        // family that stops early leaves them.
        if axes & 1 != 0 {
            super::apart_by(out, axes, 0b1);
        }
        true
    }

    /// Whether a point lies in both shapes at the relative pose `rel`
    /// (`b`'s in `a`'s frame): the point of each farthest into the other
    /// along the last direction, tested against the other
    /// ([`Convex::contains`]). Where a search checks a touch the shapes
    /// mostly overlap a little, and the deepest point of one (a box's
    /// corner, a cone's rim) lies in the other: a few hundred instructions
    /// where GJK takes thousands to close its simplex around the origin.
    fn overlap_witnessed(&self, rel: &Isometry3<f64>) -> bool {
        let Some(m) = self.last.get() else {
            return false;
        };
        let m_in_b = rel.rotation.inverse() * m;
        let deepest_b = rel * nalgebra::Point3::from(self.b.support_point(&-m_in_b));
        if self.a.contains(&deepest_b.coords) {
            return true;
        }
        let deepest_a = rel.inverse_transform_point(&self.a.support_point(&m).into());
        self.b.contains(&deepest_a.coords)
    }

    /// How far apart the shapes are along the unit direction `m` (in
    /// `a`'s frame, from `a` towards `b`) at the relative pose `rel`, from
    /// their supports in plain `f64`: negative where they overlap along it.
    fn gap_along(&self, m: &Vector3<f64>, rel: &Isometry3<f64>) -> f64 {
        m.dot(&rel.translation.vector)
            - self.a.support_f64(m)
            - self.b.support_f64(&-(rel.rotation.inverse() * m))
    }

    /// The closest points' unit normal (from `a` towards `b`, `a`'s frame)
    /// and their distance at the relative pose `rel`, by parry3d-f64's GJK
    /// over our own support points, started from the last such query's
    /// simplex (kept for a curved pair); `Some(None)` when the shapes
    /// overlap, `None` when GJK has no answer. With `enough`, GJK stops as
    /// soon as the shapes are known to be farther apart than that (the
    /// distance then reads infinite) or within it: the normal is then its
    /// last direction and the distance a bound from above (a touch check:
    /// cone queries 10 % fewer instructions than GJK run to convergence).
    fn closest_at(
        &self,
        rel: &Isometry3<f64>,
        enough: Option<f64>,
    ) -> Option<Option<(Vector3<f64>, f64)>> {
        let pos12 = pose64_from_iso(rel);
        let cold = || {
            let start = match self.last.get() {
                Some(last) => Vec64::new(last.x, last.y, last.z),
                None => pos12.translation.try_normalize().unwrap_or(Vec64::X),
            };
            let mut simplex = Simplex64::new();
            simplex.reset(Cso64::from_shapes(&pos12, &self.a, &self.b, start));
            simplex
        };
        let gjk = |simplex: &mut Simplex64| {
            gjk64::closest_points(
                &pos12,
                &self.a,
                &self.b,
                enough.unwrap_or(f64::from(PREDICTION)),
                enough.is_none(),
                simplex,
            )
        };
        let search = || {
            let mut kept = self.warm.borrow_mut().take();
            let last = kept.as_ref().and_then(|w| w.f64.as_ref());
            let found_last = last.and_then(|w| w.2);
            let warm = last.map(|(simplex, old12, _)| carried(simplex, old12, &pos12));
            // parry's GJK can end on a tetrahedron that holds the origin
            // and still answer the closest points (its tetrahedron case with
            // a positive lower bound); started from that one, it answers
            // `Intersection` at once, for shapes apart (a cone 1.4 mm above
            // a floor box, asked twice at one pose: a near miss the stage
            // clamped). Such an answer is asked again from scratch when the
            // normal that simplex gave still separates the shapes
            // (overlapping shapes are apart along none; on the cone
            // benchmark every such answer was a true overlap).
            let from_tetrahedron = warm.as_ref().is_some_and(|s| s.dimension() == 3);
            let mut simplex = warm.unwrap_or_else(cold);
            let mut found = gjk(&mut simplex);
            if from_tetrahedron
                && found == Gjk64Result::Intersection
                && found_last.is_some_and(|m| self.gap_along(&m, rel) > 0.0)
            {
                simplex = cold();
                found = gjk(&mut simplex);
            }
            let unit = |n: Vec64| Vector3::new(n.x, n.y, n.z).try_normalize(1.0e-9);
            let answer = match found {
                Gjk64Result::ClosestPoints(p1, p2, n) => {
                    unit(n).map(|n| Some((n, (p2 - p1).length())))
                }
                Gjk64Result::Intersection => Some(None),
                // Stopped early: apart by more than `enough` along `n`
                // (or given up), or within it. The simplex's point
                // nearest the origin is a point of the shapes' difference,
                // its length a bound of their distance from above.
                Gjk64Result::NoIntersection(n) if enough.is_some() => {
                    unit(n).map(|n| Some((n, f64::INFINITY)))
                }
                Gjk64Result::Proximity(n) => {
                    unit(n).map(|n| Some((n, simplex.project_origin().length())))
                }
                _ => None,
            };
            if self.curved {
                let normal = answer.flatten().map(|(n, _)| n);
                kept.get_or_insert_with(Box::default).f64 = Some((simplex, pos12, normal));
            }
            self.warm.replace(kept);
            answer
        };
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(search))
            .ok()
            .flatten()
    }

    /// A positive lower bound of the gap beyond the skin over `span`, from
    /// the exact poses at its middle and no enclosed pose: the gap there
    /// along a unit direction `n` (the last node's as it was in the world,
    /// else the closest points' at the middle), less how fast the shapes
    /// can close along `n` (their centres' relative speed along it and
    /// their turning speeds across it, [`SpeedAlong`]) times the
    /// half-width. `None` where that is not positive; the closest points'
    /// direction found at the middle is then kept for `eval` on the node.
    /// The poses at the middle and the supports are rounded a few times in
    /// terms no larger than the shapes' sizes and positions, which
    /// [`Middle`] pads for (as [`Self::eval_at_a_time`] does).
    ///
    /// [`SpeedAlong`]: crate::motion::SpeedAlong
    pub fn apart_from_middle(&self, span: TimeSpan, a: Exact, b: Exact) -> Option<f64> {
        let middle = Middle::new(span, a, b, (self.a.extent(), self.b.extent()));
        let apart = |n: &Vector3<f64>| {
            let gap = self.gap_along(&(middle.ia.rotation.inverse() * n), &middle.rel);
            middle.apart(gap, self.skin, n)
        };
        if let Some(lo) = self.last_world.get().and_then(|n| apart(&n)) {
            return Some(lo);
        }
        // The search for a new direction (the generators' Newton, GJK)
        // starts from the last one as it was in the world too: a piece of
        // a fast spin turns `a`'s frame half a radian from the last
        // (capsule queries at 200-1000 rad/s 0.5 % fewer instructions,
        // cone 0.8 %).
        if let Some(n) = self.last_world.get() {
            self.last.set(Some(middle.ia.rotation.inverse() * n));
        }
        let (m, _) = self.direction(&middle.ia, &middle.ib, span.hi - span.lo);
        let n = middle.ia.rotation * m;
        self.last.set(Some(m));
        self.last_world.set(Some(n));
        let found = apart(&n);
        self.directed.set(found.is_none());
        found
    }

    #[inline(never)]
    pub fn eval<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        axes: u64,
        out: &mut [E],
    ) {
        let mid = span.lo + 0.5 * (span.hi - span.lo);
        let (ia, ib) = (a.pose_at(mid), b.pose_at(mid));
        // The frames' origins' offset, read by every axis.
        let d = b.pose.translation - a.pose.translation;
        // Axis 0: the direction `n`, fixed in the world.
        let world_axis = |n: &Vector3<f64>| {
            let norm = norm_up(n);
            let along = dot(&d, n);
            let da = tr_mul(&a.pose.rotation, n);
            let db = -tr_mul(&b.pose.rotation, n);
            along - self.a.support(&da, norm) - self.b.support(&db, norm) - up(self.skin * norm)
        };
        // The last node's direction first (in a depth-first search that is
        // the parent's or the sibling's, a nearby time): when it proves the
        // pair apart here, no closest-points query is needed. It is tried
        // as it was in the world, not turned on with `a`: between the
        // half-radian pieces of a fast spin `a`'s frame carries it half a
        // radian or more, while the direction that separates shapes apart
        // follows mostly where they are (at 200–1000 rad/s cone queries
        // 4.5 % fewer instructions, hull–mesh 5.4 %; every other kind and
        // spin within 0.6 %).
        // (Only where that query is parry's: the closed form is cheaper
        // than the extra axis. A cylinder against a box skips it past its
        // ends too: its nodes mostly straddle the contact, where the try
        // failed 94 % of the time, each failure costing an axis.) Not on
        // a node whose direction `apart_from_middle` just found: it is
        // taken as it is.
        let directed = self.directed.replace(false);
        if axes & 1 != 0
            && !directed
            && !self.closed_form
            && let Some(last) = self.last_world.get()
        {
            out[0] = world_axis(&last);
            if super::apart_by(out, axes, 0b1) {
                return;
            }
        }
        let width = span.hi - span.lo;
        let (m, distance) = match self.last.get().filter(|_| directed) {
            Some(m) => (m, None),
            None => self.direction(&ia, &ib, width),
        };
        self.last.set(Some(m));
        let n = ia.rotation * m;
        self.last_world.set(Some(n));
        if axes & 1 != 0 {
            out[0] = world_axis(&n);
        }
        if axes & !0b1 == 0 || super::apart_by(out, axes, 0b1) {
            return;
        }
        let single = span.lo == span.hi;
        if single {
            // At a single time the direction fixed in either frame is the
            // world one: axes 1 and 2 would repeat axis 0. Its upper bound
            // is raised to parry's distance less the skin: `f32` GJK's
            // normal may be off by a few milliradians, which across a
            // metre-wide shape understates the gap along it by millimetres
            // (a cylinder 1.7 mm from a box showed 2 mm deep along it, and
            // the search took that for a touch), while the distance itself
            // errs only to second order. An enclosure may always be widened;
            // the lower bound, which proves pairs apart, is left as it is.
            let mut along_n = if axes & 1 != 0 {
                out[0]
            } else {
                world_axis(&n)
            };
            if let Some(d) = distance {
                let range = along_n.range();
                let hi = range.hi.max(d - self.skin);
                along_n = E::from_interval(Interval::new(range.lo, hi));
            }
            if axes & 1 != 0 {
                out[0] = along_n;
            }
            for (k, slot) in out.iter_mut().enumerate().take(Self::AXES).skip(1) {
                if axes >> k & 1 != 0 {
                    *slot = along_n;
                }
            }
        }
        // A direction fixed in one side's frame, turned into the world with
        // that side: `w = R_a(τ)·m` (or `R_b(τ)·k`). The gap along `w` is
        // `d·w − h_a(R_aᵀw) − h_b(−R_bᵀw)` with `d` the origins' offset, and
        // the own side's support is exact in `f64`. (No relative pose: that
        // took 36 enclosure products on every node.)
        let along = |w: &Vector3<E>| E::dot([d.x, d.y, d.z], [w.x, w.y, w.z]);
        let in_a = |m: &Vector3<f64>| {
            let norm = norm_up(m);
            let w = a.pose.rotate(m);
            let db = -b.pose.inverse_rotate(&w);
            along(&w) - self.a.support_f64(m) - self.b.support(&db, norm) - up(self.skin * norm)
        };
        let in_b = |k: &Vector3<f64>| {
            let norm = norm_up(k);
            let w = b.pose.rotate(k);
            let da = a.pose.inverse_rotate(&w);
            along(&w) - self.a.support(&da, norm) - self.b.support_f64(&(-k)) - up(self.skin * norm)
        };
        let k = ib.rotation.inverse() * n;
        // A side that does not turn holds its frame's direction fixed in
        // the world: its axis is axis 0 again (against a floor or a wall,
        // axis 2 of every node), so it takes axis 0's enclosure.
        let world = (axes & 1 != 0).then_some(out[0]);
        if axes & 0b10 != 0 && !single {
            out[1] = match world.filter(|_| !a.motion.turns()) {
                Some(same) => same,
                None => in_a(&m),
            };
        }
        if axes & 0b100 != 0 && !single {
            out[2] = match world.filter(|_| !b.motion.turns()) {
                Some(same) => same,
                None => in_b(&k),
            };
        }
        // The face normals, fixed in their triangle's frame and turned to
        // point from `a` towards `b` at the node's middle.
        let mut slot = Self::AXES;
        if let Some(f) = self.face_a {
            if axes >> slot & 1 != 0 {
                out[slot] = in_a(&if f.dot(&m) >= 0.0 { f } else { -f });
            }
            slot += 1;
        }
        if let Some(f) = self.face_b
            && axes >> slot & 1 != 0
        {
            out[slot] = in_b(&if f.dot(&k) >= 0.0 { f } else { -f });
        }
    }
}

/// `simplex`, found at the relative pose `old12`, carried to `pos12`: its
/// vertices are differences of points of the two shapes, kept in `a`'s
/// frame, so `b`'s points move with `b`'s pose.
fn carried(simplex: &Simplex64, old12: &Pose64, pos12: &Pose64) -> Simplex64 {
    let mut simplex = simplex.clone();
    let shift = *pos12 * old12.inverse();
    simplex.modify_pnts(&|p| *p = Cso64::new(p.orig1, shift * p.orig2));
    simplex
}

/// The closest points of two cores with a closed form (points, segments,
/// boxes; a cylinder and a box, see [`cylinder_box`]) as a unit direction
/// from `a` towards `b`, in `a`'s frame (`rel`: `b`'s pose in `a`'s
/// frame), in plain `f64` with no GJK: the direction a capsule pair asks
/// for on every node. Any direction gives a sound axis; this one is
/// parry's closest-points normal up to rounding. `None` for other cores,
/// and when the cores (nearly) meet: parry's penetration normal is the
/// better hint then.
fn core_direction(a: &Core, b: &Core, rel: &Isometry3<f64>) -> Option<Vector3<f64>> {
    let segment = |c: &Core| match c {
        Core::Point => Some([Vector3::zeros(); 2]),
        Core::Segment(s) => Some(*s),
        _ => None,
    };
    let from_a_to_b = match (segment(a), segment(b), a, b) {
        (Some(sa), Some(sb), _, _) => {
            let sb = sb
                .map(|p| rel * nalgebra::Point3::from(p))
                .map(|p| p.coords);
            let (p, q) = segment_segment(&sa, &sb);
            q - p
        }
        (Some(sa), None, _, Core::Cuboid(half)) => {
            // In the box's frame, then back.
            let inv = rel.inverse();
            let sa = sa.map(|p| (inv * nalgebra::Point3::from(p)).coords);
            let (p, q) = segment_box(&sa, half);
            rel.rotation * (q - p)
        }
        (None, Some(sb), Core::Cuboid(half), _) => {
            let sb = sb.map(|p| (rel * nalgebra::Point3::from(p)).coords);
            let (p, q) = segment_box(&sb, half);
            p - q
        }
        (None, None, Core::Cylinder { half_height, .. }, Core::Cuboid(half)) => {
            // In the box's frame, then back.
            rel.rotation * cylinder_box(*half_height, &rel.inverse(), half)?
        }
        (None, None, Core::Cuboid(half), Core::Cylinder { half_height, .. }) => {
            -cylinder_box(*half_height, rel, half)?
        }
        _ => return None,
    };
    from_a_to_b.try_normalize(1.0e-9)
}

/// The closest-points direction of a box of half-extents `half` and a
/// convex shape `other` at `pose` (its frame in the box's), in the box's
/// frame from the box towards `other`, where a face of the box holds the
/// closest points: of the three faces turned towards `other`, the one
/// along whose normal they are farthest apart, when the point of `other`
/// deepest along that normal lies over the face. That point and its foot
/// on the face are then apart by exactly the gap along the normal, which
/// no two points of the shapes undercut, so the normal is the closest
/// points' direction. `None` where an edge or a corner of the box is
/// nearest, or no face normal separates them.
fn face_box(half: &Vector3<f64>, other: &Convex, pose: &Isometry3<f64>) -> Option<Vector3<f64>> {
    let c = pose.translation.vector;
    let mut best: Option<(f64, usize, Vector3<f64>)> = None;
    for i in 0..3 {
        let mut n = Vector3::zeros();
        n[i] = 1.0f64.copysign(c[i]);
        let gap =
            n.dot(&c) - other.support_f64(&-pose.rotation.inverse_transform_vector(&n)) - half[i];
        if gap > 0.0 && best.is_none_or(|(g, _, _)| gap > g) {
            best = Some((gap, i, n));
        }
    }
    let (_, i, n) = best?;
    let deepest = pose
        * nalgebra::Point3::from(other.support_point(&-pose.rotation.inverse_transform_vector(&n)));
    let over = (0..3).all(|j| j == i || deepest[j].abs() <= half[j]);
    over.then_some(n)
}

/// The closest-points direction of a cylinder of `half_height` at `pose`
/// (its frame in the box's) and the box of half-extents `half`, in the
/// box's frame from the cylinder towards the box, where it has a closed
/// form: when the box's point nearest the cylinder's axis lies beside the
/// axis, not past an end. The cylinder is a capsule's middle part there,
/// so its closest points (or, overlapping, the axis's approach to the box)
/// are the capsule's: from the axis's closest point to the box's. `None`
/// otherwise: past an end they are on a cap or its rim, found by GJK (a
/// closed-form guess there, from the cap's point nearest the box's, could
/// be far off against a large box and left near misses unproved).
fn cylinder_box(
    half_height: f64,
    pose: &Isometry3<f64>,
    half: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let axis = [
        Vector3::new(0.0, -half_height, 0.0),
        Vector3::new(0.0, half_height, 0.0),
    ]
    .map(|p| (pose * nalgebra::Point3::from(p)).coords);
    let (p, q) = segment_box(&axis, half);
    beside_axis(&axis, &p).then_some(q - p)
}

/// Whether the point `p` of the segment `axis` lies strictly between its
/// ends (by more than 1e-9 of its length): where a cylinder's axis point
/// nearest a box lies so, the cylinder's closest points to it are its
/// capsule's (see [`cylinder_box`]).
pub(crate) fn beside_axis(axis: &[Vector3<f64>; 2], p: &Vector3<f64>) -> bool {
    let along = axis[1] - axis[0];
    let s = (p - axis[0]).dot(&along) / along.norm_squared();
    s > 1.0e-9 && s < 1.0 - 1.0e-9
}

/// Whether [`core_direction`] has a closed form for these cores (it may
/// still decline a pair whose cores meet, or a cylinder seen past an end).
fn has_closed_form(a: &Core, b: &Core) -> bool {
    let segment = |c: &Core| matches!(c, Core::Point | Core::Segment(_));
    let cuboid = |c: &Core| matches!(c, Core::Cuboid(_));
    let cylinder = |c: &Core| matches!(c, Core::Cylinder { .. });
    segment(a) && (segment(b) || cuboid(b))
        || cuboid(a) && (segment(b) || cylinder(b))
        || cylinder(a) && cuboid(b)
}

/// The closest points of segments `a` and `b` (on `a`, on `b`): the
/// parameters of the unclamped closest pair, clamped to the segments in
/// turn (exact for segments; points are segments of length 0).
pub(crate) fn segment_segment(
    a: &[Vector3<f64>; 2],
    b: &[Vector3<f64>; 2],
) -> (Vector3<f64>, Vector3<f64>) {
    let (u, v, w) = (a[1] - a[0], b[1] - b[0], a[0] - b[0]);
    let (uu, vv, uv, uw, vw) = (u.dot(&u), v.dot(&v), u.dot(&v), u.dot(&w), v.dot(&w));
    let tiny = 1.0e-300;
    let (s, t) = if uu <= tiny && vv <= tiny {
        (0.0, 0.0)
    } else if uu <= tiny {
        (0.0, (vw / vv).clamp(0.0, 1.0))
    } else if vv <= tiny {
        ((-uw / uu).clamp(0.0, 1.0), 0.0)
    } else {
        let det = uu * vv - uv * uv;
        let s = if det > tiny {
            ((uv * vw - vv * uw) / det).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let t = (uv * s + vw) / vv;
        if t < 0.0 {
            ((-uw / uu).clamp(0.0, 1.0), 0.0)
        } else if t > 1.0 {
            (((uv - uw) / uu).clamp(0.0, 1.0), 1.0)
        } else {
            (s, t)
        }
    };
    (a[0] + u * s, b[0] + v * t)
}

/// The closest points of segment `s` and the box of half-extents `half`
/// (centred at the origin, in its frame): (on the segment, in the box).
///
/// The squared distance from `s(t) = s0 + t·d` to the box is
/// `Σ_i max(|s_i(t)| − h_i, 0)²`, convex in `t` and a quadratic between the
/// (at most six) parameters where a coordinate crosses a face plane; its
/// minimum lies in the piece where its slope turns from negative.
/// (Alternating projections, which this replaces, zig-zag slowly for a
/// segment nearly parallel to a face: 4 steps left directions that cost
/// some capsule queries 0.03 of the step of accuracy.)
pub(crate) fn segment_box(
    s: &[Vector3<f64>; 2],
    half: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let (s0, d) = (s[0], s[1] - s[0]);
    // The slope of half the squared distance at `t`: continuous, and
    // rising with `t` (the distance is convex).
    let slope = |t: f64| {
        (0..3)
            .map(|i| {
                let x = s0[i] + t * d[i];
                d[i] * (x - x.clamp(-half[i], half[i]))
            })
            .sum::<f64>()
    };
    let best_t = if slope(0.0) >= 0.0 {
        0.0
    } else if slope(1.0) <= 0.0 {
        1.0
    } else {
        // The minimiser lies between the last face crossing where the
        // slope is negative and the first where it is not (no sorting:
        // the slope rises with `t`), a single piece, where the distance is
        // one quadratic: Σ over the faces the piece lies beyond (at its
        // middle) of (s0_i + t·d_i ∓ h_i)², whose slope is `qa·t + qb`.
        let (mut a, mut b) = (0.0f64, 1.0f64);
        for i in 0..3 {
            if d[i] != 0.0 {
                for face in [-half[i], half[i]] {
                    let t = (face - s0[i]) / d[i];
                    if t > a && t < b {
                        if slope(t) < 0.0 {
                            a = t;
                        } else {
                            b = t;
                        }
                    }
                }
            }
        }
        let mid = 0.5 * (a + b);
        let (mut qa, mut qb) = (0.0, 0.0);
        for i in 0..3 {
            let x = s0[i] + mid * d[i];
            let face = if x > half[i] {
                half[i]
            } else if x < -half[i] {
                -half[i]
            } else {
                continue;
            };
            qa += d[i] * d[i];
            qb += d[i] * (s0[i] - face);
        }
        if qa > 0.0 { (-qb / qa).clamp(a, b) } else { a }
    };
    let p = s0 + d * best_t;
    let q = Vector3::from_fn(|i, _| p[i].clamp(-half[i], half[i]));
    (p, q)
}

/// The unit normal of a triangle core (none for a degenerate one, or any
/// other core).
fn face_normal(c: &Convex) -> Option<Vector3<f64>> {
    match &c.core {
        super::support::Core::Triangle([p, q, r]) => {
            (q - p).cross(&(r - p)).try_normalize(1.0e-300)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosure::Affine;
    use crate::motion::Motion;
    use nalgebra::Translation3;
    use rapier3d::parry::shape::{Cuboid, Cylinder};

    /// A cylinder over a box, `gap` metres above it (negative: sunk in),
    /// both still; the axes at one time, with `last` as the last node's
    /// direction (in the cylinder's frame).
    fn axes_at_a_time(gap: f64, last: Vector3<f64>) -> [Affine; 3] {
        let (cylinder, cuboid) = (Cylinder::new(0.5, 0.3), Cuboid::new(Vector::splat(1.0)));
        let convex = |s: &dyn Shape| Convex::from_shape(s).unwrap().unwrap();
        let pair = SupportMap::new(
            convex(&cylinder),
            Arc::new(cylinder),
            convex(&cuboid),
            Arc::new(cuboid),
            0.0,
        );
        pair.last.set(Some(last));
        let still = |y: f64| Motion::fixed(Translation3::new(0.1, y, 0.2).into()).unwrap();
        let (ma, mb) = (still(1.5 + gap), still(0.0));
        let span = TimeSpan::new(0.5, 0.5);
        let (pa, pb) = (ma.pose(span), mb.pose(span));
        let (a, b) = (
            Side {
                pose: &pa,
                motion: &ma,
                kept: None,
            },
            Side {
                pose: &pb,
                motion: &mb,
                kept: None,
            },
        );
        let mut out = [Affine::constant(0.0); 3];
        pair.eval(span, &a, &b, 0b111, &mut out);
        out
    }

    /// At a single time overlapping shapes show as touching along the last
    /// direction, however poor, and shapes apart show as apart: that time
    /// needs no penetration normal.
    #[test]
    fn a_single_time_is_judged_without_the_penetration_normal() {
        let poor = Vector3::new(1.0, 0.2, -0.3).normalize();
        for out in [axes_at_a_time(-0.01, poor), axes_at_a_time(-1.0e-5, poor)] {
            assert!(out.iter().all(|x| x.range().hi <= 0.0), "{out:?}");
        }
        let apart = axes_at_a_time(0.01, poor);
        assert!(apart.iter().any(|x| x.range().lo > 0.009), "{apart:?}");
    }

    /// At a single time a cone and a box are judged from GJK in `f64`
    /// alone, or a point in both: on 4,000 random poses (half of them
    /// with a last direction, half without), a pair it proves apart is apart by at
    /// least that bound (parry3d-f64's distance), one it sees touching is
    /// within 1e-7 of the sizes of touching, and every pair farther apart
    /// than 1e-6 m, or overlapping, is told one or the other.
    #[test]
    fn a_cone_at_a_single_time_is_judged_by_gjk_in_f64() {
        use parry3d_f64::shape::{Cone as Cone64, Cuboid as Cuboid64};
        use rapier3d::parry::shape::Cone;
        let (cone, cuboid) = (Cone::new(0.4, 0.3), Cuboid::new(Vector::new(0.6, 0.3, 0.9)));
        // The same shapes in `f64`, of the `f32` ones' very sizes (0.6 in
        // `f32` is 2e-8 more than in `f64`).
        let wide = f64::from;
        let (cone64, cuboid64) = (
            Cone64::new(wide(0.4f32), wide(0.3f32)),
            Cuboid64::new(parry3d_f64::math::Vector::new(
                wide(0.6f32),
                wide(0.3f32),
                wide(0.9f32),
            )),
        );
        let convex = |s: &dyn Shape| Convex::from_shape(s).unwrap().unwrap();
        let mut next = numbers(5);
        let (mut apart, mut touching) = (0, 0);
        let new_pair = |skin: f64| {
            SupportMap::new(
                convex(&cone),
                Arc::new(cone),
                convex(&cuboid),
                Arc::new(cuboid),
                skin,
            )
        };
        // Pairs kept from case to case, whose last direction (the last
        // case's) the point test reads.
        let kept = [new_pair(0.0), new_pair(0.01)];
        for case in 0..4000 {
            let skin = if case % 4 < 2 { 0.0 } else { 0.01 };
            let fresh;
            let pair = if case % 2 == 0 {
                fresh = new_pair(skin);
                &fresh
            } else {
                &kept[case % 4 / 2]
            };
            let pose = |scale: f64, next: &mut dyn FnMut() -> f64| {
                Isometry3::new(
                    Vector3::new(next(), next(), next()) * scale,
                    Vector3::new(next(), next(), next()) * 3.0,
                )
            };
            let (pa, pb) = (pose(1.2, &mut next), pose(0.2, &mut next));
            let (ma, mb) = (Motion::fixed(pa).unwrap(), Motion::fixed(pb).unwrap());
            let mut out = [Affine::constant(0.0); 3];
            assert!(pair.eval_at_a_time(0.5, &ma, &mb, 0b111, &mut out));
            let distance = parry3d_f64::query::distance(
                &pose64_from_iso(&pa),
                &cone64,
                &pose64_from_iso(&pb),
                &cuboid64,
            )
            .unwrap()
            .distance;
            let gap = distance - skin;
            let lo = out[0].range().lo;
            let all_hi = out.iter().map(|x| x.range().hi).fold(f64::MIN, f64::max);
            assert!(
                lo <= gap + 1.0e-9,
                "case {case}: proved {lo} apart, parry {gap}"
            );
            if lo > 0.0 {
                apart += 1;
            }
            if all_hi <= 0.0 {
                touching += 1;
                assert!(gap <= 1.0e-6, "case {case}: touching, parry {gap} apart");
            }
            if gap > 1.0e-6 || distance == 0.0 {
                assert!(lo > 0.0 || all_hi <= 0.0, "case {case}: undecided at {gap}");
            }
        }
        assert!(
            apart > 400 && touching > 400,
            "apart {apart}, touching {touching}"
        );
    }

    /// A cylinder or a capsule and a box at a single time: a point found
    /// in both shapes lies in both (parry3d-f64's distance is 0); where
    /// one is, or GJK in `f64` judges the pair (the cylinder), every axis
    /// bounds the gap from below and a touch is told only within 1e-6 m
    /// of one; the capsule is judged only by a point in both. With the
    /// penetration normal as the last direction, most overlapping poses
    /// of 3,000 find such a point.
    #[test]
    fn a_point_in_both_shapes_tells_a_touch_at_a_single_time() {
        use parry3d_f64::shape::{
            Capsule as Capsule64, Cuboid as Cuboid64, Cylinder as Cylinder64,
        };
        use rapier3d::parry::shape::Capsule;
        let wide = f64::from;
        let cuboid = Cuboid::new(Vector::new(0.6, 0.3, 0.9));
        let cuboid64 = Cuboid64::new(parry3d_f64::math::Vector::new(
            wide(0.6f32),
            wide(0.3f32),
            wide(0.9f32),
        ));
        let convex = |s: &dyn Shape| Convex::from_shape(s).unwrap().unwrap();
        let shapes: [(Arc<dyn Shape>, Box<dyn parry3d_f64::shape::Shape>); 2] = [
            (
                Arc::new(Cylinder::new(0.4, 0.3)),
                Box::new(Cylinder64::new(wide(0.4f32), wide(0.3f32))),
            ),
            (
                Arc::new(Capsule::new_y(0.4, 0.2)),
                Box::new(Capsule64::new_y(wide(0.4f32), wide(0.2f32))),
            ),
        ];
        let mut next = numbers(9);
        for (shape, shape64) in &shapes {
            let (mut overlapping, mut witnessed) = (0, 0);
            for case in 0..3000 {
                let pair = SupportMap::new(
                    convex(shape.as_ref()),
                    shape.clone(),
                    convex(&cuboid),
                    Arc::new(cuboid),
                    if case % 2 == 0 { 0.0 } else { 0.01 },
                );
                let pose = |scale: f64, next: &mut dyn FnMut() -> f64| {
                    Isometry3::new(
                        Vector3::new(next(), next(), next()) * scale,
                        Vector3::new(next(), next(), next()) * 3.0,
                    )
                };
                let (pa, pb) = (pose(1.0, &mut next), pose(0.2, &mut next));
                let (pa64, pb64) = (pose64_from_iso(&pa), pose64_from_iso(&pb));
                let contact =
                    parry3d_f64::query::contact(&pa64, shape64.as_ref(), &pb64, &cuboid64, 10.0)
                        .unwrap()
                        .unwrap();
                let n = contact.normal1;
                pair.last
                    .set(Some(pa.rotation.inverse() * Vector3::new(n.x, n.y, n.z)));
                let (ma, mb) = (Motion::fixed(pa).unwrap(), Motion::fixed(pb).unwrap());
                let mut out = [Affine::constant(0.0); 3];
                // At the poses the pair reads (`pose_at` rounds).
                let rel = ma.pose_at(0.5).inv_mul(&mb.pose_at(0.5));
                let point_in_both = pair.overlap_witnessed(&rel);
                let judged = pair.eval_at_a_time(0.5, &ma, &mb, 0b111, &mut out);
                let gap = contact.dist.max(0.0) - pair.skin;
                if contact.dist < 0.0 {
                    overlapping += 1;
                }
                if point_in_both {
                    witnessed += 1;
                    assert!(
                        contact.dist <= 1.0e-9,
                        "case {case}: a point in both, {gap} apart"
                    );
                    assert!(judged, "case {case}");
                }
                if shape.as_capsule().is_some() {
                    assert_eq!(judged, point_in_both, "case {case}");
                }
                if judged {
                    let lo = out[0].range().lo;
                    let all_hi = out.iter().map(|x| x.range().hi).fold(f64::MIN, f64::max);
                    assert!(
                        lo <= gap + 1.0e-9,
                        "case {case}: proved {lo} apart, parry {gap}"
                    );
                    if all_hi <= 0.0 {
                        assert!(gap <= 1.0e-6, "case {case}: touching, parry {gap} apart");
                    }
                    if point_in_both {
                        assert!(all_hi <= 0.0, "case {case}: {out:?}");
                    }
                }
            }
            assert!(
                overlapping > 300 && witnessed * 2 > overlapping,
                "{witnessed} of {overlapping} overlapping poses found a point in both"
            );
        }
    }

    /// Seeded numbers uniform in [-1, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut seed = seed;
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Where `core_direction` answers for a cylinder and a box (the box's
    /// point nearest the cylinder's axis lies beside it), its direction is
    /// the closest-points normal: parry3d-f64's contact normal agrees to
    /// 1e-6 on 3,000 random poses of a cylinder apart from a box, either
    /// order (688 of the 2,694 apart answered). (A cylinder past its end
    /// is left to GJK: answering there with the capsule's direction fails
    /// this at once.)
    #[test]
    fn a_cylinder_beside_a_box_takes_its_closest_points_normal() {
        use parry3d_f64::shape::{Cuboid as Cuboid64, Cylinder as Cylinder64, Shape as Shape64};
        let mut next = numbers(11);
        let (h, r, half) = (0.5, 0.2, Vector3::new(0.6, 0.3, 0.9));
        let cylinder = Core::Cylinder {
            half_height: h,
            radius: r,
        };
        let cuboid = Core::Cuboid(half);
        let shape_cylinder = Cylinder64::new(h, r);
        let shape_cuboid = Cuboid64::new(parry3d_f64::math::Vector::new(half.x, half.y, half.z));
        let (mut answered, mut apart) = (0, 0);
        for case in 0..3000 {
            let rel = Isometry3::new(
                Vector3::new(next(), next(), next()) * 2.0,
                Vector3::new(next(), next(), next()) * 3.0,
            );
            let cylinder_first = case % 2 == 0;
            let (a, b, sa, sb): (_, _, &dyn Shape64, &dyn Shape64) = if cylinder_first {
                (&cylinder, &cuboid, &shape_cylinder, &shape_cuboid)
            } else {
                (&cuboid, &cylinder, &shape_cuboid, &shape_cylinder)
            };
            let identity = parry3d_f64::math::Pose::IDENTITY;
            let contact =
                parry3d_f64::query::contact(&identity, sa, &pose64_from_iso(&rel), sb, 10.0);
            let Ok(Some(contact)) = contact else {
                continue;
            };
            if contact.dist < 1.0e-3 {
                continue;
            }
            apart += 1;
            let Some(n) = core_direction(a, b, &rel) else {
                continue;
            };
            answered += 1;
            let normal = Vector3::new(contact.normal1.x, contact.normal1.y, contact.normal1.z);
            assert!(
                n.dot(&normal) > 1.0 - 1.0e-6,
                "case {case}: {n:?} against parry's {normal:?} at distance {}",
                contact.dist
            );
        }
        assert!(
            answered * 5 >= apart,
            "only {answered} of {apart} pairs apart answered"
        );
    }

    /// Against dense sampling of the segment, on segments nearly parallel
    /// to a face (where alternating projections stalled), crossing
    /// corners, and degenerate (a point).
    #[test]
    fn segment_box_finds_the_closest_points() {
        let half = Vector3::new(0.5, 0.2, 1.0);
        let dist =
            |p: &Vector3<f64>| Vector3::from_fn(|i, _| (p[i].abs() - half[i]).max(0.0)).norm();
        let mut uniform = numbers(7);
        let mut next = || 2.0 * uniform();
        let mut segments = vec![
            [Vector3::new(-3.0, 0.3, 0.0), Vector3::new(3.0, 0.3001, 0.0)],
            [Vector3::new(0.6, 0.25, -2.0), Vector3::new(0.61, 0.26, 2.0)],
            [Vector3::new(1.0, 1.0, 1.5), Vector3::new(1.0, 1.0, 1.5)],
        ];
        for _ in 0..300 {
            segments.push([
                Vector3::new(next(), next(), next()),
                Vector3::new(next(), next(), next()),
            ]);
        }
        for s in &segments {
            let (p, q) = segment_box(s, &half);
            let sampled = (0..=20_000)
                .map(|k| dist(&(s[0] + (s[1] - s[0]) * (k as f64 / 20_000.0))))
                .fold(f64::INFINITY, f64::min);
            let found = (p - q).norm();
            assert!(
                found <= sampled + 1e-9,
                "{s:?}: {found} vs sampled {sampled}"
            );
            assert!(
                (dist(&p) - found).abs() < 1e-12,
                "q is p's closest box point"
            );
        }
    }
}
