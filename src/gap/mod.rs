//! Distance functions ("gaps"), one family of shape pairs per file.
//!
//! A pair's gap is a list of *axis* functions of time. Each is written once,
//! generically over the [`Enclosure`] arithmetic, from the two shapes'
//! enclosed poses on a node, and is built so that **an axis `> 0` proves
//! the shapes farther apart than the skin** at every time of the node. The
//! pair may touch only where every axis is `≤ 0` (separating axes compose as
//! AND, docs/design.md §3). Skins are baked into the axes at construction, in
//! each axis's own units.
//!
//! | pair | family | file |
//! |---|---|---|
//! | ball–ball | squared centre distance | `ball_ball.rs` |
//! | ball–cuboid, ball–round cuboid | exact clamped distance in the box frame + 3 face slabs | `ball_cuboid.rs` |
//! | cuboid–cuboid, zero skin | the 15 separating axes | `cuboid_cuboid.rs` |
//! | cuboid–triangle, zero skin | the 13 separating axes | `cuboid_triangle.rs` |
//! | ball–triangle | vertex–face axes, radius as skin | `ball_triangle.rs` |
//! | ball–segment | end planes + adaptive direction | `ball_segment.rs` |
//! | triangle–triangle | face normals, edge crosses, adaptive | `triangle_triangle.rs` |
//! | half-space–any convex shape | plane distance minus the support reach (exact) | `halfspace.rs` |
//! | every other pair (cuboid–cuboid with a skin or a border included) of ball, cuboid, capsule, segment, triangle, convex polyhedron, cylinder, cone and their round variants | adaptive separating axes: the closest-points direction at the node's middle (closed form for points, segments and boxes, and a cylinder against a box beside its axis; parry's contact otherwise), fixed in the world, in `a`'s and in `b`'s frame | `support_map.rs` |
//! | vertex–face, edge–edge (linear vertices) | primitive axes | `primitives.rs` |
//! | shape/mesh–composite (TriMesh, HeightField, Polyline, Compound) | bounding gap, expanded through the BVH | `composite.rs` |
//!
//! The shapes' support functions over enclosures (the reach of each kind
//! along a turning direction) are in `support.rs`. Half-space against
//! half-space is not supported (they always meet unless exactly opposite).

mod ball_ball;
mod ball_cuboid;
mod ball_segment;
mod ball_triangle;
pub(crate) mod composite;
mod cuboid_cuboid;
mod cuboid_triangle;
mod generators;
mod halfspace;
pub(crate) mod primitives;
mod support;
mod support_map;
mod triangle_triangle;

pub(crate) use ball_ball::BallBall;
pub(crate) use ball_cuboid::BallCuboid;
pub(crate) use ball_segment::BallSegment;
pub(crate) use ball_triangle::BallTriangle;
pub(crate) use cuboid_cuboid::CuboidCuboid;
pub(crate) use cuboid_triangle::CuboidTriangle;
pub(crate) use generators::{RoundBox, round_box};
pub(crate) use halfspace::HalfSpaceConvex;
use support::ORTHO_SLACK;
pub(crate) use support::{Convex, Core};
pub(crate) use support_map::{SupportMap, beside_axis, segment_box, segment_segment};
pub(crate) use triangle_triangle::TriangleTriangle;

use crate::convert::vec_from_glam;
use crate::enclosure::rounding::{down, up};
use crate::enclosure::{Enclosure, TimeSpan};
use crate::error::{CcdError, check_finite};
use crate::motion::{Motion, Pose, SpeedAlong, Trajectory};
use nalgebra::{Isometry3, Vector3};
use rapier3d::parry::math::Vector;
use rapier3d::parry::shape::{Ball, Segment, Shape, Triangle, TypedShape};
use std::cell::Cell;
use std::sync::Arc;

/// A frame's exact pose at one time, kept where the search keeps its
/// frames: the pairs of a node read their frames at the node's middle, and
/// a hull against each triangle of a mesh asks for the same two poses
/// (a turning pose costs a sine and a cosine).
pub(crate) type KeptPose = Cell<Option<(f64, Isometry3<f64>)>>;

/// One shape of a pair as an axis function sees it on a node.
pub(crate) struct Side<'p, E: Enclosure> {
    /// The shape frame's pose over the node. Its `rotation` is meaningful
    /// only when the family says it reads it ([`PairGap::reads_rotation`]);
    /// otherwise it may hold the start rotation alone (saves a matrix
    /// product per node for balls).
    pub pose: &'p Pose<E>,
    /// The frame's whole motion (for adaptive choices at the node's middle).
    pub motion: &'p Motion,
    /// Where the search keeps the frame's last exact pose, if it does.
    pub kept: Option<&'p KeptPose>,
}

