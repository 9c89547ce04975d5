//! Meshes and composites: the vertex–face / edge–edge primitives against the
//! Tight-Inclusion sample queries (exact ground truth), and composite shapes
//! (TriMesh, HeightField, Polyline, Compound) against dense sampling of the
//! exact motions with parry's own queries.
//!
//! Reproduce the printed tables with
//! `cargo test --release --test gap_composite -- --nocapture`.

mod common;

use affine_ccd::query::{QueryOptions, edge_edge_toi, vertex_face_toi};
use affine_ccd::{Arithmetic, RootStatus};
use nalgebra::Point3;
use std::path::PathBuf;

/// The sample queries, relative to this crate's manifest directory.
const SAMPLE_DIR: &str = "../shared/data/ccd-sample-queries/unit-tests";

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
                 they live in shared/data beside the crate",
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
