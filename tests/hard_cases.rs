//! Hard cases with exact answers: grazing at the skin, contact at the ends
//! of the step, many turns per step, tiny and huge scales, far from the
//! origin, and determinism. Inputs are f32 values, as rapier gives them.

mod common;

use affine_ccd::query::{QueryOptions, time_of_impact};
use affine_ccd::{Arithmetic, Motion, RootStatus, Trajectory};
use common::pose64;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rapier3d::parry::shape::Ball;

const DT: f64 = 1.0 / 60.0;

/// An f32-exact position, as rapier would hand it over.
fn p32(x: f64, y: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x as f32 as f64, y as f32 as f64, z as f32 as f64)
}

fn linear(at: Vector3<f64>, velocity: Vector3<f64>) -> Motion {
    Motion::from_velocities(
        Isometry3::from_parts(Translation3::from(at), UnitQuaternion::identity()),
        Point3::from(at),
        velocity,
        Vector3::zeros(),
        DT,
    )
    .unwrap()
}

fn ball_toi(
    r1: f32,
    m1: &Motion,
    r2: f32,
    m2: &Motion,
    options: &QueryOptions,
) -> Option<affine_ccd::Toi> {
    time_of_impact(&Ball::new(r1), m1, &Ball::new(r2), m2, options).unwrap()
}

#[test]
fn grazing_at_the_skin_is_decided_by_the_side_of_the_skin() {
    // Ball 1 (r = 0.5) passes ball 2 (r = 0.5) with its centre's closest
    // approach 1 + skin + offset; skin = 0.01.
    let skin = 0.01;
    for kind in Arithmetic::ALL {
        let options = QueryOptions {
            skin,
            arithmetic: kind,
            epsilon: 1e-6,
            ..QueryOptions::default()
        };
        for (offset, must_hit) in [(-1e-6, true), (1e-4, false), (-1e-4, true)] {
            let y = 1.0 + skin + offset;
            let m1 = linear(Vector3::new(-1.0, y, 0.0), Vector3::new(120.0, 0.0, 0.0));
            let m2 = Motion::fixed(Isometry3::identity()).unwrap();
            let got = ball_toi(0.5, &m1, 0.5, &m2, &options);
            if must_hit {
                let toi = got
                    .unwrap_or_else(|| panic!("{kind:?}: missed a pass {offset} inside the skin"));
                // Closest approach is at x = 0: τ = 1/2.
                assert!(
                    toi.fraction <= 0.5 + 1e-9,
                    "{kind:?}: {} after closest approach",
                    toi.fraction
                );
            } else {
                assert!(
                    got.is_none(),
                    "{kind:?}: a pass {offset} outside the skin reported {got:?}"
                );
            }
        }
    }
}

#[test]
fn contact_at_the_start_and_at_the_end_of_the_step() {
    let options = QueryOptions::default();
    // Touching at τ = 0: reported as such.
    let m1 = linear(Vector3::new(-1.0, 0.0, 0.0), Vector3::new(-60.0, 0.0, 0.0));
    let m2 = Motion::fixed(Isometry3::identity()).unwrap();
    let toi = ball_toi(0.5, &m1, 0.5, &m2, &options).expect("touching at the start");
    assert_eq!(toi.status, RootStatus::InitiallyTouching);
    assert_eq!(toi.fraction, 0.0);
    // Contact exactly at τ = 1: centre from x = −2 to −1 in the step.
    let m1 = linear(Vector3::new(-2.0, 0.0, 0.0), Vector3::new(60.0, 0.0, 0.0));
    let toi = ball_toi(0.5, &m1, 0.5, &m2, &options).expect("touching at the end");
    assert_eq!(toi.status, RootStatus::Hit);
    assert!(
        toi.fraction <= 1.0 && 1.0 - toi.fraction <= options.epsilon,
        "{}",
        toi.fraction
    );
}

/// Earliest sampled τ at which the two ball centres come within `reach`.
fn sampled(m1: &Motion, m2: &Motion, reach: f64) -> Option<f64> {
    let gap = |t: f64| {
        (m1.pose_at(t).translation.vector - m2.pose_at(t).translation.vector).norm() - reach
    };
    let n = 1 << 16;
    (0..=n)
        .map(|i| i as f64 / n as f64)
        .find(|&t| gap(t) <= 0.0)
}

