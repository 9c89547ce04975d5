//! The earliest-root solver against exact answers: two balls in linear
//! motion (analytic), balls on spinning bodies (dense sampling), and random
//! AND/OR sets of polynomial axes (brute force).

mod common;

use affine_ccd::query::{QueryOptions, time_of_impact};
use affine_ccd::solve::{GapSet, SolveOptions, SolveOutcome, Solver};
use affine_ccd::{
    Arithmetic, CcdError, Enclosure, InArithmetic, Motion, RootStatus, TimeSpan, Trajectory,
};
use common::{Rng, quantile};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rapier3d::parry::shape::Ball;

const DT: f64 = 1.0 / 60.0;

/// The first τ ∈ [0, 1] where |p + d·τ| = reach, from the quadratic;
/// `Some(0)` when already within reach.
fn analytic_toi(p: Vector3<f64>, d: Vector3<f64>, reach: f64) -> Option<f64> {
    let c = p.norm_squared() - reach * reach;
    if c <= 0.0 {
        return Some(0.0);
    }
    let a = d.norm_squared();
    let b = 2.0 * p.dot(&d);
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 || disc < 0.0 {
        return None;
    }
    // The smaller root, in the cancellation-free form.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let roots = [q / a, c / q];
    let t = roots[0].min(roots[1]);
    (0.0..=1.0).contains(&t).then_some(t)
}

/// The smallest distance between the surfaces over the step.
fn min_gap(p: Vector3<f64>, d: Vector3<f64>, reach: f64) -> f64 {
    let a = d.norm_squared();
    let t = if a > 0.0 {
        (-p.dot(&d) / a).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p + d * t).norm() - reach
}

struct Case {
    r1: f64,
    r2: f64,
    m1: Motion,
    m2: Motion,
    /// Relative start and displacement of ball 1's centre from ball 2's.
    p: Vector3<f64>,
    d: Vector3<f64>,
}

fn linear_case(rng: &mut Rng, both_moving: bool) -> Case {
    let r1 = rng.range(0.01, 1.0);
    let r2 = rng.range(0.01, 1.0);
    let c1 = rng.vector(3.0);
    // Apart at the start (mostly): up to 2 m of clearance.
    let c2 = c1 + rng.vector(1.0).normalize() * (r1 + r2 + rng.range(-0.05, 2.0));
    // Aimed roughly at the other ball, so that about half the cases hit.
    let v1 = (c2 - c1).normalize() * rng.range(0.0, 100.0) + rng.vector(30.0);
    let v2 = if both_moving {
        rng.vector(100.0)
    } else {
        Vector3::zeros()
    };
    let iso = |c: Vector3<f64>| Isometry3::from_parts(Translation3::from(c), rng_free_rotation());
    let m1 = Motion::from_velocities(iso(c1), Point3::from(c1), v1, Vector3::zeros(), DT).unwrap();
    let m2 = Motion::from_velocities(iso(c2), Point3::from(c2), v2, Vector3::zeros(), DT).unwrap();
    // The analytic answer uses the motions' own per-step displacements.
    let d = m1.displacement() - m2.displacement();
    Case {
        r1,
        r2,
        m1,
        m2,
        p: c1 - c2,
        d,
    }
}

fn rng_free_rotation() -> nalgebra::UnitQuaternion<f64> {
    nalgebra::UnitQuaternion::identity()
}

