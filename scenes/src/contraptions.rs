//! Closed boxes, machines and stacks: the bounce house, a pinball table
//! with kinematic flippers, a stack hit by a projectile, a fast kinematic
//! sweeper, and a control scene where nothing is fast.

use super::guard::Guard;
use super::kit::{Lcg, PaddleRow, crossing_guards, fixed_box};
use super::script::{Motion, Script};
use super::{Effects, Scene, Setup};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::bounding_volume::Aabb;
use rapier3d::prelude::{CoefficientCombineRule, ColliderBuilder, PhysicsWorld, RigidBodyBuilder};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    let bouncy = Effects {
        gravity: true,
        rotation: true,
        restitution: true,
        friction: true,
        kinematic: false,
        settles: false,
    };
    vec![
        Scene {
            name: "bounce_house",
            about: "boxes and capsules at 30-50 m/s, 30-60 rad/s, restitution 1, in a closed box of 5 cm walls",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: bouncy,
            built_to_tunnel: true,
            view: [0, 1],
            build: bounce_house,
        },
        Scene {
            name: "bounce_house_dt10",
            about: "large step (0.1 s): the bounce house at 15-25 m/s",
            dt: 0.1,
            steps: 60,
            effects: bouncy,
            built_to_tunnel: true,
            view: [0, 1],
            build: bounce_house_dt10,
        },
        Scene {
            name: "pinball",
            about: "tilted table, 2 cm rails, glass cover, kinematic flippers, a ball at 30 m/s",
            dt: 1.0 / 60.0,
            steps: 240,
            effects: Effects {
                kinematic: true,
                ..bouncy
            },
            built_to_tunnel: true,
            view: [0, 2],
            build: pinball,
        },
        Scene {
            name: "stack_projectile",
            about: "a 3 x 5 stack of boxes hit by a ball at 200 m/s and a cuboid at 150 m/s",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: Effects {
                restitution: false,
                ..bouncy
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: stack_projectile,
        },
        Scene {
            name: "kinematic_sweeper",
            about: "a 6 cm kinematic paddle sliding at 60 m/s through a row of resting boxes",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: Effects {
                gravity: true,
                friction: true,
                kinematic: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: kinematic_sweeper,
        },
        Scene {
            name: "control_slow",
            about: "control: slow balls and boxes dropped on a thick floor and slid into a thick wall",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: Effects {
                gravity: true,
                friction: true,
                ..Effects::default()
            },
            built_to_tunnel: false,
            view: [0, 1],
            build: control_slow,
        },
    ]
}

/// Six walls of half thickness `wall` around the cube [-inner, inner]³,
/// overlapping at the edges so there is no crack. Returns the inner region.
fn closed_box(world: &mut PhysicsWorld, inner: Real, wall: Real, restitution: Real) -> Aabb {
    let outer = inner + 2.0 * wall;
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut center = Vector::ZERO;
            center[axis] = sign * (inner + wall);
            let mut half = Vector::splat(outer);
            half[axis] = wall;
            world.insert_collider(
                ColliderBuilder::cuboid(half.x, half.y, half.z)
                    .translation(center)
                    .restitution(restitution)
                    .restitution_combine_rule(CoefficientCombineRule::Max),
                None,
            );
        }
    }
    Aabb::new(Vector::splat(-inner), Vector::splat(inner))
}

/// Fills the house with `count` boxes and capsules at `speed` (m/s, random
/// directions) and `spin` (rad/s) ranges, and guards them inside.
fn fill_house(
    world: &mut PhysicsWorld,
    region: Aabb,
    count: usize,
    speed: (Real, Real),
    spin: (Real, Real),
) -> Setup {
    let mut rng = Lcg(23);
    let mut guards = Vec::new();
    for k in 0..count {
        let at = Vector::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        );
        let dir = Vector::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(Vector::X);
        let axis = Vector::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(Vector::Z);
        let body = RigidBodyBuilder::dynamic()
            .translation(at)
            .linvel(dir * rng.range(speed.0, speed.1))
            .angvel(axis * rng.range(spin.0, spin.1))
            .ccd_enabled(true);
        let shape = if k % 2 == 0 {
            ColliderBuilder::cuboid(0.15, 0.1, 0.05)
        } else {
            ColliderBuilder::capsule_y(0.2, 0.06)
        };
        let collider = shape
            .restitution(1.0)
            .restitution_combine_rule(CoefficientCombineRule::Max)
            .friction(0.3);
        let body = world.insert(body, collider).0;
        guards.push(Guard::Inside { body, region });
    }
    Setup {
        guards,
        ..Setup::default()
    }
}