#[test]
fn many_turns_in_one_step_stay_correct() {
    // A ball 1 m off the axis of a body turning by π, 2π and 20π in one
    // step sweeps past a fixed ball placed on its circle.
    for turns in [0.5, 1.0, 10.0] {
        let w = std::f64::consts::TAU * turns / DT;
        let start = Isometry3::translation(1.0, 0.0, 0.0);
        let m1 = Motion::from_velocities(
            start,
            Point3::origin(),
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, w),
            DT,
        )
        .unwrap();
        // The target sits at angle 3π/4 (reached after 3/8 of a turn).
        let a = 0.75 * std::f64::consts::PI;
        let m2 = Motion::fixed(Isometry3::translation(a.cos(), a.sin(), 0.0)).unwrap();
        let truth = sampled(&m1, &m2, 0.2);
        for kind in Arithmetic::ALL {
            let options = QueryOptions {
                arithmetic: kind,
                ..QueryOptions::default()
            };
            let toi = ball_toi(0.1, &m1, 0.1, &m2, &options);
            match (truth, toi) {
                (Some(t), Some(toi)) => {
                    assert!(
                        toi.fraction <= t + 1e-9,
                        "{turns} turns {kind:?}: {} after {t}",
                        toi.fraction
                    );
                    assert!(
                        t - toi.fraction <= 2e-4,
                        "{turns} turns {kind:?}: {} vs {t}",
                        toi.fraction
                    );
                }
                (Some(t), None) if turns >= 0.5 => panic!("{turns} turns {kind:?}: missed {t}"),
                _ => {}
            }
        }
        assert!(truth.is_some(), "{turns} turns: the set-up should collide");
    }
}

#[test]
fn tiny_huge_and_far_shapes() {
    // (radius, distance scale, origin offset)
    for (r, scale, far) in [
        (1e-4, 1e-3, 0.0),
        (1e4, 3e4, 0.0),
        (0.5, 2.0, 1e4),
        (0.5, 2.0, 1e5),
    ] {
        let origin = p32(far, far, -far);
        let m1 = linear(
            origin + p32(-scale, 0.0, 0.0),
            Vector3::new(2.0 * scale / DT, 0.0, 0.0),
        );
        let m2 = Motion::fixed(Isometry3::translation(origin.x, origin.y, origin.z)).unwrap();
        let reach = 2.0 * f64::from(r as f32);
        // The centre travels along x (from about −scale to +scale, as
        // rounded to f32): contact when x = origin − reach.
        let x0 = m1.pose_at(0.0).translation.x - origin.x;
        let t_true = (-reach - x0) / m1.displacement().x;
        let toi = ball_toi(r as f32, &m1, r as f32, &m2, &QueryOptions::default())
            .unwrap_or_else(|| panic!("r={r} scale={scale} far={far}: missed"));
        assert!(
            toi.fraction <= t_true + 1e-9,
            "r={r} far={far}: {} after {t_true}",
            toi.fraction
        );
        assert!(
            t_true - toi.fraction <= 1e-4 + 1e-9,
            "r={r} far={far}: {} vs {t_true}",
            toi.fraction
        );
    }
}

#[test]
fn zero_motion_and_rotation_about_the_contact_point() {
    let options = QueryOptions::default();
    // Two apart balls, neither moving: no impact, cheaply.
    let m1 = Motion::fixed(Isometry3::translation(-1.0, 0.0, 0.0)).unwrap();
    let m2 = Motion::fixed(Isometry3::translation(1.0, 0.0, 0.0)).unwrap();
    let got = time_of_impact(&Ball::new(0.5), &m1, &Ball::new(0.5), &m2, &options).unwrap();
    assert!(got.is_none());
    // A ball spinning about its own centre, next to another: its centre
    // does not move, so nothing happens however fast it spins.
    let m1 = Motion::from_velocities(
        Isometry3::translation(-1.0, 0.0, 0.0),
        Point3::new(-1.0, 0.0, 0.0),
        Vector3::zeros(),
        Vector3::new(0.0, 0.0, 1000.0),
        DT,
    )
    .unwrap();
    let got = time_of_impact(&Ball::new(0.5), &m1, &Ball::new(0.49), &m2, &options).unwrap();
    assert!(got.is_none(), "a ball spinning in place reported {got:?}");
}