#[test]
fn linear_balls_match_the_analytic_time_in_every_arithmetic() {
    let cases: Vec<Case> = {
        let mut rng = Rng::new(7);
        (0..3000)
            .map(|i| linear_case(&mut rng, i % 2 == 0))
            .collect()
    };
    let eps = 1.0e-3;
    for kind in Arithmetic::ALL {
        let options = QueryOptions {
            epsilon: eps,
            arithmetic: kind,
            ..QueryOptions::default()
        };
        let (mut hits, mut false_positives, mut worst_fp_gap) = (0, 0, 0.0f64);
        let mut evaluations = Vec::new();
        for (i, case) in cases.iter().enumerate() {
            let reach = case.r1 + case.r2;
            let truth = analytic_toi(case.p, case.d, reach);
            let got = time_of_impact(
                &Ball::new(case.r1 as f32),
                &case.m1,
                &Ball::new(case.r2 as f32),
                &case.m2,
                &options,
            )
            .unwrap();
            // The shapes are f32 balls: compare with the f32 radii.
            let reach32 = f64::from(case.r1 as f32) + f64::from(case.r2 as f32);
            let truth32 = analytic_toi(case.p, case.d, reach32);
            match (truth32.or(truth), got) {
                (Some(t), Some(toi)) => {
                    hits += 1;
                    if toi.status == RootStatus::Hit {
                        evaluations.push(toi.stats.pair_evaluations as f64);
                    }
                    assert!(
                        toi.fraction <= t + 1e-9,
                        "{kind:?} case {i}: reported {} after the true {t}",
                        toi.fraction
                    );
                    assert!(
                        t - toi.fraction <= eps + 1e-9,
                        "{kind:?} case {i}: reported {} more than ε before the true {t} ({:?})",
                        toi.fraction,
                        toi.status
                    );
                }
                (Some(t), None) => panic!("{kind:?} case {i}: missed a hit at {t}"),
                (None, Some(_)) => {
                    false_positives += 1;
                    worst_fp_gap = worst_fp_gap.max(min_gap(case.p, case.d, reach32));
                }
                (None, None) => {}
            }
        }
        println!(
            "{:>8}: {hits} hits, {false_positives} false positives (largest true gap {worst_fp_gap:.2e} m), \
             pair evaluations per hit: median {} p99 {}",
            kind.name(),
            quantile(&evaluations, 0.5),
            quantile(&evaluations, 0.99)
        );
        assert!(hits > 800, "the case set should hold many hits ({hits})");
        assert!(
            worst_fp_gap < 2.0e-3,
            "{kind:?}: a false positive with a true gap of {worst_fp_gap} m is not near contact"
        );
    }
}

/// Earliest τ at which `gap(τ) ≤ 0`, by 4096 samples then bisection;
/// `None` when no sample reaches it.
fn sampled_toi(gap: impl Fn(f64) -> f64) -> Option<f64> {
    const SAMPLES: usize = 4096;
    if gap(0.0) <= 0.0 {
        return Some(0.0);
    }
    let mut prev = 0.0;
    for i in 1..=SAMPLES {
        let t = i as f64 / SAMPLES as f64;
        if gap(t) <= 0.0 {
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if gap(mid) <= 0.0 { hi = mid } else { lo = mid }
            }
            return Some(hi);
        }
        prev = t;
    }
    None
}

#[test]
fn balls_on_spinning_bodies_match_dense_sampling() {
    let mut rng = Rng::new(11);
    let eps = 1.0e-3;
    let (mut hits, mut fps) = (0, 0);
    for i in 0..1500 {
        // Each ball sits off its body's centre of mass, so spinning moves it.
        let mut body = |moving: bool| {
            let com = rng.vector(2.0);
            let arm = rng.vector(1.0);
            let (v, w) = if moving {
                (
                    rng.vector(60.0),
                    rng.vector(if i % 3 == 0 { 300.0 } else { 50.0 }),
                )
            } else {
                (Vector3::zeros(), Vector3::zeros())
            };
            let start = Isometry3::from_parts(Translation3::from(com + arm), rng.rotation());
            Motion::from_velocities(start, Point3::from(com), v, w, DT).unwrap()
        };
        let m1 = body(true);
        let m2 = body(i % 2 == 0);
        // Aim body 1 at body 2's centre (plus spin and noise): most cases meet.
        let aim = (m2.center() - m1.center()) / DT * rng.range(0.2, 1.2);
        let m1 = Motion::from_velocities(
            m1.pose_at(0.0),
            m1.center(),
            aim + rng.vector(10.0),
            m1.rotation() / DT,
            DT,
        )
        .unwrap();
        let (r1, r2) = (rng.range(0.05, 0.5) as f32, rng.range(0.05, 0.5) as f32);
        let reach = f64::from(r1) + f64::from(r2);
        let gap = |t: f64| {
            (m1.pose_at(t).translation.vector - m2.pose_at(t).translation.vector).norm() - reach
        };
        let truth = sampled_toi(gap);
        let options = QueryOptions {
            epsilon: eps,
            ..QueryOptions::default()
        };
        let got = time_of_impact(&Ball::new(r1), &m1, &Ball::new(r2), &m2, &options).unwrap();
        match (truth, got) {
            (Some(t), Some(toi)) => {
                hits += 1;
                assert!(
                    toi.fraction <= t + 1e-9,
                    "case {i}: {} after {t}",
                    toi.fraction
                );
                assert!(
                    t - toi.fraction <= eps + 1e-9 || gap(toi.fraction + eps) < 1e-6,
                    "case {i}: {} too early for {t}",
                    toi.fraction
                );
            }
            (Some(t), None) => panic!("case {i}: missed the hit at {t}"),
            (None, Some(toi)) => {
                fps += 1;
                let near = (0..=4096)
                    .map(|k| gap(k as f64 / 4096.0))
                    .fold(f64::MAX, f64::min);
                assert!(
                    near < 1e-2,
                    "case {i}: false positive at {} with gap {near}: {toi:?}",
                    toi.fraction
                );
            }
            (None, None) => {}
        }
    }
    println!("spinning balls: {hits} hits, {fps} false positives");
    assert!(hits > 100);
}

