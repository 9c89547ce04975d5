//! Scenes run twice in the same test: with the affine-ccd stage, and with
//! rapier's built-in CCD (`ccd_enabled` on the fast bodies, its best
//! setting). The stage must never tunnel where rapier does not, and must
//! not tunnel at all in these scenes.
//!
//! Run: `cargo test --release --test rapier_stage`.

mod common;

use affine_ccd::rapier::{AffineCcd, CcdConfig};
use common::Run;
use rapier3d::parry::shape::Cuboid;
use rapier3d::prelude::*;
use std::sync::mpsc::channel;

const STEPS: usize = 60;

/// Which CCD runs a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ccd {
    Affine,
    Rapier,
}

impl Run {
    fn new(ccd: Ccd, gravity: Vector) -> Run {
        let world = PhysicsWorld {
            gravity,
            ..PhysicsWorld::default()
        };
        match ccd {
            Ccd::Affine => Run::affine(world, CcdConfig::default()),
            Ccd::Rapier => Run::rapier(world),
        }
    }

    fn fixed(&mut self, collider: impl Into<Collider>, at: Vector) -> ColliderHandle {
        self.world
            .insert(RigidBodyBuilder::fixed().translation(at), collider)
            .1
    }

    fn dynamic(
        &mut self,
        body: RigidBodyBuilder,
        collider: impl Into<Collider>,
    ) -> RigidBodyHandle {
        self.world.insert(body.ccd_enabled(true), collider).0
    }

    fn x(&self, h: RigidBodyHandle) -> f32 {
        self.world.bodies[h].translation().x
    }
}

/// A 0.1 m thick fixed wall at x = 0 and one projectile to be fired at it
/// at 200 m/s from x = −5: the world, the projectile, the wall.
fn projectile_and_wall(
    ccd: Ccd,
    collider: ColliderBuilder,
) -> (Run, RigidBodyHandle, ColliderHandle) {
    let mut run = Run::new(ccd, Vector::ZERO);
    let wall = run.fixed(ColliderBuilder::cuboid(0.05, 2.0, 2.0), Vector::ZERO);
    let h = run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-5.0, 0.0, 0.0))
            .linvel(Vector::new(200.0, 0.0, 0.0)),
        collider,
    );
    (run, h, wall)
}

/// The projectile fired at the wall; the largest x its centre reached at a
/// step end.
fn fire_at_wall(ccd: Ccd, collider: ColliderBuilder) -> f32 {
    let (mut run, h, _) = projectile_and_wall(ccd, collider);
    let mut max_x = f32::MIN;
    for _ in 0..STEPS {
        run.step();
        max_x = max_x.max(run.x(h));
    }
    max_x
}

/// Fires `collider` with both CCDs; asserts the stage stops it on the near
/// side and does no worse than rapier. Returns whether rapier tunnelled.
fn wall_scenario(name: &str, collider: ColliderBuilder) -> bool {
    let ours = fire_at_wall(Ccd::Affine, collider.clone());
    let theirs = fire_at_wall(Ccd::Rapier, collider);
    println!("{name}: max x with affine-ccd {ours:.3} m, with rapier's CCD {theirs:.3} m");
    assert!(
        ours < 0.0,
        "{name}: affine-ccd let it through the wall (max x = {ours} m)"
    );
    assert!(ours < 0.0 || theirs >= 0.0, "{name}: worse than rapier");
    theirs >= 0.0
}

#[test]
fn a_ball_at_200_m_s_stops_at_a_thin_wall() {
    wall_scenario("ball", ColliderBuilder::ball(0.25));
}

#[test]
fn a_cuboid_at_200_m_s_stops_at_a_thin_wall() {
    wall_scenario("cuboid", ColliderBuilder::cuboid(0.25, 0.25, 0.25));
}

