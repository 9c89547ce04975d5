//! Meshes and composites: the vertex–face / edge–edge primitives against the
//! Tight-Inclusion sample queries (exact ground truth), and composite shapes
//! (TriMesh, HeightField, Polyline, Compound) against dense sampling of the
//! exact motions with parry's own queries.
//!
//! Reproduce the printed tables with
//! `cargo test --release --test gap_composite -- --nocapture`.

mod common;

use affine_ccd::convert::pose_from_iso;
use affine_ccd::query::{
    QueryOptions, ShapeMotion, edge_edge_toi, is_supported, time_of_impact, time_of_impact_many,
    vertex_face_toi,
};
use affine_ccd::{Arithmetic, Motion, RootStatus, Trajectory};
use common::{Rng, pose64, quantile};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rapier3d::parry::math::{Pose, Vector};
use rapier3d::parry::shape::{Ball, Cuboid, HeightField, Polyline, Shape, SharedShape, TriMesh};
use rapier3d::parry::utils::Array2;
use std::path::PathBuf;

/// The sample queries, relative to this crate's manifest directory.
const SAMPLE_DIR: &str = "tests/data/ccd-sample-queries/unit-tests";

/// One sample query: 8 points and the exact answer.
struct Sample {
    file: String,
    index: usize,
    points: [Point3<f64>; 8],
    truth: bool,
}

/// `num/den` from their decimal strings. Both are integers exactly
/// representable as `f64` and `den` is a power of two (README), so parsing
/// each and dividing is exact; `den` may exceed 64 bits, hence no `u64`.
fn rational(num: &str, den: &str) -> f64 {
    let n: f64 = num.trim().parse().expect("numerator");
    let d: f64 = den.trim().parse().expect("denominator");
    assert!(d != 0.0, "zero denominator");
    n / d
}

fn load_samples(kind: &str) -> Vec<Sample> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(SAMPLE_DIR)
        .join(kind);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| {
            panic!(
                "the sample queries are missing: cannot read {} ({e}); \
                 they live in tests/data of the repository",
                dir.display()
            )
        })
        .map(|entry| entry.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no CSV files in {}", dir.display());
    let mut samples = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).expect("readable CSV");
        let rows: Vec<(Point3<f64>, bool)> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|line| {
                let c: Vec<&str> = line.split(',').collect();
                assert_eq!(c.len(), 7, "{}: bad row {line}", path.display());
                let p = Point3::new(
                    rational(c[0], c[1]),
                    rational(c[2], c[3]),
                    rational(c[4], c[5]),
                );
                (p, c[6].trim() == "1")
            })
            .collect();
        assert_eq!(
            rows.len() % 8,
            0,
            "{}: rows not a multiple of 8",
            path.display()
        );
        for (index, chunk) in rows.chunks(8).enumerate() {
            samples.push(Sample {
                file: path.file_name().unwrap().to_string_lossy().into_owned(),
                index,
                points: std::array::from_fn(|k| chunk[k].0),
                truth: chunk[0].1,
            });
        }
    }
    samples
}

/// Run one kind of sample query in one arithmetic; returns
/// (positives, found, false positives, misses listed, evaluations).
fn run_samples(
    kind: &str,
    arithmetic: Arithmetic,
) -> (usize, usize, Vec<String>, Vec<String>, u64) {
    let samples = load_samples(kind);
    let options = QueryOptions {
        arithmetic,
        epsilon: 1.0e-6,
        max_evaluations: 1_000_000,
        ..QueryOptions::default()
    };
    let (mut positives, mut found, mut evaluations) = (0, 0, 0u64);
    let (mut false_positives, mut misses) = (Vec::new(), Vec::new());
    for s in &samples {
        let p = &s.points;
        let got = if kind == "vertex-face" {
            vertex_face_toi(
                (p[0], p[4]),
                (p[1], p[5]),
                (p[2], p[6]),
                (p[3], p[7]),
                &options,
            )
        } else {
            edge_edge_toi(
                (p[0], p[4]),
                (p[1], p[5]),
                (p[2], p[6]),
                (p[3], p[7]),
                &options,
            )
        }
        .expect("valid query");
        let name = format!("{}#{}", s.file, s.index);
        if let Some(toi) = &got {
            evaluations += toi.stats.pair_evaluations;
            assert_ne!(toi.status, RootStatus::Separated);
        }
        match (s.truth, got) {
            (true, Some(_)) => {
                positives += 1;
                found += 1;
            }
            (true, None) => {
                positives += 1;
                misses.push(name);
            }
            (false, Some(toi)) => false_positives.push(format!(
                "{name} at τ = {:.3e} ({:?})",
                toi.fraction, toi.status
            )),
            (false, None) => {}
        }
    }
    (positives, found, false_positives, misses, evaluations)
}

