//! TEMPORARY — delete at merge. A stand-in for `crate::query` and
//! `crate::convert` (being written on `main`) with exactly their signatures,
//! built on parry's `cast_shapes_nonlinear`, so that the rapier stage
//! compiles and its tests run before the real query lands.
//!
//! It is NOT sound: parry works in `f32`, has no skin (the skin is emulated
//! by backing the hit off by `skin / closing speed`), ignores `epsilon`,
//! `arithmetic` and `max_evaluations`, ignores a motion's acceleration, and
//! answers `Unsupported` where parry does (cone or ball against a
//! half-space, for instance).
#![allow(dead_code)]

use crate::enclosure::{Arithmetic, TimeSpan};
use crate::error::CcdError;
use crate::motion::{Motion, Trajectory};
use crate::solve::{RootStatus, SolveStats};
use nalgebra::{Isometry3, Point3, Vector3};
use rapier3d::parry::query::{
    DefaultQueryDispatcher, NonlinearRigidMotion, QueryDispatcher, ShapeCastStatus,
};
use rapier3d::parry::shape::Shape;

/// Query parameters (see the real `crate::query::QueryOptions`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryOptions {
    /// Accuracy, a fraction of the step.
    pub epsilon: f64,
    /// Report when the shapes come within this distance, metres.
    pub skin: f64,
    pub arithmetic: Arithmetic,
    pub max_evaluations: u64,
    pub time_range: TimeSpan,
}

impl Default for QueryOptions {
    fn default() -> QueryOptions {
        QueryOptions {
            epsilon: 1.0e-4,
            skin: 0.0,
            arithmetic: Arithmetic::default(),
            max_evaluations: 100_000,
            time_range: TimeSpan::STEP,
        }
    }
}

/// A time of impact (see the real `crate::query::Toi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toi {
    /// Fraction of the step.
    pub fraction: f64,
    /// Seconds.
    pub time: f64,
    pub status: RootStatus,
    pub witness1: Point3<f64>,
    pub witness2: Point3<f64>,
    /// World, from shape 1 towards shape 2.
    pub normal1: Vector3<f64>,
    pub stats: SolveStats,
}

pub struct ShapeMotion<'a> {
    pub shape: &'a dyn Shape,
    pub motion: Motion,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManyToi {
    pub toi: Toi,
    pub moving: usize,
    pub target: usize,
}

/// Conversions between rapier's glam `f32` types and our nalgebra `f64`.
pub mod convert {
    use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
    use rapier3d::math::{Pose, Rotation, Vector};

    pub fn iso_from_pose(p: &Pose) -> Isometry3<f64> {
        let q = p.rotation;
        Isometry3::from_parts(
            Translation3::from(vec_from_glam(p.translation)),
            UnitQuaternion::new_normalize(Quaternion::new(
                q.w as f64, q.x as f64, q.y as f64, q.z as f64,
            )),
        )
    }

    pub fn vec_from_glam(v: Vector) -> Vector3<f64> {
        Vector3::new(v.x as f64, v.y as f64, v.z as f64)
    }

    pub fn point_from_glam(v: Vector) -> Point3<f64> {
        Point3::from(vec_from_glam(v))
    }

    pub fn glam_from_vec(v: &Vector3<f64>) -> Vector {
        Vector::new(v.x as f32, v.y as f32, v.z as f32)
    }

    pub fn pose_from_iso(iso: &Isometry3<f64>) -> Pose {
        let q = iso.rotation.quaternion();
        let rotation = Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32);
        Pose::from_parts(glam_from_vec(&iso.translation.vector), rotation.normalize())
    }
}

use convert::{glam_from_vec, pose_from_iso, vec_from_glam};

/// The motion as parry sees it, over time `τ ∈ [0, 1]` (velocities per step).
fn parry_motion(m: &Motion) -> NonlinearRigidMotion {
    let start = pose_from_iso(&m.pose_at(0.0));
    let center = glam_from_vec(&m.center().coords);
    NonlinearRigidMotion::new(
        start,
        start.inverse_transform_point(center),
        glam_from_vec(&m.displacement()),
        glam_from_vec(&m.rotation()),
    )
}

/// How far any point of `shape` may travel over the step, metres.
fn travel(shape: &dyn Shape, m: &Motion) -> f64 {
    if m.is_fixed() {
        return 0.0;
    }
    let sphere = shape.compute_local_bounding_sphere();
    m.travel_bound(sphere.center.length() as f64 + sphere.radius as f64)
}