/// The stage's report counts each pair evaluation once by family: the
/// counts add up to its evaluations, and a box fired at a box wall spends
/// them on the box family (or shortcuts) in the step it is clamped in.
#[test]
fn the_report_counts_evaluations_by_family() {
    use affine_ccd::query::Family;
    let (mut run, _, _) =
        projectile_and_wall(Ccd::Affine, ColliderBuilder::cuboid(0.25, 0.25, 0.25));
    let mut clamped = 0;
    for _ in 0..STEPS {
        run.step();
        let report = run.stage.as_ref().unwrap().report();
        let by = report.evaluations_by_family;
        assert_eq!(by.total(), report.evaluations, "{by:?}");
        if report.clamps() > 0 {
            clamped += 1;
            assert!(by.get(Family::CuboidCuboid) > 0, "{by:?}");
            assert_eq!(
                by.get(Family::CuboidCuboid) + by.get(Family::Shortcut),
                report.evaluations,
                "{by:?}"
            );
        }
    }
    assert!(clamped > 0, "the box was never clamped");
}

/// Bodies flying on together at 60 m/s (a row of cubes 1 mm apart, as a
/// paddle leaves them) cannot pass through one another: the stage leaves
/// those pairs to rapier's contacts and clamps none of them. A cube
/// catching up with another at 30 m/s is still swept against it, and
/// stopped behind it.
#[test]
fn bodies_moving_together_are_left_to_contacts() {
    let cube = || ColliderBuilder::cuboid(0.1, 0.1, 0.1);
    let flying = |x: f32, speed: f32| {
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(x, 0.0, 0.0))
            .linvel(Vector::new(speed, 0.0, 0.0))
    };

    let mut row = Run::new(Ccd::Affine, Vector::ZERO);
    let cubes: Vec<_> = (0..3)
        .map(|k| row.dynamic(flying(0.201 * k as f32, 60.0), cube()))
        .collect();
    let mut together = 0;
    for _ in 0..10 {
        row.step();
        let report = row.stage.as_ref().unwrap().report();
        together += report.pairs_moving_together;
        assert_eq!(report.clamps(), 0, "{report:?}");
    }
    // Each cube's first sweep finds its neighbours moving with it.
    assert!(together >= 10 * 4, "{together} pairs moving together");
    for pair in cubes.windows(2) {
        let gap = row.x(pair[1]) - row.x(pair[0]) - 0.2;
        assert!(gap.abs() < 2.0e-3, "the row came apart by {gap} m");
    }

    // 0.3 m apart, closing 0.5 m a step: they meet within the first step.
    let mut chase = Run::new(Ccd::Affine, Vector::ZERO);
    let leader = chase.dynamic(flying(0.0, 30.0), cube());
    let chaser = chase.dynamic(flying(-0.5, 60.0), cube());
    chase.step();
    let report = chase.stage.as_ref().unwrap().report();
    assert_eq!(report.pairs_moving_together, 0, "{report:?}");
    assert!(report.hits.iter().any(|h| h.body == chaser), "{report:?}");
    for _ in 0..10 {
        assert!(
            chase.x(chaser) < chase.x(leader),
            "the chaser passed the leader"
        );
        chase.step();
    }
}

/// Two fast balls whose paths cross at right angles, one passing the
/// crossing 0.45 m ahead of the other: their swept boxes meet, but the
/// first one's sweep proves them apart over the step, and the other's
/// takes that answer instead of searching the pair again, so it counts
/// once; neither is stopped. On a collision course instead the pair is
/// searched from both sides (a hit is not taken over) and stopped.
#[test]
fn two_fast_bodies_proved_apart_are_searched_once() {
    let ball = || ColliderBuilder::ball(0.1);
    let flying =
        |at: Vector, velocity: Vector| RigidBodyBuilder::dynamic().translation(at).linvel(velocity);
    let crossing = |x: f32| {
        let mut run = Run::new(Ccd::Affine, Vector::ZERO);
        run.dynamic(
            flying(Vector::new(-0.5, 0.0, 0.0), Vector::new(60.0, 0.0, 0.0)),
            ball(),
        );
        run.dynamic(
            flying(Vector::new(x, 0.0, 0.5), Vector::new(0.0, 0.0, -60.0)),
            ball(),
        );
        run.step();
        run.stage.as_ref().unwrap().report().clone()
    };
    let passing = crossing(0.45);
    assert_eq!(passing.bodies_swept, 2, "{passing:?}");
    assert_eq!(passing.pairs, 1, "{passing:?}");
    assert_eq!(passing.clamps(), 0, "{passing:?}");

    // The second ball at the crossing when the first is.
    let meeting = crossing(0.0);
    assert!(meeting.clamps() > 0, "{meeting:?}");
    assert!(meeting.pairs >= 2, "{meeting:?}");
}

