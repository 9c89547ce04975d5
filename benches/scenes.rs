//! Step time of every demo scene under `off` (rapier, no CCD), `rapier`
//! (its own CCD) and `affine` (this crate's stage), measured in one run,
//! reported as ratios: affine/rapier and affine/off.
//!
//! Where rapier loses bodies that the stage keeps in play (a paddle that
//! passes through a row of boxes leaves them asleep; pushed, they slide and
//! collide), rapier's pipeline has more to do under the stage, and
//! affine/rapier counts that too. So the table also gives the pipeline's
//! own share of the affine run (each step less the stage's time, as
//! `CcdReport::elapsed` measures it: the sweeps, queries and clamps) and
//! affine/pipeline: what the stage costs on top of rapier stepping the
//! same world.
//!
//! The median step of a scene that settles is an idle one, where the stage
//! does next to nothing and what rapier does decides the ratio; the last
//! column, `run a/r`, is affine/rapier over the whole run's steps (each
//! backend's least disturbed run), where the busy steps weigh in.
//!
//! `cargo bench --bench scenes` (prints a table; no criterion: each scene
//! run is already a median over its steps). `-- --substeps N` runs rapier
//! and affine cutting steps into at most N pieces (`max_ccd_substeps`,
//! `CcdConfig::substeps`).

use affine_ccd_scenes::backend::BackendConfig;
use affine_ccd_scenes::{self as scenes, Backend, RunOptions, run_scene};

/// Each scene is run this many times per backend, the backends taking
/// turns (so a slow spell of the machine falls on all three); the smallest
/// median step time is kept (the least disturbed run).
const REPEATS: usize = 5;

/// The quiet scene's whole run lasts about a millisecond, where one
/// disturbance shifts the ratio by a third: it is run this many more times,
/// off and affine taking turns, the least disturbed run of each kept.
const QUIET_REPEATS: usize = 60;

/// The value after `--substeps`, if given (cargo adds its own `--bench`).
fn substeps_arg() -> Option<u32> {
    let args: Vec<String> = std::env::args().collect();
    let at = args.iter().position(|a| a == "--substeps")?;
    match args.get(at + 1).and_then(|v| v.parse().ok()) {
        Some(n) if n >= 1 => Some(n),
        _ => {
            eprintln!("--substeps needs a count of at least 1");
            std::process::exit(2);
        }
    }
}

/// The scene with no fast body: there the stage should cost nothing
/// measurable over rapier with CCD off.
const QUIET: &str = "control_slow";

fn main() {
    let substeps = substeps_arg();
    let options = RunOptions {
        backend: BackendConfig {
            substeps,
            ..BackendConfig::default()
        },
        ..RunOptions::default()
    };
    match substeps {
        Some(n) => println!("reproduce: cargo bench --bench scenes -- --substeps {n}"),
        None => println!("reproduce: cargo bench --bench scenes"),
    }
    println!(
        "{:<26} {:>9} {:>9} {:>9} {:>13} {:>10} {:>10} {:>15} {:>8}",
        "scene",
        "off ms",
        "rapier ms",
        "affine ms",
        "affine/rapier",
        "affine/off",
        "pipe ms",
        "affine/pipeline",
        "run a/r"
    );
    for scene in scenes::all() {
        let mut medians = [f64::INFINITY; 3];
        let mut totals = [f64::INFINITY; 3];
        // The affine run's steps less its stage time (see the module docs).
        let mut pipeline = f64::INFINITY;
        for _ in 0..REPEATS {
            for ((slot, total), backend) in medians.iter_mut().zip(totals.iter_mut()).zip([
                Backend::Off,
                Backend::Rapier,
                Backend::Affine,
            ]) {
                if let Ok(run) = run_scene(&scene, backend, &options) {
                    *slot = slot.min(run.median_step_ms);
                    *total = total.min(run.total_step_ms);
                    if let Some(ms) = run
                        .median_pipeline_ms
                        .filter(|_| backend == Backend::Affine)
                    {
                        pipeline = pipeline.min(ms);
                    }
                }
            }
        }
        let [off, rapier, affine] = medians;
        println!(
            "{:<26} {:>9.4} {:>9.4} {:>9.4} {:>13.2} {:>10.2} {:>10.4} {:>15.2} {:>8.2}",
            scene.name,
            off,
            rapier,
            affine,
            affine / rapier,
            affine / off,
            pipeline,
            affine / pipeline,
            totals[2] / totals[1]
        );
        if scene.name == QUIET {
            print_quiet(&scene, &options, totals);
        }
    }
}

/// The quiet scene's whole run, off against affine. Its world sleeps after
/// a second, so its median step is an idle one (well under a microsecond,
/// mostly clock noise): the whole run's step time says what the stage
/// costs on the steps that do work. `totals` are the table's runs.
fn print_quiet(scene: &scenes::Scene, options: &RunOptions, totals: [f64; 3]) {
    let [mut off, _, mut affine] = totals;
    for _ in 0..QUIET_REPEATS {
        for (total, backend) in [(&mut off, Backend::Off), (&mut affine, Backend::Affine)] {
            if let Ok(run) = run_scene(scene, backend, options) {
                *total = total.min(run.total_step_ms);
            }
        }
    }
    println!(
        "{QUIET}, whole run (best of {}): off {off:.3} ms, affine {affine:.3} ms, affine/off {:.3}",
        REPEATS + QUIET_REPEATS,
        affine / off
    );
}
