//! Scenes rebuilt from public rapier CCD reports: a spinning slab onto a
//! two-triangle floor (rapier#524), two fast CCD bodies passing through each
//! other (rapier#984), a fast kinematic paddle through resting boxes
//! (rapier#303), bodies sliding on a trimesh at a quarter-second step
//! (rapier#217) and a small bouncing ball on a thin floor (rapier#932).

use super::kit::{
    PaddleRow, beyond_guards, crossing_guards, fixed_mesh, grid_mesh, mutual_guards, thin_wall,
};
use super::{Effects, Scene, Setup};
use rapier3d::math::{Real, Vector};
use rapier3d::prelude::{CoefficientCombineRule, ColliderBuilder, PhysicsWorld, RigidBodyBuilder};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "rotating_slab_quad",
            about: "rapier#524: a 3 cm slab spinning at 30 rad/s falls 5 m onto a 2-triangle trimesh floor and comes to rest",
            dt: 1.0 / 60.0,
            steps: 600,
            effects: Effects {
                gravity: true,
                rotation: true,
                friction: true,
                settles: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: rotating_slab_quad,
        },
        Scene {
            name: "ccd_pair_pass",
            about: "rapier#984: pairs of CCD bodies (thin boxes, a ball and a thin box) meeting head-on at 2 x 150 m/s",
            dt: 1.0 / 60.0,
            steps: 60,
            effects: Effects::default(),
            built_to_tunnel: true,
            view: [0, 1],
            build: ccd_pair_pass,
        },
        Scene {
            name: "kinematic_push",
            about: "rapier#303: a 6 cm kinematic paddle at 40 m/s, one way, through a row of six resting 30 cm CCD boxes",
            dt: 1.0 / 60.0,
            steps: 60,
            effects: Effects {
                gravity: true,
                friction: true,
                kinematic: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: kinematic_push,
        },
        Scene {
            name: "slide_dt025",
            about: "rapier#217: step 0.25 s: a capsule and a cuboid slide at 5 m/s on a 3200-triangle trimesh floor and stop",
            dt: 0.25,
            steps: 40,
            effects: Effects {
                gravity: true,
                friction: true,
                settles: true,
                ..Effects::default()
            },
            built_to_tunnel: false,
            view: [0, 1],
            build: slide_dt025,
        },
        Scene {
            name: "bounce_ball_932",
            about: "rapier#932: balls (r 5 cm) at 50 and 30 m/s down onto a 2 cm floor, restitution 1 (Max)",
            dt: 1.0 / 60.0,
            steps: 180,
            effects: Effects {
                gravity: true,
                restitution: true,
                ..Effects::default()
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: bounce_ball_932,
        },
    ]
}

fn rotating_slab_quad(world: &mut PhysicsWorld) -> Setup {
    // One quad, 20 m a side, at y = 0: 4 vertices, 2 triangles.
    let Some(floor) = fixed_mesh(world, grid_mesh(-10.0, -10.0, 20.0, 1, |_, _| 0.0)) else {
        return Setup::default();
    };
    // 2 m x 3 cm x 1 m, spinning end over end about z: the tips move at
    // 30 m/s, the slab falls 5 m (9.9 m/s at impact).
    let body = RigidBodyBuilder::dynamic()
        .translation(Vector::new(0.0, 5.0, 0.0))
        .angvel(Vector::new(0.0, 0.0, 30.0))
        .ccd_enabled(true);
    let slab = world
        .insert(body, ColliderBuilder::cuboid(1.0, 0.015, 0.5).friction(0.6))
        .0;
    Setup {
        guards: crossing_guards(&[slab], &[floor]),
        ..Setup::default()
    }
}

fn ccd_pair_pass(world: &mut PhysicsWorld) -> Setup {
    let pairs = [
        (
            ColliderBuilder::cuboid(0.02, 0.5, 0.5),
            ColliderBuilder::cuboid(0.02, 0.5, 0.5),
        ),
        (
            ColliderBuilder::ball(0.1),
            ColliderBuilder::cuboid(0.02, 0.5, 0.5),
        ),
    ];
    let mut guards = Vec::new();
    for (k, (left, right)) in pairs.into_iter().enumerate() {
        let y = 2.0 * k as Real;
        let speed = 150.0;
        // 7.6 m apart, closing by 5 m a step: 2.6 m apart after the first
        // step, swapped by 2.4 m after the second if nothing stops them.
        let fire = |world: &mut PhysicsWorld, collider: ColliderBuilder, x: Real, v: Real| {
            let body = RigidBodyBuilder::dynamic()
                .translation(Vector::new(x, y, 0.0))
                .linvel(Vector::new(v, 0.0, 0.0))
                .ccd_enabled(true);
            world.insert(body, collider).0
        };
        let a = fire(world, left, -3.8, speed);
        let b = fire(world, right, 3.8, -speed);
        guards.extend(mutual_guards(world, a, b));
    }
    Setup {
        guards,
        ..Setup::default()
    }
}

