//! Headless: the tunnelling counts of a few bevy_rapier scenes, with
//! bevy_rapier's own CCD (`Ccd::enabled()` on the fast bodies) and with
//! `AffineCcdPlugin`.
//!
//! `cargo run --release -p affine-ccd-bevy --example bullets`

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Backend, Watch, blades, bullets, head_on, run, run_counting};

fn main() {
    type Scene = fn(&mut bevy::prelude::App, usize) -> Vec<Watch>;
    let scenes: [(&str, Scene, usize); 3] = [
        ("bullets (150 m/s at a 6 cm wall)", bullets, 8),
        ("head-on thin boxes (±150 m/s)", head_on, 8),
        ("spinning blade (300 rad/s) by a wall", blades, 8),
    ];
    let updates = 120;
    println!(
        "{:<38} {:>5} {:>12} {:>11} {:>7}",
        "scene", "lanes", "bevy_rapier", "affine-ccd", "clamps"
    );
    println!("{}", "-".repeat(77));
    for (name, scene, n) in scenes {
        let rapier = run(Backend::Rapier, scene, n, updates);
        let (affine, clamps) = run_counting(Backend::Affine, scene, n, updates);
        println!("{name:<38} {n:>5} {rapier:>12} {affine:>11} {clamps:>7}");
    }
    println!(
        "tunnelled: bodies on the far side of their wall, pairs that swapped sides, after \
         {updates} updates at 60 Hz; clamps: the plugin's CcdHit messages"
    );
}
