//! Convex shapes as support functions over enclosures.
//!
//! A convex shape `S` in its own frame is known to the gap families through
//! its support function `h(d) = max_{x ∈ S} x·d`: the farthest the shape
//! reaches along `d`. For a shape posed by `x ↦ R·x + t`, its reach along a
//! world direction `n` is `t·n + h(Rᵀn)`, so a separating-axis gap needs
//! nothing else. Here `d` is an enclosure (it turns with the body), and the
//! result is an enclosure of an **upper bound** of `h(d)` for every time of
//! the node, which is the safe side for a gap (a larger reach only makes the
//! gap smaller).
//!
//! Every kind is a *core* (a point, a box, a segment, ...) plus a *border*:
//! the radius of a ball swept over the core. A ball is a point with a
//! border, a capsule a segment with one, and parry's `Round*` shapes are
//! their inner shape with theirs. The border's reach is `border·|d|`.
//!
//! | kind | core | `h(d)` of the core |
//! |---|---|---|
//! | ball | point | `0` |
//! | cuboid (half-extents `e`) | box | `Σ e_i·|d_i|` |
//! | capsule, segment | segment `a b` | `max(a·d, b·d)` |
//! | triangle | triangle `a b c` | `max(a·d, b·d, c·d)` |
//! | convex polyhedron | vertices | `max_v v·d` |
//! | cylinder (axis y, half-height `h`, radius `r`) | | `h·|d_y| + r·√(d_x² + d_z²)` |
//! | cone (apex at `+h` on y, base radius `r` at `−h`) | | `max(h·d_y, −h·d_y + r·√(d_x² + d_z²))` |
//!
//! The callers know `|d|` in advance: `d` is a fixed vector turned by
//! rotations, so `|d|` equals the fixed vector's norm. `√(d_x² + d_z²)` is
//! then taken as `√(|d|² − d_y²)`, one square instead of two, and the
//! border's `|d|` costs nothing.

use crate::enclosure::rounding::{bound, err, up};
use crate::enclosure::{Enclosure, Interval};
use crate::error::{CcdError, check_finite};
use crate::motion::{column, row};
use nalgebra::{Matrix3, Vector3};
use rapier3d::parry::math::Vector;
use rapier3d::parry::shape::{Shape, TypedShape};
use std::sync::Arc;

use super::length;

/// How far from orthonormal the rotations the core takes as exact may be,
/// relative. A motion's start matrix comes from a unit quaternion in `f64`
/// (a few ulps, ~1e-15, from orthonormal); the turn over the step is
/// enclosed exactly. Formulas that assume `|R·v| = |v|` or `RᵀR = I` are
/// off by at most this share of the lengths involved, so each family pads
/// its skin by `ORTHO_SLACK·(extents + skin)`: a thousandfold margin.
pub(crate) const ORTHO_SLACK: f64 = 1.0e-12;

/// The shape without its border.
#[derive(Clone, Debug)]
pub(crate) enum Core {
    /// A single point at the origin (a ball's centre).
    Point,
    /// A box centred at the origin with these half-extents (metres).
    Cuboid(Vector3<f64>),
    /// A segment between two points.
    Segment([Vector3<f64>; 2]),
    /// A triangle.
    Triangle([Vector3<f64>; 3]),
    /// The convex hull of these vertices.
    Polyhedron(Arc<[Vector3<f64>]>),
    /// A cylinder along y.
    Cylinder { half_height: f64, radius: f64 },
    /// A cone along y, apex at `+half_height`.
    Cone { half_height: f64, radius: f64 },
}

/// A convex shape: a core plus a border radius (metres).
#[derive(Clone, Debug)]
pub(crate) struct Convex {
    pub core: Core,
    pub border: f64,
}

fn point(what: &'static str, v: Vector) -> Result<Vector3<f64>, CcdError> {
    Ok(Vector3::new(
        check_finite(what, f64::from(v.x))?,
        check_finite(what, f64::from(v.y))?,
        check_finite(what, f64::from(v.z))?,
    ))
}

fn half_extents(v: Vector) -> Result<Vector3<f64>, CcdError> {
    Ok(Vector3::new(
        length("cuboid half-extent", v.x)?,
        length("cuboid half-extent", v.y)?,
        length("cuboid half-extent", v.z)?,
    ))
}

