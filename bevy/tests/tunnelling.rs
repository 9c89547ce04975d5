//! The plugin's scenes tunnel 0 times where bevy_rapier's own CCD tunnels.

mod common;

use affine_ccd_bevy::{AffineCcdStage, CcdHit};
use bevy::prelude::*;
use bevy_rapier3d::prelude::Collider;
use common::{Backend, app, blades, bullets, head_on, run, tunnelled};

const UPDATES: usize = 300;

#[test]
fn head_on_pairs_tunnel_with_rapier_not_with_the_plugin() {
    let rapier = run(Backend::Rapier, head_on, 6, UPDATES);
    let affine = run(Backend::Affine, head_on, 6, UPDATES);
    assert!(rapier > 0, "bevy_rapier's CCD should let some pairs swap");
    assert_eq!(affine, 0);
}

#[test]
fn bullets_and_blades_do_not_tunnel_with_the_plugin() {
    assert_eq!(run(Backend::Affine, bullets, 6, UPDATES), 0);
    assert_eq!(run(Backend::Affine, blades, 6, UPDATES), 0);
}

#[test]
fn clamps_are_reported_with_entities() {
    let mut app = app(Backend::Affine);
    let watch = bullets(&mut app, 3);
    common::record(&mut app);
    for _ in 0..60 {
        app.update();
    }
    let hits: Vec<CcdHit> = app.world().resource::<common::Seen>().hits.clone();
    assert_eq!(tunnelled(&mut app, &watch), 0);
    assert!(!hits.is_empty(), "the bullets should be clamped");
    for hit in &hits {
        assert!(app.world().get_entity(hit.body).is_ok());
        assert!(app.world().get::<Collider>(hit.collider1).is_some());
        assert!(app.world().get::<Collider>(hit.collider2).is_some());
        assert!((0.0..=1.0).contains(&hit.fraction));
        assert!(hit.normal.is_finite() && hit.point.is_finite());
    }
    // The context carries the stage and its reports.
    let mut q = app.world_mut().query::<&AffineCcdStage>();
    assert_eq!(q.iter(app.world()).count(), 1);
}
