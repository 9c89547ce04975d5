//! Without fast bodies the plugin changes nothing: a stack of boxes and a few
//! balls rolling on a floor end with the same transforms, to the bit.

mod common;

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use common::{Backend, app};

fn slow_scene(app: &mut App) -> Vec<Entity> {
    app.world_mut().spawn((
        RigidBody::Fixed,
        Collider::cuboid(20.0, 0.1, 20.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
    ));
    let mut bodies = Vec::new();
    for i in 0..6 {
        bodies.push(
            app.world_mut()
                .spawn((
                    RigidBody::Dynamic,
                    Collider::cuboid(0.25, 0.25, 0.25),
                    Transform::from_xyz(-3.0 + 1.2 * i as f32, 0.3 + 0.2 * i as f32, -2.0)
                        .with_rotation(Quat::from_rotation_x(0.1 * i as f32)),
                    ActiveEvents::COLLISION_EVENTS,
                ))
                .id(),
        );
    }
    for i in 0..4 {
        bodies.push(
            app.world_mut()
                .spawn((
                    RigidBody::Dynamic,
                    Collider::ball(0.2),
                    Transform::from_xyz(3.0, 0.25, 1.0 * i as f32),
                    Velocity::linear(Vec3::new(-1.0, 0.0, 0.5)),
                ))
                .id(),
        );
    }
    bodies
}

fn final_poses(backend: Backend) -> (Vec<Transform>, usize) {
    let mut app = app(backend);
    if backend == Backend::Rapier {
        // Rapier 0.36 sweeps every fast-ish dynamic body against fixed
        // colliders unless `max_ccd_substeps` is 0 (the stage's setting):
        // compare with rapier's CCD off, the stage's only other change.
        let mut q = app.world_mut().query::<&mut RapierContextSimulation>();
        q.single_mut(app.world_mut())
            .unwrap()
            .integration_parameters
            .max_ccd_substeps = 0;
    }
    let bodies = slow_scene(&mut app);
    common::record(&mut app);
    for _ in 0..300 {
        app.update();
    }
    let started = app
        .world()
        .resource::<common::Seen>()
        .collisions
        .iter()
        .filter(|e| matches!(e, CollisionEvent::Started(..)))
        .count();
    let poses = bodies
        .iter()
        .map(|e| *app.world().get::<Transform>(*e).unwrap())
        .collect();
    (poses, started)
}

#[test]
#[ignore = "open: the boxes end up to 2e-4 m off bevy_rapier's own step even with the stage \
            replaced by a plain `PhysicsPipeline::step` (the balls match to the bit); see the \
            hand-back of issue 12"]
fn no_fast_bodies_same_transforms_and_events() {
    let (rapier, rapier_events) = final_poses(Backend::Rapier);
    let (affine, affine_events) = final_poses(Backend::Affine);
    for (a, b) in rapier.iter().zip(&affine) {
        assert_eq!(a.translation, b.translation);
        assert_eq!(a.rotation, b.rotation);
    }
    assert!(rapier_events > 0);
    assert_eq!(rapier_events, affine_events);
}