impl<E: Enclosure> Side<'_, E> {
    /// The frame's exact pose at `t`: the kept one when it is for `t`.
    pub fn pose_at(&self, t: f64) -> Isometry3<f64> {
        match self.kept {
            Some(kept) => kept_pose_at(self.motion, kept, t),
            None => self.motion.pose_at(t),
        }
    }
}

/// `motion`'s exact pose at `t`: the one `kept` holds when it is for `t`,
/// else computed and kept.
pub(crate) fn kept_pose_at(motion: &Motion, kept: &KeptPose, t: f64) -> Isometry3<f64> {
    if let Some((at, pose)) = kept.get()
        && at == t
    {
        return pose;
    }
    let pose = motion.pose_at(t);
    kept.set(Some((t, pose)));
    pose
}

/// The sizes of two shapes `extents` across (their extents summed) at the
/// exact poses `ia`, `ib`, and the pad that covers a gap computed there in
/// plain `f64`: the poses, the relative pose and the supports are each
/// rounded a few times in terms no larger than those sizes, and 1e-12 of
/// them covers that many times over (as `ORTHO_SLACK` pads the skin).
pub(crate) fn rounding_slack(ia: &Isometry3<f64>, ib: &Isometry3<f64>, extents: f64) -> (f64, f64) {
    let sizes = up(ia.translation.vector.norm() + ib.translation.vector.norm() + extents);
    (sizes, up(ORTHO_SLACK * sizes))
}

/// A side's motion and its exact pose kept for the node (see
/// [`kept_pose_at`]): what a middle test reads of it.
pub(crate) type Exact<'a> = (&'a Motion, &'a KeptPose);

/// Two sides at the exact poses of a node's middle, for the middle tests
/// of a fast spin's pieces (`apart_from_middle`): a gap found there along a
/// direction fixed in the world bounds the gap over the whole node, less
/// how fast it can close along that direction ([`SpeedAlong`]) times the
/// half-width, with no pose enclosed.
pub(crate) struct Middle {
    pub ia: Isometry3<f64>,
    pub ib: Isometry3<f64>,
    /// `b`'s pose in `a`'s frame.
    pub rel: Isometry3<f64>,
    half_width: f64,
    /// See [`rounding_slack`].
    slack: f64,
    speeds: SpeedAlong,
}

impl Middle {
    /// `extents`: how far each shape reaches from its frame's origin,
    /// metres.
    #[inline]
    pub fn new(
        span: TimeSpan,
        (ma, kept_a): Exact,
        (mb, kept_b): Exact,
        (extent_a, extent_b): (f64, f64),
    ) -> Middle {
        let (mid, half_width) = span.center_radius();
        let (ia, ib) = (kept_pose_at(ma, kept_a, mid), kept_pose_at(mb, kept_b, mid));
        let (_, slack) = rounding_slack(&ia, &ib, extent_a + extent_b);
        Middle {
            rel: ia.inv_mul(&ib),
            ia,
            ib,
            half_width,
            slack,
            speeds: ma.relative_speed_along(extent_a, mb, extent_b),
        }
    }

    /// A positive lower bound over the node of the gap beyond `skin`, from
    /// `gap`, the shapes' gap at the middle along the world unit direction
    /// `n` (either way: the speed bound reads both); `None` where it is not
    /// positive.
    #[inline]
    pub fn apart(&self, gap: f64, skin: f64, n: &Vector3<f64>) -> Option<f64> {
        let lo = down(down(gap - self.slack - skin) - up(self.speeds.at(n) * self.half_width));
        (lo > 0.0).then_some(lo)
    }
}

/// Each side of a pair seen from the other over a node, where the search
/// keeps them: where many pairs share the same two frames (a box against
/// each triangle of a mesh), once per node instead of once per pair, those
/// the family reads ([`PairGap::reads_relative`]). Any other is computed
/// from the sides when read.
#[derive(Clone, Copy)]
pub(crate) struct Relative<'p, E: Enclosure> {
    pub b_in_a: Option<&'p Pose<E>>,
    pub a_in_b: Option<&'p Pose<E>>,
}