fn vertices(points: &[Vector]) -> Result<Core, CcdError> {
    let vs = points
        .iter()
        .map(|p| point("convex polyhedron vertex", *p))
        .collect::<Result<Vec<_>, _>>()?;
    if vs.is_empty() {
        // No vertex: nothing to reach. parry never builds one, but a point
        // at the origin is the safe reading (never smaller than nothing).
        return Ok(Core::Point);
    }
    Ok(Core::Polyhedron(vs.into()))
}

fn triangle(a: Vector, b: Vector, c: Vector) -> Result<Core, CcdError> {
    Ok(Core::Triangle([
        point("triangle vertex", a)?,
        point("triangle vertex", b)?,
        point("triangle vertex", c)?,
    ]))
}

impl Convex {
    /// The shape as a core and a border, or `None` for kinds that are not
    /// bounded convex shapes (half-spaces, meshes, compounds, custom).
    pub fn from_shape(shape: &dyn Shape) -> Result<Option<Convex>, CcdError> {
        use TypedShape as T;
        let round = |core, border: f32| -> Result<Option<Convex>, CcdError> {
            Ok(Some(Convex {
                core,
                border: length("border radius", border)?,
            }))
        };
        match shape.as_typed_shape() {
            T::Ball(b) => round(Core::Point, b.radius),
            T::Cuboid(c) => round(Core::Cuboid(half_extents(c.half_extents)?), 0.0),
            T::Capsule(c) => round(
                Core::Segment([
                    point("capsule end", c.segment.a)?,
                    point("capsule end", c.segment.b)?,
                ]),
                c.radius,
            ),
            T::Segment(s) => round(
                Core::Segment([point("segment end", s.a)?, point("segment end", s.b)?]),
                0.0,
            ),
            T::Triangle(t) => round(triangle(t.a, t.b, t.c)?, 0.0),
            T::ConvexPolyhedron(p) => round(vertices(p.points())?, 0.0),
            T::Cylinder(c) => round(
                Core::Cylinder {
                    half_height: length("cylinder half-height", c.half_height)?,
                    radius: length("cylinder radius", c.radius)?,
                },
                0.0,
            ),
            T::Cone(c) => round(
                Core::Cone {
                    half_height: length("cone half-height", c.half_height)?,
                    radius: length("cone radius", c.radius)?,
                },
                0.0,
            ),
            T::RoundCuboid(r) => round(
                Core::Cuboid(half_extents(r.inner_shape.half_extents)?),
                r.border_radius,
            ),
            T::RoundTriangle(r) => {
                let t = &r.inner_shape;
                round(triangle(t.a, t.b, t.c)?, r.border_radius)
            }
            T::RoundCylinder(r) => round(
                Core::Cylinder {
                    half_height: length("cylinder half-height", r.inner_shape.half_height)?,
                    radius: length("cylinder radius", r.inner_shape.radius)?,
                },
                r.border_radius,
            ),
            T::RoundCone(r) => round(
                Core::Cone {
                    half_height: length("cone half-height", r.inner_shape.half_height)?,
                    radius: length("cone radius", r.inner_shape.radius)?,
                },
                r.border_radius,
            ),
            T::RoundConvexPolyhedron(r) => {
                round(vertices(r.inner_shape.points())?, r.border_radius)
            }
            _ => Ok(None),
        }
    }

    /// An enclosure of an upper bound of `h(d)`, the shape's reach along
    /// `d`, given `norm ≥ |d|` for the true `d` at every time of the node.
    pub fn support<E: Enclosure>(&self, d: &Vector3<E>, norm: f64) -> E {
        let core = match &self.core {
            Core::Point => E::zero(),
            Core::Cuboid(e) => E::dot_f64([d.x.abs(), d.y.abs(), d.z.abs()], [e.x, e.y, e.z]),
            Core::Segment([a, b]) => dot(d, a).max(dot(d, b)),
            Core::Triangle(vs) => vertex_reach(vs, d),
            Core::Polyhedron(vs) => vertex_reach(vs, d),
            Core::Cylinder {
                half_height,
                radius,
            } => d.y.abs() * *half_height + radial(d, norm) * *radius,
            Core::Cone {
                half_height,
                radius,
            } => {
                let apex = d.y * *half_height;
                let rim = radial(d, norm) * *radius - apex;
                apex.max(rim)
            }
        };
        if self.border > 0.0 {
            core + up(self.border * norm)
        } else {
            core
        }
    }

