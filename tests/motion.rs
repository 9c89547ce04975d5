//! Motion: enclosures contain the exact pose, constructors reproduce their
//! inputs, and terms a body does not have cost nothing.

mod common;

use affine_ccd::{
    Affine, Enclosure, Interval, Motion, Pose, Taylor2, Taylor3, TimeSpan, Trajectory,
};
use common::Rng;
use nalgebra::{Isometry3, Point3, Translation3, Vector3};

const DT: f64 = 1.0 / 60.0;

fn random_motion(rng: &mut Rng, spin: f64) -> Motion {
    let com = rng.vector(5.0);
    let start = Isometry3::from_parts(Translation3::from(com + rng.vector(1.0)), rng.rotation());
    Motion::from_velocities(
        start,
        Point3::from(com),
        rng.vector(100.0),
        rng.vector(spin),
        DT,
    )
    .unwrap()
    .with_acceleration(rng.vector(20.0))
    .unwrap()
}

/// Every entry of `pose` contains `exact`'s (at time `t`, for the message).
fn contains<E: Enclosure>(pose: &Pose<E>, exact: &Isometry3<f64>, t: f64) -> Result<(), String> {
    let r = exact.rotation.to_rotation_matrix();
    for i in 0..3 {
        let range = pose.translation[i].range();
        let x = exact.translation.vector[i];
        // Ground truth is itself f64: allow its rounding.
        let tol = 1e-12 * (1.0 + x.abs());
        if !(range.lo - tol <= x && x <= range.hi + tol) {
            return Err(format!(
                "{:?} t={t}: translation[{i}] {x} not in {range:?}",
                E::KIND
            ));
        }
        for j in 0..3 {
            let range = pose.rotation[(i, j)].range();
            let x = r[(i, j)];
            if !(range.lo - 1e-12 <= x && x <= range.hi + 1e-12) {
                return Err(format!(
                    "{:?} t={t}: R[{i}{j}] {x} not in {range:?}",
                    E::KIND
                ));
            }
        }
    }
    Ok(())
}

/// 17 times evenly spread over `span`.
fn sample_times(span: TimeSpan) -> impl Iterator<Item = f64> {
    (0..=16).map(move |k| span.lo + span.width() * k as f64 / 16.0)
}

/// Every entry of the enclosed pose over `span` contains the exact pose at
/// sampled times of the span.
fn encloses<E: Enclosure>(motion: &Motion, span: TimeSpan) -> Result<(), String> {
    let pose: Pose<E> = motion.pose(span);
    sample_times(span).try_for_each(|t| contains(&pose, &motion.pose_at(t), t))
}

#[test]
fn enclosed_poses_contain_the_exact_motion() {
    let mut rng = Rng::new(5);
    for case in 0..400 {
        // Up to 1000 rad/s: 16 rad, more than two turns, in one step.
        let spin = [0.0, 10.0, 300.0, 1000.0][case % 4];
        let motion = random_motion(&mut rng, spin);
        let lo = rng.range(0.0, 1.0);
        let width = [1.0, 0.1, 1e-3, 1e-6][rng.below(4)];
        let span = TimeSpan::new(lo * (1.0 - width), lo * (1.0 - width) + width);
        for result in [
            encloses::<Interval>(&motion, span),
            encloses::<Affine>(&motion, span),
            encloses::<Taylor2>(&motion, span),
            encloses::<Taylor3>(&motion, span),
        ] {
            result.unwrap_or_else(|e| panic!("case {case} spin {spin}: {e}"));
        }
    }
}

/// Every entry of `a`'s view of `b` over `span` (`Pose::relative`)
/// contains the exact `a⁻¹·b` at sampled times of the span.
fn encloses_relative<E: Enclosure>(a: &Motion, b: &Motion, span: TimeSpan) -> Result<(), String> {
    let rel = a.pose::<E>(span).relative(&b.pose(span));
    sample_times(span).try_for_each(|t| contains(&rel, &a.pose_at(t).inv_mul(&b.pose_at(t)), t))
}

