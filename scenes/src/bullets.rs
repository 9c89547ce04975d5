//! Fast projectiles: balls, cuboids, cones and cylinders against thin walls
//! and a half-space, and fast dynamic bodies meeting head-on.

use super::kit::{beyond_guards, crossing_guards, mutual_guards, thin_wall};
use super::{Effects, Scene, Setup};
use rapier3d::math::Vector;
use rapier3d::parry::shape::SharedShape;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "bullet_balls",
            about: "5 balls (r 5 cm) at 150 m/s into a 10 cm fixed wall",
            dt: 1.0 / 60.0,
            steps: 120,
            effects: Effects::default(),
            built_to_tunnel: true,
            view: [0, 1],
            build: bullet_balls,
        },
        Scene {
            name: "bullet_cuboids",
            about: "5 slowly tumbling cuboids at 120 m/s into a 2 cm fixed wall",
            dt: 1.0 / 60.0,
            steps: 120,
            effects: Effects {
                rotation: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: bullet_cuboids,
        },
        Scene {
            name: "bullet_balls_dt10",
            about: "large step (0.1 s): balls at 60 m/s under gravity into a 10 cm wall",
            dt: 0.1,
            steps: 60,
            effects: Effects {
                gravity: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: bullet_balls_dt10,
        },
        Scene {
            name: "cones_cylinders_halfspace",
            about: "cones and cylinders at 200 m/s into a wall, and at 80 m/s into a half-space floor",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: Effects {
                gravity: true,
                rotation: true,
                friction: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: cones_cylinders_halfspace,
        },
        Scene {
            name: "head_on_pairs",
            about: "pairs of balls, cuboids and capsules meeting head-on at 2 x 100 m/s",
            dt: 1.0 / 60.0,
            steps: 120,
            effects: Effects {
                restitution: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: head_on_pairs,
        },
    ]
}

/// Fires one dynamic CCD body with `collider` from `at` at `velocity`.
fn fire(
    world: &mut PhysicsWorld,
    collider: ColliderBuilder,
    at: Vector,
    velocity: Vector,
    spin: Vector,
) -> RigidBodyHandle {
    let body = RigidBodyBuilder::dynamic()
        .translation(at)
        .linvel(velocity)
        .angvel(spin)
        .ccd_enabled(true);
    world.insert(body, collider).0
}

fn bullet_balls(world: &mut PhysicsWorld) -> Setup {
    let (_, face) = thin_wall(
        world,
        Vector::new(5.0, 0.0, 0.0),
        Vector::new(0.05, 3.0, 3.0),
        0,
        1.0,
    );
    let bullets: Vec<_> = (0..5)
        .map(|k| {
            let at = Vector::new(0.3 * k as f32, -1.0 + 0.5 * k as f32, 0.4 * k as f32 - 0.8);
            fire(
                world,
                ColliderBuilder::ball(0.05),
                at,
                Vector::new(150.0, 0.0, 0.0),
                Vector::ZERO,
            )
        })
        .collect();
    Setup {
        guards: beyond_guards(&bullets, face),
        ..Setup::default()
    }
}

fn bullet_cuboids(world: &mut PhysicsWorld) -> Setup {
    let (_, face) = thin_wall(
        world,
        Vector::new(5.0, 0.0, 0.0),
        Vector::new(0.01, 3.0, 3.0),
        0,
        1.0,
    );
    let bullets: Vec<_> = (0..5)
        .map(|k| {
            let at = Vector::new(0.2 * k as f32, -1.0 + 0.5 * k as f32, 0.3 * k as f32 - 0.6);
            let spin = Vector::new(0.0, 4.0 + 2.0 * k as f32, 1.0);
            let shape = ColliderBuilder::cuboid(0.1, 0.03, 0.03);
            fire(world, shape, at, Vector::new(120.0, 0.0, 0.0), spin)
        })
        .collect();
    Setup {
        guards: beyond_guards(&bullets, face),
        ..Setup::default()
    }
}

fn bullet_balls_dt10(world: &mut PhysicsWorld) -> Setup {
    // 6 m per step: the wall at x = 9 lies between the first two end poses.
    let (_, face) = thin_wall(
        world,
        Vector::new(9.0, 0.0, 0.0),
        Vector::new(0.05, 20.0, 4.0),
        0,
        1.0,
    );
    let bullets: Vec<_> = (0..4)
        .map(|k| {
            let at = Vector::new(0.5 * k as f32, 1.0 + 0.5 * k as f32, 0.5 * k as f32 - 1.0);
            fire(
                world,
                ColliderBuilder::ball(0.1),
                at,
                Vector::new(60.0, 2.0, 0.0),
                Vector::ZERO,
            )
        })
        .collect();
    Setup {
        guards: beyond_guards(&bullets, face),
        ..Setup::default()
    }
}

fn cones_cylinders_halfspace(world: &mut PhysicsWorld) -> Setup {
    let floor = world.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y)).friction(0.6),
        None,
    );
    let (_, face) = thin_wall(
        world,
        Vector::new(6.0, 4.0, 0.0),
        Vector::new(0.05, 4.0, 4.0),
        0,
        1.0,
    );
    let mut fired = Vec::new();
    let mut dropped = Vec::new();
    for k in 0..3 {
        let z = -1.5 + 1.5 * k as f32;
        fired.push(fire(
            world,
            ColliderBuilder::cone(0.15, 0.08),
            Vector::new(0.0, 2.0, z),
            Vector::new(200.0, 0.0, 0.0),
            Vector::new(0.0, 0.0, 3.0),
        ));
        fired.push(fire(
            world,
            ColliderBuilder::cylinder(0.1, 0.06),
            Vector::new(0.0, 3.0, z + 0.5),
            Vector::new(200.0, 0.0, 0.0),
            Vector::new(3.0, 0.0, 0.0),
        ));
        dropped.push(fire(
            world,
            ColliderBuilder::cylinder(0.05, 0.2),
            Vector::new(-3.0, 8.0, z),
            Vector::new(0.0, -80.0, 0.0),
            Vector::new(2.0, 0.0, 1.0),
        ));
        dropped.push(fire(
            world,
            ColliderBuilder::cone(0.2, 0.15),
            Vector::new(-2.0, 8.0, z + 0.5),
            Vector::new(0.0, -80.0, 0.0),
            Vector::new(1.0, 2.0, 0.0),
        ));
    }
    let mut guards = beyond_guards(&fired, face);
    let all: Vec<_> = fired.iter().chain(&dropped).copied().collect();
    guards.extend(crossing_guards(&all, &[floor]));
    Setup {
        guards,
        ..Setup::default()
    }
}

