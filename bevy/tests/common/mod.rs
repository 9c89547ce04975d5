//! Scenes built with bevy_rapier components, run with or without the plugin
//! (shared by the tests and the `bullets` example).
#![allow(dead_code)]

use affine_ccd_bevy::AffineCcdPlugin;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use std::cmp::Ordering::Less;
use std::time::Duration;

/// Which CCD steps the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// bevy_rapier's own CCD (the fast bodies have `Ccd::enabled()`).
    Rapier,
    /// `AffineCcdPlugin`.
    Affine,
}

pub const DT: f32 = 1.0 / 60.0;

/// A headless app stepping at a fixed 60 Hz, one step per update, with a
/// manual clock (deterministic).
pub fn app(backend: Backend) -> App {
    app_in(backend, false)
}

/// [`app`], with bevy_rapier in `FixedUpdate` when `fixed_schedule`.
pub fn app_in(backend: Backend, fixed_schedule: bool) -> App {
    let mut app = App::new();
    let rapier = RapierPhysicsPlugin::<NoUserData>::default();
    if fixed_schedule {
        app.add_plugins((MinimalPlugins, rapier.in_fixed_schedule()))
            .insert_resource(Time::<Fixed>::from_seconds(DT as f64));
    } else {
        app.add_plugins((MinimalPlugins, rapier));
    }
    if backend == Backend::Affine {
        app.add_plugins(AffineCcdPlugin::default());
    }
    app.insert_resource(TimestepMode::Fixed {
        dt: DT,
        substeps: 1,
    })
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
        DT,
    )));
    app.finish();
    app.cleanup();
    // Startup: the rapier context is spawned.
    app.update();
    // The plugin's resources are entities too (bevy 0.20): pad so that the
    // scene's entities get the same indices with either backend (rapier's
    // results depend on the order of bodies and colliders, which follows
    // the entities).
    while app.world_mut().spawn_empty().id().index_u32() < 99 {}
    app
}

/// Something to count at the end: the body must stay on the `-x` side of
/// `wall_x`, or (for a pair) `a` must stay left of `b`.
pub enum Watch {
    Side { body: Entity, wall_x: f32 },
    Pair { a: Entity, b: Entity },
}

/// A fixed thin wall (half thickness `half`) at `x`, `z`.
fn wall(app: &mut App, x: f32, z: f32, half: f32) {
    app.world_mut().spawn((
        RigidBody::Fixed,
        Collider::cuboid(half, 2.0, 0.9),
        Transform::from_xyz(x, 0.0, z),
    ));
}

/// Bullets: balls of 5 cm radius at 150 m/s towards a 6 cm wall, one lane
/// each (the lanes start at different distances, so they reach the wall at
/// different points of a step).
pub fn bullets(app: &mut App, n: usize) -> Vec<Watch> {
    let mut watch = Vec::new();
    for i in 0..n {
        let z = 2.0 * i as f32;
        wall(app, 0.0, z, 0.03);
        let body = app
            .world_mut()
            .spawn((
                RigidBody::Dynamic,
                Collider::ball(0.05),
                Transform::from_xyz(-3.0 - 0.37 * i as f32, 0.0, z),
                Velocity::linear(Vec3::new(150.0, 0.0, 0.0)),
                GravityScale(0.0),
                Ccd::enabled(),
            ))
            .id();
        watch.push(Watch::Side { body, wall_x: 0.0 });
    }
    watch
}

/// Head-on: two thin boxes (4 cm) at ±150 m/s towards each other.
pub fn head_on(app: &mut App, n: usize) -> Vec<Watch> {
    let mut watch = Vec::new();
    for i in 0..n {
        let z = 2.0 * i as f32;
        let gap = 2.0 + 0.29 * i as f32;
        let mut spawn = |x: f32, v: f32| {
            app.world_mut()
                .spawn((
                    RigidBody::Dynamic,
                    Collider::cuboid(0.02, 0.5, 0.5),
                    Transform::from_xyz(x, 0.0, z),
                    Velocity::linear(Vec3::new(v, 0.0, 0.0)),
                    GravityScale(0.0),
                    Ccd::enabled(),
                ))
                .id()
        };
        let a = spawn(-gap, 150.0);
        let b = spawn(gap, -150.0);
        watch.push(Watch::Pair { a, b });
    }
    watch
}

/// A thin blade (1.2 m × 4 cm) spinning at 300 rad/s about `z`, its centre
/// 0.4 m from a 6 cm wall and moving towards it at 20 m/s: its ends sweep
/// through the wall's plane.
pub fn blades(app: &mut App, n: usize) -> Vec<Watch> {
    let mut watch = Vec::new();
    for i in 0..n {
        let z = 2.0 * i as f32;
        wall(app, 0.0, z, 0.03);
        let body = app
            .world_mut()
            .spawn((
                RigidBody::Dynamic,
                Collider::cuboid(0.6, 0.02, 0.1),
                Transform::from_xyz(-0.4, 0.0, z)
                    .with_rotation(Quat::from_rotation_z(0.3 * i as f32)),
                Velocity {
                    linear: Vec3::new(20.0, 0.0, 0.0),
                    angular: Vec3::new(0.0, 0.0, 300.0),
                },
                GravityScale(0.0),
                Ccd::enabled(),
            ))
            .id();
        watch.push(Watch::Side { body, wall_x: 0.0 });
    }
    watch
}

/// How many of `watch` tunnelled.
pub fn tunnelled(app: &mut App, watch: &[Watch]) -> usize {
    let x = |app: &mut App, e: Entity| {
        app.world()
            .get::<Transform>(e)
            .map_or(f32::NAN, |t| t.translation.x)
    };
    watch
        .iter()
        .filter(|w| match **w {
            // A NaN position (a lost body) counts as tunnelled.
            Watch::Side { body, wall_x } => x(app, body).partial_cmp(&wall_x) != Some(Less),
            Watch::Pair { a, b } => x(app, a).partial_cmp(&x(app, b)) != Some(Less),
        })
        .count()
}

/// Runs a scene for `updates` updates and counts the tunnelling.
pub fn run(
    backend: Backend,
    scene: fn(&mut App, usize) -> Vec<Watch>,
    n: usize,
    updates: usize,
) -> usize {
    run_counting(backend, scene, n, updates).0
}

/// Runs a scene: (tunnelled, clamps by the plugin).
pub fn run_counting(
    backend: Backend,
    scene: fn(&mut App, usize) -> Vec<Watch>,
    n: usize,
    updates: usize,
) -> (usize, usize) {
    let mut app = app(backend);
    let watch = scene(&mut app, n);
    record(&mut app);
    for _ in 0..updates {
        app.update();
    }
    let clamps = app.world().resource::<Seen>().hits.len();
    (tunnelled(&mut app, &watch), clamps)
}

/// Every collision event and clamp seen so far (read by a system, so each is
/// seen once).
#[derive(Resource, Default)]
pub struct Seen {
    pub collisions: Vec<CollisionEvent>,
    pub hits: Vec<affine_ccd_bevy::CcdHit>,
}

pub fn record(app: &mut App) {
    app.init_resource::<Seen>().add_systems(
        Last,
        |mut seen: ResMut<Seen>,
         mut collisions: MessageReader<CollisionEvent>,
         hits: Option<MessageReader<affine_ccd_bevy::CcdHit>>| {
            seen.collisions.extend(collisions.read().copied());
            if let Some(mut hits) = hits {
                seen.hits.extend(hits.read().copied());
            }
        },
    );
}