impl<E: Enclosure> Relative<'_, E> {
    /// `b`'s pose in `a`'s frame.
    pub fn b_in_a(&self, a: &Side<E>, b: &Side<E>) -> Pose<E> {
        match self.b_in_a {
            Some(kept) => *kept,
            None => a.pose.relative(b.pose),
        }
    }

    /// `a`'s pose in `b`'s frame.
    pub fn a_in_b(&self, a: &Side<E>, b: &Side<E>) -> Pose<E> {
        match self.a_in_b {
            Some(kept) => *kept,
            None => b.pose.relative(a.pose),
        }
    }
}

/// The gap of one shape pair: its family and the family's parameters.
#[derive(Clone, Debug)]
pub(crate) enum PairGap {
    BallBall(BallBall),
    BallTriangle(BallTriangle),
    BallSegment(BallSegment),
    TriangleTriangle(TriangleTriangle),
    BallCuboid(BallCuboid),
    CuboidCuboid(CuboidCuboid),
    CuboidTriangle(CuboidTriangle),
    HalfSpace(HalfSpaceConvex),
    SupportMap(SupportMap),
}

impl PairGap {
    /// How many axis functions the pair has.
    pub fn axis_count(&self) -> usize {
        match self {
            PairGap::BallBall(_) => BallBall::AXES,
            PairGap::BallTriangle(_) => BallTriangle::AXES,
            PairGap::BallSegment(_) => BallSegment::AXES,
            PairGap::TriangleTriangle(_) => TriangleTriangle::AXES,
            PairGap::BallCuboid(_) => BallCuboid::AXES,
            PairGap::CuboidCuboid(_) => CuboidCuboid::AXES,
            PairGap::CuboidTriangle(_) => CuboidTriangle::AXES,
            PairGap::HalfSpace(_) => HalfSpaceConvex::AXES,
            PairGap::SupportMap(g) => g.axis_count(),
        }
    }

    /// Whether every axis `≤ 0` at a time means the shapes touch then
    /// (see `solve::GapSet::is_exact`): true for the families
    /// whose axis sets are complete; false where an adaptive axis stands in.
    pub fn is_exact(&self) -> bool {
        matches!(
            self,
            PairGap::BallBall(_)
                | PairGap::BallCuboid(_)
                | PairGap::CuboidCuboid(_)
                | PairGap::CuboidTriangle(_)
                | PairGap::HalfSpace(_)
        )
    }

    /// Whether the family reads `b`'s pose in `a`'s frame and `a`'s in
    /// `b`'s ([`Relative`]).
    pub fn reads_relative(&self) -> [bool; 2] {
        match self {
            PairGap::CuboidCuboid(_) | PairGap::CuboidTriangle(_) => [true, false],
            PairGap::TriangleTriangle(_) => [true, true],
            _ => [false, false],
        }
    }

    /// Whether the family reads each side's rotation, `[a, b]`.
    pub fn reads_rotation(&self) -> [bool; 2] {
        match self {
            PairGap::BallBall(_) => [false, false],
            // A ball is its frame's origin grown: only the other side turns
            // it into view.
            PairGap::BallCuboid(_) | PairGap::BallTriangle(_) | PairGap::BallSegment(_) => {
                [false, true]
            }
            _ => [true, true],
        }
    }

    /// [`PairGap::reads_rotation`] in the caller's order: `swapped` when
    /// the family's `a` side is the caller's second shape.
    pub fn reads_rotation_as(&self, swapped: bool) -> [bool; 2] {
        let [a, b] = self.reads_rotation();
        if swapped { [b, a] } else { [a, b] }
    }

    /// The axes at the single time `t` without enclosing the poses, where
    /// the family can (see `SupportMap::eval_at_a_time`); `false` when it
    /// cannot, with `out` untouched.
    pub fn eval_at_a_time<E: Enclosure>(
        &self,
        t: f64,
        a: &crate::motion::Motion,
        b: &crate::motion::Motion,
        axes: u64,
        out: &mut [E],
    ) -> bool {
        match self {
            PairGap::SupportMap(g) => g.eval_at_a_time(t, a, b, axes, out),
            _ => false,
        }
    }

    /// A positive lower bound of the gap over `span` from the exact poses
    /// at its middle, where the family has one that proves the pair apart
    /// (see `SupportMap::apart_from_middle`).
    pub fn apart_from_middle(&self, span: TimeSpan, a: Exact, b: Exact) -> Option<f64> {
        match self {
            PairGap::SupportMap(g) => g.apart_from_middle(span, a, b),
            PairGap::CuboidCuboid(g) => g.apart_from_middle(span, a, b),
            PairGap::CuboidTriangle(g) => g.apart_from_middle(span, a, b),
            _ => None,
        }
    }

