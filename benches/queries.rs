//! Time per query, per pair kind: affine-ccd at several ε in every
//! arithmetic, and parry's `cast_shapes_nonlinear` and
//! `sweep_time_of_impact` on the same seeded cases (one batch of cases per
//! measurement, so the numbers are per batch; divide by the batch size).
//!
//! Each pair kind comes twice: at ordinary spins (≤ 50 rad/s per axis, the
//! accuracy report's cases) and at 200–1000 rad/s (groups `<kind>-fast-spin`,
//! affine at ε = 1e-4 and the two parry methods only).
//!
//! `cargo bench --bench queries` (all), or filter, e.g.
//! `cargo bench --bench queries -- cuboid-cuboid`. At the end it prints,
//! per pair kind and spin measured in this run, parry nonlinear's time over
//! affine's at ε = 1e-4 (≥ 1: affine is the faster), from criterion's own
//! median estimates, beside how often each method missed a contact of the
//! cases' sampled truth or reported it late.

mod common;

use affine_ccd::Arithmetic;
use affine_ccd::query::QueryOptions;
use common::{Case, Spin, TRUTH_SAMPLES, pair_kinds, parry_nonlinear, parry_sweep};
use criterion::{BenchmarkId, Criterion};
use std::hint::black_box;
use std::time::{Duration, SystemTime};

/// Cases per pair kind and batch.
const BATCH: usize = 100;

/// How one method fared on a batch against the sampled truth.
#[derive(Clone, Copy, Default)]
struct Fared {
    /// Contacts of the truth the method answered "no hit" to.
    missed: usize,
    /// Hits reported later than the truth's first contact by more than two
    /// of its samples.
    late: usize,
}

impl Fared {
    fn of(cases: &[Case], method: impl Fn(&Case) -> Option<f64>) -> Fared {
        let mut fared = Fared::default();
        for case in cases {
            let Some(truth) = case.truth.first_contact else {
                continue;
            };
            match method(case) {
                None => fared.missed += 1,
                Some(t) if t > truth + 2.0 / TRUTH_SAMPLES as f64 => fared.late += 1,
                Some(_) => {}
            }
        }
        fared
    }
}

/// One printed row: a batch's group and how each method fared on it.
struct Row {
    group: String,
    /// Cases whose sampled truth has a contact.
    contacts: usize,
    affine: Fared,
    nonlinear: Option<Fared>,
}

/// One of parry's methods on a case (see `common`).
type Peer = fn(&Case) -> Result<Option<f64>, ()>;

/// affine-ccd's answer on a case, at `options`.
fn affine_toi(case: &Case, options: &QueryOptions) -> Option<f64> {
    common::affine(case, options)
        .ok()
        .flatten()
        .map(|t| t.fraction)
}

fn run_affine(cases: &[Case], options: &QueryOptions) -> usize {
    cases
        .iter()
        .filter(|c| affine_toi(c, options).is_some())
        .count()
}

/// Benchmarks every batch; returns the rows of the final table.
fn queries(c: &mut Criterion) -> Vec<Row> {
    let mut rows = Vec::new();
    for spin in [Spin::Ordinary, Spin::Fast] {
        for (k, kind) in pair_kinds().iter().enumerate() {
            let group = match spin {
                Spin::Ordinary => kind.name.to_string(),
                Spin::Fast => format!("{}-fast-spin", kind.name),
            };
            let cases = common::cases_spinning(kind, BATCH, 1000 + k as u64, spin);
            if cases.is_empty() {
                eprintln!("{group}: not supported, skipped");
                continue;
            }
            let at_1e4 = QueryOptions {
                epsilon: 1e-4,
                ..QueryOptions::default()
            };
            let has_nonlinear = parry_nonlinear(&cases[0]).is_ok();
            rows.push(Row {
                group: group.clone(),
                contacts: cases
                    .iter()
                    .filter(|c| c.truth.first_contact.is_some())
                    .count(),
                affine: Fared::of(&cases, |c| affine_toi(c, &at_1e4)),
                nonlinear: has_nonlinear
                    .then(|| Fared::of(&cases, |c| parry_nonlinear(c).ok().flatten())),
            });
            let mut group = c.benchmark_group(group);
            group
                .sample_size(10)
                .measurement_time(Duration::from_millis(800))
                .warm_up_time(Duration::from_millis(200));
            let (arithmetics, epsilons): (&[Arithmetic], &[f64]) = match spin {
                Spin::Ordinary => (&Arithmetic::ALL, &[1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6]),
                Spin::Fast => (&[Arithmetic::Affine], &[1e-4]),
            };
            for &arithmetic in arithmetics {
                for &eps in epsilons {
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
            let peers: [(&str, Peer); 2] = [
                ("parry_nonlinear", parry_nonlinear),
                ("parry_sweep", parry_sweep),
            ];
            for (name, peer) in peers {
                if peer(&cases[0]).is_err() {
                    continue; // parry does not take this pair kind
                }
                group.bench_function(name, |b| {
                    b.iter(|| {
                        black_box(
                            cases
                                .iter()
                                .filter(|c| matches!(peer(c), Ok(Some(_))))
                                .count(),
                        )
                    })
                });
            }
            group.finish();
        }
    }
    rows
}

/// criterion's median estimate of one benchmark, in ns per batch, if it
/// was measured in this run (files older than `since` are left from
/// earlier runs).
fn median_ns(group: &str, path: &str, since: SystemTime) -> Option<f64> {
    let dir = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    let file = format!("{dir}/criterion/{group}/{path}/new/estimates.json");
    let written = std::fs::metadata(&file).ok()?.modified().ok()?;
    if written < since {
        return None;
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(file).ok()?).ok()?;
    json["median"]["point_estimate"].as_f64()
}

/// The ratios the issue asks for, one row per batch measured.
fn print_ratios(rows: &[Row], since: SystemTime) {
    println!(
        "\nper query, ε = 1e-4, medians of criterion's samples (µs per query); \
         missed/late: of the batch's contacts in the sampled truth"
    );
    println!(
        "{:<26} {:>9} {:>9} {:>10} {:>10} {:>11} {:>14} {:>12}",
        "batch",
        "contacts",
        "affine",
        "missed/late",
        "nonlinear",
        "missed/late",
        "nonlinear/affine",
        "parry sweep"
    );
    let per_query = |ns: f64| ns / 1.0e3 / BATCH as f64;
    let fared =
        |f: Option<Fared>| f.map_or("n/a".to_string(), |f| format!("{}/{}", f.missed, f.late));
    for row in rows {
        let Some(affine) = median_ns(&row.group, "affine/1e-4", since) else {
            continue;
        };
        let nonlinear = median_ns(&row.group, "parry_nonlinear", since);
        let sweep = median_ns(&row.group, "parry_sweep", since);
        let show = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{:.2}", per_query(v)));
        let ratio = nonlinear.map_or("n/a".to_string(), |n| format!("{:.2}", n / affine));
        println!(
            "{:<26} {:>9} {:>9.2} {:>10} {:>10} {:>11} {:>14} {:>12}",
            row.group,
            row.contacts,
            per_query(affine),
            fared(Some(row.affine)),
            show(nonlinear),
            fared(row.nonlinear),
            ratio,
            show(sweep)
        );
    }
}

/// What criterion's `criterion_group!`/`criterion_main!` would do, keeping
/// the rows for the table.
fn main() {
    let since = SystemTime::now();
    let mut criterion = Criterion::default().configure_from_args();
    let rows = queries(&mut criterion);
    criterion.final_summary();
    print_ratios(&rows, since);
}
