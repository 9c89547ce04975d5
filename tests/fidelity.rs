//! The stage removes tunnelling and nothing else: a landed slab settles
//! where rapier's does, a near miss keeps its velocity, a shallow hit
//! changes it about as much as an inelastic contact would.
//!
//! `cargo test --release --test fidelity -- --nocapture` prints the numbers
//! beside rapier's own CCD.

mod common;

use affine_ccd::rapier::CcdConfig;
use common::Run;
use rapier3d::prelude::*;

/// Who steps the world.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ccd {
    /// Rapier's own CCD (the body has `ccd_enabled`).
    Rapier,
    /// This crate's stage, default configuration.
    Affine,
    /// Rapier with no CCD at all.
    Off,
}

fn run(ccd: Ccd, mut world: PhysicsWorld) -> Run {
    match ccd {
        Ccd::Affine => Run::affine(world, CcdConfig::default()),
        Ccd::Rapier => Run::rapier(world),
        Ccd::Off => {
            world.integration_parameters.max_ccd_substeps = 0;
            Run::rapier(world)
        }
    }
}

/// How a dropped slab ends.
#[derive(Debug)]
struct Landing {
    /// The first step from which it stays at rest flat on the floor.
    rest_from: Option<usize>,
    /// Largest |v| (m/s) seen after step 120.
    late_speed: f32,
    height: f32,
}

/// A slab `cuboid(1, 0.03, 1)` dropped from y = 5, tilted by `tilt` radians
/// about `axis`, onto a flat two-triangle trimesh floor; 600 steps of 1/60 s.
fn drop_slab(ccd: Ccd, axis: Vector, tilt: f32) -> Landing {
    let mut world = PhysicsWorld::default();
    let s = 10.0;
    let floor = ColliderBuilder::trimesh(
        vec![
            Vector::new(-s, 0.0, -s),
            Vector::new(s, 0.0, -s),
            Vector::new(s, 0.0, s),
            Vector::new(-s, 0.0, s),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )
    .expect("a valid floor");
    world.insert(RigidBodyBuilder::fixed(), floor);
    let body = RigidBodyBuilder::dynamic()
        .translation(Vector::new(0.0, 5.0, 0.0))
        .rotation(axis * tilt)
        .ccd_enabled(ccd == Ccd::Rapier);
    let (slab, _) = world.insert(body, ColliderBuilder::cuboid(1.0, 0.03, 1.0));
    let mut run = run(ccd, world);
    let (mut rest_from, mut late_speed) = (None, 0.0f32);
    for k in 0..600 {
        run.step();
        let rb = &run.world.bodies[slab];
        let up = rb.rotation() * Vector::Y;
        let tilt_now = up.y.clamp(-1.0, 1.0).acos();
        let (v, w) = (rb.linvel().length(), rb.angvel().length());
        let flat = tilt_now < 0.01 && (rb.translation().y - 0.03).abs() < 0.005;
        if v < 0.01 && w < 0.01 && flat {
            rest_from.get_or_insert(k);
        } else {
            rest_from = None;
        }
        if k >= 120 {
            late_speed = late_speed.max(v);
        }
    }
    Landing {
        rest_from,
        late_speed,
        height: run.world.bodies[slab].translation().y,
    }
}

#[test]
fn a_landed_slab_settles_flat_by_step_120_at_every_tilt() {
    for (name, axis) in [("x", Vector::X), ("z", Vector::Z)] {
        for tilt in [0.0, 0.05, 0.1, 0.3] {
            let ours = drop_slab(Ccd::Affine, axis, tilt);
            let theirs = drop_slab(Ccd::Rapier, axis, tilt);
            println!("tilt {tilt} about {name}: affine {ours:?}, rapier {theirs:?}");
            assert!(
                ours.rest_from.is_some_and(|k| k < 120),
                "tilt {tilt} about {name}: not at rest flat by step 120 ({ours:?})"
            );
            // Where rapier's own CCD settles too, the slab rests where it does.
            if theirs.rest_from.is_some() {
                assert!(
                    (ours.height - theirs.height).abs() < 5.0e-3,
                    "tilt {tilt} about {name}: rests at y = {}, rapier's at {}",
                    ours.height,
                    theirs.height
                );
            }
            assert!(
                ours.late_speed < 0.01,
                "tilt {tilt} about {name}: moves at {} m/s after step 120",
                ours.late_speed
            );
        }
    }
}

/// A ball (r 0.1) at 100 m/s along x whose centre passes the vertical edge
/// of a box turned 45° about y at `0.1 + gap` from it (a surface gap of
/// `gap` metres at the closest approach), starting at `x0`; 8 steps, no
/// gravity. The change of its velocity, m/s.
fn pass_edge(ccd: Ccd, gap: f32, x0: f32) -> f32 {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..PhysicsWorld::default()
    };
    let (_, post) = world.insert(
        RigidBodyBuilder::fixed().rotation(Vector::Y * std::f32::consts::FRAC_PI_4),
        ColliderBuilder::cuboid(0.5, 1.0, 0.5),
    );
    // The edge nearest +z is the vertical line x = 0, z = edge.
    let edge = world.colliders[post].compute_aabb().maxs.z;
    let v0 = Vector::new(100.0, 0.0, 0.0);
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(x0, 0.0, edge + 0.1 + gap))
            .linvel(v0)
            .ccd_enabled(ccd == Ccd::Rapier),
        ColliderBuilder::ball(0.1),
    );
    let mut run = run(ccd, world);
    for _ in 0..8 {
        run.step();
    }
    (run.world.bodies[ball].linvel() - v0).length()
}