#[test]
fn same_input_same_output_bit_for_bit() {
    let run = || {
        let m1 = Motion::from_velocities(
            Isometry3::translation(-1.0, 0.2, 0.1),
            Point3::new(-1.2, 0.2, 0.1),
            Vector3::new(90.0, 1.0, -2.0),
            Vector3::new(3.0, 40.0, -7.0),
            DT,
        )
        .unwrap();
        let m2 = Motion::fixed(Isometry3::translation(0.5, 0.0, 0.0)).unwrap();
        Arithmetic::ALL.map(|kind| {
            let options = QueryOptions {
                arithmetic: kind,
                ..QueryOptions::default()
            };
            time_of_impact(&Ball::new(0.3), &m1, &Ball::new(0.3), &m2, &options)
                .unwrap()
                .map(|t| (t.fraction.to_bits(), t.stats.pair_evaluations))
        })
    };
    let first = run();
    assert!(
        first.iter().all(Option::is_some),
        "the set-up should hit: {first:?}"
    );
    for _ in 0..5 {
        assert_eq!(run(), first);
    }
}

#[test]
fn bad_options_and_sizes_are_typed_errors_naming_the_value() {
    let m = Motion::fixed(Isometry3::identity()).unwrap();
    for (options, name) in [
        (
            QueryOptions {
                epsilon: 0.0,
                ..QueryOptions::default()
            },
            "epsilon",
        ),
        (
            QueryOptions {
                epsilon: f64::NAN,
                ..QueryOptions::default()
            },
            "epsilon",
        ),
        (
            QueryOptions {
                skin: -1.0,
                ..QueryOptions::default()
            },
            "skin",
        ),
        (
            QueryOptions {
                skin: f64::INFINITY,
                ..QueryOptions::default()
            },
            "skin",
        ),
        (
            QueryOptions {
                max_evaluations: 0,
                ..QueryOptions::default()
            },
            "max_evaluations",
        ),
    ] {
        let err = time_of_impact(&Ball::new(1.0), &m, &Ball::new(1.0), &m, &options).unwrap_err();
        assert!(err.to_string().contains(name), "{err} does not name {name}");
    }
    for radius in [f32::NAN, f32::INFINITY, -1.0] {
        let err = time_of_impact(
            &Ball::new(radius),
            &m,
            &Ball::new(1.0),
            &m,
            &QueryOptions::default(),
        );
        let err = err.expect_err("a bad radius must be an error");
        assert!(err.to_string().contains("radius"), "{err}");
    }
    // A huge but finite budget is fine.
    let options = QueryOptions {
        max_evaluations: u64::MAX,
        ..QueryOptions::default()
    };
    assert!(time_of_impact(&Ball::new(1.0), &m, &Ball::new(1.0), &m, &options).is_ok());
}

use rapier3d::parry::math::Vector;
use rapier3d::parry::shape::{Capsule, Cuboid, Shape, TriMesh, Triangle};

/// Earliest sampled contact of two shapes by parry's distance (f32 poses).
fn sampled_contact(s1: &dyn Shape, m1: &Motion, s2: &dyn Shape, m2: &Motion) -> Option<f64> {
    affine_ccd_scenes::truth::sample(s1, m1, s2, m2, 0.0, 4096)
        .expect("parry answers")
        .first_contact
}