    /// An upper bound of `h(d)` for a fixed `d`, in plain `f64` with each
    /// rounding bounded: a sum or product of non-negative terms through
    /// [`bound`], a dot product of mixed signs padded by `2ε` of the sum
    /// of its terms' sizes (a three-term dot product errs by at most
    /// `γ₃ < 1.6ε` of that). The same bound as [`Self::support`] over
    /// point intervals, at a tenth of its cost (it runs two or three times
    /// a node of every support-map pair).
    pub fn support_f64(&self, d: &Vector3<f64>) -> f64 {
        // `v·d` rounded up.
        let dot_up = |v: &Vector3<f64>| {
            let sizes =
                bound(v.x.abs() * d.x.abs() + v.y.abs() * d.y.abs() + v.z.abs() * d.z.abs());
            up(v.dot(d) + 2.0 * f64::EPSILON * sizes)
        };
        let farthest =
            |vs: &[Vector3<f64>]| vs.iter().map(dot_up).fold(f64::NEG_INFINITY, f64::max);
        let radial = || (d.x * d.x + d.z * d.z).sqrt();
        let core = match &self.core {
            Core::Point => 0.0,
            Core::Cuboid(e) => bound(d.x.abs() * e.x + d.y.abs() * e.y + d.z.abs() * e.z),
            Core::Segment(vs) => farthest(vs),
            Core::Triangle(vs) => farthest(vs),
            Core::Polyhedron(vs) => farthest(vs),
            Core::Cylinder {
                half_height,
                radius,
            } => bound(d.y.abs() * half_height + radial() * radius),
            Core::Cone {
                half_height,
                radius,
            } => {
                // The apex's reach `d_y·h` within one rounding.
                let apex = d.y * half_height;
                let apex_err = err(apex);
                let rim = up(bound(radial() * radius) - (apex - apex_err));
                up(apex + apex_err).max(rim)
            }
        };
        if self.border > 0.0 {
            up(core + up(self.border * norm_up(d)))
        } else {
            core
        }
    }

    /// A point of the shape farthest along `d` (plain `f64`, no bound):
    /// what a closest-points search (GJK) asks of it. `d` need not be
    /// unit; a zero `d` gives some point of the shape.
    pub fn support_point(&self, d: &Vector3<f64>) -> Vector3<f64> {
        let farthest = |vs: &[Vector3<f64>]| {
            let mut best = vs[0];
            let mut reach = best.dot(d);
            for v in &vs[1..] {
                let r = v.dot(d);
                if r > reach {
                    (best, reach) = (*v, r);
                }
            }
            best
        };
        let radial = |radius: f64| {
            let r = Vector3::new(d.x, 0.0, d.z);
            r.try_normalize(1.0e-300)
                .map_or(Vector3::zeros(), |u| u * radius)
        };
        let core = match &self.core {
            Core::Point => Vector3::zeros(),
            Core::Cuboid(e) => {
                Vector3::new(e.x.copysign(d.x), e.y.copysign(d.y), e.z.copysign(d.z))
            }
            Core::Segment(ps) => farthest(ps),
            Core::Triangle(ps) => farthest(ps),
            Core::Polyhedron(ps) => farthest(ps),
            Core::Cylinder {
                half_height,
                radius,
            } => radial(*radius) + Vector3::new(0.0, half_height.copysign(d.y), 0.0),
            Core::Cone {
                half_height,
                radius,
            } => {
                let apex = Vector3::new(0.0, *half_height, 0.0);
                let rim = radial(*radius) - apex;
                if apex.dot(d) >= rim.dot(d) { apex } else { rim }
            }
        };
        match d.try_normalize(1.0e-300) {
            Some(u) if self.border > 0.0 => core + u * self.border,
            _ => core,
        }
    }