#[test]
fn sample_queries_have_no_false_negatives() {
    for arithmetic in [
        Arithmetic::Affine,
        Arithmetic::Interval,
        Arithmetic::Taylor2,
    ] {
        for kind in ["vertex-face", "edge-edge"] {
            let (positives, found, fps, misses, evals) = run_samples(kind, arithmetic);
            println!(
                "{:>8} {kind:>11}: {found}/{positives} positives found, {} false positives, \
                 {evals} pair evaluations on reported queries",
                arithmetic.name(),
                fps.len()
            );
            for fp in &fps {
                println!("    false positive: {fp}");
            }
            assert!(
                misses.is_empty(),
                "{arithmetic:?} {kind}: missed true contacts: {misses:?}"
            );
            let expected = if kind == "vertex-face" { 124 } else { 36 };
            assert_eq!(positives, expected, "{kind}: positives in the data set");
        }
    }
}

// ---------------------------------------------------------------------
// Composites against dense sampling.

const DT: f64 = 1.0 / 60.0;
/// Samples of the exact motions per case (≥ 2048).
const SAMPLES: usize = 4096;

/// parry's distance at τ, from the motions' own `f64` poses (rounded to
/// parry's `f32`).
fn distance_at(s1: &dyn Shape, m1: &Motion, s2: &dyn Shape, m2: &Motion, tau: f64) -> f64 {
    let (p1, p2): (Pose, Pose) = (
        pose_from_iso(&m1.pose_at(tau)),
        pose_from_iso(&m2.pose_at(tau)),
    );
    f64::from(
        rapier3d::parry::query::distance(&p1, s1, &p2, s2)
            .expect("parry supports the pair")
            .distance,
    )
}

/// The first τ at which parry sees the shapes touch (dense samples, then
/// bisection), and the smallest sampled distance.
fn sampled_truth(s1: &dyn Shape, m1: &Motion, s2: &dyn Shape, m2: &Motion) -> (Option<f64>, f64) {
    first_touch(|t| distance_at(s1, m1, s2, m2, t))
}

/// The first τ at which `distance` is `≤ 0` (dense samples, then
/// bisection), and the smallest sampled distance.
fn first_touch(distance: impl Fn(f64) -> f64) -> (Option<f64>, f64) {
    let mut min = f64::INFINITY;
    let mut prev = 0.0;
    for i in 0..=SAMPLES {
        let t = i as f64 / SAMPLES as f64;
        let d = distance(t);
        min = min.min(d);
        if d <= 0.0 {
            if i == 0 {
                return (Some(0.0), d);
            }
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if distance(mid) <= 0.0 {
                    hi = mid
                } else {
                    lo = mid
                }
            }
            return (Some(hi), min);
        }
        prev = t;
    }
    (None, min)
}

/// One scenario's tally.
#[derive(Default)]
struct Tally {
    cases: usize,
    hits: usize,
    false_positives: Vec<(usize, f64, f64)>,
    misses: Vec<String>,
    evaluations: Vec<f64>,
}

impl Tally {
    fn check(
        &mut self,
        case: usize,
        s1: &dyn Shape,
        m1: &Motion,
        s2: &dyn Shape,
        m2: &Motion,
        options: &QueryOptions,
    ) {
        self.check_against(case, s1, m1, s2, s2, m2, options)
    }