#[test]
fn a_cone_at_200_m_s_stops_at_a_thin_wall() {
    let rapier_tunnels = wall_scenario(
        "cone",
        ColliderBuilder::cone(0.3, 0.2).rotation(Vector::new(
            0.0,
            0.0,
            -std::f32::consts::FRAC_PI_2,
        )),
    );
    println!("rapier's CCD tunnels the cone: {rapier_tunnels}");
}

#[test]
fn a_compound_of_cylinders_at_200_m_s_stops_at_a_thin_wall() {
    let compound = ColliderBuilder::compound(vec![
        (
            Pose::translation(0.0, 0.3, 0.0),
            SharedShape::cylinder(0.2, 0.1),
        ),
        (
            Pose::translation(0.0, -0.3, 0.0),
            SharedShape::cylinder(0.2, 0.1),
        ),
    ]);
    let rapier_tunnels = wall_scenario("compound of cylinders", compound);
    println!("rapier's CCD tunnels the compound: {rapier_tunnels}");
}

/// The gap (metres, negative: depth) between a projectile fired at 200 m/s
/// at the thin wall and the wall, at the end of the step its CCD stopped it
/// (the first step that ends within 2 cm of the wall).
fn gap_at_stop(ccd: Ccd, collider: ColliderBuilder) -> f32 {
    let (mut run, h, wall) = projectile_and_wall(ccd, collider);
    let moving = run.world.bodies[h].colliders()[0];
    for _ in 0..STEPS {
        run.step();
        let (a, b) = (&run.world.colliders[moving], &run.world.colliders[wall]);
        let found =
            rapier3d::parry::query::contact(a.position(), a.shape(), b.position(), b.shape(), 0.02);
        if let Ok(Some(c)) = found {
            return c.dist;
        }
    }
    f32::INFINITY
}

/// Where a clamp leaves a body is where rapier's own CCD leaves it (its
/// rest poses are the reference): a box `slop` (rapier's allowed linear
/// error, 5 mm) before the wall, a ball `slop` into it, each within parry's
/// tolerance of a quarter slop. A clamp at the contact itself, or a skin
/// before it, lands a few millimetres elsewhere, and a landing body then
/// tumbles elsewhere.
#[test]
fn a_clamped_body_stands_where_rapiers_ccd_would_stop_it() {
    let slop = IntegrationParameters::default().allowed_linear_error();
    for (name, collider, stop) in [
        ("box", ColliderBuilder::cuboid(0.25, 0.25, 0.25), slop),
        ("ball", ColliderBuilder::ball(0.25), -slop),
    ] {
        let ours = gap_at_stop(Ccd::Affine, collider.clone());
        let theirs = gap_at_stop(Ccd::Rapier, collider);
        println!("{name}: gap at the stop {ours:.5} m (rapier's CCD {theirs:.5} m, target {stop})");
        assert!(
            (ours - stop).abs() <= 0.25 * slop,
            "{name}: stopped {ours} m from the wall, rapier stops at {stop} m"
        );
        assert!(
            (theirs - stop).abs() <= 0.25 * slop,
            "{name}: rapier's CCD itself stopped at {theirs} m (expected {stop} m)"
        );
    }
}

/// A shape falling at 200 m/s onto a half-space at y = 0: the lowest y its
/// centre reached at a step end.
fn fall_on_half_space(ccd: Ccd, collider: ColliderBuilder) -> f32 {
    let mut run = Run::new(ccd, Vector::new(0.0, -9.81, 0.0));
    run.fixed(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y)),
        Vector::ZERO,
    );
    let h = run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 5.0, 0.0))
            .linvel(Vector::new(0.0, -200.0, 0.0)),
        collider,
    );
    let mut min_y = f32::MAX;
    for _ in 0..STEPS {
        run.step();
        min_y = min_y.min(run.world.bodies[h].translation().y);
    }
    min_y
}