/// A set of pairs whose axes are polynomials in τ, for brute-force checks
/// of the AND (axes) / OR (pairs) logic.
struct PolySet {
    /// pairs → axes → coefficients of τ⁰, τ¹, τ², τ³.
    pairs: Vec<Vec<[f64; 4]>>,
    /// What the set answers for `GapSet::useful_width`.
    useful: f64,
    /// What the set answers for `GapSet::is_exact`: `false` makes the
    /// solver treat its touches as likely only, confirmed at single times
    /// (the adaptive-axis families' path).
    exact: bool,
}

impl PolySet {
    fn value(c: &[f64; 4], t: f64) -> f64 {
        ((c[3] * t + c[2]) * t + c[1]) * t + c[0]
    }

    /// Earliest sample time at which some pair has every axis ≤ 0.
    fn brute_force(&self, samples: usize) -> Option<f64> {
        self.brute_force_among(samples, |_| true)
    }

    /// [`PolySet::brute_force`] over the pairs `keep` accepts.
    fn brute_force_among(
        &self,
        samples: usize,
        keep: impl Fn(&Vec<[f64; 4]>) -> bool,
    ) -> Option<f64> {
        (0..=samples).map(|i| i as f64 / samples as f64).find(|&t| {
            self.pairs
                .iter()
                .filter(|axes| keep(axes))
                .any(|axes| axes.iter().all(|c| PolySet::value(c, t) <= 0.0))
        })
    }
}

/// A search of `set` in the arithmetic `kind`, through the crate's one
/// arithmetic dispatch.
fn solve_in(
    kind: Arithmetic,
    solver: &mut Solver,
    set: &mut PolySet,
    options: &SolveOptions,
) -> Result<SolveOutcome, CcdError> {
    struct Run<'a> {
        solver: &'a mut Solver,
        set: &'a mut PolySet,
        options: &'a SolveOptions,
    }
    impl InArithmetic for Run<'_> {
        type Output = Result<SolveOutcome, CcdError>;
        fn run<E: Enclosure>(self) -> Self::Output {
            self.solver.solve::<E, _>(self.set, self.options)
        }
    }
    kind.dispatch(Run {
        solver,
        set,
        options,
    })
}

impl<E: Enclosure> GapSet<E> for PolySet {
    fn pair_count(&self) -> usize {
        self.pairs.len()
    }
    fn axis_count(&self, pair: usize) -> usize {
        self.pairs[pair].len()
    }
    fn is_exact(&self, _pair: usize) -> bool {
        self.exact // true to life: the axes are the functions themselves
    }
    fn useful_width(&self) -> f64 {
        self.useful
    }
    fn eval(&mut self, pair: usize, span: TimeSpan, axes: u64, out: &mut [E]) {
        let t = E::time(span);
        for (k, c) in self.pairs[pair].iter().enumerate() {
            if axes >> k & 1 == 1 {
                out[k] = ((t * c[3] + c[2]) * t + c[1]) * t + c[0];
            }
        }
    }
}

/// A random set for case `case`: 1–5 pairs of 1–`axes` cubic axes, their
/// constant terms in `starts`. Every other case cuts wide nodes straight
/// into pieces (what a fast-turning pair asks for), as narrow as 1/300 of
/// the step, and every other pair of cases claims its axes are not exact.
fn random_set(rng: &mut Rng, case: usize, starts: (f64, f64), axes: usize) -> PolySet {
    let pairs = (0..1 + rng.below(5))
        .map(|_| {
            (0..1 + rng.below(axes))
                .map(|_| {
                    [
                        rng.range(starts.0, starts.1),
                        rng.range(-2.0, 2.0),
                        rng.range(-2.0, 2.0),
                        rng.range(-1.0, 1.0),
                    ]
                })
                .collect()
        })
        .collect();
    let useful = if case % 2 == 0 {
        f64::INFINITY
    } else {
        rng.range(0.003, 0.4)
    };
    PolySet {
        pairs,
        useful,
        exact: case % 4 < 2,
    }
}