    /// Whether the point `p` (in the shape's frame) lies in the shape, in
    /// plain `f64`: a witness that two shapes overlap (a point in both), not
    /// a bound, so a point within rounding of the surface may go either way.
    /// `false` for the shapes with no test written here (hulls, triangles,
    /// rounded cylinders and cones): they are asked by GJK instead.
    pub fn contains(&self, p: &Vector3<f64>) -> bool {
        let r = self.border;
        match &self.core {
            Core::Point => p.norm_squared() <= r * r,
            Core::Cuboid(e) => {
                let out = (p.abs() - e).sup(&Vector3::zeros());
                out.norm_squared() <= r * r
            }
            Core::Segment([a, b]) => {
                let ab = b - a;
                let along = (p - a).dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE);
                let nearest = a + ab * along.clamp(0.0, 1.0);
                (p - nearest).norm_squared() <= r * r
            }
            Core::Cylinder {
                half_height,
                radius,
            } if r == 0.0 => p.y.abs() <= *half_height && p.x * p.x + p.z * p.z <= radius * radius,
            // The radius shrinks linearly from the base (`-half_height`) to
            // the apex (`+half_height`).
            Core::Cone {
                half_height,
                radius,
            } if r == 0.0 => {
                p.y.abs() <= *half_height
                    && p.x.hypot(p.z) * (2.0 * half_height) <= radius * (half_height - p.y)
            }
            _ => false,
        }
    }

    /// Whether [`Self::contains`] has a test for this shape.
    pub fn tests_points(&self) -> bool {
        match self.core {
            Core::Point | Core::Cuboid(_) | Core::Segment(_) => true,
            Core::Cylinder { .. } | Core::Cone { .. } => self.border == 0.0,
            Core::Triangle(_) | Core::Polyhedron(_) => false,
        }
    }

    /// An upper bound of `|x|` over the shape (metres): how far it reaches
    /// from its frame's origin.
    pub fn extent(&self) -> f64 {
        let core = match &self.core {
            Core::Point => 0.0,
            Core::Cuboid(e) => e.norm(),
            Core::Segment(ps) => ps.iter().map(|p| p.norm()).fold(0.0, f64::max),
            Core::Triangle(ps) => ps.iter().map(|p| p.norm()).fold(0.0, f64::max),
            Core::Polyhedron(ps) => ps.iter().map(|p| p.norm()).fold(0.0, f64::max),
            Core::Cylinder {
                half_height,
                radius,
            }
            | Core::Cone {
                half_height,
                radius,
            } => half_height.hypot(*radius),
        };
        padded_extent(core + self.border)
    }
}

/// An extent `x` (metres) computed from norms, rounded up: a relative
/// error of a few ulps in the norms is covered many times.
#[inline]
pub(crate) fn padded_extent(x: f64) -> f64 {
    up(x * (1.0 + 1.0e-14))
}

/// How far a box of half-extents `half` centred at the origin reaches
/// along `d`, `Σ h_i·|d_i|`, in plain `f64` (not rounded up, as
/// [`Convex::support_f64`] has it).
#[inline]
pub(crate) fn box_reach(half: &Vector3<f64>, d: &Vector3<f64>) -> f64 {
    d.x.abs() * half.x + d.y.abs() * half.y + d.z.abs() * half.z
}

/// `v·w` for an enclosed `v` and a fixed `w`.
pub(crate) fn dot<E: Enclosure>(v: &Vector3<E>, w: &Vector3<f64>) -> E {
    E::dot_f64([v.x, v.y, v.z], [w.x, w.y, w.z])
}

/// `R·w` for an enclosed `R` and a fixed `w`.
pub(crate) fn mul<E: Enclosure>(r: &Matrix3<E>, w: &Vector3<f64>) -> Vector3<E> {
    Vector3::from_fn(|i, _| E::dot_f64(row(r, i), [w.x, w.y, w.z]))
}

/// `Rᵀ·w` for an enclosed `R` and a fixed `w`.
pub(crate) fn tr_mul<E: Enclosure>(r: &Matrix3<E>, w: &Vector3<f64>) -> Vector3<E> {
    Vector3::from_fn(|j, _| E::dot_f64(column(r, j), [w.x, w.y, w.z]))
}

/// An upper bound of `|v|`: `norm()` is within two ulps of the truth.
pub(crate) fn norm_up(v: &Vector3<f64>) -> f64 {
    up(v.norm() * (1.0 + 4.0 * f64::EPSILON))
}