#[test]
fn a_ball_and_a_cylinder_falling_fast_stay_above_a_half_space() {
    for (name, collider, half_height) in [
        ("ball", ColliderBuilder::ball(0.25), 0.25),
        ("cylinder", ColliderBuilder::cylinder(0.25, 0.2), 0.25),
    ] {
        let ours = fall_on_half_space(Ccd::Affine, collider.clone());
        let theirs = fall_on_half_space(Ccd::Rapier, collider);
        println!(
            "{name}: lowest centre y with affine-ccd {ours:.3} m, with rapier's CCD {theirs:.3} m"
        );
        assert!(
            ours > half_height - 0.05,
            "{name}: affine-ccd sank into the half-space (lowest y = {ours} m)"
        );
        assert!(ours >= theirs.min(ours), "{name}: worse than rapier");
    }
}

/// Two cuboids head-on at ±200 m/s; true when they ever swapped sides.
fn head_on(ccd: Ccd) -> bool {
    let mut run = Run::new(ccd, Vector::ZERO);
    let a = run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-5.0, 0.0, 0.0))
            .linvel(Vector::new(200.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.1, 0.5, 0.5),
    );
    let b = run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(5.0, 0.0, 0.0))
            .linvel(Vector::new(-200.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.1, 0.5, 0.5),
    );
    (0..STEPS).any(|_| {
        run.step();
        run.x(a) > run.x(b)
    })
}

#[test]
fn two_fast_cuboids_head_on_collide() {
    let (ours, theirs) = (head_on(Ccd::Affine), head_on(Ccd::Rapier));
    println!(
        "head-on: passed through each other with affine-ccd {ours}, with rapier's CCD {theirs}"
    );
    assert!(!ours, "affine-ccd let the cuboids pass through each other");
}

/// A body pinned in place (translations locked), spinning at 300 rad/s
/// about z, its 1 m arm reaching past a thin wall at x = 0.5. The largest
/// |x| of its arm's tip at a step end: above 0.52 the tip went through.
fn spin_beside_wall(ccd: Ccd, collider: ColliderBuilder) -> f32 {
    let mut run = Run::new(ccd, Vector::ZERO);
    run.fixed(
        ColliderBuilder::cuboid(0.01, 2.0, 2.0),
        Vector::new(0.5, 0.0, 0.0),
    );
    let h = run.dynamic(
        RigidBodyBuilder::dynamic()
            .rotation(Vector::new(0.0, 0.0, std::f32::consts::FRAC_PI_2))
            .angvel(Vector::new(0.0, 0.0, 300.0))
            .allow_fast_rotation(true)
            .lock_translations(),
        collider,
    );
    let mut worst = 0.0f32;
    for _ in 0..STEPS {
        run.step();
        let tip = run.world.bodies[h].rotation() * Vector::X;
        worst = worst.max(tip.x.abs());
    }
    worst
}

fn spin_scenario(name: &str, collider: ColliderBuilder) {
    let ours = spin_beside_wall(Ccd::Affine, collider.clone());
    let theirs = spin_beside_wall(Ccd::Rapier, collider);
    println!(
        "{name}: largest tip |x| with affine-ccd {ours:.3}, with rapier's CCD {theirs:.3} (through above 0.52)"
    );
    assert!(
        ours <= 0.52,
        "{name}: affine-ccd let the spinning arm through the wall (|x| = {ours})"
    );
}

#[test]
fn a_thin_rod_spinning_at_300_rad_s_never_ends_a_step_through_a_wall() {
    spin_scenario("rod", ColliderBuilder::cuboid(1.0, 0.01, 0.01));
}

#[test]
fn a_fast_spinning_trimesh_never_ends_a_step_through_a_box() {
    let (vertices, indices) = Cuboid::new(Vector::new(1.0, 0.02, 0.02)).to_trimesh();
    let mesh = ColliderBuilder::trimesh(vertices, indices)
        .expect("a valid mesh")
        .mass_properties(MassProperties::from_cuboid(
            1.0,
            Vector::new(1.0, 0.02, 0.02),
        ));
    spin_scenario("trimesh", mesh);
}

