//! Workloads shared by the benches and the accuracy report: seeded random
//! pair cases with their ground truth, and the two parry methods we compare
//! against, run on the same cases.
#![allow(dead_code)]

use affine_ccd::convert::{glam_from_vec, pose_from_iso};
use affine_ccd::{Motion, Trajectory, query};
use affine_ccd_scenes::truth::{self, Truth};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rapier3d::parry::math::Vector;
use rapier3d::parry::query::{
    NonlinearRigidMotion, cast_shapes_nonlinear,
    sweep_toi::{Sweep, SweepToiStatus, ToiProxy, sweep_time_of_impact},
};
use rapier3d::parry::shape::SharedShape;

/// The step length of every case, seconds.
pub const DT: f64 = 1.0 / 60.0;

/// Rapier's default linear slop (m): the separation parry's sweep aims at.
pub const SWEEP_SLOP: f32 = 0.002;

/// Ground-truth samples per case.
pub const TRUTH_SAMPLES: usize = 2048;

/// The tests' seeded generator (one copy for tests, benches and examples).
#[path = "../../tests/common/mod.rs"]
mod test_common;
pub use test_common::Rng;

/// A pair kind of the benchmark: a name and how to make its two shapes.
pub struct PairKind {
    pub name: &'static str,
    pub make: fn(&mut Rng) -> (SharedShape, SharedShape),
}

fn size(rng: &mut Rng) -> f32 {
    rng.range(0.05, 1.0) as f32
}

fn cuboid(rng: &mut Rng) -> SharedShape {
    SharedShape::cuboid(size(rng), size(rng), size(rng))
}

fn hull(rng: &mut Rng) -> SharedShape {
    let s = size(rng) as f64;
    let points: Vec<Vector> = (0..12)
        .map(|_| glam_from_vec(&(rng.vector(1.0) * s)))
        .collect();
    SharedShape::convex_hull(&points).unwrap_or_else(|| SharedShape::ball(s as f32))
}

/// A 10 × 10 grid of triangles (200), bumpy, about 4 m across.
fn terrain(rng: &mut Rng) -> SharedShape {
    let n = 11;
    let mut vertices = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (i as f64 * 0.4 - 2.0, j as f64 * 0.4 - 2.0);
            vertices.push(Vector::new(x as f32, rng.range(-0.1, 0.1) as f32, z as f32));
        }
    }
    let mut indices = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let a = (i * n + j) as u32;
            indices.push([a, a + 1, a + n as u32]);
            indices.push([a + 1, a + n as u32 + 1, a + n as u32]);
        }
    }
    SharedShape::trimesh(vertices, indices).expect("a valid grid mesh")
}

/// The pair kinds of the benchmark list.
pub fn pair_kinds() -> Vec<PairKind> {
    vec![
        PairKind {
            name: "ball-ball",
            make: |r| (SharedShape::ball(size(r)), SharedShape::ball(size(r))),
        },
        PairKind {
            name: "ball-cuboid",
            make: |r| (SharedShape::ball(size(r)), cuboid(r)),
        },
        PairKind {
            name: "cuboid-cuboid",
            make: |r| (cuboid(r), cuboid(r)),
        },
        PairKind {
            name: "capsule-cuboid",
            make: |r| (SharedShape::capsule_y(size(r), size(r)), cuboid(r)),
        },
        PairKind {
            name: "cuboid-triangle",
            make: |r| {
                let s = 2.0 * size(r) as f64;
                let (a, b, c) = (r.vector(s), r.vector(s), r.vector(s));
                (
                    cuboid(r),
                    SharedShape::triangle(glam_from_vec(&a), glam_from_vec(&b), glam_from_vec(&c)),
                )
            },
        },
        PairKind {
            name: "cylinder-cuboid",
            make: |r| (SharedShape::cylinder(size(r), size(r)), cuboid(r)),
        },
        PairKind {
            name: "cone-cuboid",
            make: |r| (SharedShape::cone(size(r), size(r)), cuboid(r)),
        },
        PairKind {
            name: "hull-trimesh",
            make: |r| (hull(r), terrain(r)),
        },
    ]
}

/// One case: two shapes, their motions (both as ours and as parry's
/// velocity motions), and the ground truth.
pub struct Case {
    pub shape1: SharedShape,
    pub shape2: SharedShape,
    pub motion1: Motion,
    pub motion2: Motion,
    pub parry1: NonlinearRigidMotion,
    pub parry2: NonlinearRigidMotion,
    pub truth: Truth,
}

fn motion_pair(
    start: Isometry3<f64>,
    com: Point3<f64>,
    v: Vector3<f64>,
    w: Vector3<f64>,
) -> (Motion, NonlinearRigidMotion) {
    let ours = Motion::from_velocities(start, com, v, w, DT).expect("finite case");
    let local_center = start.inverse_transform_point(&com).coords;
    let parry = NonlinearRigidMotion::new(
        pose_from_iso(&start),
        glam_from_vec(&local_center),
        glam_from_vec(&v),
        glam_from_vec(&w),
    );
    (ours, parry)
}