    /// Enclose the axes set in `axes` over `span` into `out`. A family may
    /// stop early once an axis proves the pair apart ([`apart_by`]). The
    /// families that read one side's pose in the other's frame take it
    /// from `relative` where it is kept.
    ///
    /// Each family's `eval` is `#[inline(never)]`: the pair set's `eval`,
    /// which dispatches here, copies two poses on every call, and when the
    /// compiler inlined one family into it (the ball–box one, after an
    /// unrelated change) it copied them through `memcpy` for every family
    /// (ball–ball queries: 3 % more instructions, every scene 0.1–0.7 %).
    pub fn eval<E: Enclosure>(
        &self,
        span: TimeSpan,
        a: &Side<E>,
        b: &Side<E>,
        relative: &Relative<E>,
        axes: u64,
        out: &mut [E],
    ) {
        match self {
            PairGap::BallBall(g) => g.eval(span, a, b, axes, out),
            PairGap::BallTriangle(g) => g.eval(span, a, b, axes, out),
            PairGap::BallSegment(g) => g.eval(span, a, b, axes, out),
            PairGap::TriangleTriangle(g) => g.eval(span, a, b, relative, axes, out),
            PairGap::BallCuboid(g) => g.eval(span, a, b, axes, out),
            PairGap::CuboidCuboid(g) => g.eval(a, b, relative, axes, out),
            PairGap::CuboidTriangle(g) => g.eval(a, b, relative, axes, out),
            PairGap::HalfSpace(g) => g.eval(span, a, b, axes, out),
            PairGap::SupportMap(g) => g.eval(span, a, b, axes, out),
        }
    }
}

/// A pair gap together with whether the family holds the shapes in the
/// opposite order (its `a` side is the caller's second shape).
pub(crate) struct Built {
    pub gap: PairGap,
    pub swapped: bool,
}

impl Built {
    /// Whether the family reads each side's rotation, in the caller's
    /// order (see [`PairGap::reads_rotation`]).
    pub fn reads_rotation(&self) -> [bool; 2] {
        self.gap.reads_rotation_as(self.swapped)
    }
}

/// A whole convex shape read once for many pairs: the families' core and
/// border, and parry's copy for the direction hint. A composite's parts
/// meet the same convex shape again and again (a hull over a mesh:
/// hundreds of triangle pairs), and reading a hull copies its vertices
/// twice.
#[derive(Clone)]
pub(crate) struct Prepared {
    convex: Convex,
    shape: Arc<dyn Shape>,
}

impl Prepared {
    /// `None` for a shape that is not a bounded convex one.
    pub fn of(shape: &dyn Shape) -> Result<Option<Prepared>, CcdError> {
        Ok(Convex::from_shape(shape)?.map(|convex| Prepared {
            convex,
            shape: Arc::from(shape.clone_dyn()),
        }))
    }
}

/// The gap for `shape1` against `shape2` with the given skin (metres), or
/// `Unsupported` for a pair of kinds no family handles.
pub(crate) fn build(shape1: &dyn Shape, shape2: &dyn Shape, skin: f64) -> Result<Built, CcdError> {
    build_prepared((shape1, None), (shape2, None), skin)
}

