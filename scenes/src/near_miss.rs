//! Near misses: fast bodies passing the edge or the corner of a fixed box
//! at gaps from 1 cm of overlap to 1 cm of clearance. Nothing should be
//! stopped: a graze by a few millimetres at most, a clean pass otherwise.
//! Control scenes for false impacts and for how the engines treat a contact
//! that only exists between two steps.

use super::kit::crossing_guards;
use super::{Effects, Scene, Setup};
use rapier3d::math::{Real, Rotation, Vector};
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder};
use std::f64::consts::SQRT_2;

/// The scenes of this family.
pub fn scenes() -> Vec<Scene> {
    vec![
        Scene {
            name: "near_miss_edges",
            about: "balls (r 10 cm) at 100 m/s past the edge of boxes turned 45°, gaps -1 cm to +1 cm",
            dt: 1.0 / 60.0,
            steps: 60,
            effects: Effects::default(),
            built_to_tunnel: false,
            view: [0, 2],
            build: near_miss_edges,
        },
        Scene {
            name: "near_miss_corners",
            about: "cubes (10 cm half) at 60 m/s, some spinning at 20 rad/s, past the corner of a box, gaps -1 cm to +1 cm",
            dt: 1.0 / 60.0,
            steps: 60,
            effects: Effects {
                rotation: true,
                ..Effects::default()
            },
            built_to_tunnel: false,
            view: [0, 2],
            build: near_miss_corners,
        },
    ]
}

/// Signed gaps (metres) between the mover's surface and the feature it
/// passes at the closest approach; negative is an overlap.
const EDGE_GAPS: [f64; 7] = [-1.0e-2, -1.0e-3, -1.0e-4, 0.0, 1.0e-4, 1.0e-3, 1.0e-2];

/// Lanes are 3 m apart along y: each mover only ever meets its own box.
fn lane(k: usize) -> Real {
    3.0 * k as Real
}

fn near_miss_edges(world: &mut PhysicsWorld) -> Setup {
    // Each box (half extents h) sits at (0, y_k, 0), turned 45° about y: in
    // the xz plane it is a square standing on a vertex, whose vertical edges
    // are at (±h√2, 0) and (0, ±h√2). Its ball moves along +x at y = y_k and
    // z = h√2 + r + gap: the closest point of the box to the ball's path is
    // the edge at (0, h√2) (the two faces meeting there slope away at 45°),
    // so the ball's surface passes it at exactly `gap`, as the centre crosses
    // x = 0. Offsets are computed in f64 and rounded once to f32 (~6e-8 m).
    //
    // 100 m/s is 1.67 m a step: from x = -4.2 the end poses are at -2.53,
    // -0.87 and 0.80, so the closest approach lies mid-step and no end pose
    // is within 0.6 m of the box.
    let (h, r) = (0.5, 0.1);
    let turn = Rotation::from_axis_angle(Vector::Y, std::f32::consts::FRAC_PI_4);
    let mut balls = Vec::new();
    let mut boxes = Vec::new();
    for (k, gap) in EDGE_GAPS.into_iter().enumerate() {
        let y = lane(k);
        boxes.push(
            world.insert_collider(
                ColliderBuilder::cuboid(h, h, h)
                    .translation(Vector::new(0.0, y, 0.0))
                    .rotation(turn.to_scaled_axis()),
                None,
            ),
        );
        let z = (h as f64 * SQRT_2 + r as f64 + gap) as Real;
        let body = RigidBodyBuilder::dynamic()
            .translation(Vector::new(-4.2, y, z))
            .linvel(Vector::new(100.0, 0.0, 0.0))
            .ccd_enabled(true);
        balls.push(world.insert(body, ColliderBuilder::ball(r)).0);
    }
    // Nothing should be stopped; the guards only check that no centre of
    // mass enters a box (which no backend should ever do here).
    Setup {
        guards: crossing_guards(&balls, &boxes),
        ..Setup::default()
    }
}