fn bounce_house(world: &mut PhysicsWorld) -> Setup {
    let region = closed_box(world, 2.0, 0.025, 1.0);
    fill_house(world, region, 14, (30.0, 50.0), (30.0, 60.0))
}

fn bounce_house_dt10(world: &mut PhysicsWorld) -> Setup {
    let region = closed_box(world, 2.0, 0.025, 1.0);
    fill_house(world, region, 10, (15.0, 25.0), (10.0, 30.0))
}

fn pinball(world: &mut PhysicsWorld) -> Setup {
    // The table lies in the xz plane, 1 m x 2 m; tilting gravity towards +z
    // by 7° is the same as tilting the table.
    let tilt: Real = 7.0_f32.to_radians();
    world.gravity = Vector::new(0.0, -9.81 * tilt.cos(), 9.81 * tilt.sin());
    let rail = 0.01; // half thickness: 2 cm rails
    let bouncy = |b: ColliderBuilder| b.restitution(0.6).friction(0.2);
    // Playfield and glass cover.
    fixed_box(
        world,
        Vector::new(0.0, -0.01, 0.0),
        Vector::new(0.5, 0.01, 1.0),
    );
    fixed_box(
        world,
        Vector::new(0.0, 0.07, 0.0),
        Vector::new(0.5, 0.01, 1.0),
    );
    // Rails.
    for (center, half) in [
        (
            Vector::new(-0.5 - rail, 0.03, 0.0),
            Vector::new(rail, 0.05, 1.0 + 2.0 * rail),
        ),
        (
            Vector::new(0.5 + rail, 0.03, 0.0),
            Vector::new(rail, 0.05, 1.0 + 2.0 * rail),
        ),
        (
            Vector::new(0.0, 0.03, -1.0 - rail),
            Vector::new(0.5, 0.05, rail),
        ),
        (
            Vector::new(0.0, 0.03, 1.0 + rail),
            Vector::new(0.5, 0.05, rail),
        ),
    ] {
        world.insert_collider(
            bouncy(ColliderBuilder::cuboid(half.x, half.y, half.z)).translation(center),
            None,
        );
    }
    // Flippers: kinematic, pivoting about y near the bottom (+z) end.
    let mut scripts = Vec::new();
    for side in [-1.0, 1.0] {
        let pivot = Vector::new(0.25 * side, 0.025, 0.75);
        let base = Pose::from_translation(pivot);
        let body = world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(base));
        world.insert_collider(
            bouncy(ColliderBuilder::cuboid(0.12, 0.02, 0.015)).translation(Vector::new(
                -0.12 * side,
                0.0,
                0.0,
            )),
            Some(body),
        );
        scripts.push(Script {
            body,
            motion: Motion::Flick {
                base,
                axis: Vector::Y,
                // Both flippers swing their free end towards -z (up the table).
                low: 0.4 * side,
                high: -0.5 * side,
                flick: 0.04,
                period: 0.4,
            },
        });
    }
    // Balls: one fast shot up the table, three slower ones.
    let shots = [
        (Vector::new(0.3, 0.0, 0.5), Vector::new(-3.0, 0.0, -30.0)),
        (Vector::new(-0.2, 0.0, 0.0), Vector::new(8.0, 0.0, 6.0)),
        (Vector::new(0.1, 0.0, -0.5), Vector::new(-5.0, 0.0, 12.0)),
        (Vector::new(-0.3, 0.0, -0.8), Vector::new(10.0, 0.0, 15.0)),
    ];
    let region = Aabb::new(Vector::new(-0.5, 0.0, -1.0), Vector::new(0.5, 0.06, 1.0));
    // The region alone guards the table: leaving it means passing the
    // playfield, the glass or a rail.
    let mut guards = Vec::new();
    for (offset, velocity) in shots {
        let body = RigidBodyBuilder::dynamic()
            .translation(offset + Vector::Y * 0.027)
            .linvel(velocity)
            .ccd_enabled(true);
        let ball = world.insert(body, bouncy(ColliderBuilder::ball(0.027))).0;
        guards.push(Guard::Inside { body: ball, region });
    }
    Setup { guards, scripts }
}

