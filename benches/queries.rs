//! Time per query, per pair kind: affine-ccd at several ε in every
//! arithmetic, and parry's `cast_shapes_nonlinear` and
//! `sweep_time_of_impact` on the same seeded cases (one batch of cases per
//! measurement, so the numbers are per batch; divide by the batch size).
//!
//! `cargo bench --bench queries` (all), or filter, e.g.
//! `cargo bench --bench queries -- cuboid-cuboid`. At the end it prints,
//! per pair kind measured, parry's times over affine's at ε = 1e-4 (the
//! issue's target is ≥ 1), from criterion's own median estimates.

mod common;

use affine_ccd::Arithmetic;
use affine_ccd::query::{QueryOptions, time_of_impact};
use common::{Case, pair_kinds, parry_nonlinear, parry_sweep};
use criterion::{BenchmarkId, Criterion, criterion_group};
use std::hint::black_box;
use std::time::Duration;

/// Cases per pair kind and batch.
const BATCH: usize = 100;

fn run_affine(cases: &[Case], options: &QueryOptions) -> usize {
    cases
        .iter()
        .filter(|c| {
            matches!(
                time_of_impact(
                    c.shape1.as_ref(),
                    &c.motion1,
                    c.shape2.as_ref(),
                    &c.motion2,
                    options
                ),
                Ok(Some(_))
            )
        })
        .count()
}

fn queries(c: &mut Criterion) {
    for (k, kind) in pair_kinds().iter().enumerate() {
        let cases = common::cases(kind, BATCH, 1000 + k as u64);
        if cases.is_empty() {
            eprintln!("{}: not supported, skipped", kind.name);
            continue;
        }
        let mut group = c.benchmark_group(kind.name);
        group
            .sample_size(10)
            .measurement_time(Duration::from_millis(800))
            .warm_up_time(Duration::from_millis(200));
        for arithmetic in Arithmetic::ALL {
            for eps in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
                let options = QueryOptions {
                    epsilon: eps,
                    arithmetic,
                    ..QueryOptions::default()
                };
                group.bench_with_input(
                    BenchmarkId::new(arithmetic.name(), format!("{eps:.0e}")),
                    &options,
                    |b, o| b.iter(|| black_box(run_affine(&cases, o))),
                );
            }
        }
        if parry_nonlinear(&cases[0]).is_ok() {
            group.bench_function("parry_nonlinear", |b| {
                b.iter(|| {
                    black_box(
                        cases
                            .iter()
                            .filter(|c| matches!(parry_nonlinear(c), Ok(Some(_))))
                            .count(),
                    )
                })
            });
        }
        if parry_sweep(&cases[0]).is_ok() {
            group.bench_function("parry_sweep", |b| {
                b.iter(|| {
                    black_box(
                        cases
                            .iter()
                            .filter(|c| matches!(parry_sweep(c), Ok(Some(_))))
                            .count(),
                    )
                })
            });
        }
        group.finish();
    }
}

/// criterion's median estimate of one benchmark, in ns per batch, from the
/// run that just ended (`None` when it was filtered out or not run).
fn median_ns(group: &str, path: &str) -> Option<f64> {
    let dir = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    let file = format!("{dir}/criterion/{group}/{path}/new/estimates.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).ok()?).ok()?;
    json["median"]["point_estimate"].as_f64()
}

/// The ratios the issue asks for, one row per pair kind.
fn print_ratios() {
    println!("\nper query, ε = 1e-4, medians of criterion's samples (µs per query):");
    println!(
        "{:<16} {:>10} {:>16} {:>24} {:>12}",
        "pair kind", "affine", "parry nonlinear", "parry nonlinear/affine", "parry sweep"
    );
    let per_query = |ns: f64| ns / 1.0e3 / BATCH as f64;
    for kind in pair_kinds() {
        let Some(affine) = median_ns(kind.name, "affine/1e-4") else {
            continue;
        };
        let nonlinear = median_ns(kind.name, "parry_nonlinear");
        let sweep = median_ns(kind.name, "parry_sweep");
        let show = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{:.2}", per_query(v)));
        let ratio = nonlinear.map_or("n/a".to_string(), |n| format!("{:.2}", n / affine));
        println!(
            "{:<16} {:>10.2} {:>16} {:>24} {:>12}",
            kind.name,
            per_query(affine),
            show(nonlinear),
            ratio,
            show(sweep)
        );
    }
}

criterion_group!(benches, queries);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    print_ratios();
}