    /// As `check`, with the truth computed on `truth2`, the same geometry
    /// as `s2` in a form parry's distance supports for this pair.
    #[allow(clippy::too_many_arguments)]
    fn check_against(
        &mut self,
        case: usize,
        s1: &dyn Shape,
        m1: &Motion,
        s2: &dyn Shape,
        truth2: &dyn Shape,
        m2: &Motion,
        options: &QueryOptions,
    ) {
        self.cases += 1;
        let (truth, min_gap) = sampled_truth(s1, m1, truth2, m2);
        let got = time_of_impact(s1, m1, s2, m2, options).expect("supported pair");
        match (truth, got) {
            (Some(t), Some(toi)) => {
                self.hits += 1;
                self.evaluations.push(toi.stats.pair_evaluations as f64);
                // f32 poses in the truth: allow their rounding in time.
                if toi.fraction > t + 1.0e-5 {
                    self.misses.push(format!(
                        "case {case}: reported {} after the true {t}",
                        toi.fraction
                    ));
                }
            }
            (Some(t), None) => self
                .misses
                .push(format!("case {case}: missed a contact at τ = {t}")),
            (None, Some(toi)) => {
                self.evaluations.push(toi.stats.pair_evaluations as f64);
                self.false_positives.push((case, toi.fraction, min_gap));
            }
            (None, None) => {}
        }
    }

    fn report(&self, name: &str) {
        println!(
            "{name}: {} cases, {} hits, {} false positives, pair evaluations per reported query: median {} p99 {} max {}",
            self.cases,
            self.hits,
            self.false_positives.len(),
            quantile(&self.evaluations, 0.5),
            quantile(&self.evaluations, 0.99),
            quantile(&self.evaluations, 1.0),
        );
        for (case, tau, gap) in &self.false_positives {
            println!(
                "    false positive: case {case} at τ = {tau:.4}, smallest sampled gap {gap:.2e} m"
            );
        }
        assert!(self.misses.is_empty(), "{name}: {:?}", self.misses);
    }
}

fn motion(rng: &mut Rng, start: Vector3<f64>, v: Vector3<f64>, w: Vector3<f64>) -> Motion {
    let iso = Isometry3::from_parts(Translation3::from(start), rng.rotation());
    Motion::from_velocities(iso, Point3::from(start), v, w, DT).unwrap()
}

fn fixed(at: Vector3<f64>) -> Motion {
    Motion::fixed(Isometry3::translation(at.x, at.y, at.z)).unwrap()
}

/// A flat grid of `n × n` quads, `size` metres wide, at y = 0.
fn floor_mesh(n: usize, size: f32) -> TriMesh {
    grid_mesh(n, n, size, size, |_, _| 0.0)
}