#[test]
fn parallel_faces_and_edges_of_aligned_boxes() {
    // Aligned boxes: every cross-product axis vanishes (|n| = 0). Face to
    // face, and edge to edge (one box turned 90° about z, still parallel).
    let a = Cuboid::new(Vector::new(0.5, 0.5, 0.5));
    let b = Cuboid::new(Vector::new(0.5, 0.2, 0.5));
    for (turn, offset_y) in [(0.0, 0.0), (std::f64::consts::FRAC_PI_2, 0.0), (0.0, 0.69)] {
        let start = Isometry3::from_parts(
            Translation3::new(-2.0, offset_y, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, turn),
        );
        let m1 = Motion::from_velocities(
            start,
            Point3::new(-2.0, offset_y, 0.0),
            Vector3::new(120.0, 0.0, 0.0),
            Vector3::zeros(),
            DT,
        )
        .unwrap();
        let m2 = Motion::fixed(Isometry3::identity()).unwrap();
        let truth = sampled_contact(&a, &m1, &b, &m2);
        for kind in Arithmetic::ALL {
            let options = QueryOptions {
                arithmetic: kind,
                ..QueryOptions::default()
            };
            let got = time_of_impact(&a, &m1, &b, &m2, &options).unwrap();
            match (truth, got) {
                (Some(t), Some(toi)) => {
                    assert!(
                        toi.fraction <= t + 1e-6,
                        "turn {turn} {kind:?}: {} after {t}",
                        toi.fraction
                    );
                    assert!(
                        t - toi.fraction <= 1e-3,
                        "turn {turn} {kind:?}: {} long before {t}",
                        toi.fraction
                    );
                }
                (Some(t), None) => panic!("turn {turn} {kind:?}: missed the contact at {t}"),
                (None, _) => panic!("turn {turn}: the set-up should collide"),
            }
        }
    }
}

#[test]
fn degenerate_shapes_answer_without_panic() {
    let fixed = Motion::fixed(Isometry3::identity()).unwrap();
    let flying = Motion::from_velocities(
        Isometry3::translation(-2.0, 0.0, 0.0),
        Point3::new(-2.0, 0.0, 0.0),
        Vector3::new(150.0, 0.0, 0.0),
        Vector3::new(0.0, 0.0, 30.0),
        DT,
    )
    .unwrap();
    let flat_box = Cuboid::new(Vector::new(0.0, 0.5, 0.5)); // zero half-extent
    let point_capsule = Capsule::new(Vector::ZERO, Vector::ZERO, 0.2); // zero length
    let sliver = Triangle::new(
        Vector::new(0.0, -1.0, 0.0),
        Vector::new(0.0, 0.0, 0.0),
        Vector::new(0.0, 1.0, 0.0),
    ); // zero area
    let wall = Cuboid::new(Vector::new(0.05, 1.0, 1.0));
    let shapes: [(&str, &dyn Shape); 3] = [
        ("flat box", &flat_box),
        ("point capsule", &point_capsule),
        ("sliver triangle", &sliver),
    ];
    for (name, shape) in shapes {
        let got = time_of_impact(shape, &flying, &wall, &fixed, &QueryOptions::default());
        match got {
            // Each sweeps through the wall's plane: a sound answer must hit.
            Ok(Some(toi)) => assert!(toi.fraction < 1.0, "{name}: {toi:?}"),
            Ok(None) => panic!("{name}: passed through the wall unreported"),
            Err(e) => println!("{name}: typed error {e}"),
        }
    }
    // An empty mesh cannot even be built by parry; a mesh of one zero-area
    // triangle can, and must not panic.
    let empty = TriMesh::new(vec![Vector::ZERO; 3], vec![[0, 1, 2]]);
    if let Ok(mesh) = empty {
        let got = time_of_impact(
            &Ball::new(0.1),
            &flying,
            &mesh,
            &fixed,
            &QueryOptions::default(),
        );
        println!("degenerate mesh: {got:?}");
    }
    // Collinear hull points: parry refuses the hull, so there is nothing to ask.
    let collinear = [
        Vector::new(0.0, 0.0, 0.0),
        Vector::new(1.0, 0.0, 0.0),
        Vector::new(2.0, 0.0, 0.0),
    ];
    assert!(rapier3d::parry::shape::ConvexPolyhedron::from_convex_hull(&collinear).is_none());
}

#[test]
fn witness_normal_against_a_rotated_half_space_points_into_it() {
    // A ball falling onto a floor tilted by 0.3 rad, the floor second.
    let floor = rapier3d::parry::shape::HalfSpace::new(Vector::new(0.0, 1.0, 0.0));
    let tilt = UnitQuaternion::from_euler_angles(0.3, 0.0, 0.0);
    let m2 = Motion::fixed(Isometry3::from_parts(Translation3::identity(), tilt)).unwrap();
    let m1 = linear(Vector3::new(0.0, 2.0, 0.0), Vector3::new(0.0, -200.0, 0.0));
    let toi = time_of_impact(&Ball::new(0.5), &m1, &floor, &m2, &QueryOptions::default())
        .unwrap()
        .expect("the ball reaches the floor");
    let up = tilt * Vector3::y();
    // The normal from the ball towards the floor is minus the floor's normal.
    assert!(
        (toi.normal1 + up).norm() < 1e-3,
        "normal {:?}, floor normal {up:?}",
        toi.normal1
    );
}