/// A ball crossing a fixed 0.1 m sensor slab within one step: the
/// (started, stopped) events seen for the pair.
fn cross_sensor(ccd: Ccd) -> (usize, usize) {
    let mut run = Run::new(ccd, Vector::ZERO);
    run.fixed(
        ColliderBuilder::cuboid(0.05, 2.0, 2.0)
            .sensor(true)
            .active_events(ActiveEvents::COLLISION_EVENTS),
        Vector::ZERO,
    );
    run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-1.5, 0.0, 0.0))
            .linvel(Vector::new(200.0, 0.0, 0.0)),
        ColliderBuilder::ball(0.1).active_events(ActiveEvents::COLLISION_EVENTS),
    );
    let (send, recv) = channel();
    let (force_send, _force_recv) = channel();
    let (tear_send, _tear_recv) = channel();
    let events = ChannelEventCollector::new(send, force_send, tear_send);
    for _ in 0..3 {
        match &mut run.stage {
            Some(stage) => {
                stage.step_with_events(&mut run.world, &(), &events);
            }
            None => run.world.step_with_events(&(), &events),
        }
    }
    let all: Vec<CollisionEvent> = recv.try_iter().collect();
    (
        all.iter().filter(|e| e.started()).count(),
        all.iter().filter(|e| e.stopped()).count(),
    )
}

#[test]
fn a_sensor_crossed_in_one_step_reports_started_and_stopped() {
    let (ours, theirs) = (cross_sensor(Ccd::Affine), cross_sensor(Ccd::Rapier));
    println!("sensor (started, stopped): affine-ccd {ours:?}, rapier's CCD {theirs:?}");
    assert_eq!(
        ours,
        (1, 1),
        "affine-ccd: expected one Started and one Stopped event"
    );
}

/// A slow scene: boxes dropped on a floor, a ball rolling.
fn slow_scene(run: &mut Run) -> Vec<RigidBodyHandle> {
    run.fixed(ColliderBuilder::cuboid(10.0, 0.1, 10.0), Vector::ZERO);
    let mut handles = Vec::new();
    for i in 0..5 {
        let at = Vector::new(0.1 * i as f32, 0.5 + 1.1 * i as f32, 0.0);
        handles.push(
            run.world
                .insert(
                    RigidBodyBuilder::dynamic().translation(at),
                    ColliderBuilder::cuboid(0.5, 0.5, 0.5),
                )
                .0,
        );
    }
    handles.push(
        run.world
            .insert(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(3.0, 0.5, 0.0))
                    .linvel(Vector::new(2.0, 0.0, 0.0)),
                ColliderBuilder::ball(0.4),
            )
            .0,
    );
    handles
}

#[test]
fn a_scene_without_fast_bodies_steps_bit_identically() {
    let gravity = Vector::new(0.0, -9.81, 0.0);
    let (mut ours, mut theirs) = (
        Run::new(Ccd::Affine, gravity),
        Run::new(Ccd::Rapier, gravity),
    );
    let (a, b) = (slow_scene(&mut ours), slow_scene(&mut theirs));
    for step in 0..200 {
        ours.step();
        theirs.step();
        common::assert_same_poses(step, &ours, &a, &theirs, &b);
        let report = ours.stage.as_ref().unwrap().report();
        assert_eq!(
            report.clamps(),
            0,
            "step {step}: a slow scene was clamped: {report:?}"
        );
    }
}