/// `√(d_x² + d_z²)` as `√(|d|² − d_y²)`, given `norm ≥ |d|`. Where the
/// square root cannot be taken, `norm` itself bounds it.
fn radial<E: Enclosure>(d: &Vector3<E>, norm: f64) -> E {
    (E::constant(up(norm * norm)) - d.y.sqr())
        .sqrt()
        .unwrap_or(E::constant(norm))
}

/// `max_v v·d` over the vertices, from lines: over the node each
/// component of `d` lies within a radius of a line (its enclosure's
/// [`Enclosure::line`]), so each `v·d` lies between two
/// lines, and the greatest of them lies below the chord of the greatest
/// upper line between the node's ends (a greatest of lines is convex)
/// and above any one vertex's lower line (the one highest mid-node is
/// taken). Three plain dot products per vertex, where an enclosed dot
/// product and its range cost several times as much (this runs for every
/// vertex on every node); and where the farthest vertex changes over the
/// node the bound keeps a slope, where the greatest of the vertices'
/// enclosures fell back to a range.
fn vertex_reach<E: Enclosure>(vs: &[Vector3<f64>], d: &Vector3<E>) -> E {
    // Past this a component's parts could overflow a vertex's products
    // (vertices are finite `f32` values, under 3.5e38): the whole line.
    const LARGEST: f64 = 1.0e250;
    if vs.is_empty() {
        return E::constant(f64::INFINITY);
    }
    // `d`'s components as `c + s·e ± r`, and their sizes `|c| + |s| + r`
    // (a vertex's terms below add up to at most `|v|·w`).
    let [(c0, s0, r0), (c1, s1, r1), (c2, s2, r2)] = [d.x, d.y, d.z].map(|k| k.line());
    let [w0, w1, w2] =
        [(c0, s0, r0), (c1, s1, r1), (c2, s2, r2)].map(|(c, s, r)| c.abs() + s.abs() + r);
    // (Written so that a NaN fails it too.)
    if !(w0 <= LARGEST && w1 <= LARGEST && w2 <= LARGEST) {
        return E::from_interval(Interval::ENTIRE);
    }
    // Per vertex `v·d ∈ a + b·e ± rho`; the chord's ends (the greatest
    // upper line at `e = ±1`) and the lower line highest at `e = 0`.
    let (mut top_plus, mut top_minus) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut low = (f64::NEG_INFINITY, 0.0);
    let mut size = 0.0_f64;
    for v in vs {
        let (x, y, z) = (v.x.abs(), v.y.abs(), v.z.abs());
        let a = v.x * c0 + v.y * c1 + v.z * c2;
        let b = v.x * s0 + v.y * s1 + v.z * s2;
        let rho = x * r0 + y * r1 + z * r2;
        size = size.max(x * w0 + y * w1 + z * w2);
        let (plus, minus, mid) = (a + b + rho, a - b + rho, a - rho);
        top_plus = top_plus.max(plus);
        top_minus = top_minus.max(minus);
        if mid > low.0 {
            low = (mid, b);
        }
    }
    // The roundings of every vertex's sums and lines above, and of the
    // padding itself: each a few half-ulps of terms `size` bounds. One
    // pad for all vertices, added once to the greatest and the highest.
    let pad = 8.0 * f64::EPSILON * bound(size) + f64::MIN_POSITIVE;
    let (top_plus, top_minus) = (top_plus + pad, top_minus + pad);
    let low = (low.0 - pad, low.1);
    // The chord through `(−1, top_minus)` and `(1, top_plus)`, raised by
    // the roundings of its centre and slope.
    let slack = 2.0 * f64::EPSILON * (top_plus.abs() + top_minus.abs());
    let chord = (
        0.5 * (top_plus + top_minus) + slack,
        0.5 * (top_plus - top_minus),
    );
    E::between(low, chord)
}