/// A motion as the accuracy report's cases print it: the centre of mass,
/// the frame's origin from it, the start rotation (quaternion `[i, j, k, w]`),
/// and the step's displacement and rotation vector.
fn printed_motion(
    center: [f64; 3],
    arm: [f64; 3],
    q: [f64; 4],
    d: [f64; 3],
    w: [f64; 3],
) -> Motion {
    let center = Point3::from(Vector3::from(center));
    let rotation =
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2]));
    let start = Isometry3::from_parts(
        Translation3::from(center.coords + Vector3::from(arm)),
        rotation,
    );
    let (d, w) = (Vector3::from(d), Vector3::from(w));
    Motion::from_velocities(start, center, d / DT, w / DT, DT).unwrap()
}

/// A cylinder (`hh`, `r`) on `m1` closing on a box (`half`) on `m2`:
/// the reported time and the first touch in `f64` (parry3d-f64's distance,
/// dense sampling then bisection), as the last time found apart.
fn cylinder_box_report_and_touch(
    (hh, r): (f32, f32),
    half: [f32; 3],
    m1: &Motion,
    m2: &Motion,
    options: &QueryOptions,
) -> (f64, f64) {
    use parry3d_f64 as p64;
    use rapier3d::parry::shape::{Cuboid, Cylinder};
    let toi = time_of_impact(
        &Cylinder::new(hh, r),
        m1,
        &Cuboid::new(rapier3d::math::Vector::from(half)),
        m2,
        options,
    )
    .unwrap()
    .expect("the shapes meet");
    let s1 = p64::shape::Cylinder::new(f64::from(hh), f64::from(r));
    let s2 = p64::shape::Cuboid::new(p64::math::Vector::new(
        f64::from(half[0]),
        f64::from(half[1]),
        f64::from(half[2]),
    ));
    let gap = |t: f64| {
        p64::query::distance(&pose64(&m1.pose_at(t)), &s1, &pose64(&m2.pose_at(t)), &s2)
            .unwrap()
            .distance
    };
    let n = 20_000;
    let k = (1..=n)
        .find(|&k| gap(k as f64 / n as f64) <= 0.0)
        .expect("f64 touch");
    let (mut apart, mut touching) = ((k - 1) as f64 / n as f64, k as f64 / n as f64);
    for _ in 0..40 {
        let mid = 0.5 * (apart + touching);
        if gap(mid) <= 0.0 {
            touching = mid;
        } else {
            apart = mid;
        }
    }
    (toi.fraction, apart)
}

