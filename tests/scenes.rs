//! Every scene under every available backend, judged by both oracles.
//!
//! Scenario: each scene is run headless (steps capped at [`MAX_STEPS`] so the
//! whole test stays well within a minute in release). Assertions:
//!
//! - `off` fails on every scene built to tunnel (its guards see a body
//!   pass an obstacle, or the contact counter sees a missed contact or a
//!   deep end; where a guard sees one, the counter must too): otherwise the
//!   oracle could never fail and would prove nothing;
//! - every backend is clean on the control scene with slow bodies: otherwise
//!   the oracle reports false alarms;
//! - `affine` has zero tunnelling events, missed contacts and deep ends on
//!   every scene, and no count above `rapier`'s.
//!
//! Run: `cargo test --release --test scenes -- --nocapture` to see the table.

use affine_ccd_scenes::{self as scenes, Backend, RunOptions, SceneReport, run_scene};

/// Upper bound on the steps of any scene in this test.
const MAX_STEPS: usize = 300;

#[test]
fn the_oracle_sees_tunnelling_without_ccd_and_nothing_on_slow_scenes() {
    let started = std::time::Instant::now();
    let mut reports: Vec<(scenes::Scene, SceneReport)> = Vec::new();
    let mut failures: Vec<String> = Vec::new();
    for scene in scenes::all() {
        for backend in Backend::ALL {
            let options = RunOptions {
                steps: Some(scene.steps.min(MAX_STEPS)),
                ..RunOptions::default()
            };
            match run_scene(&scene, backend, &options) {
                Ok(report) => reports.push((scene, report)),
                Err(e) => failures.push(format!("{} / {backend}: {e}", scene.name)),
            }
        }
    }

    println!(
        "{:<26} {:<7} {:>10} {:>7} {:>5} {:>6} {:>8}",
        "scene", "backend", "tunnelling", "missed", "deep", "steps", "step ms"
    );
    for (_, r) in &reports {
        println!(
            "{:<26} {:<7} {:>10} {:>7} {:>5} {:>6} {:>8.3}",
            r.scene,
            r.backend.name(),
            r.tunnelling,
            r.missed_contacts,
            r.deep_ends,
            r.steps,
            r.median_step_ms
        );
    }
    println!(
        "{} runs in {:.1} s",
        reports.len(),
        started.elapsed().as_secs_f64()
    );

    for (scene, r) in &reports {
        if r.backend == Backend::Off && scene.built_to_tunnel {
            if r.is_clean() {
                failures.push(format!(
                    "{}: off shows no tunnelling, missed contact or deep end: the scene cannot fail",
                    r.scene
                ));
            }
            if r.tunnelling > 0 && r.missed_contacts + r.deep_ends == 0 {
                failures.push(format!(
                    "{}: off tunnels ({} events) but the contact counter saw nothing",
                    r.scene, r.tunnelling
                ));
            }
        }
        if !scene.built_to_tunnel && !r.is_clean() {
            failures.push(format!(
                "{} (control) / {}: {} tunnelling, {} missed, {} deep: expected all zero",
                r.scene, r.backend, r.tunnelling, r.missed_contacts, r.deep_ends
            ));
        }
    }

    // The affine stage: clean on every scene, and never worse than rapier.
    let mut affine_runs = 0;
    for (scene, r) in reports.iter().filter(|(_, r)| r.backend == Backend::Affine) {
        affine_runs += 1;
        if !r.is_clean() {
            failures.push(format!(
                "{} / affine: {} tunnelling, {} missed, {} deep: expected all zero",
                r.scene, r.tunnelling, r.missed_contacts, r.deep_ends
            ));
        }
        let rapier = reports
            .iter()
            .find(|(s, q)| s.name == scene.name && q.backend == Backend::Rapier)
            .map(|(_, q)| q);
        if let Some(q) = rapier {
            let worse = r.tunnelling > q.tunnelling
                || r.missed_contacts > q.missed_contacts
                || r.deep_ends > q.deep_ends;
            if worse {
                failures.push(format!(
                    "{}: affine ({}, {}, {}) is worse than rapier ({}, {}, {})",
                    r.scene,
                    r.tunnelling,
                    r.missed_contacts,
                    r.deep_ends,
                    q.tunnelling,
                    q.missed_contacts,
                    q.deep_ends
                ));
            }
        }
    }
    assert_eq!(
        affine_runs,
        scenes::all().len(),
        "the affine backend must run on every scene"
    );

    assert!(
        reports.iter().any(|(s, _)| !s.built_to_tunnel),
        "no control scene in the catalogue"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The stage cutting steps at the first impact (`CcdConfig::substeps`):
/// as clean as the clamp on every scene, beside rapier's own CCD with the
/// same `max_ccd_substeps`.
#[test]
fn with_substeps_the_stage_stays_clean_on_every_scene() {
    use affine_ccd_scenes::backend::BackendConfig;
    let mut failures = Vec::new();
    for scene in scenes::all() {
        let options = RunOptions {
            steps: Some(scene.steps.min(MAX_STEPS)),
            backend: BackendConfig {
                substeps: Some(4),
                ..BackendConfig::default()
            },
            ..RunOptions::default()
        };
        let ours = run_scene(&scene, Backend::Affine, &options).expect("affine runs");
        let theirs = run_scene(&scene, Backend::Rapier, &options).expect("rapier runs");
        println!(
            "{:<26} substeps 4: affine ({}, {}, {}), rapier ({}, {}, {}) (tunnelling, missed, deep)",
            scene.name,
            ours.tunnelling,
            ours.missed_contacts,
            ours.deep_ends,
            theirs.tunnelling,
            theirs.missed_contacts,
            theirs.deep_ends
        );
        if !ours.is_clean() {
            failures.push(format!(
                "{} / affine, 4 substeps: {} tunnelling, {} missed, {} deep: expected all zero",
                scene.name, ours.tunnelling, ours.missed_contacts, ours.deep_ends
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The fidelity counters under rapier and affine, one row per run.
fn print_fidelity(reports: &[SceneReport]) {
    println!(
        "{:<26} {:<7} {:>6} {:>5} {:>12} {:>12} {:>8}",
        "scene", "backend", "frozen", "defl", "rest dy/d mm", "energy rise", "energy %"
    );
    for r in reports {
        let rest = match (r.settles, r.rest) {
            (false, _) => "-".to_string(),
            (true, Some(gap)) => format!("{:.1}/{:.0}", gap.height * 1e3, gap.distance * 1e3),
            (true, None) => "?".to_string(),
        };
        let (rise, percent) = match r.energy {
            Some(e) => (
                format!("{:.4} J", e.max_rise),
                format!("{:.2}", e.rise_percent()),
            ),
            None => ("-".to_string(), "-".to_string()),
        };
        println!(
            "{:<26} {:<7} {:>6} {:>5} {:>12} {:>12} {:>8}",
            r.scene,
            r.backend.name(),
            r.frozen,
            r.deflected,
            rest,
            rise,
            percent
        );
    }
}

/// The stage removes tunnelling and nothing else, beside rapier's own CCD
/// on every scene (settling scenes run their full length, so that they are
/// at rest when compared):
///
/// - no body is held still while its velocity says it moves (`frozen`);
/// - on the near-miss scenes no body whose free path touches nothing has its
///   velocity changed (`deflected`). Elsewhere rapier's speculative contacts
///   change velocities at gaps of microns to centimetres under every
///   backend (measured in the issue notes), so the count is printed, not
///   asserted;
/// - the largest one-step rise of the mechanical energy is at most
///   rapier's plus 1 % of the run's largest kinetic energy;
/// - on settling scenes each body comes to rest where rapier's does: its
///   final centre of mass within 5 mm of rapier's and its orientation
///   within 0.01 rad (bodies rapier lost through something left out), wherever
///   rapier's own outcome is reproducible: rapier run again with every
///   body raised 0.1 mm ends within 5 mm of its first run. Where it does
///   not (a slide at dt = 0.25 s catching on mesh edges, rapier#217), the
///   reference says nothing finer than that and only the final height is
///   asserted (within 5 mm); the distances are printed.
#[test]
fn affine_is_faithful_on_every_scene() {
    let mut reports: Vec<SceneReport> = Vec::new();
    let mut failures = Vec::new();
    for scene in scenes::all() {
        let steps = if scene.effects.settles {
            scene.steps
        } else {
            scene.steps.min(MAX_STEPS)
        };
        let options = RunOptions {
            steps: Some(steps),
            ..RunOptions::default()
        };
        let theirs = run_scene(&scene, Backend::Rapier, &options).expect("rapier runs");
        let mut ours = run_scene(&scene, Backend::Affine, &options).expect("affine runs");
        ours.compare_rest(&theirs);
        // How far rapier's own outcome moves when the start does by 0.1 mm.
        let spread = scene.effects.settles.then(|| {
            let lifted = RunOptions {
                lift: 1.0e-4,
                ..options
            };
            let mut again = run_scene(&scene, Backend::Rapier, &lifted).expect("rapier runs");
            again.compare_rest(&theirs);
            again.rest.expect("a settling scene gets a rest gap")
        });
        if ours.frozen > 0 {
            failures.push(format!(
                "{}: affine held {} body-steps (rapier {})",
                scene.name, ours.frozen, theirs.frozen
            ));
        }
        if scene.name.starts_with("near_miss") && ours.deflected > 0 {
            failures.push(format!(
                "{}: affine deflected {} near misses (rapier {})",
                scene.name, ours.deflected, theirs.deflected
            ));
        }
        if let (Some(a), Some(r)) = (ours.energy_rise_percent(), theirs.energy_rise_percent())
            && a > r + 1.0
        {
            failures.push(format!(
                "{}: energy rose {a:.2} % in a step under affine, {r:.2} % under rapier",
                scene.name
            ));
        }
        if let (Some(gap), Some(spread)) = (ours.rest, spread) {
            let reproducible = spread.distance <= 5.0e-3;
            println!(
                "{}: rest {:.1} mm / {:.4} rad (up axis {:.4} rad, height {:.1} mm) from rapier's; \
                 rapier raised 0.1 mm: {:.1} mm / {:.4} rad{}",
                scene.name,
                gap.distance * 1e3,
                gap.angle,
                gap.tilt,
                gap.height * 1e3,
                spread.distance * 1e3,
                spread.angle,
                if reproducible {
                    ""
                } else {
                    " (not reproducible)"
                }
            );
            if gap.height > 5.0e-3 {
                failures.push(format!(
                    "{}: a body rests {:.1} mm higher or lower than rapier's",
                    scene.name,
                    gap.height * 1e3
                ));
            }
            if reproducible && (gap.distance > 5.0e-3 || gap.angle > 0.01) {
                failures.push(format!(
                    "{}: a body rests {:.1} mm and {:.4} rad from rapier's",
                    scene.name,
                    gap.distance * 1e3,
                    gap.angle
                ));
            }
        }
        reports.push(theirs);
        reports.push(ours);
    }
    print_fidelity(&reports);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A settling scene of this test's own: three boxes dropped 0.3 m onto a
/// floor, each on its own, no CCD needed. It comes to rest well within
/// its 150 steps.
fn three_boxes_settle(world: &mut rapier3d::prelude::PhysicsWorld) -> scenes::Setup {
    use rapier3d::math::Vector;
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};
    world.insert_collider(
        ColliderBuilder::cuboid(5.0, 0.1, 5.0).translation(Vector::new(0.0, -0.1, 0.0)),
        None,
    );
    for i in 0..3 {
        let x = -1.5 + 1.5 * i as f32;
        world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.5 + 0.1 * i as f32, 0.0)),
            ColliderBuilder::cuboid(0.2, 0.2, 0.2).friction(0.8),
        );
    }
    scenes::Setup::default()
}

const SETTLE: scenes::Scene = scenes::Scene {
    name: "test_three_boxes_settle",
    about: "three boxes dropped onto a floor, each on its own",
    dt: 1.0 / 60.0,
    steps: 150,
    effects: scenes::Effects {
        gravity: true,
        rotation: false,
        restitution: false,
        friction: true,
        kinematic: false,
        settles: true,
    },
    built_to_tunnel: false,
    view: [0, 1],
    build: three_boxes_settle,
};

/// The rest comparison on a settling scene: rapier against itself is 0,
/// `off` (the same as rapier where no body is fast) is 0 too, and the
/// counters all report on every backend.
#[test]
fn the_rest_counter_compares_final_poses_with_rapier() {
    let options = RunOptions::default();
    let reference = run_scene(&SETTLE, Backend::Rapier, &options).expect("rapier runs");
    let mut reports = Vec::new();
    for backend in Backend::ALL {
        let mut report = run_scene(&SETTLE, backend, &options).expect("backend runs");
        assert!(report.settles && report.rest.is_none());
        report.compare_rest(&reference);
        reports.push(report);
    }
    print_fidelity(&reports);
    for r in &reports {
        let gap = r.rest.expect("a settling scene gets a rest gap");
        assert!(
            gap.distance.is_finite() && gap.angle.is_finite(),
            "{}: {gap:?}",
            r.backend
        );
        assert_eq!(
            r.final_bodies.len(),
            3,
            "{}: three boxes (the floor has no body)",
            r.backend
        );
        assert!(
            r.energy.is_some(),
            "{}: closed scene, energy measured",
            r.backend
        );
        if r.backend != Backend::Affine {
            assert_eq!(gap.distance, 0.0, "{}: the same run as rapier's", r.backend);
            assert_eq!(gap.angle, 0.0, "{}", r.backend);
        }
    }
    // The boxes really came to rest: not still falling at the end.
    for (_, state) in &reference.final_bodies {
        assert!(state.linvel.length() < 0.05, "{state:?}");
    }
}

/// A fast spinner held at its start (its clamp at the step's start) ends
/// the rounds: in `spinning_trimesh`'s first step the 250 rad/s mesh
/// touches the wall at once, and each of the three bodies is swept at most
/// twice (the first sweeps, then the clamped body and its neighbours
/// against its cut). The held mesh was once swept turning a whole turn in
/// place (the turn hint of no turn), found held again with the same cut in
/// every round, for all eight rounds (24 sweeps); a cut that leaves a
/// motion as it was now ends the rounds, and a held body no longer turns.
#[test]
fn a_body_held_at_its_start_ends_the_rounds() {
    let scene = scenes::all()
        .into_iter()
        .find(|s| s.name == "spinning_trimesh")
        .expect("the scene");
    let (mut world, _) = scene.instantiate();
    let mut stage = affine_ccd::rapier::AffineCcd::default();
    stage.install(&mut world);
    let report = stage.step(&mut world);
    assert_eq!(report.clamps(), 1, "{report:?}");
    assert_eq!(report.hits[0].fraction, 0.0, "{report:?}");
    assert!(report.bodies_swept <= 6, "{report:?}");
}
