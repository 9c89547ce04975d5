//! The stage with `CcdConfig::substeps` > 1: the step is cut at the first
//! predicted impact and each piece is solved and clamped. Each scene also
//! runs with the default post-solve clamp and with rapier's own CCD (its
//! `max_ccd_substeps` set alike), in the same test.
//!
//! Run: `cargo test --release --test substeps -- --nocapture`.

mod common;

use affine_ccd::rapier::CcdConfig;
use common::Run;
use rapier3d::prelude::*;

/// Which CCD steps a scene, with how many pieces per step at most.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ccd {
    Affine(u32),
    Rapier(usize),
}

impl Run {
    fn new(ccd: Ccd) -> Run {
        let mut world = PhysicsWorld {
            gravity: Vector::ZERO,
            ..PhysicsWorld::default()
        };
        match ccd {
            Ccd::Affine(substeps) => Run::affine(
                world,
                CcdConfig {
                    substeps,
                    ..CcdConfig::default()
                },
            ),
            Ccd::Rapier(substeps) => {
                world.integration_parameters.max_ccd_substeps = substeps;
                Run::rapier(world)
            }
        }
    }
}

/// Speed of the ball, m/s, and its radius, m.
const SPEED: f32 = 100.0;
const RADIUS: f32 = 0.25;
/// Height of the ball's centre at the start, m (the floor's top is y = 0).
const HEIGHT: f32 = 5.0;

/// A ball fired straight down at a fixed floor, both perfectly elastic,
/// no gravity. Returns the ball's height after each of `steps` steps.
fn bounce(ccd: Ccd, steps: usize) -> Vec<f32> {
    let mut run = Run::new(ccd);
    run.world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.05, 0.0)),
        ColliderBuilder::cuboid(5.0, 0.05, 5.0).restitution(1.0),
    );
    let ball = run
        .world
        .insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, HEIGHT, 0.0))
                .linvel(Vector::new(0.0, -SPEED, 0.0))
                .ccd_enabled(true),
            ColliderBuilder::ball(RADIUS).restitution(1.0),
        )
        .0;
    (0..steps)
        .map(|_| {
            run.step();
            run.world.bodies[ball].translation().y
        })
        .collect()
}

/// The exact height of the bouncing ball at time `t`.
fn exact_height(t: f32) -> f32 {
    let hit = (HEIGHT - RADIUS) / SPEED;
    RADIUS + SPEED * (t - hit).abs()
}

#[test]
fn substeps_bounce_a_fast_ball_within_the_step_it_hits() {
    let dt = IntegrationParameters::default().dt;
    let steps = 6;
    // The step in which the ball reaches the floor.
    let hit_step = ((HEIGHT - RADIUS) / SPEED / dt).floor() as usize;
    let mut errors = Vec::new();
    for ccd in [
        Ccd::Affine(1),
        Ccd::Affine(4),
        Ccd::Rapier(1),
        Ccd::Rapier(4),
    ] {
        let heights = bounce(ccd, steps);
        let error = heights
            .iter()
            .enumerate()
            .skip(hit_step)
            .map(|(i, y)| (y - exact_height((i + 1) as f32 * dt)).abs())
            .fold(0.0, f32::max);
        println!("{ccd:?}: heights {heights:.3?}, largest error after the hit {error:.4} m");
        assert!(
            heights.iter().all(|&y| y > 0.0),
            "{ccd:?}: the ball went through the floor: {heights:?}"
        );
        errors.push((ccd, error));
    }
    let error = |c: Ccd| errors.iter().find(|(k, _)| *k == c).unwrap().1;
    // A clamp waits at the floor for the rest of the step; a cut step
    // bounces at the impact, so the ball then runs on the exact path.
    // Rapier's solver turns the velocity in the piece that meets the
    // contact without moving the ball, so that piece is lost: the stage
    // makes it the shortest allowed (`min_ccd_dt`); rapier's own substeps
    // lose the rest of the step after the impact.
    let lost = SPEED * IntegrationParameters::default().min_ccd_dt;
    assert!(
        error(Ccd::Affine(4)) <= 1.1 * lost,
        "substeps: the bounce lost more than one shortest piece ({lost} m): {errors:?}"
    );
    assert!(
        error(Ccd::Affine(4)) < 0.25 * error(Ccd::Rapier(4)),
        "substeps: not nearer the exact bounce than rapier's substeps: {errors:?}"
    );
}