/// The velocity change of an inelastic contact at first touch for a graze
/// `depth` metres deep: the approach component of 100 m/s along the normal.
fn inelastic_change(depth: f32) -> f32 {
    let c = (0.1 - depth) / 0.1;
    100.0 * (1.0 - c * c).sqrt()
}

#[test]
fn a_near_miss_keeps_its_velocity_and_a_shallow_hit_changes_it_as_a_contact_would() {
    // Three starting points put the pass early, midway and late in a step.
    for x0 in [-5.0, -5.3, -5.8] {
        let miss = pass_edge(Ccd::Affine, 1.0e-4, x0);
        let miss_rapier = pass_edge(Ccd::Rapier, 1.0e-4, x0);
        let hit = pass_edge(Ccd::Affine, -1.0e-4, x0);
        let hit_rapier = pass_edge(Ccd::Rapier, -1.0e-4, x0);
        let limit = 2.0 * inelastic_change(1.0e-4);
        println!(
            "x0 {x0}: +1e-4 m: affine {miss:.2e}, rapier {miss_rapier:.2e} m/s; \
             -1e-4 m: affine {hit:.3}, rapier {hit_rapier:.3} m/s (limit {limit:.2})"
        );
        assert!(
            miss <= 1.0e-6,
            "x0 {x0}: a near miss 1e-4 m clear changed by {miss} m/s"
        );
        // A contact that late in a step cannot get deep before it ends is
        // left to rapier's contacts, which keep a tangential graze (0 m/s):
        // only the upper bound is the contract.
        assert!(
            hit <= limit,
            "x0 {x0}: a 1e-4 m deep graze changed by {hit} m/s (limit {limit})"
        );
    }
}

/// A cone (half-height 0.3, radius 0.2) laid on its side just above a
/// floor and set rolling at `spin` rad/s, stepped `steps` times: its final
/// speed (m/s) and the stage's clamps (0 for rapier).
fn roll_cone(ccd: Ccd, spin: f32, steps: usize) -> (f32, usize) {
    let mut run = run(
        ccd,
        PhysicsWorld {
            gravity: Vector::new(0.0, -9.81, 0.0),
            ..PhysicsWorld::default()
        },
    );
    run.world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(20.0, 0.1, 20.0),
    );
    let on_side = Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2);
    let cone = run
        .world
        .insert(
            RigidBodyBuilder::dynamic()
                .pose(Pose::from_parts(Vector::new(0.0, 0.35, 0.0), on_side))
                .angvel(Vector::new(0.0, 0.0, -spin))
                .linvel(Vector::new(0.2 * spin, 0.0, 0.0))
                .ccd_enabled(ccd == Ccd::Rapier),
            ColliderBuilder::cone(0.3, 0.2),
        )
        .0;
    let mut clamps = 0;
    for _ in 0..steps {
        run.step();
        if let Some(stage) = &run.stage {
            clamps += stage.report().clamps();
        }
    }
    (run.world.bodies[cone].linvel().length(), clamps)
}

/// A cone rolling on the floor turns about its centre over a step, not
/// about its contact line, and so dips a few millimetres into the floor by
/// the step's end (about 2 mm at 8 rad/s, 6 mm at 15): the contacts undo
/// that, as they do without CCD. The stage leaves it rolling as rapier's
/// own CCD does; holding it back at each such dip (as a sink of 5 mm did)
/// stopped it dead within 200 steps. At 25 rad/s it bounces on landing and
/// its rim skims the floor a millimetre or so above it: taking that for a
/// touch (a GJK answer believed, see `a_cone_skimming_a_floor_box_is_not_touching`)
/// clamped it in mid-air until it stood still. Where it lands after a
/// bounce decides how it rolls on, and rapier's own runs differ there (at
/// 25 rad/s 0.90 m/s with its CCD, 0.39 without): the stage's cone is held
/// to half the speed of the slower of the two.
#[test]
fn a_rolling_cone_keeps_rolling_as_with_rapiers_ccd() {
    for (spin, most_clamps) in [(8.0, 0), (15.0, 4), (25.0, 5)] {
        let (speed, clamps) = roll_cone(Ccd::Affine, spin, 300);
        let (speed_rapier, _) = roll_cone(Ccd::Rapier, spin, 300);
        let (speed_off, _) = roll_cone(Ccd::Off, spin, 300);
        println!(
            "{spin} rad/s: after 300 steps affine {speed:.3} m/s ({clamps} clamps), \
             rapier {speed_rapier:.3} m/s, rapier without CCD {speed_off:.3} m/s"
        );
        // The clamps allowed are its landing's (it starts 5 cm up) and, at
        // 25 rad/s, its bounces'.
        assert!(
            clamps <= most_clamps,
            "{spin} rad/s: the rolling cone was clamped {clamps} times"
        );
        let slower = speed_rapier.min(speed_off);
        assert!(
            speed > 0.5 * slower,
            "{spin} rad/s: the cone slowed to {speed} m/s, rapier's rolls on at {slower} or more"
        );
    }
}