/// A search of a set whose earliest touch is at `t` (by brute force)
/// neither misses it nor reports it late.
fn assert_in_time(got: &SolveOutcome, t: f64, case: usize, kind: Arithmetic) {
    assert_ne!(
        got.status,
        RootStatus::Separated,
        "case {case} {kind:?}: missed {t}"
    );
    assert!(
        got.time <= t,
        "case {case} {kind:?}: {} after {t}",
        got.time
    );
}

#[test]
fn and_or_sets_match_brute_force() {
    let mut rng = Rng::new(3);
    let mut solver = Solver::new();
    let eps = 1.0e-4;
    let samples = 20_000;
    let mut hits = 0;
    for case in 0..1500 {
        let mut set = random_set(&mut rng, case, (-0.2, 1.0), 4);
        let truth = set.brute_force(samples);
        for kind in Arithmetic::ALL {
            let options = SolveOptions {
                epsilon: eps,
                ..SolveOptions::default()
            };
            let got = solve_in(kind, &mut solver, &mut set, &options).unwrap();
            match truth {
                Some(t) => {
                    assert_in_time(&got, t, case, kind);
                    // The pair named must really reach ≤ 0 near the report.
                    let pair = &set.pairs[got.pair.unwrap()];
                    let reaches = (0..=200).any(|i| {
                        let s = (got.time + i as f64 * eps / 100.0).min(1.0);
                        pair.iter().all(|c| PolySet::value(c, s) <= 1e-6)
                    });
                    if got.status == RootStatus::Hit && t - got.time > 2.0 / samples as f64 + eps {
                        assert!(reaches, "case {case} {kind:?}: {} far before {t}", got.time);
                    }
                }
                None => {
                    if got.status != RootStatus::Separated {
                        // Only a near-touch may be reported: some pair's
                        // largest axis comes within a small margin of zero.
                        let closest = (0..=samples)
                            .map(|i| i as f64 / samples as f64)
                            .map(|t| {
                                set.pairs
                                    .iter()
                                    .map(|axes| {
                                        axes.iter()
                                            .map(|c| PolySet::value(c, t))
                                            .fold(f64::MIN, f64::max)
                                    })
                                    .fold(f64::MAX, f64::min)
                            })
                            .fold(f64::MAX, f64::min);
                        assert!(
                            closest < 1e-3,
                            "case {case} {kind:?}: false hit, margin {closest}"
                        );
                    }
                }
            }
        }
        hits += usize::from(truth.is_some());
    }
    assert!(hits > 200, "the random sets should hold many hits ({hits})");
}

#[test]
fn ignored_initial_contacts_match_brute_force() {
    use affine_ccd::InitialContact;
    // Random sets as above, many of whose pairs touch at the start (every
    // axis ≤ 0 at τ = 0): those are left out, and the search must find the
    // earliest touch of the others, never late, whichever node first sees
    // the touch at the start (a sure one on exact axes, a likely one, or
    // only the report).
    let mut rng = Rng::new(11);
    let mut solver = Solver::new();
    let eps = 1.0e-4;
    let samples = 20_000;
    let (mut left_out, mut hits) = (0, 0);
    for case in 0..1500 {
        let mut set = random_set(&mut rng, case, (-0.5, 0.6), 3);
        let at_start = |axes: &Vec<[f64; 4]>| axes.iter().all(|c| c[0] <= 0.0);
        left_out += set.pairs.iter().filter(|axes| at_start(axes)).count();
        let truth = set.brute_force_among(samples, |axes| !at_start(axes));
        for kind in Arithmetic::ALL {
            let options = SolveOptions {
                epsilon: eps,
                initial_contact: InitialContact::Ignore,
                ..SolveOptions::default()
            };
            let got = solve_in(kind, &mut solver, &mut set, &options).unwrap();
            assert_ne!(got.status, RootStatus::InitiallyTouching, "case {case}");
            if let Some(pair) = got.pair {
                // A pair left out is never the one reported.
                assert!(
                    !at_start(&set.pairs[pair]),
                    "case {case} {kind:?}: pair {pair}"
                );
            }
            if let Some(t) = truth {
                assert_in_time(&got, t, case, kind);
            }
        }
        hits += usize::from(truth.is_some());
    }
    assert!(
        left_out > 300,
        "many pairs should touch at the start ({left_out})"
    );
    assert!(hits > 200, "the random sets should hold many hits ({hits})");
}