#[test]
fn relative_poses_contain_the_exact_relative_pose() {
    // Either side turning or not: a side that does not turn has an exact
    // rotation, which `relative` multiplies as plain numbers.
    let mut rng = Rng::new(11);
    for case in 0..400 {
        let spins = [(0.0, 0.0), (0.0, 300.0), (300.0, 0.0), (10.0, 1000.0)][case % 4];
        let a = random_motion(&mut rng, spins.0);
        let b = random_motion(&mut rng, spins.1);
        let lo = rng.range(0.0, 1.0);
        let width = [1.0, 0.1, 1e-3, 1e-6][rng.below(4)];
        let span = TimeSpan::new(lo * (1.0 - width), lo * (1.0 - width) + width);
        for result in [
            encloses_relative::<Interval>(&a, &b, span),
            encloses_relative::<Affine>(&a, &b, span),
            encloses_relative::<Taylor2>(&a, &b, span),
        ] {
            result.unwrap_or_else(|e| panic!("case {case} spins {spins:?}: {e}"));
        }
    }
}

#[test]
fn narrow_nodes_give_narrow_poses() {
    // Soundness alone would allow [−∞, ∞]: check the enclosures are useful.
    let mut rng = Rng::new(9);
    let motion = random_motion(&mut rng, 50.0);
    let pose: Pose<Affine> = motion.pose(TimeSpan::new(0.5, 0.5 + 1e-3));
    for i in 0..3 {
        let w = pose.translation[i].range().width();
        assert!(w < 0.01, "translation[{i}] width {w} over a 1e-3 node");
        for j in 0..3 {
            let w = pose.rotation[(i, j)].range().width();
            assert!(w < 1e-3, "R[{i}{j}] width {w} over a 1e-3 node");
        }
    }
}

#[test]
fn from_poses_reproduces_both_poses_with_whole_turns() {
    let mut rng = Rng::new(21);
    for case in 0..300 {
        let start = Isometry3::from_parts(Translation3::from(rng.vector(10.0)), rng.rotation());
        // Angular velocities up to 1000 rad/s: the end pose alone cannot say
        // how many whole turns were made; the hint does.
        let w = rng.vector(1000.0);
        let local_com = Point3::from(rng.vector(0.5));
        let truth =
            Motion::from_velocities(start, start * local_com, rng.vector(50.0), w, DT).unwrap();
        let end = truth.pose_at(1.0);
        let motion = Motion::from_poses(start, end, local_com, DT, w).unwrap();
        for (t, expected) in [(0.0, start), (1.0, end)] {
            let got = motion.pose_at(t);
            let dp = (got.translation.vector - expected.translation.vector).norm();
            let dr = got.rotation.angle_to(&expected.rotation);
            assert!(
                dp < 1e-9 && dr < 1e-9,
                "case {case} t={t}: off by {dp} m, {dr} rad"
            );
        }
        // Same turns as the true motion: the middle matches too.
        let (a, b) = (motion.pose_at(0.5), truth.pose_at(0.5));
        let dr = a.rotation.angle_to(&b.rotation);
        assert!(
            dr < 1e-6,
            "case {case}: middle off by {dr} rad (whole turns lost)"
        );
    }
}

#[test]
fn absent_terms_cost_nothing() {
    // No angular velocity: the rotation is the exact constant start matrix.
    let start = Isometry3::from_parts(
        Translation3::new(1.0, 2.0, 3.0),
        nalgebra::UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3),
    );
    let m = Motion::from_velocities(
        start,
        Point3::new(1.0, 2.0, 3.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::zeros(),
        DT,
    )
    .unwrap();
    let pose: Pose<Affine> = m.pose(TimeSpan::STEP);
    for e in pose.rotation.iter() {
        assert_eq!(e.r, 0.0, "constant rotation entry carries error {e:?}");
        assert_eq!(e.s, 0.0);
    }
    // No acceleration: translation is exactly linear (slope only).
    assert!(pose.translation.x.r < 1e-15, "{:?}", pose.translation.x);
}