fn validate(opts: &QueryOptions) -> Result<(), CcdError> {
    let TimeSpan { lo, hi } = opts.time_range;
    if !(0.0 <= lo && lo <= hi && hi <= 1.0) {
        return Err(CcdError::BadParameter {
            what: "time range",
            value: lo,
            expected: "0 <= start <= end <= 1",
        });
    }
    if !(opts.skin >= 0.0 && opts.skin.is_finite()) {
        return Err(CcdError::BadParameter {
            what: "skin",
            value: opts.skin,
            expected: "a finite distance >= 0 metres",
        });
    }
    Ok(())
}

fn unsupported(s1: &dyn Shape, s2: &dyn Shape) -> CcdError {
    CcdError::Unsupported {
        what: format!(
            "{:?} against {:?} (parry shim)",
            s1.shape_type(),
            s2.shape_type()
        ),
    }
}

pub fn time_of_impact(
    shape1: &dyn Shape,
    motion1: &Motion,
    shape2: &dyn Shape,
    motion2: &Motion,
    opts: &QueryOptions,
) -> Result<Option<Toi>, CcdError> {
    validate(opts)?;
    let TimeSpan { lo, hi } = opts.time_range;
    let dt = motion1.dt().max(motion2.dt());
    let d = &DefaultQueryDispatcher;
    let toi = |fraction: f64, status, p1: Isometry3<f64>, w1, w2, n1: Vector3<f64>| Toi {
        fraction,
        time: fraction * dt,
        status,
        witness1: p1 * w1,
        witness2: w2,
        normal1: p1.rotation * n1,
        stats: SolveStats::default(),
    };

    // Within the skin at the start?
    let (p1, p2) = (motion1.pose_at(lo), motion2.pose_at(lo));
    let pos12 = pose_from_iso(&p1).inv_mul(&pose_from_iso(&p2));
    if let Ok(Some(c)) = d.contact(&pos12, shape1, shape2, opts.skin as f32) {
        let w2 = p2 * Point3::from(vec_from_glam(c.point2));
        return Ok(Some(toi(
            lo,
            RootStatus::InitiallyTouching,
            p1,
            Point3::from(vec_from_glam(c.point1)),
            w2,
            vec_from_glam(c.normal1),
        )));
    }
    let hit = d
        .cast_shapes_nonlinear(
            &parry_motion(motion1),
            shape1,
            &parry_motion(motion2),
            shape2,
            lo as f32,
            hi as f32,
            true,
        )
        .map_err(|_| unsupported(shape1, shape2))?;
    let Some(hit) = hit else {
        return Ok(None);
    };
    let t = (hit.time_of_impact as f64).clamp(lo, hi);
    let status = match hit.status {
        ShapeCastStatus::Converged => RootStatus::Hit,
        ShapeCastStatus::PenetratingOrWithinTargetDist if t <= lo => RootStatus::InitiallyTouching,
        ShapeCastStatus::PenetratingOrWithinTargetDist => RootStatus::Hit,
        ShapeCastStatus::OutOfIterations | ShapeCastStatus::Failed => RootStatus::BudgetExhausted,
    };
    // Emulated skin: back off by the time the gap needs to close by `skin`.
    let speed = travel(shape1, motion1) + travel(shape2, motion2);
    let fraction = if speed > 0.0 && speed.is_finite() {
        (t - opts.skin / speed).max(lo)
    } else {
        t
    };
    let (q1, q2) = (motion1.pose_at(t), motion2.pose_at(t));
    Ok(Some(toi(
        fraction,
        status,
        q1,
        Point3::from(vec_from_glam(hit.witness1)),
        q2 * Point3::from(vec_from_glam(hit.witness2)),
        vec_from_glam(hit.normal1),
    )))
}

pub fn time_of_impact_many(
    moving: &[ShapeMotion],
    targets: &[ShapeMotion],
    opts: &QueryOptions,
) -> Result<Option<ManyToi>, CcdError> {
    validate(opts)?;
    let mut best: Option<ManyToi> = None;
    let o = *opts;
    for (i, m) in moving.iter().enumerate() {
        for (j, t) in targets.iter().enumerate() {
            if let Some(toi) = time_of_impact(m.shape, &m.motion, t.shape, &t.motion, &o)? {
                if best.is_none_or(|b| toi.fraction < b.toi.fraction) {
                    best = Some(ManyToi {
                        toi,
                        moving: i,
                        target: j,
                    });
                }
            }
        }
    }
    Ok(best)
}