fn head_on_pairs(world: &mut PhysicsWorld) -> Setup {
    let shapes = [
        (ColliderBuilder::ball(0.1), ColliderBuilder::ball(0.1)),
        (
            ColliderBuilder::cuboid(0.1, 0.1, 0.1),
            ColliderBuilder::cuboid(0.05, 0.15, 0.15),
        ),
        (
            ColliderBuilder::ball(0.08),
            ColliderBuilder::capsule_y(0.2, 0.05),
        ),
        (
            ColliderBuilder::capsule_x(0.1, 0.05),
            ColliderBuilder::cuboid(0.02, 0.2, 0.2),
        ),
    ];
    let mut guards = Vec::new();
    for (k, (left, right)) in shapes.into_iter().enumerate() {
        let y = 1.5 * k as f32;
        let speed = 100.0;
        // 5.1 m apart: the gap closes by 3.33 m a step, so the two bodies are
        // never in contact at the end of a step.
        let restitution = 0.5;
        let a = fire(
            world,
            left.restitution(restitution),
            Vector::new(-2.55, y, 0.0),
            Vector::new(speed, 0.0, 0.0),
            Vector::ZERO,
        );
        let b = fire(
            world,
            right.restitution(restitution),
            Vector::new(2.55, y, 0.0),
            Vector::new(-speed, 0.0, 0.0),
            Vector::ZERO,
        );
        guards.extend(mutual_guards(world, a, b));
    }
    Setup {
        guards,
        ..Setup::default()
    }
}
