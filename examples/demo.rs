//! Headless demo: runs every scene under every backend and prints one table.
//!
//! ```text
//! cargo run --release --example demo -- [--scene NAME]... [--backend NAME]...
//!     [--steps N] [--epsilon X] [--substeps N] [--json FILE] [--svg DIR]
//! ```
//!
//! `--scene` matches substrings of scene names and may repeat; `--backend`
//! takes off, rapier or affine and may repeat (default: all three);
//! `--steps` overrides every scene's step count; `--epsilon` is handed to the
//! affine backend; `--substeps` cuts steps at the first impact into at most
//! N pieces (rapier's `max_ccd_substeps`, the stage's
//! `CcdConfig::substeps`); `--json` writes the rows to a file; `--svg` writes one
//! side-view drawing per scene and backend into a folder.

use affine_ccd_scenes::runner::RunError;
use affine_ccd_scenes::{self as scenes, Backend, RunOptions, SceneReport, run_scene};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// The parsed command line.
#[derive(Debug, Default)]
struct Args {
    scenes: Vec<String>,
    backends: Vec<Backend>,
    steps: Option<usize>,
    epsilon: Option<f64>,
    substeps: Option<u32>,
    json: Option<PathBuf>,
    svg: Option<PathBuf>,
    profile: bool,
}

const USAGE: &str = "usage: demo [--scene NAME]... [--backend off|rapier|affine]... \
[--steps N] [--epsilon X] [--substeps N] [--json FILE] [--svg DIR] [--profile]";