/// A cylinder closing on a box at a shallow angle (found by the accuracy
/// report's cases: seed 7, cylinder–cuboid 29; seed 1005, cylinder–cuboid
/// 55): the adaptive axes took their direction from parry's `f32` GJK, a
/// few milliradians off here, along which the shapes showed 2 mm deep while
/// 1.7 mm apart. The search took such a point for a touch and reported the
/// first case 5.0e-4 of the step early (5 ε). With parry's distance
/// bounding that check it was 3.4e-4 early, and the second 2.4e-3 early
/// (where parry's warm-started GJK answered "intersecting" 1.07 mm apart);
/// with the narrow nodes' direction from GJK in `f64` both are within ε of
/// the first touch found in `f64`.
#[test]
fn a_shallow_cylinder_box_approach_is_reported_close_to_the_touch() {
    let case_29 = (
        (0.8003557f32, 0.8690821f32),
        [0.3502107f32, 0.89540744, 0.9304288],
        printed_motion(
            [
                -0.7444782843315281,
                -0.20856681525938342,
                -1.2388350512691415,
            ],
            [
                -0.014825141173265166,
                -0.00821375182035039,
                0.02877935887040506,
            ],
            [
                0.2322877994215283,
                -0.6512566350266016,
                0.6211508401575709,
                0.36888861102679155,
            ],
            [0.5854513649654208, 0.0682639628757926, 0.48064533034465323],
            [
                -0.11138046175945865,
                -0.5475068500634559,
                0.4258935008602099,
            ],
        ),
        printed_motion(
            [
                0.24817660356311788,
                0.18402566716608015,
                -0.20251212053136713,
            ],
            [0.0; 3],
            [
                0.3762939143389381,
                -0.41098671055259584,
                0.149682133950857,
                0.816754597511734,
            ],
            [
                0.027556115330076084,
                -0.007228676758021398,
                -0.36335685540013296,
            ],
            [
                0.7707762216718657,
                -0.45868290276025625,
                -0.20148217002916707,
            ],
        ),
    );
    let case_55 = (
        (0.2899096f32, 0.35077906f32),
        [0.8540467f32, 0.9836802, 0.8918304],
        printed_motion(
            [-0.9909249424724214, -0.4956051067074419, 0.9978914346838876],
            [
                0.04057584957563787,
                -0.047052142786025264,
                0.034121009838355754,
            ],
            [
                0.7528543622752961,
                0.6520533355955759,
                0.07430839886945775,
                0.05014996110863868,
            ],
            [0.649275588734729, 0.7645226120790484, -1.0885627111177039],
            [
                -0.07914908528109628,
                -0.1128298352188029,
                -0.7454626349524358,
            ],
        ),
        printed_motion(
            [-0.349950938571302, 0.4991977572430377, -0.4319063505680609],
            [0.0; 3],
            [
                -0.036999829664185406,
                -0.14795161668983217,
                -0.13730932552038402,
                -0.9787172629768127,
            ],
            [
                0.08602714285117846,
                0.4378459622426085,
                -0.09572863779701611,
            ],
            [0.46638709267211975, -0.83161869411016, -0.4630209410103588],
        ),
    );
    let options = QueryOptions::default();
    for (name, (cylinder, half, m1, m2)) in [("29", case_29), ("55", case_55)] {
        let (reported, apart) = cylinder_box_report_and_touch(cylinder, half, &m1, &m2, &options);
        let early = apart - reported;
        println!("case {name}: reported {reported} touch {apart} early {early:e}");
        assert!(
            early >= 0.0,
            "case {name}: reported {reported} after the touch {apart}"
        );
        assert!(
            early <= options.epsilon,
            "case {name}: reported {reported} is {early:e} of the step before the touch {apart}"
        );
    }
}

/// A spinning cone whose rim passes 1.4 to 3 mm above a floor box over the
/// step (from a scratch run of a cone rolling off at 25 rad/s, which the
/// stage clamped in mid-air, losing 8 cm of its path): no touch within
/// any skin below that, and few evaluations to prove it. Asked twice at
/// one time of the search, parry's GJK in `f64`, started the second time
/// from the simplex it had converged on there, answered that the shapes
/// overlap, and the search took that for a touch at 0.084 of the step.
#[test]
fn a_cone_skimming_a_floor_box_is_not_touching() {
    use nalgebra::Quaternion;
    use rapier3d::parry::shape::Cone;
    let pose = |t: [f32; 3], q: [f32; 4]| {
        let [x, y, z, w] = q.map(f64::from);
        Isometry3::from_parts(
            Translation3::from(Vector3::from(t.map(f64::from))),
            UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)),
        )
    };
    let start = pose(
        [1.962_297_8, 0.451_285_24, 0.313_059_36],
        [0.295_678_2, -0.396_332_8, 0.275_600_6, 0.824_341_65],
    );
    let end = pose(
        [2.037_632_2, 0.458_049_06, 0.353_768_86],
        [0.339_859_07, -0.546_069_2, 0.152_867_48, 0.750_290_5],
    );
    let spin = Vector3::new(17.630_081, -12.749_682, -13.306_724).map(|x: f32| x as f64);
    let cone_motion =
        Motion::from_poses(start, end, Point3::new(0.0, -0.15, 0.0), DT, spin).unwrap();
    let floor_motion = Motion::fixed(Isometry3::identity()).unwrap();
    let (cone, floor) = (
        Cone::new(0.3, 0.2),
        Cuboid::new(Vector::new(20.0, 0.1, 20.0)),
    );
    // Ground truth: parry3d-f64's distance along the exact motion.
    let (cone64, floor64) = (
        parry3d_f64::shape::Cone::new(0.3, 0.2),
        parry3d_f64::shape::Cuboid::new(parry3d_f64::math::Vector::new(20.0, 0.1, 20.0)),
    );
    let least = (0..=1000)
        .map(|k| {
            let p = pose64(&cone_motion.pose_at(k as f64 / 1000.0));
            let identity = parry3d_f64::math::Pose::IDENTITY;
            parry3d_f64::query::distance(&p, &cone64, &identity, &floor64)
                .unwrap()
                .distance
        })
        .fold(f64::INFINITY, f64::min);
    assert!(least > 1.4e-3, "the rim comes within {least} m");
    for skin in [0.0, 1.0e-3] {
        let options = QueryOptions {
            skin,
            ..QueryOptions::default()
        };
        let mut query = affine_ccd::query::Query::default();
        let found = query
            .one(&cone, &cone_motion, &floor, &floor_motion, &options)
            .unwrap();
        assert!(
            found.is_none(),
            "skin {skin}: a touch reported at {:?}, the rim never within {least} m",
            found.map(|t| t.fraction)
        );
        // The work: along the floor's face normal the rim is proved apart
        // at once; along parry's directions, a milliradian off, the floor's
        // 20 m reach swallowed the 0.4 mm left over the skin and the search
        // took 2,211 evaluations.
        let spent = query.spent().pair_evaluations;
        assert!(spent <= 50, "skin {skin}: {spent} evaluations");
    }
}