/// [`build`], with either shape already read ([`Prepared::of`] on the same
/// shape).
pub(crate) fn build_prepared(
    (shape1, prepared1): (&dyn Shape, Option<&Prepared>),
    (shape2, prepared2): (&dyn Shape, Option<&Prepared>),
    skin: f64,
) -> Result<Built, CcdError> {
    use TypedShape as T;
    let convex = |shape: &dyn Shape, prepared: Option<&Prepared>| match prepared {
        Some(p) => Ok(Some(p.convex.clone())),
        None => Convex::from_shape(shape),
    };
    let shared = |shape: &dyn Shape, prepared: Option<&Prepared>| match prepared {
        Some(p) => p.shape.clone(),
        None => Arc::from(shape.clone_dyn()),
    };
    let straight = |gap| {
        Ok(Built {
            gap,
            swapped: false,
        })
    };
    let mirrored = |gap| Ok(Built { gap, swapped: true });
    match (shape1.as_typed_shape(), shape2.as_typed_shape()) {
        (T::Ball(b1), T::Ball(b2)) => straight(PairGap::BallBall(BallBall::new(
            radius(b1.radius)?,
            radius(b2.radius)?,
            skin,
        ))),
        (T::Ball(b), T::Triangle(t)) => straight(ball_triangle(b, t, skin)?),
        (T::Triangle(t), T::Ball(b)) => mirrored(ball_triangle(b, t, skin)?),
        (T::Ball(b), T::Segment(s)) => straight(ball_segment(b, s, skin)?),
        (T::Segment(s), T::Ball(b)) => mirrored(ball_segment(b, s, skin)?),
        (T::Triangle(t1), T::Triangle(t2)) => straight(PairGap::TriangleTriangle(
            TriangleTriangle::new(corners(t1)?, corners(t2)?, skin),
        )),
        (T::HalfSpace(h), _) => match Convex::from_shape(shape2)? {
            Some(c) => straight(PairGap::HalfSpace(half_space(h, c, skin)?)),
            None => unsupported(shape1, shape2),
        },
        (_, T::HalfSpace(h)) => match Convex::from_shape(shape1)? {
            Some(c) => mirrored(PairGap::HalfSpace(half_space(h, c, skin)?)),
            None => unsupported(shape1, shape2),
        },
        _ => match (convex(shape1, prepared1)?, convex(shape2, prepared2)?) {
            (Some(c1), Some(c2)) => match (&c1.core, &c2.core) {
                (Core::Point, Core::Cuboid(h)) => straight(PairGap::BallCuboid(BallCuboid::new(
                    c1.border, *h, c2.border, skin,
                ))),
                (Core::Cuboid(h), Core::Point) => mirrored(PairGap::BallCuboid(BallCuboid::new(
                    c2.border, *h, c1.border, skin,
                ))),
                // The 15 axes are exact for touching, not for distance:
                // with a skin or a border, corners would count as close
                // up to √3 times too early; the adaptive axes are exact.
                (Core::Cuboid(h1), Core::Cuboid(h2))
                    if skin == 0.0 && c1.border == 0.0 && c2.border == 0.0 =>
                {
                    straight(PairGap::CuboidCuboid(CuboidCuboid::new(
                        *h1, c1.border, *h2, c2.border, skin,
                    )))
                }
                (Core::Cuboid(h), Core::Triangle(t))
                    if skin == 0.0 && c1.border == 0.0 && c2.border == 0.0 =>
                {
                    straight(PairGap::CuboidTriangle(CuboidTriangle::new(*h, *t)))
                }
                (Core::Triangle(t), Core::Cuboid(h))
                    if skin == 0.0 && c1.border == 0.0 && c2.border == 0.0 =>
                {
                    mirrored(PairGap::CuboidTriangle(CuboidTriangle::new(*h, *t)))
                }
                _ => straight(PairGap::SupportMap(SupportMap::new(
                    c1,
                    shared(shape1, prepared1),
                    c2,
                    shared(shape2, prepared2),
                    skin,
                ))),
            },
            _ => unsupported(shape1, shape2),
        },
    }
}

fn unsupported(shape1: &dyn Shape, shape2: &dyn Shape) -> Result<Built, CcdError> {
    Err(CcdError::Unsupported {
        what: format!(
            "{:?} against {:?}",
            shape1.shape_type(),
            shape2.shape_type()
        ),
    })
}

/// The half-space family for a half-space against a convex shape.
fn half_space(
    h: &rapier3d::parry::shape::HalfSpace,
    other: Convex,
    skin: f64,
) -> Result<HalfSpaceConvex, CcdError> {
    let n = h.normal;
    let normal = nalgebra::Vector3::new(
        check_finite("half-space normal", f64::from(n.x))?,
        check_finite("half-space normal", f64::from(n.y))?,
        check_finite("half-space normal", f64::from(n.z))?,
    );
    Ok(HalfSpaceConvex::new(normal, other, skin))
}

/// A length of a shape (radius, half-extent) checked finite and `≥ 0`.
pub(crate) fn length(what: &'static str, x: f32) -> Result<f64, CcdError> {
    let x = check_finite(what, f64::from(x))?;
    if x < 0.0 {
        return Err(CcdError::BadParameter {
            what,
            value: x,
            expected: "a length >= 0 metres",
        });
    }
    Ok(x)
}

fn ball_triangle(b: &Ball, t: &Triangle, skin: f64) -> Result<PairGap, CcdError> {
    Ok(PairGap::BallTriangle(BallTriangle::new(
        radius(b.radius)?,
        corners(t)?,
        skin,
    )))
}