#[test]
fn a_nan_velocity_skips_that_body_and_the_others_step_on() {
    for ccd in [Ccd::Affine, Ccd::Rapier] {
        let mut run = Run::new(ccd, Vector::ZERO);
        let movers: Vec<_> = (0..3)
            .map(|i| {
                run.world
                    .insert(
                        RigidBodyBuilder::dynamic()
                            .translation(Vector::new(0.0, 2.0 * i as f32, 0.0))
                            .linvel(Vector::new(if i == 2 { 300.0 } else { 1.0 }, 0.0, 0.0)),
                        ColliderBuilder::ball(0.25),
                    )
                    .0
            })
            .collect();
        let bad = run
            .world
            .insert(
                RigidBodyBuilder::dynamic().translation(Vector::new(0.0, -3.0, 0.0)),
                ColliderBuilder::ball(0.25),
            )
            .0;
        run.world.bodies[bad].set_linvel(Vector::new(f32::NAN, 0.0, 0.0), true);
        for _ in 0..5 {
            run.step();
        }
        for h in &movers {
            let x = run.x(*h);
            assert!(
                x.is_finite() && x > 0.0,
                "{ccd:?}: a healthy body did not step on (x = {x})"
            );
        }
        assert!(
            run.world.bodies[bad].position().is_finite(),
            "{ccd:?}: the NaN body's pose is lost"
        );
    }
    // The first step's report names the body (rapier then quarantines
    // it, so later reports do not): a NaN velocity, a NaN pose or an
    // infinite spin, each set by the user before the step (the stage
    // leaves the check to rapier's quarantine before the step and checks
    // again before it sweeps anything).
    type Corrupt = fn(&mut RigidBody);
    let corruptions: [(&str, Corrupt); 3] = [
        ("NaN velocity", |rb| {
            rb.set_linvel(Vector::new(f32::NAN, 0.0, 0.0), true)
        }),
        ("NaN pose", |rb| {
            rb.set_translation(Vector::new(0.0, f32::NAN, 0.0), true)
        }),
        ("infinite spin", |rb| {
            rb.set_angvel(Vector::new(0.0, f32::INFINITY, 0.0), true)
        }),
    ];
    for (what, corrupt) in corruptions {
        let mut run = Run::new(Ccd::Affine, Vector::ZERO);
        let bad = run
            .world
            .insert(RigidBodyBuilder::dynamic(), ColliderBuilder::ball(0.25))
            .0;
        let fast = run
            .world
            .insert(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(0.0, 3.0, 0.0))
                    .linvel(Vector::new(300.0, 0.0, 0.0)),
                ColliderBuilder::ball(0.25),
            )
            .0;
        corrupt(&mut run.world.bodies[bad]);
        run.step();
        assert!(
            run.reported_non_finite(bad),
            "{what}: the body is not reported: {:?}",
            run.stage.as_ref().map(|s| s.report())
        );
        assert!(
            run.x(fast) > 4.0,
            "{what}: the healthy fast body did not step on (x = {})",
            run.x(fast)
        );
    }
}

#[test]
fn the_config_round_trips_through_serde() {
    let config = CcdConfig {
        opt_out_bit: Some(3),
        ..CcdConfig::default()
    };
    let text = serde_json::to_string(&config).unwrap();
    let back: CcdConfig = serde_json::from_str(&text).unwrap();
    assert_eq!(back, config, "{text}");
}

#[test]
fn an_opted_out_body_is_not_clamped() {
    let mut run = Run::new(Ccd::Affine, Vector::ZERO);
    run.stage.as_mut().unwrap().config_mut().opt_out_bit = Some(0);
    run.fixed(ColliderBuilder::cuboid(0.05, 2.0, 2.0), Vector::ZERO);
    run.world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-5.0, 0.0, 0.0))
            .linvel(Vector::new(200.0, 0.0, 0.0))
            .user_data(1),
        ColliderBuilder::ball(0.25),
    );
    for _ in 0..5 {
        run.step();
        assert_eq!(run.stage.as_ref().unwrap().report().bodies_swept, 0);
    }
}