/// Our shapes as parry3d-f64's GJK sees them (the direction of a narrow
/// node, `support_map::SupportMap::closest_f64`).
impl parry3d_f64::shape::SupportMap for Convex {
    fn local_support_point(&self, dir: parry3d_f64::math::Vector) -> parry3d_f64::math::Vector {
        let p = self.support_point(&Vector3::new(dir.x, dir.y, dir.z));
        parry3d_f64::math::Vector::new(p.x, p.y, p.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosure::{Affine, Taylor2};
    use proptest::prelude::*;

    /// One core of each kind, by `kind` in `0..7`: a point, a box, a
    /// segment, a triangle, a tetrahedron's hull, a cylinder and a cone
    /// (half-height 0.4, radius 0.3).
    fn sample_core(kind: usize) -> Core {
        let v = |x: f64, y: f64, z: f64| Vector3::new(x, y, z);
        match kind {
            0 => Core::Point,
            1 => Core::Cuboid(v(0.5, 0.2, 1.0)),
            2 => Core::Segment([v(0.0, -0.4, 0.1), v(0.3, 0.4, -0.2)]),
            3 => Core::Triangle([v(0.0, 0.0, 0.0), v(1.0, 0.2, 0.0), v(0.1, 0.9, 0.3)]),
            4 => Core::Polyhedron(
                vec![
                    v(1.0, 0.0, 0.0),
                    v(-0.5, 0.8, 0.1),
                    v(-0.4, -0.7, 0.2),
                    v(0.0, 0.1, 0.9),
                ]
                .into(),
            ),
            5 => Core::Cylinder {
                half_height: 0.4,
                radius: 0.3,
            },
            _ => Core::Cone {
                half_height: 0.4,
                radius: 0.3,
            },
        }
    }

    proptest! {
        /// A hull's or triangle's reach along a direction that moves over
        /// the node (`d = c + s·e ± r` per component, `e ∈ [−1, 1]`) holds
        /// the farthest vertex at every `e` and every direction within
        /// the radii (the corners of that box: the farthest vertex is
        /// convex in the direction), from above and from below, in every
        /// arithmetic.
        #[test]
        fn the_polytope_reach_holds_the_farthest_vertex_at_every_time(
            vertices in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 1..24),
            scale in -3i32..4,
            centre in prop::array::uniform3(-10.0f64..10.0),
            slopes in prop::array::uniform3(prop_oneof![Just(0.0f64), -2.0f64..2.0]),
            radii in prop::array::uniform3(prop_oneof![Just(0.0f64), 0.0f64..0.5]),
        ) {
            let vs: Vec<Vector3<f64>> = vertices
                .iter()
                .map(|v| Vector3::from(*v) * 10f64.powi(scale))
                .collect();
            let farthest = |x: &Vector3<f64>| {
                vs.iter().map(|v| v.dot(x)).fold(f64::NEG_INFINITY, f64::max)
            };
            // The reach from each arithmetic, as its bounds at `e`.
            let affine = vertex_reach(
                &vs,
                &Vector3::from_fn(|k, _| Affine { c: centre[k], s: slopes[k], r: radii[k] }),
            );
            let taylor = vertex_reach(
                &vs,
                &Vector3::from_fn(|k, _| Taylor2 { c: [centre[k], slopes[k], 0.0], r: radii[k] }),
            );
            let interval = vertex_reach(
                &vs,
                &Vector3::from_fn(|k, _| {
                    let reach = slopes[k].abs() + radii[k];
                    Interval::new(centre[k] - reach, centre[k] + reach)
                }),
            );
            // Each arithmetic's bounds at `e`.
            let bounds = |e: f64| {
                let (a, t) = (affine.c + affine.s * e, taylor.c[0] + taylor.c[1] * e + taylor.c[2] * e * e);
                [
                    ("affine", a - affine.r, a + affine.r),
                    ("taylor", t - taylor.r, t + taylor.r),
                    ("interval", interval.lo, interval.hi),
                ]
            };
            for i in 0..=64 {
                let e = -1.0 + i as f64 / 32.0;
                for corner in 0..8 {
                    let x = Vector3::from_fn(|k, _| {
                        let side = if corner >> k & 1 == 1 { 1.0 } else { -1.0 };
                        centre[k] + slopes[k] * e + side * radii[k]
                    });
                    let reach = farthest(&x);
                    let rounding = 1.0e-12 * (1.0 + reach.abs());
                    for (name, lo, hi) in bounds(e) {
                        prop_assert!(
                            lo - rounding <= reach && reach <= hi + rounding,
                            "{name}, e {e}: {reach} not in [{lo}, {hi}]"
                        );
                    }
                }
            }
        }

        /// `support_point` is a farthest point of the shape: along its own
        /// direction it reaches the shape's reach `h(d)` (`support_f64`),
        /// and along any other direction it reaches no farther than the
        /// shape does (so it lies in the shape). Every core, with and
        /// without a border, and zero components in `d` (a cylinder seen
        /// along its axis).
        #[test]
        fn the_support_point_is_a_farthest_point(
            kind in 0usize..7,
            border in prop_oneof![Just(0.0f64), 0.01f64..0.5],
            d in prop::array::uniform3(prop_oneof![Just(0.0f64), -2.0f64..2.0]),
            others in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 8),
        ) {
            let core = sample_core(kind);
            let shape = Convex { core, border };
            let d = Vector3::from(d);
            let p = shape.support_point(&d);
            // `support_f64` is an upper bound: a cylinder's or cone's radial
            // reach `sqrt(|d|² − d_y²)` from a rounded-up `|d|` is up to
            // ~1e-8·|d| over (seen along the axis, where it is 0).
            let rounding = 1.0e-7 * (1.0 + d.norm());
            let reach = shape.support_f64(&d);
            prop_assert!(p.dot(&d) >= reach - rounding, "{} below h(d) {}", p.dot(&d), reach);
            for u in others.iter().map(|u| Vector3::from(*u)) {
                let limit = shape.support_f64(&u) + 1.0e-12 * (1.0 + u.norm());
                prop_assert!(p.dot(&u) <= limit, "{p:?} beyond the shape along {u:?}");
            }
        }

        /// The point test takes in the shape and nothing else: a point it
        /// takes in lies within the shape's reach along 32 directions (a
        /// false "inside" would show a touch where the shapes are apart),
        /// and a point a little inside the hull of the centre and the
        /// farthest points along random directions is taken in. Shapes
        /// with no test take in nothing.
        #[test]
        fn the_point_test_takes_in_the_shape_and_nothing_else(
            kind in 0usize..7,
            border in prop_oneof![Just(0.0f64), 0.0f64..0.3],
            p in prop::array::uniform3(-1.2f64..1.2),
            directions in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 1..6),
            weights in prop::collection::vec(0.0f64..1.0, 6),
            others in prop::collection::vec(prop::array::uniform3(-1.0f64..1.0), 32),
        ) {
            let core = sample_core(kind);
            // A point inside the core (on it, for a point or a segment).
            let centre = match &core {
                Core::Segment([a, b]) => (a + b) / 2.0,
                Core::Triangle(vs) => (vs[0] + vs[1] + vs[2]) / 3.0,
                _ => Vector3::zeros(),
            };
            let shape = Convex { core, border };
            let p = Vector3::from(p);
            if shape.contains(&p) {
                prop_assert!(shape.tests_points());
                for u in others.iter().map(|u| Vector3::from(*u)) {
                    let reach = shape.support_f64(&u) + 1.0e-12;
                    prop_assert!(p.dot(&u) <= reach, "{p:?} taken in, beyond the shape along {u:?}");
                }
            }
            // A point and a segment need a border to have an inside.
            let thin = matches!(shape.core, Core::Point | Core::Segment(_));
            let solid = shape.tests_points() && (!thin || border > 0.0);
            if solid {
                let mut sum = 0.0;
                let mut hull = Vector3::zeros();
                for (d, w) in directions.iter().zip(&weights) {
                    hull += shape.support_point(&Vector3::from(*d)) * *w;
                    sum += w;
                }
                let inner = if sum > 0.0 { centre + (hull / sum - centre) * 0.999 } else { centre };
                prop_assert!(shape.contains(&inner), "{inner:?} not taken in");
            }
        }