fn kinematic_push(world: &mut PhysicsWorld) -> Setup {
    // A 50 m floor: the paddle goes 40 m in the run, the boxes ahead of it.
    super::kit::fixed_box(
        world,
        Vector::new(15.0, -0.5, 0.0),
        Vector::new(25.0, 0.5, 5.0),
    );
    // 40 m out in the first half of a 2 s round trip: 40 m/s, 0.67 m a step;
    // the 60-step run ends as the paddle reaches `to`, so it only goes one way.
    PaddleRow {
        from: Vector::new(-4.0, 0.5, 0.0),
        to: Vector::new(36.0, 0.5, 0.0),
        period: 2.0,
        boxes: 6,
        first: Vector::new(-2.5, 0.15, 0.0),
        spacing: 1.1,
        half: 0.15,
        ccd: true,
    }
    .build(world)
}

fn slide_dt025(world: &mut PhysicsWorld) -> Setup {
    // 40 m x 40 m, 1 m cells: 3200 triangles at y = 0.
    let Some(floor) = fixed_mesh(world, grid_mesh(-20.0, -20.0, 40.0, 40, |_, _| 0.0)) else {
        return Setup::default();
    };
    // Both start 1 cm above the floor sliding along +x at 5 m/s; friction
    // (0.5) stops them in about a second, 2.5 m on. The capsule lies along
    // its direction of motion so it slides rather than rolls.
    let slide = |at: Vector| {
        RigidBodyBuilder::dynamic()
            .translation(at)
            .linvel(Vector::new(5.0, 0.0, 0.0))
            .ccd_enabled(true)
    };
    let capsule = world
        .insert(
            slide(Vector::new(-5.0, 0.11, -3.0)),
            ColliderBuilder::capsule_x(0.3, 0.1).friction(0.5),
        )
        .0;
    let cuboid = world
        .insert(
            slide(Vector::new(-5.0, 0.26, 3.0)),
            ColliderBuilder::cuboid(0.25, 0.25, 0.25).friction(0.5),
        )
        .0;
    Setup {
        guards: crossing_guards(&[capsule, cuboid], &[floor]),
        ..Setup::default()
    }
}

fn bounce_ball_932(world: &mut PhysicsWorld) -> Setup {
    // A 2 cm floor whose top is at y = 0; the bodies come from above, so the
    // forbidden side is -y.
    let (floor, face) = thin_wall(
        world,
        Vector::new(0.0, -0.01, 0.0),
        Vector::new(4.0, 0.01, 4.0),
        1,
        -1.0,
    );
    let balls: Vec<_> = [(-1.0, 50.0), (1.0, 30.0)]
        .into_iter()
        .map(|(x, speed)| {
            let body = RigidBodyBuilder::dynamic()
                .translation(Vector::new(x, 5.0, 0.0))
                .linvel(Vector::new(0.0, -speed, 0.0))
                .ccd_enabled(true);
            let ball = ColliderBuilder::ball(0.05)
                .restitution(1.0)
                .restitution_combine_rule(CoefficientCombineRule::Max);
            world.insert(body, ball).0
        })
        .collect();
    let mut guards = beyond_guards(&balls, face);
    guards.extend(crossing_guards(&balls, &[floor]));
    Setup {
        guards,
        ..Setup::default()
    }
}

#[cfg(test)]
mod tests {
    use super::super::kit::all_at_rest;

    /// The scenes that claim `settles` do come to rest under plain rapier.
    #[test]
    fn settling_scenes_come_to_rest() {
        for scene in super::scenes().into_iter().filter(|s| s.effects.settles) {
            let (mut world, _) = scene.instantiate();
            for _ in 0..scene.steps {
                world.step();
            }
            assert!(
                all_at_rest(&world, 0.02, 0.05),
                "{} does not come to rest",
                scene.name
            );
        }
    }
}
