//! Without fast bodies the plugin changes nothing: boxes landing, a stack and
//! balls rolling on a floor end with the same transforms as with bevy_rapier
//! alone (its own CCD on, as by default), to the bit, with the same events.

mod common;

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use common::{Backend, DT, app};
use std::time::Duration;

fn slow_scene(app: &mut App) -> Vec<Entity> {
    // Every entity has the same components: bevy_rapier gives out handles
    // in query order, which follows the archetypes, and the plugin's
    // components on the context entity shift the archetypes' order; one
    // archetype keeps the handles, hence rapier's order, the same.
    app.world_mut().spawn((
        RigidBody::Fixed,
        Collider::cuboid(20.0, 0.1, 20.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
        Velocity::zero(),
        ActiveEvents::COLLISION_EVENTS,
        TransformInterpolation::default(),
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
                    Velocity::zero(),
                    ActiveEvents::COLLISION_EVENTS,
                    TransformInterpolation::default(),
                ))
                .id(),
        );
    }
    // A stack: contacts that last the whole run.
    for i in 0..4 {
        bodies.push(
            app.world_mut()
                .spawn((
                    RigidBody::Dynamic,
                    Collider::cuboid(0.3, 0.2, 0.3),
                    Transform::from_xyz(4.0 + 0.02 * i as f32, 0.21 + 0.41 * i as f32, -4.0),
                    Velocity::zero(),
                    ActiveEvents::COLLISION_EVENTS,
                    TransformInterpolation::default(),
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
                    ActiveEvents::COLLISION_EVENTS,
                    TransformInterpolation::default(),
                ))
                .id(),
        );
    }
    bodies
}

fn final_poses(backend: Backend, mode: TimestepMode, frame: f32) -> (Vec<Transform>, usize) {
    let mut app = app(backend);
    app.insert_resource(mode)
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
            frame,
        )));
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

fn same_as_bevy_rapier(mode: TimestepMode, frame: f32) {
    let (rapier, rapier_events) = final_poses(Backend::Rapier, mode, frame);
    let (affine, affine_events) = final_poses(Backend::Affine, mode, frame);
    for (a, b) in rapier.iter().zip(&affine) {
        assert_eq!(a.translation, b.translation, "{mode:?}, frame {frame}");
        assert_eq!(a.rotation, b.rotation, "{mode:?}, frame {frame}");
    }
    assert!(rapier_events > 0);
    assert_eq!(rapier_events, affine_events);
}

#[test]
fn no_fast_bodies_same_transforms_and_events() {
    same_as_bevy_rapier(
        TimestepMode::Fixed {
            dt: DT,
            substeps: 1,
        },
        DT,
    );
}

/// The timestep modes as bevy_rapier runs them: substeps, steps skipped or
/// doubled by interpolation, the interpolated transforms written back.
#[test]
fn no_fast_bodies_same_in_every_timestep_mode() {
    same_as_bevy_rapier(
        TimestepMode::Fixed {
            dt: DT,
            substeps: 3,
        },
        DT,
    );
    let variable = TimestepMode::Variable {
        max_dt: DT,
        time_scale: 1.0,
        substeps: 2,
    };
    same_as_bevy_rapier(variable, 0.7 * DT);
    for frame in [0.4 * DT, 1.7 * DT] {
        for time_scale in [1.0, 0.5] {
            let interpolated = TimestepMode::Interpolated {
                dt: DT,
                time_scale,
                substeps: 2,
            };
            same_as_bevy_rapier(interpolated, frame);
        }
    }
}