#[test]
fn a_blade_spinning_flat_over_a_floor_is_proved_apart_at_once() {
    // A 1 m blade and a 0.8 m disc, 2 cm thick, spin at 900 rad/s (15 rad,
    // over two turns, in the step) about the vertical, 2 cm over a floor
    // box, sliding along it. However far they turn they stay in their
    // slab: the family proves each apart over the whole step at once (a
    // shape turning that far is otherwise only evaluated on nodes over
    // which it turns less: 31 evaluations here).
    use rapier3d::parry::shape::Cylinder;
    let floor = Cuboid::new(Vector::new(20.0, 0.1, 20.0));
    let floor_motion = Motion::fixed(Isometry3::identity()).unwrap();
    let (blade, disc) = (
        Cuboid::new(Vector::new(0.5, 0.01, 0.05)),
        Cylinder::new(0.01, 0.4),
    );
    let spinning = |height: f64, spin: Vector3<f64>| {
        let at = p32(0.2, height, -0.1);
        let start = Isometry3::from_parts(Translation3::from(at), UnitQuaternion::identity());
        Motion::from_velocities(
            start,
            Point3::from(at),
            Vector3::new(3.0, 0.0, 1.0),
            spin,
            DT,
        )
        .unwrap()
    };
    let flat = spinning(0.13, Vector3::new(0.0, 900.0, 0.0));
    let shapes: [(&str, &dyn Shape); 2] = [("blade", &blade), ("disc", &disc)];
    for (name, shape) in shapes {
        let mut query = affine_ccd::query::Query::default();
        let found = query
            .one(
                shape,
                &flat,
                &floor,
                &floor_motion,
                &QueryOptions::default(),
            )
            .unwrap();
        assert!(found.is_none(), "{name}: a touch at {found:?}");
        let spent = query.spent().pair_evaluations;
        assert!(spent <= 3, "{name}: {spent} evaluations");
    }
    // The blade turning over about a level axis, its tip dipping 5 cm into
    // the floor: found no later than the sampled truth's first contact.
    let over = spinning(0.55, Vector3::new(0.0, 0.0, 900.0));
    let truth = sampled_contact(&blade, &over, &floor, &floor_motion).expect("the tip dips");
    let found = time_of_impact(
        &blade,
        &over,
        &floor,
        &floor_motion,
        &QueryOptions::default(),
    )
    .unwrap()
    .expect("a touch");
    assert!(
        found.fraction <= truth && found.fraction > truth - 0.01,
        "found {} against the truth's {truth}",
        found.fraction
    );
}
