//! Bodies dropped tilted onto floors and left to come to rest, each on its
//! own: the same box, slab, capsule and ball over a flat two-triangle mesh,
//! a gently wavy mesh, and the same waves as a heightfield. Nothing here is
//! fast; the scenes are for comparing the rest poses with rapier's.

use super::kit::{crossing_guards, fixed_mesh, grid_mesh};
use super::{Effects, Scene, Setup};
use rapier3d::math::{Real, Vector};
use rapier3d::prelude::{
    Array2, ColliderBuilder, ColliderHandle, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
};

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    let settling = Effects {
        gravity: true,
        friction: true,
        settles: true,
        ..Effects::default()
    };
    // Without CCD the slab falls through the two-triangle floor (10 m/s at
    // impact, 16 cm a step, five times its thickness); on the waves it only
    // sinks, by a few centimetres, like the other bodies.
    let scene = |name, about, built_to_tunnel, build| Scene {
        name,
        about,
        dt: 1.0 / 60.0,
        steps: 600,
        effects: settling,
        built_to_tunnel,
        view: [0, 1],
        build,
    };
    vec![
        scene(
            "settle_flat",
            "a box, a slab, a capsule and a ball dropped tilted from 1-5 m onto a 2-triangle trimesh; they come to rest",
            true,
            settle_flat as fn(&mut PhysicsWorld) -> Setup,
        ),
        scene(
            "settle_wavy",
            "the same four bodies dropped into the troughs of a wavy trimesh (5 cm bumps, 2.4 m apart); they come to rest",
            true,
            settle_wavy,
        ),
        scene(
            "settle_heightfield",
            "the same four bodies dropped into the troughs of the same waves as a heightfield; they come to rest",
            true,
            settle_heightfield,
        ),
    ]
}

/// Half size of the floors (metres): they cover x, z ∈ [-7.2, 7.2].
const HALF: Real = 7.2;
/// Cells a side of the wavy floors: 0.2 m cells, so the troughs below the
/// bodies are vertices.
const CELLS: u32 = 72;
/// Wavelength of the waves (metres); the drop points are troughs.
const WAVELENGTH: Real = 2.4;

/// Height of the wavy floors (metres): 5 cm bumps, 2.4 m wavelength along x
/// and z, so the 2 m slab's edges rest on slopes, not on ridges. Troughs
/// (-5 cm) where x and z are multiples of the wavelength, e.g. at the four
/// drop points (±2.4, ±2.4).
fn waves(x: Real, z: Real) -> Real {
    let k = std::f32::consts::TAU / WAVELENGTH;
    -0.05 * (k * x).cos() * (k * z).cos()
}

/// Drops the four bodies over (±2.4, ±2.4), 4.8 m apart, and guards them above
/// `floor`. Rapier has no rolling resistance: a ball rolling in a trough of
/// the triangulated waves would rock for ever, so every body gets some
/// angular damping (2 /s) as a stand-in.
fn drop_four(world: &mut PhysicsWorld, floor: ColliderHandle) -> Setup {
    const D: Real = WAVELENGTH;
    let drops: [(Vector, Vector, ColliderBuilder); 4] = [
        // Box (0.15 half extents), 0.3 rad about z, 2 m up: landing edge
        // first at 6 m/s it moves 10 cm a step, more than half its
        // thickness, so CCD sees it (a larger box would sink its edge 3-5 cm
        // into the mesh under every backend, unseen by any CCD's test).
        (
            Vector::new(-D, 2.15, -D),
            Vector::new(0.0, 0.0, 0.3),
            ColliderBuilder::cuboid(0.15, 0.15, 0.15),
        ),
        // Slab (2 m x 6 cm x 2 m), 0.3 rad about z, 5 m up.
        (
            Vector::new(D, 5.0, -D),
            Vector::new(0.0, 0.0, 0.3),
            ColliderBuilder::cuboid(1.0, 0.03, 1.0),
        ),
        // Capsule (half height 0.3, r 0.1), standing, 0.6 rad about x and
        // 0.3 about y: it lands on one end and falls over; 1 m up.
        (
            Vector::new(-D, 1.5, D),
            Vector::new(0.6, 0.3, 0.0),
            ColliderBuilder::capsule_y(0.3, 0.1),
        ),
        // Ball (r 0.2), 0.6 rad about z (only its spin axis sees it), 3 m up.
        (
            Vector::new(D, 3.2, D),
            Vector::new(0.0, 0.0, 0.6),
            ColliderBuilder::ball(0.2),
        ),
    ];
    let bodies: Vec<RigidBodyHandle> = drops
        .into_iter()
        .map(|(at, tilt, collider)| {
            let body = RigidBodyBuilder::dynamic()
                .translation(at)
                .rotation(tilt)
                .angular_damping(2.0)
                .ccd_enabled(true);
            world.insert(body, collider.friction(0.6)).0
        })
        .collect();
    Setup {
        guards: crossing_guards(&bodies, &[floor]),
        ..Setup::default()
    }
}

fn settle_flat(world: &mut PhysicsWorld) -> Setup {
    // One quad at y = 0: 4 vertices, 2 triangles.
    let Some(floor) = fixed_mesh(world, grid_mesh(-HALF, -HALF, 2.0 * HALF, 1, |_, _| 0.0)) else {
        return Setup::default();
    };
    drop_four(world, floor)
}

fn settle_wavy(world: &mut PhysicsWorld) -> Setup {
    let Some(floor) = fixed_mesh(world, grid_mesh(-HALF, -HALF, 2.0 * HALF, CELLS, waves)) else {
        return Setup::default();
    };
    drop_four(world, floor)
}

fn settle_heightfield(world: &mut PhysicsWorld) -> Setup {
    // Rows advance along z, columns along x; the heightfield is centred on
    // the origin and spans `scale` in x and z, so its vertices are those of
    // the wavy mesh.
    let n = CELLS as usize + 1;
    let step = 2.0 * HALF / CELLS as Real;
    let mut heights = Array2::zeros(n, n);
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (-HALF + j as Real * step, -HALF + i as Real * step);
            heights[(i, j)] = waves(x, z);
        }
    }
    let scale = Vector::new(2.0 * HALF, 1.0, 2.0 * HALF);
    let floor = world.insert_collider(ColliderBuilder::heightfield(heights, scale), None);
    drop_four(world, floor)
}

#[cfg(test)]
mod tests {
    use super::super::kit::all_at_rest;

    /// Every scene of the family comes to rest under plain rapier.
    #[test]
    fn the_bodies_come_to_rest() {
        for scene in super::scenes() {
            let (mut world, _) = scene.instantiate();
            for _ in 0..scene.steps {
                world.step();
            }
            assert!(
                all_at_rest(&world, 0.02, 0.05),
                "{} does not come to rest: {:?}",
                scene.name,
                world
                    .bodies
                    .iter()
                    .map(|(_, rb)| (rb.translation(), rb.linvel().length(), rb.angvel().length()))
                    .collect::<Vec<_>>()
            );
        }
    }
}