fn ball_segment(b: &Ball, s: &Segment, skin: f64) -> Result<PairGap, CcdError> {
    let ends = [point("segment end", s.a)?, point("segment end", s.b)?];
    Ok(PairGap::BallSegment(BallSegment::new(
        radius(b.radius)?,
        ends,
        skin,
    )))
}

/// A triangle's corners as `f64` vectors, checked finite.
fn corners(t: &Triangle) -> Result<[Vector3<f64>; 3], CcdError> {
    Ok([
        point("triangle corner", t.a)?,
        point("triangle corner", t.b)?,
        point("triangle corner", t.c)?,
    ])
}

/// A shape's point as an `f64` vector (exact), checked finite.
pub(crate) fn point(what: &'static str, v: Vector) -> Result<Vector3<f64>, CcdError> {
    let p = vec_from_glam(v);
    for x in p.iter() {
        check_finite(what, *x)?;
    }
    Ok(p)
}

fn radius(r: f32) -> Result<f64, CcdError> {
    length("ball radius", r)
}

/// When one of the axes in `group` (already computed into `out`) proves
/// the pair apart on the node, every other axis of `axes` gets its value and
/// `true` comes back: the family need not compute the rest (the solver reads
/// a separated pair only to see that it is apart). Most nodes of a search
/// are apart, and most by one of the first axes (a box above a floor by the
/// floor's face), so the other dozen are saved.
pub(crate) fn apart_by<E: Enclosure>(out: &mut [E], axes: u64, group: u64) -> bool {
    let mut bits = axes & group;
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if out[k].range().lo > 0.0 {
            let value = out[k];
            let mut rest = axes & !group;
            while rest != 0 {
                let j = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                out[j] = value;
            }
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::apart_by;
    use crate::enclosure::{Enclosure, Interval};

    #[test]
    fn an_axis_that_separates_stands_in_for_the_rest() {
        let iv = |lo, hi| Interval::new(lo, hi);
        // Axes 0..4 asked for; 0 and 1 computed, 1 separates.
        let mut out = [
            iv(-1.0, 0.5),
            iv(0.25, 2.0),
            iv(-9.0, -8.0),
            iv(-9.0, -8.0),
            iv(5.0, 6.0),
        ];
        assert!(apart_by(&mut out, 0b1111, 0b11));
        assert_eq!(out[2], iv(0.25, 2.0));
        assert_eq!(out[3], iv(0.25, 2.0));
        assert_eq!(out[0], iv(-1.0, 0.5), "the group's own axes are kept");
        assert_eq!(out[4], iv(5.0, 6.0), "axes not asked for are left alone");
        // None of the group separates: nothing changes.
        let mut out = [iv(-1.0, 0.5), iv(-0.25, 2.0), iv(3.0, 4.0)];
        assert!(!apart_by(&mut out, 0b111, 0b11));
        assert_eq!(out[2], iv(3.0, 4.0));
        // A separating axis not asked for does not count.
        let mut out = [iv(1.0, 2.0), iv(-1.0, 1.0)];
        assert!(!apart_by(&mut out, 0b10, 0b11));
        assert!(out[0].range().lo > 0.0);
    }

    /// A kept pose stands for its own time only: a side asked at another
    /// time (a sub-node's middle) gets the motion's pose there, and keeps
    /// that one next.
    #[test]
    fn a_kept_pose_is_read_only_at_its_own_time() {
        use super::{KeptPose, Side, Trajectory};
        use crate::enclosure::Affine;
        use crate::motion::Motion;
        use nalgebra::{Isometry3, Point3, Vector3};
        let motion = Motion::from_velocities(
            Isometry3::identity(),
            Point3::new(0.1, 0.0, 0.0),
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::new(0.0, 40.0, 5.0),
            1.0 / 60.0,
        )
        .expect("a finite motion");
        let pose = motion.pose::<Affine>(crate::enclosure::TimeSpan::new(0.0, 1.0));
        let kept = KeptPose::default();
        let side = Side {
            pose: &pose,
            motion: &motion,
            kept: Some(&kept),
        };
        for t in [0.25, 0.25, 0.75, 0.25, 1.0] {
            assert_eq!(side.pose_at(t), motion.pose_at(t), "at {t}");
            assert_eq!(kept.get().map(|(at, _)| at), Some(t));
        }
    }
}