/// A 6 cm kinematic paddle at 60 m/s (1 m a step) towards two resting
/// boxes 1 m apart, then back: the stage carries both ahead of it (neither
/// ends behind it or inside the other) and leaves them there when it turns.
#[test]
fn a_fast_kinematic_paddle_pushes_a_train_and_lets_it_go() {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..PhysicsWorld::default()
    };
    let mut stage = AffineCcd::new(CcdConfig::default());
    stage.install(&mut world);
    let paddle = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(-1.5, 0.0, 0.0)),
    );
    world.insert_collider(ColliderBuilder::cuboid(0.03, 0.5, 1.0), Some(paddle));
    let boxes: Vec<_> = [0.0, 1.0]
        .iter()
        .map(|&x| {
            world
                .insert(
                    RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.0, 0.0)),
                    ColliderBuilder::cuboid(0.2, 0.2, 0.2),
                )
                .0
        })
        .collect();
    let x = |world: &PhysicsWorld, h: RigidBodyHandle| world.bodies[h].translation().x;
    let mut at = -1.5;
    for step in 0..6 {
        at += if step < 4 { 1.0 } else { -1.0 };
        world.bodies[paddle]
            .set_next_kinematic_position(Pose::from_translation(Vector::new(at, 0.0, 0.0)));
        stage.step(&mut world);
        let p = x(&world, paddle);
        let (a, b) = (x(&world, boxes[0]), x(&world, boxes[1]));
        if step < 4 {
            assert!(
                a - 0.2 >= p + 0.03 - 1.0e-3,
                "step {step}: box 0 at {a} behind the paddle at {p}"
            );
        }
        assert!(
            b - a >= 0.4 - 1.0e-2,
            "step {step}: the boxes overlap ({a}, {b})"
        );
    }
    let v = world.bodies[boxes[0]].linvel().x;
    assert!(v > 30.0, "the pushed box keeps the paddle's speed, not {v}");
}

/// A ball asleep just above a thin floor (no gravity) is hit from above by
/// a heavy fast block: rapier wakes it during the step and its solver
/// throws it down through the floor unless the stage sweeps a body that
/// was asleep when the step began (the long soak lost a resting compound
/// that way). Returns the lowest height the ball's centre reached at a
/// step end.
fn sleeper_hit(ccd: Ccd) -> f32 {
    let mut run = Run::new(ccd, Vector::ZERO);
    run.fixed(ColliderBuilder::cuboid(2.0, 0.01, 2.0), Vector::ZERO);
    let ball = run
        .world
        .insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, 0.3, 0.0))
                .ccd_enabled(true)
                .sleeping(true),
            ColliderBuilder::ball(0.1),
        )
        .0;
    run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 2.0, 0.0))
            .linvel(Vector::new(0.0, -150.0, 0.0)),
        ColliderBuilder::cuboid(0.3, 0.3, 0.3).density(1000.0),
    );
    let mut lowest = f32::MAX;
    for _ in 0..10 {
        run.step();
        lowest = lowest.min(run.world.bodies[ball].translation().y);
    }
    lowest
}

#[test]
fn a_sleeping_body_thrown_by_a_hit_stays_above_the_floor() {
    let (ours, theirs) = (sleeper_hit(Ccd::Affine), sleeper_hit(Ccd::Rapier));
    println!("sleeper: lowest centre with affine-ccd {ours:.3} m, with rapier's CCD {theirs:.3} m");
    assert!(
        ours > 0.0,
        "affine-ccd: the woken ball went through the floor (y = {ours} m)"
    );
}

/// A ball asleep left of a wall is moved by the user to the right of it
/// without being woken (`set_position(.., false)`), then a box bumps it
/// awake. The stage must sweep it from where it is when the step begins:
/// from the pose it had when it fell asleep, its motion would cross the
/// wall and be clamped there, on the wrong side.
#[test]
fn a_sleeping_body_moved_without_waking_starts_where_it_was_moved() {
    let mut run = Run::new(Ccd::Affine, Vector::ZERO);
    run.fixed(ColliderBuilder::cuboid(0.05, 2.0, 2.0), Vector::ZERO);
    let ball = run
        .world
        .insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(-2.0, 0.0, 0.0))
                .sleeping(true),
            ColliderBuilder::ball(0.1),
        )
        .0;
    for _ in 0..3 {
        run.step();
    }
    assert!(run.world.bodies[ball].is_sleeping(), "the ball sleeps");
    let moved = Pose::from_translation(Vector::new(2.0, 0.0, 0.0));
    run.world.bodies[ball].set_position(moved, false);
    run.dynamic(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.32, 0.0, 0.0))
            .linvel(Vector::new(-3.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.2, 0.2, 0.2),
    );
    let mut woken = false;
    for _ in 0..10 {
        run.step();
        woken |= !run.world.bodies[ball].is_sleeping();
        let x = run.x(ball);
        assert!(
            x > 1.5,
            "the ball was pulled back towards its old pose: x = {x}"
        );
    }
    assert!(woken, "the box woke the ball");
}
