//! A proptest-driven fuzz of the query API: arbitrary numbers (NaN,
//! infinities, huge and tiny values among them) become shapes, motions and
//! options. The query must answer `Ok` or a typed `Err`, never panic, and an
//! answer must lie in the searched range.
//!
//! The default run is short; `fuzz_query_long` (ignored) runs many more
//! cases: `FUZZ_CASES=2000000 cargo test --release --test fuzz_query -- --ignored`.

use affine_ccd::query::{QueryOptions, time_of_impact};
use affine_ccd::{Arithmetic, Motion, RootStatus, TimeSpan};
use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use rapier3d::parry::math::{Pose, Vector};
use rapier3d::parry::shape::{
    Ball, Capsule, Compound, Cone, Cuboid, Cylinder, HalfSpace, Segment, Shape, SharedShape,
    TriMesh, Triangle,
};

/// Numbers that break naive code, mixed with ordinary ones.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -10.0..10.0f64,
        1 => -1e6..1e6f64,
        1 => prop::sample::select(vec![
            0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, f64::NAN, f64::INFINITY,
            f64::NEG_INFINITY, f64::MIN_POSITIVE, f64::EPSILON, 1e-7,
        ]),
    ]
}

fn v32(v: [f64; 3]) -> Vector {
    Vector::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// A parry shape built from fuzzed numbers, or `None` where parry itself
/// refuses (or panics on) the numbers: that is parry's input, not ours.
fn make_shape(kind: u8, p: &[f64; 9]) -> Option<Box<dyn Shape>> {
    let a = v32([p[0], p[1], p[2]]);
    let b = v32([p[3], p[4], p[5]]);
    let c = v32([p[6], p[7], p[8]]);
    // parry's own panics are expected here; keep them quiet, or the test
    // harness keeps every message and backtrace in memory (gigabytes over
    // millions of cases).
    let loud = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let built = std::panic::catch_unwind(|| -> Option<Box<dyn Shape>> {
        Some(match kind % 10 {
            0 => Box::new(Ball::new(p[0] as f32)),
            1 => Box::new(Cuboid::new(a)),
            2 => Box::new(Capsule::new(a, b, p[6] as f32)),
            3 => Box::new(Segment::new(a, b)),
            4 => Box::new(Triangle::new(a, b, c)),
            5 => Box::new(Cylinder::new(p[0] as f32, p[1] as f32)),
            6 => Box::new(Cone::new(p[0] as f32, p[1] as f32)),
            7 => Box::new(HalfSpace::new(a)),
            8 => Box::new(TriMesh::new(vec![a, b, c], vec![[0, 1, 2]]).ok()?),
            _ => Box::new(Compound::new(vec![
                (Pose::from_translation(a), SharedShape::ball(p[6] as f32)),
                (
                    Pose::from_translation(b),
                    SharedShape::cuboid(1.0, 1.0, 1.0),
                ),
            ])),
        })
    });
    std::panic::set_hook(loud);
    built.ok().flatten()
}

fn make_motion(p: &[f64; 14]) -> Result<Motion, affine_ccd::CcdError> {
    let rotation = UnitQuaternion::new_unchecked(Quaternion::new(p[3], p[4], p[5], p[6]));
    let start = Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), rotation);
    let m = Motion::from_velocities(
        start,
        Point3::new(p[0] + p[7], p[1], p[2]),
        Vector3::new(p[8], p[9], p[10]),
        Vector3::new(p[11], p[12], p[13]),
        1.0 / 60.0,
    )?;
    m.with_acceleration(Vector3::new(p[7], p[8], 0.0))
}

fn check_one(
    kinds: (u8, u8),
    shape_numbers: &[f64; 18],
    motion_numbers: &[f64; 28],
    option_numbers: &[f64; 4],
    arithmetic: usize,
) {
    let s1: [f64; 9] = shape_numbers[..9].try_into().unwrap();
    let s2: [f64; 9] = shape_numbers[9..].try_into().unwrap();
    let (Some(shape1), Some(shape2)) = (make_shape(kinds.0, &s1), make_shape(kinds.1, &s2)) else {
        return;
    };
    let m1: [f64; 14] = motion_numbers[..14].try_into().unwrap();
    let m2: [f64; 14] = motion_numbers[14..].try_into().unwrap();
    let (Ok(motion1), Ok(motion2)) = (make_motion(&m1), make_motion(&m2)) else {
        return;
    };
    let lo = option_numbers[2].abs().min(1.0);
    let options = QueryOptions {
        epsilon: option_numbers[0],
        skin: option_numbers[1],
        arithmetic: Arithmetic::ALL[arithmetic % 4],
        max_evaluations: (option_numbers[3].abs().min(1e4) as u64).max(1),
        time_range: TimeSpan::new(lo, 1.0),
        ..QueryOptions::default()
    };
    if let Ok(Some(toi)) = time_of_impact(
        shape1.as_ref(),
        &motion1,
        shape2.as_ref(),
        &motion2,
        &options,
    ) {
        assert!(
            toi.fraction >= lo && toi.fraction <= 1.0,
            "fraction {} outside [{lo}, 1]",
            toi.fraction
        );
        assert_ne!(toi.status, RootStatus::Separated);
    }
}

fn arrays<const N: usize>() -> impl Strategy<Value = [f64; N]> {
    prop::collection::vec(number(), N).prop_map(|v| v.try_into().unwrap())
}

fn options_numbers() -> impl Strategy<Value = [f64; 4]> {
    (
        prop_oneof![3 => 1e-6..0.5f64, 1 => number()],
        prop_oneof![3 => 0.0..0.1f64, 1 => number()],
        number(),
        number(),
    )
        .prop_map(|(a, b, c, d)| [a, b, c, d])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn fuzz_query(
        kinds in (any::<u8>(), any::<u8>()),
        shapes in arrays::<18>(),
        motions in arrays::<28>(),
        options in options_numbers(),
        arithmetic in 0usize..4,
    ) {
        check_one(kinds, &shapes, &motions, &options, arithmetic);
    }
}

/// Cases of the long run: `FUZZ_CASES` from the environment, else 2,000,000.
fn long_cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000_000)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(long_cases()))]
    #[test]
    #[ignore = "minutes: run by hand and report"]
    fn fuzz_query_long(
        kinds in (any::<u8>(), any::<u8>()),
        shapes in arrays::<18>(),
        motions in arrays::<28>(),
        options in options_numbers(),
        arithmetic in 0usize..4,
    ) {
        check_one(kinds, &shapes, &motions, &options, arithmetic);
    }
}
