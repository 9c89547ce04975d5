//! What accuracy costs in time: affine-ccd at several ε in every arithmetic,
//! and parry's two methods, on the same seeded cases, against dense-sampling
//! ground truth.
//!
//! ```sh
//! cargo run --release --example accuracy            # 200 cases per pair kind
//! cargo run --release --example accuracy -- --cases 1000
//! ```
//! Prints one table and writes `docs/accuracy.md` and `docs/accuracy.svg`.

#[path = "../benches/common/mod.rs"]
mod common;

use affine_ccd::Arithmetic;
use affine_ccd::query::QueryOptions;
use common::{Case, pair_kinds, parry_nonlinear, parry_sweep};
use std::fmt::Write as _;
use std::time::Instant;

const EPSILONS: [f64; 6] = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6];

/// One method's results over every case.
struct Row {
    method: String,
    epsilon: Option<f64>,
    times_us: Vec<f64>,
    evaluations: Vec<f64>,
    errors: Vec<f64>,
    false_negatives: usize,
    false_positives: usize,
    cases: usize,
}

impl Row {
    fn new(method: String, epsilon: Option<f64>) -> Row {
        Row {
            method,
            epsilon,
            times_us: vec![],
            evaluations: vec![],
            errors: vec![],
            false_negatives: 0,
            false_positives: 0,
            cases: 0,
        }
    }

    /// Record one answer (fraction of the step or none) against the truth.
    fn record(&mut self, case: &Case, answer: Option<f64>, micros: f64, evaluations: Option<u64>) {
        self.cases += 1;
        self.times_us.push(micros);
        if let Some(e) = evaluations {
            self.evaluations.push(e as f64);
        }
        match (case.truth.first_contact, answer) {
            (Some(t), Some(a)) => self.errors.push((t - a).abs()),
            (Some(_), None) => self.false_negatives += 1,
            (None, Some(_)) => self.false_positives += 1,
            (None, None) => {}
        }
    }
}

fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let per_kind = args
        .iter()
        .position(|a| a == "--cases")
        .and_then(|i| args.get(i + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(200usize);

    let mut cases: Vec<Case> = Vec::new();
    let mut kinds_used = Vec::new();
    let mut per_kind_rows = Vec::new();
    for (k, kind) in pair_kinds().iter().enumerate() {
        let some = common::cases(kind, per_kind, 1000 + k as u64);
        if some.is_empty() {
            eprintln!("{}: not supported yet, skipped", kind.name);
            continue;
        }
        kinds_used.push(format!("{} ({})", kind.name, some.len()));
        per_kind_rows.push(kind_summary(kind.name, &some));
        cases.extend(some);
    }
    let hits = cases
        .iter()
        .filter(|c| c.truth.first_contact.is_some())
        .count();

    let mut rows = Vec::new();
    for kind in Arithmetic::ALL {
        for eps in EPSILONS {
            let mut row = Row::new(kind.name().to_string(), Some(eps));
            let options = QueryOptions {
                epsilon: eps,
                arithmetic: kind,
                ..QueryOptions::default()
            };
            for case in &cases {
                let (got, micros) = timed_query(case, &options);
                let got = got.expect("supported cases only");
                row.record(
                    case,
                    got.map(|t| t.fraction),
                    micros,
                    got.map(|t| t.stats.pair_evaluations),
                );
            }
            rows.push(row);
        }
    }
    for (name, method) in [
        (
            "parry nonlinear",
            parry_nonlinear as fn(&Case) -> Result<Option<f64>, ()>,
        ),
        ("parry sweep", parry_sweep),
    ] {
        let mut row = Row::new(name.to_string(), None);
        for case in &cases {
            let (got, micros) = fastest(|| method(case));
            if let Ok(answer) = got {
                row.record(case, answer, micros, None);
            }
        }
        rows.push(row);
    }

    let mut md = String::new();
    let command = format!("cargo run --release --example accuracy -- --cases {per_kind}");
    writeln!(md, "# What accuracy costs\n\n`{command}`\n").unwrap();
    writeln!(
        md,
        "Times are per query, each the fastest of {REPEATS} runs in a row.\n"
    )
    .unwrap();
    writeln!(
        md,
        "{} cases ({hits} hit by the ground truth): {}.\n",
        cases.len(),
        kinds_used.join(", ")
    )
    .unwrap();
    writeln!(md, "| method | ε (of step) | cases | median µs | p99 µs | max µs | median evals | median error | max error | false neg. | false pos. |").unwrap();
    writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|").unwrap();
    for r in &rows {
        writeln!(
            md,
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {} | {:.1e} | {:.1e} | {} | {} |",
            r.method,
            r.epsilon.map_or("—".into(), |e| format!("{e:.0e}")),
            r.cases,
            quantile(&r.times_us, 0.5),
            quantile(&r.times_us, 0.99),
            quantile(&r.times_us, 1.0),
            if r.evaluations.is_empty() {
                "—".into()
            } else {
                format!("{}", quantile(&r.evaluations, 0.5))
            },
            quantile(&r.errors, 0.5),
            r.errors.iter().copied().fold(0.0, f64::max),
            r.false_negatives,
            r.false_positives,
        )
        .unwrap();
    }
    writeln!(
        md,
        "\n## Per pair kind, affine at ε = 1e-4 against parry on the same cases\n"
    )
    .unwrap();
    writeln!(md, "| pair kind | cases | affine median µs | parry nonlinear µs | ratio (parry/affine) | parry sweep µs | affine median evals | affine max error | affine FN | affine FP | parry nonlinear FN | parry sweep FN |").unwrap();
    writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|").unwrap();
    for line in &per_kind_rows {
        writeln!(md, "{line}").unwrap();
    }
    print!("{md}");
    std::fs::create_dir_all("docs").ok();
    std::fs::write("docs/accuracy.md", &md).expect("write docs/accuracy.md");
    std::fs::write("docs/accuracy.svg", plot(&rows)).expect("write docs/accuracy.svg");
    eprintln!("wrote docs/accuracy.md and docs/accuracy.svg");
}

/// Each query is timed this many times in a row and the fastest kept: a
/// single timing of a few microseconds on this kind of machine wanders by
/// tens of per cent, and a slow spell would fall on one method's cases.
const REPEATS: usize = 5;

/// `query`'s answer and the fewest microseconds it took in [`REPEATS`]
/// runs.
fn fastest<T>(mut query: impl FnMut() -> T) -> (T, f64) {
    let mut best = f64::INFINITY;
    let mut answer = None;
    for _ in 0..REPEATS {
        let start = Instant::now();
        let got = query();
        best = best.min(start.elapsed().as_secs_f64() * 1e6);
        answer = Some(got);
    }
    (answer.expect("REPEATS > 0"), best)
}

/// One affine-ccd query on `case`, and the microseconds it took (the
/// fastest of [`REPEATS`]).
fn timed_query(
    case: &Case,
    options: &QueryOptions,
) -> (Result<Option<affine_ccd::Toi>, affine_ccd::CcdError>, f64) {
    fastest(|| common::affine(case, options))
}

/// One markdown row: affine at ε = 1e-4 and parry's two methods on the
/// cases of one pair kind.
fn kind_summary(name: &str, cases: &[Case]) -> String {
    let options = QueryOptions::default();
    let mut ours = Row::new("affine".into(), Some(1e-4));
    let mut nonlinear = Row::new("parry nonlinear".into(), None);
    let mut sweep = Row::new("parry sweep".into(), None);
    for case in cases {
        let (got, micros) = timed_query(case, &options);
        let got = got.expect("supported cases only");
        ours.record(
            case,
            got.map(|t| t.fraction),
            micros,
            got.map(|t| t.stats.pair_evaluations),
        );
        for (row, method) in [
            (
                &mut nonlinear,
                parry_nonlinear as fn(&Case) -> Result<Option<f64>, ()>,
            ),
            (&mut sweep, parry_sweep),
        ] {
            let (got, micros) = fastest(|| method(case));
            if let Ok(answer) = got {
                row.record(case, answer, micros, None);
            }
        }
    }
    let (a, n) = (
        quantile(&ours.times_us, 0.5),
        quantile(&nonlinear.times_us, 0.5),
    );
    let or_na = |r: &Row, v: String| if r.cases == 0 { "n/a".to_string() } else { v };
    format!(
        "| {name} | {} | {a:.2} | {} | {} | {} | {} | {:.1e} | {} | {} | {} | {} |",
        ours.cases,
        or_na(&nonlinear, format!("{n:.2}")),
        or_na(&nonlinear, format!("{:.2}", n / a)),
        or_na(&sweep, format!("{:.2}", quantile(&sweep.times_us, 0.5))),
        quantile(&ours.evaluations, 0.5),
        ours.errors.iter().copied().fold(0.0, f64::max),
        ours.false_negatives,
        ours.false_positives,
        or_na(&nonlinear, nonlinear.false_negatives.to_string()),
        or_na(&sweep, sweep.false_negatives.to_string()),
    )
}

/// Median time per query against median error, log–log, one line per
/// arithmetic (points at each ε) and one point per parry method.
fn plot(rows: &[Row]) -> String {
    let (w, h, m) = (640.0, 420.0, 60.0);
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| {
            (
                quantile(&r.errors, 0.5).max(1e-12).log10(),
                quantile(&r.times_us, 0.5).max(1e-3).log10(),
            )
        })
        .collect();
    let (xmin, xmax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ymin, ymax) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (xmin, xmax) = (xmin.floor(), xmax.ceil().max(xmin.floor() + 1.0));
    let (ymin, ymax) = (ymin.floor(), ymax.ceil().max(ymin.floor() + 1.0));
    let sx = |x: f64| m + (x - xmin) / (xmax - xmin) * (w - 2.0 * m);
    let sy = |y: f64| h - m - (y - ymin) / (ymax - ymin) * (h - 2.0 * m);
    let colours = [
        "#888", "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e",
    ];
    let mut svg = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{h}' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
    );
    writeln!(
        svg,
        "<line x1='{m}' y1='{}' x2='{}' y2='{}' stroke='black'/>",
        h - m,
        w - m,
        h - m
    )
    .unwrap();
    writeln!(
        svg,
        "<line x1='{m}' y1='{m}' x2='{m}' y2='{}' stroke='black'/>",
        h - m
    )
    .unwrap();
    for d in (xmin as i32)..=(xmax as i32) {
        writeln!(
            svg,
            "<text x='{}' y='{}' text-anchor='middle'>1e{d}</text>",
            sx(d as f64),
            h - m + 16.0
        )
        .unwrap();
    }
    for d in (ymin as i32)..=(ymax as i32) {
        writeln!(
            svg,
            "<text x='{}' y='{}' text-anchor='end'>1e{d} µs</text>",
            m - 4.0,
            sy(d as f64) + 4.0
        )
        .unwrap();
    }
    writeln!(
        svg,
        "<text x='{}' y='{}' text-anchor='middle'>median error (fraction of the step)</text>",
        w / 2.0,
        h - 12.0
    )
    .unwrap();
    writeln!(svg, "<text x='14' y='{}' transform='rotate(-90 14 {})' text-anchor='middle'>median time per query</text>", h / 2.0, h / 2.0).unwrap();
    let mut legend_y = m;
    let mut i = 0;
    while i < rows.len() {
        let name = &rows[i].method;
        let group: Vec<usize> = (i..rows.len())
            .take_while(|&j| &rows[j].method == name)
            .collect();
        let colour = colours[(legend_y as usize / 16) % colours.len()];
        let path: Vec<String> = group
            .iter()
            .map(|&j| format!("{:.1},{:.1}", sx(pts[j].0), sy(pts[j].1)))
            .collect();
        if path.len() > 1 {
            writeln!(
                svg,
                "<polyline fill='none' stroke='{colour}' stroke-width='2' points='{}'/>",
                path.join(" ")
            )
            .unwrap();
        }
        for &j in &group {
            writeln!(
                svg,
                "<circle cx='{:.1}' cy='{:.1}' r='3.5' fill='{colour}'/>",
                sx(pts[j].0),
                sy(pts[j].1)
            )
            .unwrap();
        }
        writeln!(
            svg,
            "<text x='{}' y='{legend_y}' fill='{colour}'>{name}</text>",
            w - m - 110.0
        )
        .unwrap();
        legend_y += 16.0;
        i += group.len();
    }
    svg.push_str("</svg>\n");
    svg
}
