//! Odd input: despawning bodies mid-run, NaN velocities, the other timestep
//! modes, the physics switched off.

mod common;

use bevy::ecs::message::Messages;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use common::{Backend, DT, app, bullets, head_on, tunnelled};
use std::time::Duration;

#[test]
fn despawning_bodies_mid_run_does_not_panic() {
    let mut app = app(Backend::Affine);
    let watch = bullets(&mut app, 4);
    let sensor = app
        .world_mut()
        .spawn((
            Collider::ball(0.5),
            Sensor,
            Transform::from_xyz(-6.0, 0.0, 0.0),
            ActiveEvents::COLLISION_EVENTS,
        ))
        .id();
    let ball = app
        .world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::ball(0.1),
            Transform::from_xyz(-6.0, 0.0, 0.0),
            GravityScale(0.0),
        ))
        .id();
    common::record(&mut app);
    for i in 0..200 {
        if i == 5 {
            // A body inside a sensor, then the bullets, mid-flight.
            app.world_mut().despawn(ball);
        }
        if i == 8 {
            for w in &watch {
                if let common::Watch::Side { body, .. } = w {
                    app.world_mut().despawn(*body);
                }
            }
        }
        app.update();
    }
    let removed_events = app
        .world()
        .resource::<common::Seen>()
        .collisions
        .iter()
        .filter(|e| {
            matches!(e, CollisionEvent::Stopped(a, b, flags)
                if (*a == ball || *b == ball)
                    && flags.contains(bevy_rapier3d::rapier::geometry::CollisionEventFlags::REMOVED))
        })
        .count();
    assert!(app.world().get_entity(sensor).is_ok());
    // The despawned ball's sensor event names it, as without the plugin.
    assert_eq!(removed_events, 1);
}

#[test]
fn nan_velocities_do_not_panic() {
    let mut app = app(Backend::Affine);
    let watch = head_on(&mut app, 2);
    let nan = app
        .world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::ball(0.05),
            Transform::from_xyz(0.0, 5.0, 0.0),
            Velocity::linear(Vec3::new(f32::NAN, 150.0, f32::INFINITY)),
        ))
        .id();
    let mut quarantined = 0;
    for _ in 0..100 {
        app.update();
        quarantined += app
            .world()
            .resource::<Messages<PhysicsQuarantineEvent>>()
            .iter_current_update_messages()
            .filter(|e| e.bodies.contains(&nan))
            .count();
    }
    assert_eq!(tunnelled(&mut app, &watch), 0);
    assert_eq!(quarantined, 1);
    assert!(app.world().get::<RigidBodyDisabled>(nan).is_some());
}

fn with_mode(mode: TimestepMode, frame: f32) -> usize {
    let mut app = app(Backend::Affine);
    app.insert_resource(mode)
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
            frame,
        )));
    let watch = head_on(&mut app, 4);
    for _ in 0..200 {
        app.update();
    }
    tunnelled(&mut app, &watch)
}

#[test]
fn variable_and_interpolated_modes_and_substeps() {
    let variable = TimestepMode::Variable {
        max_dt: DT,
        time_scale: 1.0,
        substeps: 2,
    };
    let interpolated = TimestepMode::Interpolated {
        dt: DT,
        time_scale: 1.0,
        substeps: 1,
    };
    assert_eq!(with_mode(variable, DT), 0);
    // Two rapier steps in some updates, none in others.
    assert_eq!(with_mode(interpolated, 1.5 * DT), 0);
    assert_eq!(with_mode(interpolated, 0.5 * DT), 0);
}

#[test]
fn inactive_physics_moves_nothing() {
    let mut app = app(Backend::Affine);
    let watch = bullets(&mut app, 1);
    let common::Watch::Side { body, .. } = watch[0] else {
        unreachable!()
    };
    let mut q = app
        .world_mut()
        .query_filtered::<&mut RapierConfiguration, With<DefaultRapierContext>>();
    q.single_mut(app.world_mut())
        .unwrap()
        .physics_pipeline_active = false;
    let start = app.world().get::<Transform>(body).unwrap().translation;
    for _ in 0..30 {
        app.update();
    }
    assert_eq!(
        app.world().get::<Transform>(body).unwrap().translation,
        start
    );
}