fn stack_projectile(world: &mut PhysicsWorld) -> Setup {
    fixed_box(
        world,
        Vector::new(0.0, -0.5, 0.0),
        Vector::new(20.0, 0.5, 20.0),
    );
    let half = 0.25;
    let mut boxes = Vec::new();
    for level in 0..5 {
        for column in 0..3 {
            let at = Vector::new(
                6.0,
                half + 2.0 * half * level as Real,
                (column as Real - 1.0) * 2.0 * half,
            );
            let body = RigidBodyBuilder::dynamic().translation(at);
            let (_, collider) = world.insert(
                body,
                ColliderBuilder::cuboid(half, half, half).friction(0.8),
            );
            boxes.push(collider);
        }
    }
    let ball = RigidBodyBuilder::dynamic()
        .translation(Vector::new(0.0, 0.75, 0.0))
        .linvel(Vector::new(200.0, 0.0, 0.0))
        .ccd_enabled(true);
    let ball = world
        .insert(ball, ColliderBuilder::ball(0.08).density(8.0))
        .0;
    let slug = RigidBodyBuilder::dynamic()
        .translation(Vector::new(-1.0, 1.75, 0.2))
        .linvel(Vector::new(150.0, 0.0, 0.0))
        .ccd_enabled(true);
    let slug = world
        .insert(slug, ColliderBuilder::cuboid(0.1, 0.04, 0.04).density(8.0))
        .0;
    Setup {
        guards: crossing_guards(&[ball, slug], &boxes),
        ..Setup::default()
    }
}

fn kinematic_sweeper(world: &mut PhysicsWorld) -> Setup {
    fixed_box(
        world,
        Vector::new(0.0, -0.5, 0.0),
        Vector::new(20.0, 0.5, 20.0),
    );
    // 24 m per 0.4 s round trip: 60 m/s, 1 m per step.
    PaddleRow {
        from: Vector::new(-6.0, 0.5, 0.0),
        to: Vector::new(6.0, 0.5, 0.0),
        period: 0.4,
        boxes: 8,
        first: Vector::new(-3.5, 0.2, 0.0),
        spacing: 1.0,
        half: 0.2,
        ccd: false,
    }
    .build(world)
}

fn control_slow(world: &mut PhysicsWorld) -> Setup {
    let floor = fixed_box(
        world,
        Vector::new(0.0, -0.5, 0.0),
        Vector::new(10.0, 0.5, 10.0),
    );
    let wall = fixed_box(
        world,
        Vector::new(3.0, 1.0, 0.0),
        Vector::new(0.5, 1.0, 3.0),
    );
    let mut bodies = Vec::new();
    for k in 0..6 {
        let x = -2.0 + 0.8 * k as Real;
        let ball = RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.5, -1.0));
        bodies.push(world.insert(ball, ColliderBuilder::ball(0.15)).0);
        let cube = RigidBodyBuilder::dynamic()
            .translation(Vector::new(x, 0.45, 1.0))
            .rotation(Vector::new(0.1 * k as Real, 0.0, 0.05));
        bodies.push(
            world
                .insert(cube, ColliderBuilder::cuboid(0.15, 0.15, 0.15))
                .0,
        );
    }
    // Slid into the thick wall at 2 m/s.
    let slider = RigidBodyBuilder::dynamic()
        .translation(Vector::new(1.5, 0.2, 0.0))
        .linvel(Vector::new(2.0, 0.0, 0.0));
    bodies.push(
        world
            .insert(slider, ColliderBuilder::cuboid(0.2, 0.2, 0.2).friction(0.1))
            .0,
    );
    Setup {
        guards: crossing_guards(&bodies, &[floor, wall]),
        ..Setup::default()
    }
}
