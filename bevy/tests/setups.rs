//! Other bevy_rapier setups: physics in `FixedUpdate`, custom hooks,
//! collision groups, a configuration per context.

mod common;

use affine_ccd::rapier::CcdConfig;
use affine_ccd_bevy::{AffineCcdPlugin, AffineCcdStage, ContextCcdConfig};
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::prelude::SolverFlags;
use common::{Backend, DT, Watch, bullets, head_on, tunnelled};
use std::time::Duration;

/// The plugin with bevy_rapier in `FixedUpdate`.
fn fixed_app(backend: Backend) -> App {
    common::app_in(backend, true)
}

#[test]
fn in_fixed_update_the_plugin_steps_instead_of_bevy_rapier() {
    let mut ends = Vec::new();
    for backend in [Backend::Rapier, Backend::Affine] {
        let mut app = fixed_app(backend);
        let free = app
            .world_mut()
            .spawn((
                RigidBody::Dynamic,
                Collider::ball(0.1),
                Transform::from_xyz(0.0, 50.0, 0.0),
                Velocity::linear(Vec3::new(1.0, 0.0, 0.0)),
                GravityScale(0.0),
            ))
            .id();
        let watch = head_on(&mut app, 4);
        for _ in 0..200 {
            app.update();
        }
        ends.push(app.world().get::<Transform>(free).unwrap().translation);
        let n = tunnelled(&mut app, &watch);
        match backend {
            Backend::Rapier => assert!(n > 0),
            Backend::Affine => assert_eq!(n, 0),
        }
    }
    // One step per fixed update, not two: the free ball went as far.
    assert!(ends[0].x > 1.0);
    assert_eq!(ends[0], ends[1]);
}

/// Hooks that let no contact through for colliders marked `Ghost`.
#[derive(Component)]
struct Ghost;

#[derive(SystemParam)]
struct GhostHooks<'w, 's> {
    ghosts: Query<'w, 's, (), With<Ghost>>,
}

impl BevyPhysicsHooks for GhostHooks<'_, '_> {
    fn filter_contact_pair(&self, context: PairFilterContextView) -> Option<SolverFlags> {
        let ghost = |e: Entity| self.ghosts.contains(e);
        if ghost(context.collider1()) || ghost(context.collider2()) {
            None
        } else {
            Some(SolverFlags::COMPUTE_RIGID_IMPULSES)
        }
    }
}

#[test]
fn hooks_and_collision_groups_filter_the_stage_too() {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        RapierPhysicsPlugin::<GhostHooks>::default(),
        AffineCcdPlugin::<GhostHooks>::with_hooks(CcdConfig::default()),
    ))
    .insert_resource(TimestepMode::Fixed {
        dt: DT,
        substeps: 1,
    })
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
        DT,
    )));
    app.finish();
    app.cleanup();
    app.update();
    let watch = bullets(&mut app, 6);
    // Bullets 0 and 1: ghosts (the hooks drop their contacts); 2 and 3: in
    // a group that meets nothing; 4 and 5: plain, stopped.
    for (i, w) in watch.iter().enumerate() {
        let Watch::Side { body, .. } = *w else {
            unreachable!()
        };
        let mut e = app.world_mut().entity_mut(body);
        match i {
            0 | 1 => {
                e.insert((Ghost, ActiveHooks::FILTER_CONTACT_PAIRS));
            }
            2 | 3 => {
                e.insert(CollisionGroups::new(Group::GROUP_2, Group::NONE));
            }
            _ => {}
        }
    }
    for _ in 0..120 {
        app.update();
    }
    let through: Vec<bool> = watch
        .iter()
        .map(|w| tunnelled(&mut app, std::slice::from_ref(w)) == 1)
        .collect();
    assert_eq!(through, [true, true, true, true, false, false]);
}

#[test]
fn a_context_config_is_used() {
    let mut app = common::app(Backend::Affine);
    let context = app
        .world_mut()
        .query_filtered::<Entity, With<DefaultRapierContext>>()
        .single(app.world())
        .unwrap();
    let config = CcdConfig {
        epsilon: 1.0e-3,
        ..CcdConfig::default()
    };
    app.world_mut()
        .entity_mut(context)
        .insert(ContextCcdConfig(config));
    let watch = bullets(&mut app, 2);
    for _ in 0..30 {
        app.update();
    }
    assert_eq!(tunnelled(&mut app, &watch), 0);
    let stage = app.world().get::<AffineCcdStage>(context).unwrap();
    assert_eq!(stage.stage().config().epsilon, 1.0e-3);
    assert_eq!(stage.reports().len(), 1);
}

#[test]
fn in_fixed_update_removed_colliders_keep_their_entities() {
    let mut counts = Vec::new();
    for backend in [Backend::Rapier, Backend::Affine] {
        let mut app = fixed_app(backend);
        common::record(&mut app);
        app.world_mut().spawn((
            Collider::ball(0.5),
            Sensor,
            Transform::from_xyz(0.0, 0.0, 0.0),
            ActiveEvents::COLLISION_EVENTS,
        ));
        let ball = app
            .world_mut()
            .spawn((
                RigidBody::Dynamic,
                Collider::ball(0.1),
                Transform::from_xyz(0.0, 0.0, 0.0),
                GravityScale(0.0),
            ))
            .id();
        for i in 0..20 {
            if i == 5 {
                app.world_mut().despawn(ball);
            }
            app.update();
        }
        let seen = app.world().resource::<common::Seen>();
        counts.push(
            seen.collisions
                .iter()
                .filter(|e| {
                    matches!(e, CollisionEvent::Stopped(a, b, flags)
                    if (*a == ball || *b == ball)
                        && flags.contains(
                            bevy_rapier3d::rapier::geometry::CollisionEventFlags::REMOVED,
                        ))
                })
                .count(),
        );
    }
    assert_eq!(counts, [1, 1]);
}