#[test]
fn budget_exhaustion_is_conservative() {
    let mut set = PolySet {
        useful: f64::INFINITY,
        exact: true,
        // Touches zero only at τ = 0.7 (a double root): hard to exclude.
        pairs: vec![vec![[0.49, -1.4, 1.0, 0.0]]],
    };
    let options = SolveOptions {
        epsilon: 1e-9,
        max_evaluations: 5,
        ..SolveOptions::default()
    };
    let got = solve_in(Arithmetic::Affine, &mut Solver::new(), &mut set, &options).unwrap();
    assert_eq!(got.status, RootStatus::BudgetExhausted);
    assert!(
        got.time <= 0.7,
        "budget answer {} is after the root",
        got.time
    );
    assert!(got.stats.pair_evaluations <= 5);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let mut set = PolySet {
        useful: f64::INFINITY,
        exact: true,
        pairs: vec![vec![[1.0, 0.0, 0.0, 0.0]]],
    };
    for eps in [0.0, -1.0, f64::NAN, 2.0] {
        let options = SolveOptions {
            epsilon: eps,
            ..SolveOptions::default()
        };
        let err = solve_in(Arithmetic::Affine, &mut Solver::new(), &mut set, &options);
        assert!(err.is_err(), "epsilon {eps} accepted");
    }
    let options = SolveOptions {
        max_evaluations: 0,
        ..SolveOptions::default()
    };
    assert!(solve_in(Arithmetic::Affine, &mut Solver::new(), &mut set, &options).is_err());
}

#[test]
fn initial_contacts_are_reported_or_left_out() {
    use affine_ccd::InitialContact;
    // Touching from the start to the end (−0.1 + 0.05τ stays ≤ 0), or only
    // for the first 1 % of the step (−0.01 + τ): the check at the start
    // finds both, whether the search halves nodes or cuts them into pieces,
    // and whether it sees the touch as sure (exact axes: the check is made
    // on the node that sees it) or only likely (made before the start
    // would be reported).
    let touchings = [[-0.1, 0.05, 0.0, 0.0], [-0.01, 1.0, 0.0, 0.0]];
    for (touching, exact) in touchings.into_iter().flat_map(|c| [(c, true), (c, false)]) {
        for useful in [f64::INFINITY, 0.1] {
            let mut set = PolySet {
                useful,
                exact,
                pairs: vec![
                    vec![touching],
                    // Reaches zero at τ = 0.5.
                    vec![[0.5, -1.0, 0.0, 0.0]],
                ],
            };
            let mut solver = Solver::new();
            let report = SolveOptions::default();
            let got = solve_in(Arithmetic::Affine, &mut solver, &mut set, &report).unwrap();
            assert_eq!(got.status, RootStatus::InitiallyTouching);
            assert_eq!((got.time, got.pair), (0.0, Some(0)));
            let ignore = SolveOptions {
                initial_contact: InitialContact::Ignore,
                ..SolveOptions::default()
            };
            let got = solve_in(Arithmetic::Affine, &mut solver, &mut set, &ignore).unwrap();
            assert_eq!(got.status, RootStatus::Hit);
            assert_eq!(got.pair, Some(1));
            assert!(
                got.time <= 0.5 && 0.5 - got.time <= ignore.epsilon,
                "{}",
                got.time
            );
            // A caller that vouches for every pair apart at the start gets
            // no check there: the touch is searched for like any other.
            let vouched = SolveOptions {
                start_apart: true,
                ..SolveOptions::default()
            };
            let got = solve_in(Arithmetic::Affine, &mut solver, &mut set, &vouched).unwrap();
            assert_eq!(got.status, RootStatus::Hit);
            assert!(got.time <= vouched.epsilon, "{}", got.time);
        }
    }
}

#[test]
fn a_pair_reaching_zero_just_after_the_start_is_a_hit_not_a_contact() {
    // Apart at the start by 1e-3 and touching from τ = 1e-3 on: the start
    // check must not call it initially touching, and the hit is on time.
    for (useful, exact) in [(f64::INFINITY, true), (0.1, true), (f64::INFINITY, false)] {
        let mut set = PolySet {
            useful,
            exact,
            pairs: vec![vec![[1.0e-3, -1.0, 0.0, 0.0]]],
        };
        let options = SolveOptions::default();
        let got = solve_in(Arithmetic::Affine, &mut Solver::new(), &mut set, &options).unwrap();
        assert_eq!(got.status, RootStatus::Hit);
        assert!(
            got.time <= 1.0e-3 && 1.0e-3 - got.time <= options.epsilon,
            "{}",
            got.time
        );
    }
}