        /// The plain `f64` reach bounds the shape from above: it is at least
        /// the exact `x·d` (products split exactly by `mul_add`, summed in
        /// double-double) for points `x` of the shape (vertices, which are
        /// exact, and points of curved surfaces drawn a hair inwards), and
        /// no looser than the interval arithmetic's reach by more than
        /// 1e-12 of `|d|`'s scale.
        #[test]
        fn the_plain_reach_is_an_upper_bound(
            kind in 0usize..7,
            border in prop_oneof![Just(0.0f64), 0.0f64..0.3],
            d in prop::array::uniform3(-1.0f64..1.0),
            scale in -6i32..7,
            angles in prop::collection::vec(0.0f64..std::f64::consts::TAU, 8),
        ) {
            let v = |x: f64, y: f64, z: f64| Vector3::new(x, y, z);
            let (h, r) = (0.4, 0.3);
            let core = sample_core(kind);
            let shape = Convex { core: core.clone(), border };
            let d = Vector3::from(d) * 10f64.powi(scale);
            let reach = shape.support_f64(&d);
            // Points of the core (exact vertices; curved ones a hair in).
            let inward = 1.0 - 1.0e-9;
            let mut points: Vec<Vector3<f64>> = match &core {
                Core::Point => vec![Vector3::zeros()],
                Core::Cuboid(e) => (0..8)
                    .map(|k| v(
                        if k & 1 == 0 { e.x } else { -e.x },
                        if k & 2 == 0 { e.y } else { -e.y },
                        if k & 4 == 0 { e.z } else { -e.z },
                    ))
                    .collect(),
                Core::Segment(vs) => vs.to_vec(),
                Core::Triangle(vs) => vs.to_vec(),
                Core::Polyhedron(vs) => vs.to_vec(),
                Core::Cylinder { .. } => angles
                    .iter()
                    .flat_map(|a| [h, -h].map(|y| v(r * a.cos(), y, r * a.sin()) * inward))
                    .collect(),
                Core::Cone { .. } => angles
                    .iter()
                    .map(|a| v(r * a.cos(), -h, r * a.sin()) * inward)
                    .chain([v(0.0, h, 0.0)])
                    .collect(),
            };
            // A curved core's farthest point itself, drawn in.
            if matches!(core, Core::Cylinder { .. } | Core::Cone { .. }) {
                points.push(Convex { core: core.clone(), border: 0.0 }.support_point(&d) * inward);
            }
            // With a border, each point moved out by it along `d` (drawn in).
            let out = d.try_normalize(0.0).map_or(Vector3::zeros(), |u| u * (border * inward));
            for p in points.iter().map(|p| p + out) {
                // `p·d` exactly, as the sum `hi + lo` of an error-free split.
                let (mut hi, mut lo) = (0.0f64, 0.0f64);
                for k in 0..3 {
                    let product = p[k] * d[k];
                    let tail = p[k].mul_add(d[k], -product);
                    let sum = hi + product;
                    let bb = sum - hi;
                    lo += (hi - (sum - bb)) + (product - bb) + tail;
                    hi = sum;
                }
                prop_assert!(reach - hi >= lo, "reach {reach:e} under {hi:e} + {lo:e} at {p:?}");
            }
            let interval = shape.support(&d.map(Interval::point), norm_up(&d)).range().hi;
            let tolerance = 1.0e-12 * (d.norm() + f64::MIN_POSITIVE);
            prop_assert!(reach <= interval + tolerance, "{reach:e} over {interval:e}");
        }
    }

    /// A direction too large for a vertex's products to stay finite, or
    /// not finite at all, reaches anywhere: the whole line, never a bound
    /// a NaN or an overflow slipped past.
    #[test]
    fn a_direction_beyond_the_products_reaches_anywhere() {
        let vs = [
            Vector3::new(1.0e38, -2.0, 0.0),
            Vector3::new(-1.0, 0.0, 3.0e38),
        ];
        let along = |k: f64| Affine {
            c: k,
            s: 0.0,
            r: 0.0,
        };
        for d in [
            Vector3::new(along(1.0e300), along(0.0), along(0.0)),
            Vector3::new(along(0.0), along(0.0), Affine::ENTIRE),
            Vector3::new(along(f64::NAN), along(1.0), along(1.0)),
        ] {
            let range = vertex_reach(&vs, &d).range();
            assert!(
                range.lo == f64::NEG_INFINITY && range.hi == f64::INFINITY,
                "{range:?}"
            );
        }
        // Just under the limit the bound is finite and holds both vertices.
        let d = Vector3::new(along(1.0e250), along(1.0), along(1.0e250));
        let range = vertex_reach(&vs, &d).range();
        assert!(range.hi.is_finite() && range.hi >= 3.0e288, "{range:?}");
    }
}