fn near_miss_corners(world: &mut PhysicsWorld) -> Setup {
    // Each box (half extents H) sits at (0, y_k, 0), turned so that its body
    // diagonal (1, 1, 1) points along +z: its corner (H, H, H) is then at
    // (0, y_k, H√3), the only point of the box that high (the three faces
    // meeting there slope down at 35°). The mover, a cube of half extents
    // a, moves along +x at y = y_k:
    //
    // - not spinning, axis-aligned, at z = H√3 + a + gap: its bottom face
    //   sweeps over the corner at exactly `gap`;
    // - spinning at 20 rad/s about x (its direction of flight), at
    //   z = H√3 + a√2 + gap: the cube stays within a√2 of its path's axis,
    //   so it clears the corner by at least `gap` (by up to gap + 0.41 a).
    //
    // 60 m/s is 1 m a step: from x = -3.5 the end poses are at -0.5 and 0.5
    // around the corner, which lies mid-step.
    let (big, a) = (0.5, 0.1);
    let diagonal = Vector::ONE.normalize();
    let turn = Rotation::from_rotation_arc(diagonal, Vector::Z);
    let movers: [(f64, Real); 7] = [
        (-1.0e-2, 0.0),
        (0.0, 0.0),
        (1.0e-3, 0.0),
        (1.0e-2, 0.0),
        (0.0, 20.0),
        (1.0e-3, 20.0),
        (1.0e-2, 20.0),
    ];
    let sqrt_3 = 3.0_f64.sqrt();
    let mut cubes = Vec::new();
    let mut boxes = Vec::new();
    for (k, (gap, spin)) in movers.into_iter().enumerate() {
        let y = lane(k);
        boxes.push(
            world.insert_collider(
                ColliderBuilder::cuboid(big, big, big)
                    .translation(Vector::new(0.0, y, 0.0))
                    .rotation(turn.to_scaled_axis()),
                None,
            ),
        );
        let reach = if spin == 0.0 {
            a as f64
        } else {
            a as f64 * SQRT_2
        };
        let z = (big as f64 * sqrt_3 + reach + gap) as Real;
        let body = RigidBodyBuilder::dynamic()
            .translation(Vector::new(-3.5, y, z))
            .linvel(Vector::new(60.0, 0.0, 0.0))
            .angvel(Vector::new(spin, 0.0, 0.0))
            .ccd_enabled(true);
        cubes.push(world.insert(body, ColliderBuilder::cuboid(a, a, a)).0);
    }
    Setup {
        guards: crossing_guards(&cubes, &boxes),
        ..Setup::default()
    }
}

#[cfg(test)]
mod tests {
    use rapier3d::parry::query;

    /// The geometry is what the comments say: at the closest approach, the
    /// signed distance between each mover and its box is the lane's gap.
    #[test]
    fn gaps_are_as_built() {
        for (scene, gaps) in [
            (0, super::EDGE_GAPS.to_vec()),
            (1, vec![-1.0e-2, 0.0, 1.0e-3, 1.0e-2]),
        ] {
            let scene = super::scenes()[scene];
            let (world, _) = scene.instantiate();
            let fixed: Vec<_> = world
                .colliders
                .iter()
                .filter(|(_, c)| c.parent().is_none())
                .map(|(_, c)| c)
                .collect();
            let moving: Vec<_> = world
                .colliders
                .iter()
                .filter(|(_, c)| c.parent().is_some())
                .map(|(_, c)| c)
                .collect();
            for (k, &gap) in gaps.iter().enumerate() {
                let (obstacle, mover) = (fixed[k], moving[k]);
                // Slide the mover to x = 0, the closest approach.
                let mut pose = *mover.position();
                pose.translation.x = 0.0;
                let d =
                    query::distance(&pose, mover.shape(), obstacle.position(), obstacle.shape())
                        .expect("supported shapes")
                        .distance;
                let depth = query::contact(
                    &pose,
                    mover.shape(),
                    obstacle.position(),
                    obstacle.shape(),
                    1.0,
                )
                .expect("supported shapes")
                .map_or(0.0, |c| c.dist);
                let signed = if d > 0.0 { d } else { depth };
                assert!(
                    (signed as f64 - gap).abs() < 2.0e-6,
                    "{} lane {k}: gap {signed} instead of {gap} (mover at {:?})",
                    scene.name,
                    pose.translation
                );
            }
        }
    }
}
