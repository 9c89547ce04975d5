//! Things falling fast onto thin floors: tilted slabs onto a trimesh
//! terrain, a rain of small balls through a thin trimesh floor, and the same
//! kind of scene 10 km from the origin where f32 keeps about a millimetre.

use super::kit::{Lcg, beyond_guards, crossing_guards, fixed_mesh, grid_mesh, thin_wall};
use super::{Effects, Scene, Setup};
use rapier3d::math::{Real, Vector};
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    let falling = Effects {
        gravity: true,
        friction: true,
        ..Effects::default()
    };
    vec![
        Scene {
            name: "slabs_on_terrain",
            about: "12 thin slabs (2 cm) dropped tilted at 40 m/s onto a wavy trimesh terrain",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: Effects {
                rotation: true,
                ..falling
            },
            built_to_tunnel: true,
            view: [0, 1],
            build: slabs_on_terrain,
        },
        Scene {
            name: "rain",
            about: "80 balls (r 3 cm) fired down at 60 m/s through a thin trimesh floor",
            dt: 1.0 / 60.0,
            steps: 120,
            effects: falling,
            built_to_tunnel: true,
            view: [0, 1],
            build: rain,
        },
        Scene {
            name: "rain_dt10",
            about: "large step (0.1 s): 40 balls at 40 m/s through a thin trimesh floor",
            dt: 0.1,
            steps: 50,
            effects: falling,
            built_to_tunnel: true,
            view: [0, 1],
            build: rain_dt10,
        },
        Scene {
            name: "far_from_origin",
            about: "10 km from the origin: bullets at a thin wall, balls onto a thin trimesh floor",
            dt: 1.0 / 60.0,
            steps: 120,
            effects: falling,
            built_to_tunnel: true,
            view: [0, 1],
            build: far_from_origin,
        },
    ]
}

/// Height of the terrain (metres) at (x, z).
fn terrain_height(x: Real, z: Real) -> Real {
    0.6 * (0.5 * x).sin() * (0.4 * z).cos()
}

fn slabs_on_terrain(world: &mut PhysicsWorld) -> Setup {
    let Some(terrain) = fixed_mesh(world, grid_mesh(-10.0, -10.0, 20.0, 20, terrain_height)) else {
        return Setup::default();
    };
    let mut rng = Lcg(7);
    let slabs: Vec<RigidBodyHandle> = (0..12)
        .map(|_| {
            let at = Vector::new(
                rng.range(-6.0, 6.0),
                rng.range(4.0, 8.0),
                rng.range(-6.0, 6.0),
            );
            let tilt = Vector::new(
                rng.range(-0.8, 0.8),
                rng.range(-3.0, 3.0),
                rng.range(-0.8, 0.8),
            );
            let body = RigidBodyBuilder::dynamic()
                .translation(at)
                .rotation(tilt)
                .linvel(Vector::new(
                    rng.range(-2.0, 2.0),
                    -40.0,
                    rng.range(-2.0, 2.0),
                ))
                .angvel(Vector::new(rng.range(-3.0, 3.0), 0.0, rng.range(-3.0, 3.0)))
                .ccd_enabled(true);
            let slab = ColliderBuilder::cuboid(0.4, 0.01, 0.25).friction(0.7);
            world.insert(body, slab).0
        })
        .collect();
    Setup {
        guards: crossing_guards(&slabs, &[terrain]),
        ..Setup::default()
    }
}

/// A shower of small CCD balls: `count` balls of radius `radius` over a
/// square of half-size `spread` around `center`, `low` to `high` metres above
/// it, all moving at `velocity` (m/s).
struct Shower {
    center: Vector,
    count: usize,
    radius: Real,
    spread: Real,
    low: Real,
    high: Real,
    velocity: Vector,
}

impl Shower {
    fn spawn(&self, world: &mut PhysicsWorld, seed: u64) -> Vec<RigidBodyHandle> {
        let mut rng = Lcg(seed);
        (0..self.count)
            .map(|_| {
                let offset = Vector::new(
                    rng.range(-self.spread, self.spread),
                    rng.range(self.low, self.high),
                    rng.range(-self.spread, self.spread),
                );
                let body = RigidBodyBuilder::dynamic()
                    .translation(self.center + offset)
                    .linvel(self.velocity)
                    .ccd_enabled(true);
                world.insert(body, ColliderBuilder::ball(self.radius)).0
            })
            .collect()
    }
}

fn rain(world: &mut PhysicsWorld) -> Setup {
    let Some(floor) = fixed_mesh(world, grid_mesh(-5.0, -5.0, 10.0, 4, |_, _| 0.0)) else {
        return Setup::default();
    };
    let balls = Shower {
        center: Vector::ZERO,
        count: 80,
        radius: 0.03,
        spread: 4.0,
        low: 2.0,
        high: 6.0,
        velocity: Vector::new(0.0, -60.0, 0.0),
    }
    .spawn(world, 11);
    Setup {
        guards: crossing_guards(&balls, &[floor]),
        ..Setup::default()
    }
}

fn rain_dt10(world: &mut PhysicsWorld) -> Setup {
    let Some(floor) = fixed_mesh(world, grid_mesh(-5.0, -5.0, 10.0, 4, |_, _| 0.0)) else {
        return Setup::default();
    };
    let balls = Shower {
        center: Vector::ZERO,
        count: 40,
        radius: 0.05,
        spread: 4.0,
        low: 1.0,
        high: 6.0,
        velocity: Vector::new(0.0, -40.0, 0.0),
    }
    .spawn(world, 13);
    Setup {
        guards: crossing_guards(&balls, &[floor]),
        ..Setup::default()
    }
}

fn far_from_origin(world: &mut PhysicsWorld) -> Setup {
    let origin = Vector::new(10_000.0, 0.0, 10_000.0);
    let Some(floor) = fixed_mesh(
        world,
        grid_mesh(origin.x - 5.0, origin.z - 5.0, 10.0, 4, |_, _| 0.0),
    ) else {
        return Setup::default();
    };
    let (_, face) = thin_wall(
        world,
        origin + Vector::new(4.0, 2.0, 0.0),
        Vector::new(0.05, 2.0, 3.0),
        0,
        1.0,
    );
    let balls = Shower {
        center: origin - Vector::X * 2.0,
        count: 20,
        radius: 0.04,
        spread: 2.5,
        low: 1.0,
        high: 4.0,
        velocity: Vector::new(0.0, -40.0, 0.0),
    }
    .spawn(world, 17);
    let bullets: Vec<_> = (0..4)
        .map(|k| {
            let at = origin + Vector::new(-1.0, 1.0 + 0.6 * k as Real, 0.8 * k as Real - 1.2);
            let body = RigidBodyBuilder::dynamic()
                .translation(at)
                .linvel(Vector::new(120.0, 0.0, 0.0))
                .ccd_enabled(true);
            world.insert(body, ColliderBuilder::ball(0.05)).0
        })
        .collect();
    let mut guards = crossing_guards(&balls, &[floor]);
    guards.extend(beyond_guards(&bullets, face));
    Setup {
        guards,
        ..Setup::default()
    }
}
