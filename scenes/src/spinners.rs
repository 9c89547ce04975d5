//! Fast rotation beside thin walls: rods, blades, fan propellers and a
//! spinning triangle-mesh body. The centre of mass barely moves; the tips
//! sweep through the wall, so the guards are `Beyond` the wall's far face.

use super::kit::{beyond_guards, box_triangles, fan_shape, spinner, thin_wall};
use super::{Effects, Scene, Setup};
use rapier3d::math::{Real, Vector};
use rapier3d::parry::mass_properties::MassProperties;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    let spinning = Effects {
        rotation: true,
        ..Effects::default()
    };
    vec![
        Scene {
            name: "spinning_rods",
            about: "capsule rods (1.9 m) spinning at 20-150 rad/s beside a 4 cm wall, rotation capped (no allow_fast_rotation)",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: spinning,
            built_to_tunnel: true,
            view: [0, 1],
            build: spinning_rods,
        },
        Scene {
            name: "spinning_blades",
            about: "thin blades spinning at 60-300 rad/s with allow_fast_rotation beside a 4 cm wall",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: spinning,
            built_to_tunnel: true,
            view: [0, 1],
            build: spinning_blades,
        },
        Scene {
            name: "fan_propellers",
            about: "3- and 4-blade compound fans at 40-200 rad/s, with and without allow_fast_rotation, beside a wall",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: spinning,
            built_to_tunnel: true,
            view: [0, 1],
            build: fan_propellers,
        },
        Scene {
            name: "spinning_trimesh",
            about: "a cross-shaped trimesh body spinning at 60-250 rad/s beside a 4 cm wall",
            dt: 1.0 / 60.0,
            steps: 150,
            effects: spinning,
            built_to_tunnel: true,
            view: [0, 1],
            build: spinning_trimesh,
        },
    ]
}

/// The wall every spinner is placed beside: thin along x, far face at x = 0.72.
fn wall(world: &mut PhysicsWorld) -> super::guard::Face {
    let (_, face) = thin_wall(
        world,
        Vector::new(0.7, 0.0, 0.0),
        Vector::new(0.02, 4.0, 6.0),
        0,
        1.0,
    );
    face
}

/// z positions of `n` spinners, 1.2 m apart so they never touch each other.
fn rows(n: usize) -> impl Iterator<Item = Real> {
    (0..n).map(move |k| 1.2 * k as Real - 0.6 * (n as Real - 1.0))
}

fn spinning_rods(world: &mut PhysicsWorld) -> Setup {
    let face = wall(world);
    let speeds = [20.0, 40.0, 80.0, 150.0];
    let rods: Vec<_> = rows(speeds.len())
        .zip(speeds)
        .map(|(z, speed)| {
            let rod = ColliderBuilder::capsule_x(0.9, 0.03);
            spinner(
                world,
                Vector::new(0.0, 0.0, z),
                rod,
                Vector::new(0.0, 0.0, speed),
                false,
            )
        })
        .collect();
    Setup {
        guards: beyond_guards(&rods, face),
        ..Setup::default()
    }
}

fn spinning_blades(world: &mut PhysicsWorld) -> Setup {
    let face = wall(world);
    let speeds = [60.0, 120.0, 200.0, 300.0];
    let blades: Vec<_> = rows(speeds.len())
        .zip(speeds)
        .map(|(z, speed)| {
            let blade = ColliderBuilder::cuboid(0.9, 0.06, 0.01);
            spinner(
                world,
                Vector::new(0.0, 0.0, z),
                blade,
                Vector::new(0.0, 0.0, speed),
                true,
            )
        })
        .collect();
    Setup {
        guards: beyond_guards(&blades, face),
        ..Setup::default()
    }
}

fn fan_propellers(world: &mut PhysicsWorld) -> Setup {
    let face = wall(world);
    // (blades, spin rad/s, allow_fast_rotation)
    let fans = [
        (3, 40.0, false),
        (4, 120.0, false),
        (3, 120.0, true),
        (4, 200.0, true),
    ];
    let bodies: Vec<_> = rows(fans.len())
        .zip(fans)
        .map(|(z, (blades, speed, fast))| {
            let shape = ColliderBuilder::new(fan_shape(blades, 0.85, 0.08, 0.02));
            spinner(
                world,
                Vector::new(0.0, 0.0, z),
                shape,
                Vector::new(0.0, 0.0, speed),
                fast,
            )
        })
        .collect();
    Setup {
        guards: beyond_guards(&bodies, face),
        ..Setup::default()
    }
}

fn spinning_trimesh(world: &mut PhysicsWorld) -> Setup {
    let face = wall(world);
    // A plus-shaped propeller as one closed triangle mesh (two crossed boxes).
    let mut mesh = (Vec::new(), Vec::new());
    box_triangles(Vector::ZERO, Vector::new(0.85, 0.05, 0.02), &mut mesh);
    box_triangles(Vector::ZERO, Vector::new(0.05, 0.85, 0.02), &mut mesh);
    // Mass and inertia given explicitly: a mesh's own volume integral does
    // not handle the overlap of the two boxes.
    let props = MassProperties::new(Vector::ZERO, 1.0, Vector::new(0.25, 0.25, 0.5));
    let speeds = [60.0, 150.0, 250.0];
    let bodies: Vec<_> = rows(speeds.len())
        .zip(speeds)
        .filter_map(|(z, speed)| {
            let collider = ColliderBuilder::trimesh(mesh.0.clone(), mesh.1.clone())
                .ok()?
                .density(0.0);
            let body = RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, 0.0, z))
                .angvel(Vector::new(0.0, 0.0, speed))
                .additional_mass_properties(props)
                .ccd_enabled(true)
                .allow_fast_rotation(true)
                .gyroscopic_forces_enabled(false);
            Some(world.insert(body, collider).0)
        })
        .collect();
    Setup {
        guards: beyond_guards(&bodies, face),
        ..Setup::default()
    }
}