/// How fast the cases' shapes turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spin {
    /// Each component of the angular velocity uniform in ±50 rad/s.
    Ordinary,
    /// 200–1000 rad/s about a random axis (a blade, a drill bit, a
    /// propeller): up to 17 rad, over two and a half turns, in one step.
    Fast,
}

impl Spin {
    /// An angular velocity of this kind, rad/s.
    fn sample(self, rng: &mut Rng) -> Vector3<f64> {
        match self {
            Spin::Ordinary => rng.vector(50.0),
            Spin::Fast => {
                let axis = rng
                    .vector(1.0)
                    .try_normalize(1.0e-6)
                    .unwrap_or(Vector3::y());
                axis * rng.range(200.0, 1000.0)
            }
        }
    }
}

/// `n` seeded cases of `kind` the crate supports: linear speed ≤ 100 m/s,
/// angular ≤ 50 rad/s, dt = 1/60 s, half with both shapes moving, the
/// first shape aimed near the second so that about half of them hit.
pub fn cases(kind: &PairKind, n: usize, seed: u64) -> Vec<Case> {
    cases_spinning(kind, n, seed, Spin::Ordinary)
}

/// As [`cases`], with the shapes turning as `spin` says.
pub fn cases_spinning(kind: &PairKind, n: usize, seed: u64, spin: Spin) -> Vec<Case> {
    let mut rng = Rng::new(seed);
    let mut out = Vec::with_capacity(n);
    let mut tries = 0;
    while out.len() < n && tries < 20 * n {
        tries += 1;
        let (shape1, shape2) = (kind.make)(&mut rng);
        if !query::is_supported(shape1.as_ref(), shape2.as_ref()) {
            break;
        }
        let target = rng.vector(0.5);
        let from = target + rng.vector(1.0).normalize() * rng.range(1.0, 2.5);
        let v1 = (target - from) / DT * rng.range(0.3, 1.2) + rng.vector(20.0);
        let v1 = if v1.norm() > 100.0 {
            v1 * (100.0 / v1.norm())
        } else {
            v1
        };
        let start1 = Isometry3::from_parts(Translation3::from(from), rng.rotation());
        let (motion1, parry1) = motion_pair(
            start1,
            Point3::from(from + rng.vector(0.05)),
            v1,
            spin.sample(&mut rng),
        );
        let both = out.len() % 2 == 1;
        let start2 = Isometry3::from_parts(Translation3::from(target), rng.rotation());
        let (v2, w2) = if both {
            (rng.vector(30.0), spin.sample(&mut rng))
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        let (motion2, parry2) = motion_pair(start2, Point3::from(target), v2, w2);
        let Ok(truth) = truth::sample(
            shape1.as_ref(),
            &motion1,
            shape2.as_ref(),
            &motion2,
            0.0,
            TRUTH_SAMPLES,
        ) else {
            break;
        };
        if truth.first_contact == Some(0.0) {
            continue; // starting in contact is the hard-case tests' business
        }
        out.push(Case {
            shape1,
            shape2,
            motion1,
            motion2,
            parry1,
            parry2,
            truth,
        });
    }
    out
}

/// affine-ccd's `time_of_impact` on the case.
pub fn affine(
    case: &Case,
    options: &query::QueryOptions,
) -> Result<Option<affine_ccd::Toi>, affine_ccd::CcdError> {
    query::time_of_impact(
        case.shape1.as_ref(),
        &case.motion1,
        case.shape2.as_ref(),
        &case.motion2,
        options,
    )
}

/// parry's `cast_shapes_nonlinear` on the case: the fraction of the step,
/// `None` for no hit, `Err` when parry does not support the pair.
pub fn parry_nonlinear(case: &Case) -> Result<Option<f64>, ()> {
    cast_shapes_nonlinear(
        &case.parry1,
        case.shape1.as_ref(),
        &case.parry2,
        case.shape2.as_ref(),
        0.0,
        DT as f32,
        true,
    )
    .map(|hit| hit.map(|h| f64::from(h.time_of_impact) / DT))
    .map_err(|_| ())
}

/// parry's `sweep_time_of_impact` (rapier's default CCD) on the case, from
/// the exact motion's two end poses; `Err` when a shape has no proxy.
pub fn parry_sweep(case: &Case) -> Result<Option<f64>, ()> {
    let proxy1 = ToiProxy::from_shape(case.shape1.as_ref()).ok_or(())?;
    let proxy2 = ToiProxy::from_shape(case.shape2.as_ref()).ok_or(())?;
    let sweep = |m: &Motion, p: &NonlinearRigidMotion| {
        Sweep::from_poses(
            &pose_from_iso(&m.pose_at(0.0)),
            &pose_from_iso(&m.pose_at(1.0)),
            p.local_center,
        )
    };
    let out = sweep_time_of_impact(
        &proxy1,
        &sweep(&case.motion1, &case.parry1),
        &proxy2,
        &sweep(&case.motion2, &case.parry2),
        1.0,
        SWEEP_SLOP,
    );
    Ok(match out.status {
        SweepToiStatus::Separated => None,
        _ => Some(f64::from(out.fraction)),
    })
}
