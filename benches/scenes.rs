//! Step time of every demo scene under `off` (rapier, no CCD), `rapier`
//! (its own CCD) and `affine` (this crate's stage), measured in one run,
//! reported as ratios: affine/rapier and affine/off.
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
        "{:<26} {:>9} {:>9} {:>9} {:>13} {:>10}",
        "scene", "off ms", "rapier ms", "affine ms", "affine/rapier", "affine/off"
    );
    for scene in scenes::all() {
        let mut medians = [f64::INFINITY; 3];
        for _ in 0..REPEATS {
            for (slot, backend) in
                medians
                    .iter_mut()
                    .zip([Backend::Off, Backend::Rapier, Backend::Affine])
            {
                if let Ok(run) = run_scene(&scene, backend, &options) {
                    *slot = slot.min(run.median_step_ms);
                }
            }
        }
        let [off, rapier, affine] = medians;
        println!(
            "{:<26} {:>9.4} {:>9.4} {:>9.4} {:>13.2} {:>10.2}",
            scene.name,
            off,
            rapier,
            affine,
            affine / rapier,
            affine / off
        );
    }
}