#[test]
fn bad_motion_input_is_a_typed_error() {
    let start = Isometry3::identity();
    let o = Point3::origin();
    let z = Vector3::zeros();
    assert!(Motion::from_velocities(start, o, Vector3::new(f64::NAN, 0.0, 0.0), z, DT).is_err());
    assert!(
        Motion::from_velocities(start, o, z, Vector3::new(0.0, f64::INFINITY, 0.0), DT).is_err()
    );
    assert!(Motion::from_velocities(start, o, z, z, -1.0).is_err());
    assert!(Motion::from_velocities(start, o, z, z, f64::NAN).is_err());
    assert!(Motion::from_poses(start, start, o, 0.0, z).is_err());
    let m = Motion::from_velocities(start, o, z, z, DT).unwrap();
    assert!(
        m.with_acceleration(Vector3::new(f64::NAN, 0.0, 0.0))
            .is_err()
    );
    // 1e300 m/s times dt is finite, its square is not: still no panic.
    let huge = Motion::from_velocities(start, o, Vector3::new(1e300, 0.0, 0.0), z, DT);
    if let Ok(m) = huge {
        let pose: Pose<Affine> = m.pose(TimeSpan::STEP);
        let _ = pose.translation.x.range();
    }
}

#[test]
fn a_local_frame_follows_its_parent() {
    let start = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.3, 0.2, -0.1));
    let parent = Motion::from_velocities(
        start,
        Point3::new(1.2, -1.8, 0.4),
        Vector3::new(20.0, -5.0, 3.0),
        Vector3::new(40.0, 10.0, -25.0),
        DT,
    )
    .unwrap()
    .with_acceleration(Vector3::new(0.0, -9.81, 0.0))
    .unwrap();
    let local = Isometry3::new(Vector3::new(0.4, 0.0, -0.7), Vector3::new(0.0, 1.1, 0.2));
    let child = parent.with_local_frame(&local);
    for i in 0..=16 {
        let tau = f64::from(i) / 16.0;
        let expected = parent.pose_at(tau) * local;
        let got = child.pose_at(tau);
        let dp = (expected.translation.vector - got.translation.vector).norm();
        let dr = expected.rotation.angle_to(&got.rotation);
        assert!(
            dp < 1e-12 && dr < 1e-12,
            "τ = {tau}: {dp} m, {dr} rad apart"
        );
        // The child's enclosed pose holds its exact pose.
        let pose: Pose<Affine> = child.pose(TimeSpan::new(tau, tau));
        for k in 0..3 {
            let x = pose.translation[k].range();
            assert!(
                x.lo - 1e-12 <= got.translation.vector[k]
                    && got.translation.vector[k] <= x.hi + 1e-12
            );
        }
    }
}

/// The balls test's bounds hold on the exact motion: a point of the frame
/// stays within `reach` of the rotation centre however the body turns,
/// over a node the centres never come closer than `centres_gap`, and a
/// centre seen from a frame that does not turn strays no farther than
/// `centre_seen_from` says (fast spins, accelerated paths, nodes of every
/// width).
#[test]
fn balls_bound_the_exact_motion() {
    let mut rng = Rng::new(31);
    let mut positive = 0;
    for case in 0..400 {
        let com = [rng.vector(3.0), rng.vector(3.0)];
        let motion = |rng: &mut Rng, com: Vector3<f64>| {
            let start =
                Isometry3::from_parts(Translation3::from(com + rng.vector(1.0)), rng.rotation());
            Motion::from_velocities(
                start,
                Point3::from(com),
                rng.vector(150.0),
                rng.vector(600.0),
                DT,
            )
            .unwrap()
            .with_acceleration(rng.vector(3000.0))
            .unwrap()
        };
        let (a, b) = (motion(&mut rng, com[0]), motion(&mut rng, com[1]));
        // A frame that slides without turning, for `centre_seen_from`.
        let still = Motion::from_velocities(
            Isometry3::from_parts(Translation3::from(rng.vector(3.0)), rng.rotation()),
            Point3::from(rng.vector(3.0)),
            rng.vector(150.0),
            Vector3::zeros(),
            DT,
        )
        .unwrap()
        .with_acceleration(rng.vector(3000.0))
        .unwrap();
        // The centre of mass is fixed in the body: where it is at `t`.
        let local_com = a.pose_at(0.0).inverse() * Point3::from(com[0]);
        let local_com_b = b.pose_at(0.0).inverse() * Point3::from(com[1]);
        let point = Point3::from(rng.vector(2.0));
        let reach = a.reach(&point.coords, 0.0);
        let lo = rng.range(0.0, 1.0);
        let hi = if case % 4 == 0 {
            lo
        } else {
            rng.range(lo, 1.0)
        };
        let span = TimeSpan::new(lo, hi);
        let gap = a.centres_gap(&b, span);
        positive += usize::from(gap > 0.0);
        assert!(a.centre_seen_from(&b, span).is_none(), "a turns");
        let (seen, stray) = still.centre_seen_from(&a, span).unwrap();
        for t in sample_times(span) {
            let from_still = still.pose_at(t).inverse() * (a.pose_at(t) * local_com);
            let off = (from_still.coords - seen).norm();
            assert!(
                off <= stray + 1e-12,
                "case {case} τ = {t}: strays {off} > {stray}"
            );
        }
        for t in sample_times(span) {
            let (pa, pb) = (a.pose_at(t), b.pose_at(t));
            let (ca, cb) = (pa * local_com, pb * local_com_b);
            let from_centre = (pa * point - ca).norm();
            assert!(
                from_centre <= reach + 1e-12,
                "case {case}: {from_centre} > reach {reach}"
            );
            let apart = (ca - cb).norm();
            assert!(
                apart >= gap - 1e-12,
                "case {case} τ = {t}: centres {apart} < gap {gap}"
            );
        }
    }
    // The bound is not vacuous: most nodes see the centres apart.
    assert!(positive > 200, "only {positive} of 400 nodes showed a gap");
}

