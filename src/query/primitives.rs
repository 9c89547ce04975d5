//! Vertex–face and edge–edge time of impact for linearly moving vertices:
//! the standard CCD queries of mesh–mesh contact (the axes are in
//! `gap::primitives`).

use super::QueryOptions;
use crate::enclosure::{Enclosure, InArithmetic};
use crate::enclosure::{Interval, TimeSpan};
use crate::error::{CcdError, check_finite};
use crate::gap::primitives::{
    EDGE_EDGE_AXES, VERTEX_FACE_AXES, closest_on_triangle, closest_segment_segment, direction,
    edge_edge_axes, vertex_face_axes,
};
use crate::solve::{GapSet, RootStatus, SolveOptions, SolveOutcome, SolveStats, Solver};
use nalgebra::{Point3, Vector3};

/// The answer of a primitive query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimitiveToi {
    /// When, as a fraction of the interval from `t0` to `t1`.
    pub fraction: f64,
    /// `Hit`, `InitiallyTouching`, or `BudgetExhausted` (a conservative
    /// time: the earliest not excluded).
    pub status: RootStatus,
    /// What the search spent.
    pub stats: SolveStats,
}

/// Which primitive a query is about.
#[derive(Clone, Copy, Debug)]
enum Kind {
    VertexFace,
    EdgeEdge,
}

/// One primitive pair of linearly moving vertices, as the solver sees it.
/// `start[k]` is vertex `k` at `t0`; `delta[k]` encloses its displacement
/// `v_k(t1) − v_k(t0)` (the subtraction rounded outward), so that
/// `v_k(τ) = start[k] + τ·delta[k]` holds the true linear motion.
struct LinearPrimitive {
    kind: Kind,
    start: [Vector3<f64>; 4],
    end: [Vector3<f64>; 4],
    delta: [Vector3<Interval>; 4],
    skin: f64,
}

impl LinearPrimitive {
    pub fn new(
        kind: Kind,
        t0: [Point3<f64>; 4],
        t1: [Point3<f64>; 4],
        skin: f64,
    ) -> LinearPrimitive {
        let start = t0.map(|p| p.coords);
        let end = t1.map(|p| p.coords);
        let delta = std::array::from_fn(|k| {
            Vector3::from_fn(|i, _| Interval::point(end[k][i]) - Interval::point(start[k][i]))
        });
        LinearPrimitive {
            kind,
            start,
            end,
            delta,
            skin,
        }
    }

    /// The vertices at one time, in `f64` (for adaptive directions).
    fn at(&self, tau: f64) -> [Vector3<f64>; 4] {
        std::array::from_fn(|k| self.start[k] + (self.end[k] - self.start[k]) * tau)
    }

    /// The adaptive direction at the middle of `span`.
    fn direction(&self, span: TimeSpan) -> Option<Vector3<f64>> {
        let v = self.at(span.lo + 0.5 * (span.hi - span.lo));
        match self.kind {
            Kind::VertexFace => direction(&closest_on_triangle(&v[0], &v[1], &v[2], &v[3]), &v[0]),
            Kind::EdgeEdge => {
                let (ca, cb) = closest_segment_segment(&v[0], &v[1], &v[2], &v[3]);
                direction(&ca, &cb)
            }
        }
    }
}

impl<E: Enclosure> GapSet<E> for LinearPrimitive {
    fn pair_count(&self) -> usize {
        1
    }

    /// The adaptive direction makes the axes inexact.
    fn is_exact(&self, _pair: usize) -> bool {
        false
    }

    fn axis_count(&self, _pair: usize) -> usize {
        match self.kind {
            Kind::VertexFace => VERTEX_FACE_AXES,
            Kind::EdgeEdge => EDGE_EDGE_AXES,
        }
    }

    fn eval(&mut self, _pair: usize, span: TimeSpan, axes: u64, out: &mut [E]) {
        let tau = E::time(span);
        let v: [Vector3<E>; 4] = std::array::from_fn(|k| {
            Vector3::from_fn(|i, _| E::constant(self.start[k][i]) + tau.scale(self.delta[k][i]))
        });
        let w = self.direction(span);
        match self.kind {
            Kind::VertexFace => {
                vertex_face_axes(&v[0], &[v[1], v[2], v[3]], self.skin, w.as_ref(), axes, out)
            }
            Kind::EdgeEdge => edge_edge_axes(
                &[v[0], v[1]],
                &[v[2], v[3]],
                self.skin,
                w.as_ref(),
                axes,
                out,
            ),
        }
    }
}

fn check_points(what: &'static str, points: &[Point3<f64>]) -> Result<(), CcdError> {
    for p in points {
        for x in p.iter() {
            check_finite(what, *x)?;
        }
    }
    Ok(())
}

fn run(
    kind: Kind,
    t0: [Point3<f64>; 4],
    t1: [Point3<f64>; 4],
    options: &QueryOptions,
) -> Result<Option<PrimitiveToi>, CcdError> {
    check_points("vertex at t0", &t0)?;
    check_points("vertex at t1", &t1)?;
    let solve = options.solve_options()?;
    let mut set = LinearPrimitive::new(kind, t0, t1, options.skin);
    let outcome = options.arithmetic.dispatch(Search {
        set: &mut set,
        options: &solve,
    })?;
    Ok(
        (outcome.status != RootStatus::Separated).then_some(PrimitiveToi {
            fraction: outcome.time,
            status: outcome.status,
            stats: outcome.stats,
        }),
    )
}