fn parse_args() -> Result<Args, String> {
    let mut args = Args::default();
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--scene" => args.scenes.push(value()?),
            "--backend" => args.backends.push(value()?.parse()?),
            "--steps" => {
                let v = value()?;
                args.steps = Some(
                    v.parse()
                        .map_err(|_| format!("--steps: `{v}` is not a count"))?,
                );
            }
            "--epsilon" => {
                let v = value()?;
                let eps: f64 = v
                    .parse()
                    .map_err(|_| format!("--epsilon: `{v}` is not a number"))?;
                if !(eps.is_finite() && eps > 0.0) {
                    return Err(format!("--epsilon must be positive, got {v}"));
                }
                args.epsilon = Some(eps);
            }
            "--substeps" => {
                let v = value()?;
                match v.parse::<u32>() {
                    Ok(n) if n >= 1 => args.substeps = Some(n),
                    _ => return Err(format!("--substeps: `{v}` is not a count of at least 1")),
                }
            }
            "--json" => args.json = Some(value()?.into()),
            "--svg" => args.svg = Some(value()?.into()),
            "--profile" => args.profile = true,
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown option `{other}`\n{USAGE}")),
        }
    }
    if args.backends.is_empty() {
        args.backends = Backend::ALL.to_vec();
    }
    Ok(args)
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(args) => args,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::from(2);
        }
    };
    let scenes = scenes::find(&args.scenes);
    if scenes.is_empty() {
        eprintln!("no scene matches {:?}", args.scenes);
        return ExitCode::from(2);
    }
    if let Some(dir) = &args.svg
        && let Err(e) = std::fs::create_dir_all(dir)
    {
        eprintln!("cannot create {}: {e}", dir.display());
        return ExitCode::FAILURE;
    }
    let mut options = RunOptions {
        steps: args.steps,
        trace: args.svg.is_some(),
        ..RunOptions::default()
    };
    options.backend.epsilon = args.epsilon;
    options.backend.substeps = args.substeps;

    let runs = scenes.len() * args.backends.len();
    let bar = if std::io::stdout().is_terminal() {
        let bar = ProgressBar::new(runs as u64);
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}") {
            bar.set_style(style);
        }
        bar
    } else {
        ProgressBar::hidden()
    };

    let started = Instant::now();
    let mut reports: Vec<SceneReport> = Vec::new();
    let mut unavailable: Vec<Backend> = Vec::new();
    for scene in &scenes {
        let first = reports.len();
        for &backend in &args.backends {
            bar.set_message(format!("{} / {}", scene.name, backend));
            match run_scene(scene, backend, &options) {
                Ok(report) => {
                    if let (Some(dir), Some(trace)) = (&args.svg, &report.trace) {
                        let path = dir.join(format!("{}-{}.svg", scene.name, backend));
                        let title = format!(
                            "{} / {}: {} tunnelling, {} missed, {} deep",
                            scene.name,
                            backend,
                            report.tunnelling,
                            report.missed_contacts,
                            report.deep_ends
                        );
                        if let Err(e) = std::fs::write(&path, trace.to_svg(&title)) {
                            bar.suspend(|| eprintln!("cannot write {}: {e}", path.display()));
                        }
                    }
                    reports.push(report);
                }
                Err(RunError::Unavailable(b)) => {
                    if !unavailable.contains(&b) {
                        unavailable.push(b);
                    }
                }
            }
            bar.inc(1);
        }
        // The rest column compares final poses with rapier's own run of the
        // same scene: the one above, or one more run (not printed).
        if scene.effects.settles {
            let listed = reports[first..]
                .iter()
                .find(|r| r.backend == Backend::Rapier)
                .cloned();
            let reference = listed.or_else(|| {
                bar.set_message(format!("{} / rapier (reference)", scene.name));
                let plain = RunOptions {
                    trace: false,
                    ..options
                };
                run_scene(scene, Backend::Rapier, &plain).ok()
            });
            if let Some(reference) = reference {
                // Rapier's own row: how far its outcome moves when every
                // body starts 0.1 mm higher (how much the reference says).
                bar.set_message(format!("{} / rapier (raised 0.1 mm)", scene.name));
                let raised = RunOptions {
                    trace: false,
                    lift: 1.0e-4,
                    ..options
                };
                let mut spread = run_scene(scene, Backend::Rapier, &raised).ok();
                if let Some(spread) = &mut spread {
                    spread.compare_rest(&reference);
                }
                for report in &mut reports[first..] {
                    report.compare_rest(&reference);
                    if report.backend == Backend::Rapier {
                        report.rest = spread.as_ref().and_then(|s| s.rest);
                    }
                }
            }
        }
    }
    bar.finish_and_clear();

    print_table(&reports);
    if args.profile {
        print_profile(&reports);
    }
    for backend in &unavailable {
        println!("{backend}: not built yet");
    }
    println!(
        "{} scenes, {} runs in {:.1} s; CCD ms: n/a = not measurable \
(rapier times its CCD only with its `profiler` feature), - = no CCD",
        scenes.len(),
        reports.len(),
        started.elapsed().as_secs_f64()
    );
    println!(
        "frozen: body-steps held (< 1 mm, < 0.01 rad) while faster than 1 m/s or 1 rad/s, \
in runs of 10+, and not held when rapier alone (no CCD) takes that step from the same state; \
defl: body-steps whose free path touched nothing but whose velocity \
changed; rest mm: largest final height difference / distance from rapier's run, bodies \
rapier lost left out (settling scenes only, - = does not settle; on rapier's row, ± = how far \
its own run moves when every body starts 0.1 mm higher); energy %: largest one-step rise of \
the mechanical energy in % of the run's largest kinetic energy (- = kinematic scripts)"
    );
    println!(
        "reproduce: cargo run --release --example demo -- {}",
        reproduce(&args)
    );

    if let Some(path) = &args.json
        && let Err(e) = std::fs::write(path, to_json(&reports))
    {
        eprintln!("cannot write {}: {e}", path.display());
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

/// The command-line arguments again, for the "reproduce" line.
fn reproduce(args: &Args) -> String {
    let mut parts: Vec<String> = Vec::new();
    for s in &args.scenes {
        parts.push(format!("--scene {s}"));
    }
    if args.backends != Backend::ALL {
        for b in &args.backends {
            parts.push(format!("--backend {b}"));
        }
    }
    if let Some(n) = args.steps {
        parts.push(format!("--steps {n}"));
    }
    if let Some(e) = args.epsilon {
        parts.push(format!("--epsilon {e}"));
    }
    if let Some(n) = args.substeps {
        parts.push(format!("--substeps {n}"));
    }
    if args.profile {
        parts.push("--profile".to_string());
    }
    parts.join(" ")
}

/// The CCD column: milliseconds, `n/a` when not measurable, `-` for `off`.
fn ccd_cell(report: &SceneReport) -> String {
    match (report.ccd_ms, report.backend) {
        (Some(ms), _) => format!("{ms:.2}"),
        (None, Backend::Off) => "-".to_string(),
        (None, _) => "n/a".to_string(),
    }
}

/// The rest column: the largest final height difference from rapier's run
/// and the largest final distance (mm, `height/distance`); on rapier's own
/// row, `±` the same for rapier started 0.1 mm higher; `-` when the scene
/// does not settle, `?` when no reference run was available.
fn rest_cell(report: &SceneReport) -> String {
    match (report.settles, report.backend, report.rest) {
        (false, _, _) => "-".to_string(),
        (true, Backend::Rapier, Some(gap)) => {
            format!("±{:.1}/{:.0}", gap.height * 1e3, gap.distance * 1e3)
        }
        (true, _, Some(gap)) => format!("{:.1}/{:.0}", gap.height * 1e3, gap.distance * 1e3),
        (true, _, None) => "?".to_string(),
    }
}

/// The energy column: the largest one-step rise in percent of the scale,
/// `-` for scenes with kinematic scripts.
fn energy_cell(report: &SceneReport) -> String {
    match report.energy_rise_percent() {
        Some(percent) => format!("{percent:.2}"),
        None => "-".to_string(),
    }
}

fn print_table(reports: &[SceneReport]) {
    let width = reports
        .iter()
        .map(|r| r.scene.len())
        .max()
        .unwrap_or(5)
        .max(5);
    println!(
        "{:<width$}  {:<7} {:>10} {:>7} {:>5} {:>6} {:>5} {:>10} {:>8} {:>6} {:>8} {:>8}",
        "scene",
        "backend",
        "tunnelling",
        "missed",
        "deep",
        "frozen",
        "defl",
        "rest mm",
        "energy %",
        "steps",
        "step ms",
        "CCD ms"
    );
    println!("{}", "-".repeat(width + 92));
    for r in reports {
        println!(
            "{:<width$}  {:<7} {:>10} {:>7} {:>5} {:>6} {:>5} {:>10} {:>8} {:>6} {:>8.3} {:>8}",
            r.scene,
            r.backend.name(),
            r.tunnelling,
            r.missed_contacts,
            r.deep_ends,
            r.frozen,
            r.deflected,
            rest_cell(r),
            energy_cell(r),
            r.steps,
            r.median_step_ms,
            ccd_cell(r)
        );
    }
}

/// Where the affine stage's time goes, per scene: per step, the bodies it
/// swept, the collider pairs it queried, the pairs moving together (left
/// to rapier unqueried), the pairs touching at the start (sampled, left to
/// rapier), the late shallow contacts (left to rapier), the pair
/// evaluations and the clamps; and its CCD time per step.
fn print_profile(reports: &[SceneReport]) {
    println!();
    println!(
        "{:<26} {:>8} {:>8} {:>9} {:>9} {:>8} {:>11} {:>8} {:>9}",
        "affine stage, per step",
        "bodies",
        "pairs",
        "together",
        "touching",
        "shallow",
        "evaluations",
        "clamps",
        "CCD ms"
    );
    for r in reports.iter().filter(|r| r.backend == Backend::Affine) {
        let (Some(p), Some(ms)) = (r.profile, r.ccd_ms) else {
            continue;
        };
        let per = |x: f64| x / p.steps.max(1) as f64;
        println!(
            "{:<26} {:>8.2} {:>8.2} {:>9.2} {:>9.2} {:>8.2} {:>11.1} {:>8.3} {:>9.4}",
            r.scene,
            per(p.bodies_swept as f64),
            per(p.pairs as f64),
            per(p.together as f64),
            per(p.touching as f64),
            per(p.shallow as f64),
            per(p.evaluations as f64),
            per(p.clamps as f64),
            per(ms)
        );
    }
    print_families(reports);
}

/// The same runs' pair evaluations per step by what each was spent on:
/// the ball families together (a few dozen operations each), the box and
/// triangle families (13-15 separating axes), the support-map pairs
/// (capsules, cylinders, cones, hulls; adaptive axes), a composite's
/// bounding boxes on the way down its tree, and the shortcuts that settled
/// a pair before its family was asked.
fn print_families(reports: &[SceneReport]) {
    use affine_ccd::query::Family;
    let columns: [(&str, &[Family]); 8] = [
        (
            "balls",
            &[
                Family::BallBall,
                Family::BallTriangle,
                Family::BallSegment,
                Family::BallCuboid,
            ],
        ),
        ("tri-tri", &[Family::TriangleTriangle]),
        ("box-box", &[Family::CuboidCuboid]),
        ("box-tri", &[Family::CuboidTriangle]),
        ("half-sp", &[Family::HalfSpace]),
        ("support", &[Family::SupportMap]),
        ("compos", &[Family::Composite]),
        ("shortcut", &[Family::Shortcut]),
    ];
    println!();
    print!("{:<26}", "evaluations per step");
    for (name, _) in &columns {
        print!(" {name:>8}");
    }
    println!();
    for r in reports.iter().filter(|r| r.backend == Backend::Affine) {
        let Some(p) = r.profile else {
            continue;
        };
        print!("{:<26}", r.scene);
        for (_, families) in &columns {
            let count: u64 = families.iter().map(|&f| p.families.get(f)).sum();
            print!(" {:>8.1}", count as f64 / p.steps.max(1) as f64);
        }
        println!();
    }
}

fn to_json(reports: &[SceneReport]) -> String {
    let rows: Vec<serde_json::Value> = reports
        .iter()
        .map(|r| {
            serde_json::json!({
                "scene": r.scene,
                "backend": r.backend.name(),
                "tunnelling_events": r.tunnelling,
                "missed_contacts": r.missed_contacts,
                "deep_ends": r.deep_ends,
                "frozen": r.frozen,
                "deflected": r.deflected,
                "settles": r.settles,
                "rest_mm": r.rest.map(|g| f64::from(g.distance) * 1e3),
                "rest_rad": r.rest.map(|g| f64::from(g.angle)),
                "rest_height_mm": r.rest.map(|g| f64::from(g.height) * 1e3),
                "rest_tilt_rad": r.rest.map(|g| f64::from(g.tilt)),
                "energy_rise_j": r.energy.map(|e| e.max_rise),
                "energy_scale_j": r.energy.map(|e| e.scale),
                "energy_rise_percent": r.energy_rise_percent(),
                "steps": r.steps,
                "median_step_ms": r.median_step_ms,
                "ccd_ms": r.ccd_ms,
            })
        })
        .collect();
    serde_json::to_string_pretty(&rows).unwrap_or_else(|_| "[]".to_string())
}