/// A grid mesh of `nx × nz` cells over `[−sx/2, sx/2] × [−sz/2, sz/2]` with
/// heights `h(x, z)`.
fn grid_mesh(nx: usize, nz: usize, sx: f32, sz: f32, h: impl Fn(f32, f32) -> f32) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..=nz {
        for j in 0..=nx {
            let x = -0.5 * sx + sx * j as f32 / nx as f32;
            let z = -0.5 * sz + sz * i as f32 / nz as f32;
            vertices.push(Vector::new(x, h(x, z), z));
        }
    }
    let mut indices = Vec::new();
    let at = |i: usize, j: usize| (i * (nx + 1) + j) as u32;
    for i in 0..nz {
        for j in 0..nx {
            indices.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
            indices.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    TriMesh::new(vertices, indices).expect("a valid mesh")
}

/// A box's surface as a 12-triangle mesh.
fn box_mesh(half: Vector3<f32>) -> TriMesh {
    let (x, y, z) = (half.x, half.y, half.z);
    let v = |a: f32, b: f32, c: f32| Vector::new(a * x, b * y, c * z);
    let vertices = vec![
        v(-1.0, -1.0, -1.0),
        v(1.0, -1.0, -1.0),
        v(1.0, 1.0, -1.0),
        v(-1.0, 1.0, -1.0),
        v(-1.0, -1.0, 1.0),
        v(1.0, -1.0, 1.0),
        v(1.0, 1.0, 1.0),
        v(-1.0, 1.0, 1.0),
    ];
    let indices = vec![
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [3, 6, 2],
        [3, 7, 6],
        [0, 4, 7],
        [0, 7, 3],
        [1, 2, 6],
        [1, 6, 5],
    ];
    TriMesh::new(vertices, indices).expect("a valid box mesh")
}

fn terrain_height(x: f32, z: f32) -> f32 {
    0.4 * (0.7 * x).sin() * (0.5 * z).cos() + 0.15 * (1.9 * x + 0.3 * z).sin()
}

fn options() -> QueryOptions {
    QueryOptions {
        epsilon: 1.0e-4,
        ..QueryOptions::default()
    }
}

#[test]
fn ball_rain_through_a_thin_floor() {
    let floor = floor_mesh(20, 10.0);
    assert_eq!(floor.num_triangles(), 800);
    let at_floor = fixed(Vector3::zeros());
    let mut rng = Rng::new(21);
    let mut tally = Tally::default();
    for case in 0..150 {
        let r = rng.range(0.02, 0.2);
        let start = Vector3::new(
            rng.range(-6.5, 6.5),
            rng.range(-0.5, 3.0),
            rng.range(-6.5, 6.5),
        );
        let v = Vector3::new(
            rng.range(-30.0, 30.0),
            rng.range(-300.0, -20.0),
            rng.range(-30.0, 30.0),
        );
        let w = rng.vector(20.0);
        let m = motion(&mut rng, start, v, w);
        tally.check(
            case,
            &Ball::new(r as f32),
            &m,
            &floor,
            &at_floor,
            &options(),
        );
    }
    tally.report("ball rain through a 800-triangle floor");
    assert!(
        tally.hits > 30,
        "the rain should hit the floor often ({})",
        tally.hits
    );
}

#[test]
fn slab_onto_a_thousand_triangle_terrain() {
    let mesh = grid_mesh(25, 20, 20.0, 16.0, terrain_height);
    assert_eq!(mesh.num_triangles(), 1000);
    let heights = Array2::new(
        21,
        26,
        (0..26)
            .flat_map(|j| (0..21).map(move |i| (i, j)))
            .map(|(i, j)| {
                terrain_height(
                    -10.0 + 20.0 * j as f32 / 25.0,
                    -8.0 + 16.0 * i as f32 / 20.0,
                )
            })
            .collect(),
    );
    let field = HeightField::new(heights, Vector::new(20.0, 1.0, 16.0));
    let slab = box_mesh(Vector3::new(1.0, 0.1, 0.7));
    let cuboid = Cuboid::new(Vector::new(1.0, 0.1, 0.7));
    let at_origin = fixed(Vector3::zeros());
    // parry's distance has no mesh–heightfield case: the truth for the
    // heightfield uses its own triangles as a mesh.
    let field_triangles: Vec<_> = field.triangles().collect();
    let field_mesh = TriMesh::new(
        field_triangles
            .iter()
            .flat_map(|t| [t.a, t.b, t.c])
            .collect(),
        (0..field_triangles.len() as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect(),
    )
    .expect("the heightfield's triangles");
    assert_eq!(field_mesh.num_triangles(), 1000);
    let terrains: [(&str, &dyn Shape, &dyn Shape); 2] = [
        ("TriMesh", &mesh, &mesh),
        ("HeightField", &field, &field_mesh),
    ];
    for (name, terrain, truth) in terrains {
        let mut movers: Vec<(&str, &dyn Shape)> = vec![("mesh slab", &slab)];
        if is_supported(&cuboid, terrain) {
            movers.push(("cuboid slab", &cuboid));
        } else {
            println!("cuboid slab vs {name}: skipped (cuboid–triangle not merged yet)");
        }
        for (mover_name, mover) in movers {
            let mut rng = Rng::new(5);
            let mut tally = Tally::default();
            for case in 0..40 {
                let start = Vector3::new(
                    rng.range(-7.0, 7.0),
                    rng.range(0.9, 2.5),
                    rng.range(-5.0, 5.0),
                );
                let v = if case % 2 == 0 {
                    Vector3::new(
                        rng.range(-20.0, 20.0),
                        rng.range(-250.0, -60.0),
                        rng.range(-20.0, 20.0),
                    )
                } else {
                    Vector3::new(
                        rng.range(-120.0, 120.0),
                        rng.range(-40.0, 40.0),
                        rng.range(-120.0, 120.0),
                    )
                };
                let w = rng.vector(15.0);
                let m = motion(&mut rng, start, v, w);
                tally.check_against(case, mover, &m, terrain, truth, &at_origin, &options());
            }
            tally.report(&format!("{mover_name} onto a 1000-triangle {name}"));
            assert!(
                tally.hits >= 15,
                "{name}: the slab should land often ({})",
                tally.hits
            );
        }
    }
}

/// A mesh's triangles handed over as targets of their own (as the rapier
/// stage hands a mesh's nearby triangles to a search) move alike, and
/// the search gives them one frame and keeps their relative poses per
/// node. Every third triangle moves differently, which breaks the runs of
/// shared frames: a tumbling box falling onto them is reported hitting
/// when and where the earliest of the single queries, one triangle each,
/// says, within the queries' accuracy.
#[test]
fn triangles_as_targets_of_their_own_agree_with_single_queries() {
    let mesh = grid_mesh(6, 6, 3.0, 3.0, terrain_height);
    let triangles: Vec<_> = mesh.triangles().collect();
    let at_origin = fixed(Vector3::zeros());
    // Every third triangle lifted by 5 cm: frames of their own, the
    // others two by two.
    let lifted = fixed(Vector3::new(0.0, 0.05, 0.0));
    let target_motion = |k: usize| if k % 3 == 1 { lifted } else { at_origin };
    let cuboid = Cuboid::new(Vector::new(0.4, 0.1, 0.3));
    let options = options();
    let mut rng = Rng::new(17);
    let (mut hits, mut both_miss) = (0, 0);
    for case in 0..40 {
        let start = Vector3::new(
            rng.range(-1.0, 1.0),
            rng.range(0.8, 1.5),
            rng.range(-1.0, 1.0),
        );
        let v = Vector3::new(
            rng.range(-20.0, 20.0),
            rng.range(-150.0, -40.0),
            rng.range(-20.0, 20.0),
        );
        let w = rng.vector(30.0);
        let m = motion(&mut rng, start, v, w);
        let targets: Vec<ShapeMotion> = triangles
            .iter()
            .enumerate()
            .map(|(k, t)| ShapeMotion {
                shape: t,
                motion: target_motion(k),
            })
            .collect();
        let moving = [ShapeMotion {
            shape: &cuboid,
            motion: m,
        }];
        let many = time_of_impact_many(&moving, &targets, &options).expect("supported");
        let singles: Vec<Option<f64>> = triangles
            .iter()
            .enumerate()
            .map(|(k, t)| {
                time_of_impact(&cuboid, &m, t, &target_motion(k), &options)
                    .expect("supported")
                    .map(|toi| toi.fraction)
            })
            .collect();
        let earliest = singles
            .iter()
            .flatten()
            .copied()
            .fold(None, |best: Option<f64>, t| {
                Some(best.map_or(t, |b| b.min(t)))
            });
        match (many, earliest) {
            (Some(hit), Some(first)) => {
                hits += 1;
                let t = hit.toi.fraction;
                assert!(
                    (t - first).abs() <= 2.0 * options.epsilon,
                    "case {case}: the search says {t}, the single queries {first}"
                );
                let own = singles[hit.target].expect("the hit triangle's own query hits too");
                assert!(
                    own <= t + 2.0 * options.epsilon,
                    "case {case}: triangle {} hit at {t}, alone at {own}",
                    hit.target
                );
            }
            (None, None) => both_miss += 1,
            (many, single) => panic!(
                "case {case}: the search says {:?}, the single queries {single:?}",
                many.map(|h| h.toi.fraction)
            ),
        }
    }
    println!("triangles as targets: {hits} hits, {both_miss} misses of 40");
    assert!(
        hits >= 20 && both_miss >= 1,
        "{hits} hits, {both_miss} misses"
    );
}

/// A plate landing nearly flat on a fine mesh meets hundreds of triangles
/// over the step: the search's wide nodes keep most of the mesh's pieces
/// whole and open them on narrower nodes. Against the sampled truth (in
/// `f64`: parry's `f32` distance put some touches 6 µm early, 2·10⁻⁵ of the
/// step, with the code before that change as with it): no contact missed,
/// none reported late, and each landing reported within a thousandth of
/// the step of the true first touch.
#[test]
fn plate_landing_flat_on_a_fine_mesh() {
    use parry3d_f64 as p64;
    // 0.1 m cells: the 2 m plate covers some 800 triangles.
    let mesh = grid_mesh(40, 40, 4.0, 4.0, |x, z| {
        0.02 * (3.0 * x).sin() * (2.0 * z).cos()
    });
    let plate = Cuboid::new(Vector::new(1.0, 0.03, 1.0));
    let v64 = |v: Vector| p64::math::Vector::new(v.x.into(), v.y.into(), v.z.into());
    let mesh64 = p64::shape::TriMesh::new(
        mesh.vertices().iter().map(|&v| v64(v)).collect(),
        mesh.indices().to_vec(),
    )
    .expect("the same mesh");
    let plate64 = p64::shape::Cuboid::new(v64(plate.half_extents));
    let gap64 = |m: &Motion, tau: f64| {
        let pose = pose64(&m.pose_at(tau));
        p64::query::distance(&pose, &plate64, &p64::math::Pose::IDENTITY, &mesh64)
            .expect("parry supports the pair")
            .distance
    };
    let at_origin = fixed(Vector3::zeros());
    let mut rng = Rng::new(11);
    let (mut hits, mut wrong, mut evaluations) = (0, Vec::new(), 0);
    for case in 0..24 {
        let start = Vector3::new(
            rng.range(-0.5, 0.5),
            0.05 + rng.range(0.02, 0.2),
            rng.range(-0.5, 0.5),
        );
        // Level, or tilted by up to a degree, turning slowly.
        let tilt = UnitQuaternion::from_scaled_axis(rng.vector(0.015));
        let iso = Isometry3::from_parts(Translation3::from(start), tilt);
        let v = Vector3::new(
            rng.range(-1.0, 1.0),
            rng.range(-15.0, -3.0),
            rng.range(-1.0, 1.0),
        );
        let m = Motion::from_velocities(iso, Point3::from(start), v, rng.vector(2.0), DT).unwrap();
        let got = time_of_impact(&plate, &m, &mesh, &at_origin, &options()).expect("supported");
        match (first_touch(|t| gap64(&m, t)).0, got) {
            (Some(t), Some(toi)) => {
                hits += 1;
                evaluations += toi.stats.pair_evaluations;
                // parry's `f64` GJK stops within nanometres of a touch,
                // some 10⁻⁸ of the step here: allow it a hundred times that.
                if toi.fraction > t + 1.0e-6 || toi.fraction < t - 1.0e-3 {
                    wrong.push(format!(
                        "case {case}: reported {} for the true {t}",
                        toi.fraction
                    ));
                }
            }
            (Some(t), None) => wrong.push(format!("case {case}: missed the touch at {t}")),
            (None, Some(toi)) => wrong.push(format!(
                "case {case}: reported {} for no touch",
                toi.fraction
            )),
            (None, None) => {}
        }
    }
    println!("plate landings: {hits} of 24, {evaluations} pair evaluations");
    assert!(wrong.is_empty(), "{wrong:?}");
    assert!(
        hits >= 12,
        "the plate should land in most cases ({hits} of 24)"
    );
}

#[test]
fn spinning_blade_past_a_box() {
    // A thin blade: 2 m × 0.1 m × 0.01 m, spinning about its centre.
    let blade = box_mesh(Vector3::new(1.0, 0.05, 0.005));
    let block = box_mesh(Vector3::new(0.5, 0.5, 0.5));
    let cuboid = Cuboid::new(Vector::new(0.5, 0.5, 0.5));
    let mut targets: Vec<(&str, &dyn Shape)> = vec![("box mesh", &block)];
    if is_supported(&blade, &cuboid) {
        targets.push(("cuboid", &cuboid));
    } else {
        println!("blade vs cuboid: skipped (cuboid–triangle not merged yet)");
    }
    for (name, target) in targets {
        let mut rng = Rng::new(99);
        let mut tally = Tally::default();
        for case in 0..60 {
            // The blade's centre passes the box at 1.2–2.2 m: its tips may
            // sweep through the box's corner region or not.
            let start = Vector3::new(
                -3.0,
                rng.range(-0.6, 0.6),
                rng.range(0.9, 1.8) * if case % 2 == 0 { 1.0 } else { -1.0 },
            );
            let v = Vector3::new(
                rng.range(150.0, 400.0),
                rng.range(-10.0, 10.0),
                rng.range(-10.0, 10.0),
            );
            let w = Vector3::new(
                rng.range(-5.0, 5.0),
                rng.range(60.0, 240.0),
                rng.range(-5.0, 5.0),
            );
            let m = motion(&mut rng, start, v, w);
            tally.check(
                case,
                &blade,
                &m,
                target,
                &fixed(Vector3::zeros()),
                &options(),
            );
        }
        tally.report(&format!("spinning blade past a {name}"));
        assert!(
            tally.hits >= 5 && tally.hits + tally.false_positives.len() < 60,
            "{name}: want hits and misses"
        );
    }
}

#[test]
fn tumbling_compound_onto_a_floor() {
    // Cylinders are the convex engineer's; until then a compound of balls,
    // one part turned in its local frame.
    let parts = vec![
        (Pose::translation(-0.6, 0.0, 0.0), SharedShape::ball(0.15)),
        (Pose::translation(0.6, 0.1, 0.0), SharedShape::ball(0.25)),
        (
            Pose::from_parts(
                Vector::new(0.0, 0.0, 0.5),
                rapier3d::parry::math::Rotation::from_rotation_y(0.7),
            ),
            SharedShape::ball(0.1),
        ),
    ];
    let compound = SharedShape::compound(parts);
    let floor = floor_mesh(16, 8.0);
    let mut rng = Rng::new(3);
    let mut tally = Tally::default();
    for case in 0..80 {
        let start = Vector3::new(
            rng.range(-4.0, 4.0),
            rng.range(0.4, 2.5),
            rng.range(-4.0, 4.0),
        );
        let v = Vector3::new(
            rng.range(-20.0, 20.0),
            rng.range(-200.0, 10.0),
            rng.range(-20.0, 20.0),
        );
        let w = rng.vector(60.0);
        let m = motion(&mut rng, start, v, w);
        tally.check(
            case,
            compound.as_ref(),
            &m,
            &floor,
            &fixed(Vector3::zeros()),
            &options(),
        );
    }
    tally.report("tumbling compound of balls onto a 512-triangle floor");
    assert!(tally.hits > 15, "{}", tally.hits);
}

#[test]
fn ball_across_a_polyline() {
    // A zig-zag fence in the plane z = 0.
    let vertices: Vec<Vector> = (0..=20)
        .map(|i| {
            Vector::new(
                -5.0 + 0.5 * i as f32,
                if i % 2 == 0 { 0.0 } else { 0.6 },
                0.0,
            )
        })
        .collect();
    let fence = Polyline::new(vertices, None);
    let mut rng = Rng::new(17);
    let mut tally = Tally::default();
    for case in 0..150 {
        let r = rng.range(0.02, 0.15);
        let start = Vector3::new(
            rng.range(-5.5, 5.5),
            rng.range(-0.3, 0.9),
            rng.range(-1.5, -0.2),
        );
        let v = Vector3::new(
            rng.range(-40.0, 40.0),
            rng.range(-20.0, 20.0),
            rng.range(30.0, 240.0),
        );
        let m = motion(&mut rng, start, v, Vector3::zeros());
        tally.check(
            case,
            &Ball::new(r as f32),
            &m,
            &fence,
            &fixed(Vector3::zeros()),
            &options(),
        );
    }
    tally.report("ball across a 20-segment polyline");
    assert!(tally.hits > 20, "{}", tally.hits);
}

#[test]
fn unsupported_leaves_are_reported_up_front() {
    let floor = floor_mesh(2, 1.0);
    let cuboid = Cuboid::new(Vector::new(0.1, 0.1, 0.1));
    let m = fixed(Vector3::new(0.0, 1.0, 0.0));
    let result = time_of_impact(&cuboid, &m, &floor, &fixed(Vector3::zeros()), &options());
    match result {
        Err(affine_ccd::CcdError::Unsupported { .. }) => {}
        Ok(_) => assert!(
            is_supported(&cuboid, &floor),
            "answered an unsupported pair"
        ),
        Err(e) => panic!("unexpected error {e}"),
    }
    let _ = UnitQuaternion::<f64>::identity();
}