/// One search of a primitive pair in the chosen arithmetic.
struct Search<'a> {
    set: &'a mut LinearPrimitive,
    options: &'a SolveOptions,
}

impl InArithmetic for Search<'_> {
    type Output = Result<SolveOutcome, CcdError>;

    fn run<E: Enclosure>(self) -> Self::Output {
        Solver::new().solve::<E, _>(self.set, self.options)
    }
}

/// The first time a linearly moving vertex comes within `options.skin` of a
/// linearly moving triangle, or `None` when it stays farther.
///
/// `v` is the vertex and `f0 f1 f2` the triangle's corners, each as
/// `(position at t0, position at t1)` in metres; every vertex moves on the
/// straight line between. The answer is a fraction of `[t0, t1]`, never
/// after the true first contact (no false negatives, rounding included) and
/// at most `options.epsilon` before it for a transversal contact.
///
/// ```
/// use affine_ccd::query::{vertex_face_toi, QueryOptions};
/// use nalgebra::{Point3, Vector3};
///
/// // A vertex falling from 1 m onto the unit triangle in the plane z = 0.
/// let p = |x, y, z| Point3::new(x, y, z);
/// let toi = vertex_face_toi(
///     (p(0.2, 0.2, 1.0), p(0.2, 0.2, -1.0)),
///     (p(0.0, 0.0, 0.0), p(0.0, 0.0, 0.0)),
///     (p(1.0, 0.0, 0.0), p(1.0, 0.0, 0.0)),
///     (p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0)),
///     &QueryOptions::default(),
/// )
/// .unwrap()
/// .expect("it hits the face halfway");
/// assert!(toi.fraction <= 0.5 && toi.fraction > 0.5 - 1e-4);
/// ```
pub fn vertex_face_toi(
    v: (Point3<f64>, Point3<f64>),
    f0: (Point3<f64>, Point3<f64>),
    f1: (Point3<f64>, Point3<f64>),
    f2: (Point3<f64>, Point3<f64>),
    options: &QueryOptions,
) -> Result<Option<PrimitiveToi>, CcdError> {
    run(
        Kind::VertexFace,
        [v.0, f0.0, f1.0, f2.0],
        [v.1, f0.1, f1.1, f2.1],
        options,
    )
}

/// The first time linearly moving edge `a0 a1` comes within `options.skin`
/// of linearly moving edge `b0 b1`, or `None` when they stay farther. Each
/// vertex is `(position at t0, position at t1)` in metres; see
/// [`vertex_face_toi`] for the guarantees.
pub fn edge_edge_toi(
    a0: (Point3<f64>, Point3<f64>),
    a1: (Point3<f64>, Point3<f64>),
    b0: (Point3<f64>, Point3<f64>),
    b1: (Point3<f64>, Point3<f64>),
    options: &QueryOptions,
) -> Result<Option<PrimitiveToi>, CcdError> {
    run(
        Kind::EdgeEdge,
        [a0.0, a1.0, b0.0, b1.0],
        [a0.1, a1.1, b0.1, b1.1],
        options,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_crossing_midway_are_found_and_parallel_ones_are_not() {
        let p = Point3::new;
        let options = QueryOptions::default();
        // Edge a along x at z = 1 → −1; edge b along y at z = 0.
        let hit = edge_edge_toi(
            (p(-1.0, 0.0, 1.0), p(-1.0, 0.0, -1.0)),
            (p(1.0, 0.0, 1.0), p(1.0, 0.0, -1.0)),
            (p(0.0, -1.0, 0.0), p(0.0, -1.0, 0.0)),
            (p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0)),
            &options,
        )
        .unwrap()
        .expect("they cross at τ = 0.5");
        assert!(hit.fraction <= 0.5 && hit.fraction > 0.5 - 1e-4, "{hit:?}");
        // Two parallel edges 1 m apart sliding along themselves.
        let miss = edge_edge_toi(
            (p(0.0, 0.0, 0.0), p(5.0, 0.0, 0.0)),
            (p(1.0, 0.0, 0.0), p(6.0, 0.0, 0.0)),
            (p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0)),
            (p(1.0, 1.0, 0.0), p(1.0, 1.0, 0.0)),
            &options,
        )
        .unwrap();
        assert_eq!(miss, None);
    }

    #[test]
    fn non_finite_vertices_are_an_error() {
        let p = Point3::new;
        let bad = vertex_face_toi(
            (p(f64::NAN, 0.0, 0.0), p(0.0, 0.0, 0.0)),
            (p(0.0, 0.0, 0.0), p(0.0, 0.0, 0.0)),
            (p(1.0, 0.0, 0.0), p(1.0, 0.0, 0.0)),
            (p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0)),
            &QueryOptions::default(),
        );
        assert!(matches!(bad, Err(CcdError::NonFinite { .. })));
    }
}