/// Balls fired at 200 m/s at a 0.1 m fixed wall from different distances,
/// so that they hit at different times of the same steps. Returns the
/// largest x any centre reached, and the most pieces and the shortest
/// piece (seconds) of any step (affine-ccd only).
fn volley(ccd: Ccd) -> (f32, usize, f64) {
    let mut run = Run::new(ccd);
    run.world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.05, 10.0, 10.0),
    );
    let balls: Vec<_> = (0..8)
        .map(|i| {
            let start = Vector::new(-3.0 - 0.37 * i as f32, 1.1 * i as f32 - 4.0, 0.0);
            run.world
                .insert(
                    RigidBodyBuilder::dynamic()
                        .translation(start)
                        .linvel(Vector::new(200.0, 0.0, 0.0))
                        .ccd_enabled(true),
                    ColliderBuilder::ball(0.2),
                )
                .0
        })
        .collect();
    let (mut max_x, mut most, mut shortest) = (f32::MIN, 0, f64::INFINITY);
    for _ in 0..30 {
        run.step();
        for b in &balls {
            max_x = max_x.max(run.world.bodies[*b].translation().x);
        }
        if let Some(stage) = &run.stage {
            most = most.max(stage.report().pieces);
            shortest = shortest.min(stage.report().shortest_piece);
        }
    }
    (max_x, most, shortest)
}

#[test]
fn a_volley_at_a_thin_wall_stops_with_few_pieces_per_step() {
    let min_dt = IntegrationParameters::default().min_ccd_dt as f64;
    let (ours, most, shortest) = volley(Ccd::Affine(3));
    let (theirs, _, _) = volley(Ccd::Rapier(3));
    println!(
        "volley: max x with affine-ccd {ours:.3} m ({most} pieces at most, shortest {shortest:.2e} s), \
         with rapier's CCD {theirs:.3} m"
    );
    assert!(ours < 0.0, "a ball went through the wall: max x = {ours}");
    assert!(
        (2..=3).contains(&most),
        "expected the impacts to cut steps into at most 3 pieces, got {most}"
    );
    assert!(
        shortest >= 0.999 * min_dt,
        "a piece of {shortest} s is shorter than min_ccd_dt ({min_dt} s)"
    );
}

/// A ball at rest just above a floor, pulled down hard (gravity, or the
/// user's force) from the second step on (the first puts the colliders in
/// the broad phase): nothing but the acceleration says it will hit within
/// that step, which would otherwise end with it past the floor. Returns
/// the pieces of the pulled step and the ball's lowest height.
fn pulled_down(ccd: Ccd, by_force: bool) -> (usize, f32) {
    let mut run = Run::new(ccd);
    let pull = Vector::new(0.0, -2_000.0, 0.0);
    run.world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.05, 0.0)),
        ColliderBuilder::cuboid(5.0, 0.05, 5.0),
    );
    let ball = run
        .world
        .insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, RADIUS + 0.2, 0.0))
                .ccd_enabled(true),
            ColliderBuilder::ball(RADIUS),
        )
        .0;
    run.step();
    if by_force {
        let mass = run.world.bodies[ball].mass();
        run.world.bodies[ball].add_force(pull * mass, true);
    } else {
        run.world.gravity = pull;
    }
    let (mut pieces, mut lowest) = (0, f32::MAX);
    for step in 0..4 {
        run.step();
        lowest = lowest.min(run.world.bodies[ball].translation().y);
        if step == 0 {
            pieces = run.stage.as_ref().map_or(0, |s| s.report().pieces);
        }
    }
    (pieces, lowest)
}

#[test]
fn gravity_and_forces_predict_the_cut() {
    for by_force in [false, true] {
        let (pieces, lowest) = pulled_down(Ccd::Affine(4), by_force);
        let (_, theirs) = pulled_down(Ccd::Rapier(4), by_force);
        let what = if by_force { "user force" } else { "gravity" };
        println!(
            "pulled by {what}: affine-ccd cut the pulled step into {pieces} pieces, lowest centre {lowest:.4} m; \
             rapier's CCD lowest {theirs:.4} m"
        );
        assert!(pieces >= 2, "{what}: the impact was not predicted");
        assert!(
            lowest > 0.9 * RADIUS,
            "{what}: the ball sank into the floor (centre at {lowest} m)"
        );
    }
}

/// A position-based kinematic paddle moved 1 m a step (60 m/s) by its
/// target while a fast ball hits a wall elsewhere and cuts the steps.
/// Returns, per step, the pieces, how far the paddle is from its target
/// and its velocity along x.
fn paddle(ccd: Ccd) -> Vec<(usize, f32, f32)> {
    let mut run = Run::new(ccd);
    run.world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.0, 20.0)),
        ColliderBuilder::cuboid(0.05, 2.0, 2.0),
    );
    run.world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-3.0, 0.0, 20.0))
            .linvel(Vector::new(200.0, 0.0, 0.0))
            .ccd_enabled(true),
        ColliderBuilder::ball(0.2),
    );
    let paddle = run
        .world
        .insert(
            RigidBodyBuilder::kinematic_position_based(),
            ColliderBuilder::cuboid(0.5, 0.5, 0.05),
        )
        .0;
    (1..=4)
        .map(|step| {
            let target = Vector::new(step as f32, 0.0, 0.0);
            run.world.bodies[paddle].set_next_kinematic_translation(target);
            run.step();
            let pieces = run.stage.as_ref().map_or(0, |s| s.report().pieces);
            let rb = &run.world.bodies[paddle];
            (pieces, (rb.translation() - target).length(), rb.linvel().x)
        })
        .collect()
}