/// `points_approach_within` never says a pair of point hulls stays within
/// a budget that the exact motion exceeds (dense sampling of `pose_at`),
/// and says so for most pairs given a little room above the sampled
/// growth (moving and turning shapes, a turning one against one that only
/// slides, accelerated paths).
#[test]
fn points_approach_holds_the_exact_motion() {
    let mut rng = Rng::new(47);
    let (mut checked, mut proved, mut leaving, mut left) = (0, 0, 0, 0);
    for case in 0..300 {
        let a = random_motion(&mut rng, 60.0);
        // Every third one slides without turning.
        let b = random_motion(&mut rng, if case % 3 == 0 { 0.0 } else { 60.0 });
        let hull = |rng: &mut Rng| {
            let count = 1 + (rng.range(0.0, 8.0) as usize);
            (0..count).map(|_| rng.vector(0.5)).collect::<Vec<_>>()
        };
        let (p, q) = (hull(&mut rng), hull(&mut rng));
        let n = rng.vector(1.0).normalize();
        // The support of a point set along `d` carried by `m` at `t`.
        let support = |m: &Motion, points: &[Vector3<f64>], d: &Vector3<f64>, t: f64| {
            let pose = m.pose_at(t);
            points
                .iter()
                .map(|v| d.dot(&(pose * Point3::from(*v)).coords))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let start = support(&a, &p, &n, 0.0) + support(&b, &q, &-n, 0.0);
        let grown = (0..=4000)
            .map(|k| {
                let t = k as f64 / 4000.0;
                support(&a, &p, &n, t) + support(&b, &q, &-n, t) - start
            })
            .fold(0.0f64, f64::max);
        if grown > 1.0e-6 {
            checked += 1;
            assert!(
                !a.points_approach_within(&n, &p, &b, &q, grown * (1.0 - 1.0e-6)),
                "case {case}: within {grown} though the motion grows that much"
            );
        }
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!(
            !a.points_approach_within(&nan, &p, &b, &q, 1.0),
            "NaN proves nothing"
        );
        let room = grown + 1.0e-3 + 0.05 * grown;
        proved += usize::from(a.points_approach_within(&n, &p, &b, &q, room));
        if grown == 0.0 {
            // Leaving along `n` from the start: no room needed.
            leaving += 1;
            left += usize::from(a.points_approach_within(&n, &p, &b, &q, 0.0));
        }
    }
    assert!(
        leaving > 20 && left * 2 > leaving,
        "{left} of {leaving} leaving pairs proved with no room"
    );
    assert!(checked > 100, "only {checked} cases grew");
    assert!(
        proved > 200,
        "only {proved} of 300 proved with room to spare"
    );
}