#[test]
fn kinematic_targets_are_interpolated_across_pieces() {
    let ours = paddle(Ccd::Affine(4));
    let theirs = paddle(Ccd::Rapier(4));
    println!(
        "paddle (pieces, distance to target, vx): affine-ccd {ours:?}, rapier's CCD {theirs:?}"
    );
    assert!(
        ours.iter().any(|s| s.0 >= 2),
        "the ball never cut a step: {ours:?}"
    );
    for (step, (pieces, off, vx)) in ours.iter().enumerate() {
        assert_eq!(*off, 0.0, "step {step}: the paddle missed its target");
        // Aimed at the whole target in the first piece, it would leave the
        // last piece standing still.
        assert!(
            (vx - 60.0).abs() < 0.1,
            "step {step} ({pieces} pieces): the paddle moved at {vx} m/s, not 60"
        );
    }
}

#[test]
fn a_scene_without_fast_bodies_steps_bit_identically_with_substeps() {
    let scene = |run: &mut Run| {
        run.world.gravity = Vector::new(0.0, -9.81, 0.0);
        run.world.insert(
            RigidBodyBuilder::fixed(),
            ColliderBuilder::cuboid(10.0, 0.1, 10.0),
        );
        (0..5)
            .map(|i| {
                let at = Vector::new(0.1 * i as f32, 0.7 + 1.1 * i as f32, 0.0);
                run.world
                    .insert(
                        RigidBodyBuilder::dynamic()
                            .translation(at)
                            .angvel(Vector::new(0.0, 1.0, 0.0)),
                        ColliderBuilder::cuboid(0.5, 0.5, 0.5),
                    )
                    .0
            })
            .collect::<Vec<_>>()
    };
    let (mut ours, mut theirs) = (Run::new(Ccd::Affine(4)), Run::new(Ccd::Rapier(1)));
    let (a, b) = (scene(&mut ours), scene(&mut theirs));
    for step in 0..200 {
        ours.step();
        theirs.step();
        assert_eq!(ours.stage.as_ref().unwrap().report().pieces, 1);
        common::assert_same_poses(step, &ours, &a, &theirs, &b);
    }
}

#[test]
fn a_sensor_crossed_before_an_impact_reports_started_and_stopped_once() {
    use std::sync::mpsc::channel;
    let mut run = Run::new(Ccd::Affine(4));
    run.world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(0.05, 2.0, 2.0)
            .sensor(true)
            .active_events(ActiveEvents::COLLISION_EVENTS),
    );
    run.world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(2.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.05, 2.0, 2.0),
    );
    run.world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-1.5, 0.0, 0.0))
            .linvel(Vector::new(200.0, 0.0, 0.0)),
        ColliderBuilder::ball(0.1).active_events(ActiveEvents::COLLISION_EVENTS),
    );
    let (send, recv) = channel();
    let (force_send, _force_recv) = channel();
    let (tear_send, _tear_recv) = channel();
    let events = ChannelEventCollector::new(send, force_send, tear_send);
    let stage = run.stage.as_mut().unwrap();
    let mut pieces = 0;
    for _ in 0..3 {
        pieces = pieces.max(stage.step_with_events(&mut run.world, &(), &events).pieces);
    }
    let all: Vec<CollisionEvent> = recv.try_iter().collect();
    let started = all.iter().filter(|e| e.started() && e.sensor()).count();
    let stopped = all.iter().filter(|e| e.stopped() && e.sensor()).count();
    println!("sensor before a wall: {pieces} pieces at most, events {all:?}");
    assert!(pieces >= 2, "the wall impact did not cut the step");
    assert_eq!((started, stopped), (1, 1), "events: {all:?}");
}

#[test]
fn a_nan_velocity_with_substeps_skips_that_body_and_the_others_step_on() {
    let mut run = Run::new(Ccd::Affine(4));
    run.world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(3.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.05, 2.0, 2.0),
    );
    let bullet = run
        .world
        .insert(
            RigidBodyBuilder::dynamic().linvel(Vector::new(300.0, 0.0, 0.0)),
            ColliderBuilder::ball(0.25),
        )
        .0;
    let bad = run
        .world
        .insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.0, -3.0, 0.0)),
            ColliderBuilder::ball(0.25),
        )
        .0;
    run.world.bodies[bad].set_linvel(Vector::new(f32::NAN, 0.0, 0.0), true);
    run.step();
    assert!(
        run.reported_non_finite(bad),
        "the NaN body is not reported: {:?}",
        run.stage.as_ref().map(|s| s.report())
    );
    for _ in 0..5 {
        run.step();
    }
    let x = run.world.bodies[bullet].translation().x;
    assert!(
        x.is_finite() && x > 0.0 && x < 3.0,
        "the bullet did not step on to the wall and stop (x = {x})"
    );
    assert!(run.world.bodies[bad].position().is_finite());
}
