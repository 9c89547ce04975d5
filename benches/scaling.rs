//! How the cost grows with the work: (1) step time of the affine stage with
//! 1 … 1,000 fast bodies; (2) step time with 10 … 4,000 bodies asleep and
//! none fast, rapier alone against the stage; (3) time per query of one moving box against a
//! floor of 8 … 131,072 triangles of constant size. Prints each series and its growth
//! exponent (least-squares slope of log time against log size).
//!
//! `cargo bench --bench scaling`

use affine_ccd::Motion;
use affine_ccd::query::{QueryOptions, time_of_impact};
use affine_ccd::rapier::AffineCcd;
use nalgebra::{Isometry3, Point3, Vector3};
use rapier3d::prelude::*;
use std::time::Instant;

/// Least-squares slope of `ln y` against `ln x`.
fn growth(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x.ln(), b + y.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in points {
        num += (x.ln() - mx) * (y.ln() - my);
        den += (x.ln() - mx).powi(2);
    }
    num / den
}

/// `n` balls fired at 150 m/s at a thin wall, one step timed (median of 5
/// steps after the first).
fn fast_bodies(n: usize) -> f64 {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..PhysicsWorld::default()
    };
    let mut ccd = AffineCcd::default();
    ccd.install(&mut world);
    let wall = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(
        ColliderBuilder::cuboid(0.05, 50.0, 50.0).translation(Vector::new(2.0, 0.0, 0.0)),
        Some(wall),
    );
    let side = (n as f64).sqrt().ceil() as usize;
    for i in 0..n {
        let (y, z) = (
            (i / side) as f32 * 0.5 - 20.0,
            (i % side) as f32 * 0.5 - 20.0,
        );
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(-1.0, y, z))
                .linvel(Vector::new(150.0, 0.0, 0.0)),
        );
        world.insert_collider(ColliderBuilder::ball(0.1), Some(body));
    }
    let mut times = Vec::new();
    for _ in 0..6 {
        let start = Instant::now();
        ccd.step(&mut world);
        times.push(start.elapsed().as_secs_f64());
    }
    times.remove(0);
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// `n` boxes asleep on a floor, no fast body: one step's time with rapier
/// alone (CCD off) and with the affine stage (median of 21 steps after the
/// first, once the boxes have settled), and how many boxes were awake at
/// the end (0: all asleep, as meant). Rapier's step skips
/// sleeping bodies; the stage still visits each once per step.
fn sleeping_bodies(n: usize) -> (f64, f64, usize) {
    let mut times = [0.0; 2];
    let mut awake = 0;
    for (k, affine) in [false, true].into_iter().enumerate() {
        let mut world = PhysicsWorld::default();
        let mut ccd = AffineCcd::default();
        if affine {
            ccd.install(&mut world);
        } else {
            world.integration_parameters.max_ccd_substeps = 0;
        }
        let floor = world.insert_body(RigidBodyBuilder::fixed());
        world.insert_collider(ColliderBuilder::cuboid(1000.0, 0.1, 1000.0), Some(floor));
        let side = (n as f64).sqrt().ceil() as usize;
        for i in 0..n {
            let (x, z) = ((i % side) as f32 * 2.0, (i / side) as f32 * 2.0);
            let body =
                world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.6, z)));
            world.insert_collider(ColliderBuilder::cuboid(0.5, 0.5, 0.5), Some(body));
        }
        let mut step = |world: &mut PhysicsWorld| {
            if affine {
                ccd.step(world);
            } else {
                world.step();
            }
        };
        // Settle: the boxes land and fall asleep (rapier's default sleep
        // timer is 2 s).
        for _ in 0..400 {
            step(&mut world);
        }
        let mut step_times = Vec::new();
        for _ in 0..22 {
            let start = Instant::now();
            step(&mut world);
            step_times.push(start.elapsed().as_secs_f64());
        }
        step_times.remove(0);
        step_times.sort_by(f64::total_cmp);
        times[k] = step_times[step_times.len() / 2];
        awake = awake.max(
            world
                .bodies
                .iter()
                .filter(|(_, b)| b.is_dynamic() && !b.is_sleeping())
                .count(),
        );
    }
    (times[0], times[1], awake)
}

/// A flat floor of about `n` triangles of constant size (1 m cells),
/// centred on the origin: the box always meets the same few triangles, so
/// the growth measures the cost of the rest of the mesh.
fn floor(n: usize) -> TriMesh {
    let cells = ((n as f64 / 2.0).sqrt().ceil() as usize).max(1);
    let step = 1.0;
    let half = cells as f32 * step / 2.0;
    let mut vertices = Vec::new();
    for i in 0..=cells {
        for j in 0..=cells {
            vertices.push(Vector::new(
                i as f32 * step - half,
                0.0,
                j as f32 * step - half,
            ));
        }
    }
    let mut indices = Vec::new();
    let row = cells as u32 + 1;
    for i in 0..cells as u32 {
        for j in 0..cells as u32 {
            let a = i * row + j;
            indices.push([a, a + 1, a + row]);
            indices.push([a + 1, a + row + 1, a + row]);
        }
    }
    TriMesh::new(vertices, indices).expect("a grid mesh")
}

/// Median time of one query: a box falling fast and spinning onto the floor.
fn query_against(mesh: &TriMesh) -> f64 {
    let body = Cuboid::new(Vector::new(0.5, 0.1, 0.3));
    let start = Isometry3::translation(0.1, 1.0, 0.1);
    let motion = Motion::from_velocities(
        start,
        Point3::new(0.1, 1.0, 0.1),
        Vector3::new(3.0, -90.0, 1.0),
        Vector3::new(5.0, 2.0, 20.0),
        1.0 / 60.0,
    )
    .expect("finite");
    let fixed = Motion::fixed(Isometry3::identity()).expect("finite");
    let options = QueryOptions::default();
    let mut times = Vec::new();
    for _ in 0..21 {
        let start = Instant::now();
        let hit = time_of_impact(&body, &motion, mesh, &fixed, &options);
        times.push(start.elapsed().as_secs_f64());
        assert!(
            matches!(hit, Ok(Some(_))),
            "the box must hit the floor: {hit:?}"
        );
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    println!("reproduce: cargo bench --bench scaling");
    let mut series = Vec::new();
    println!("{:>8} {:>14}", "bodies", "step ms");
    for n in [1, 10, 30, 100, 300, 1000] {
        let t = fast_bodies(n);
        println!("{n:>8} {:>14.4}", t * 1e3);
        series.push((n as f64, t));
    }
    println!(
        "growth exponent in fast bodies: {:.2} (1 = linear)",
        growth(&series[1..])
    );

    println!(
        "{:>8} {:>14} {:>14} {:>8} {:>6}",
        "asleep", "off step µs", "affine step µs", "ratio", "awake"
    );
    for n in [10, 100, 1000, 4000] {
        let (off, affine, awake) = sleeping_bodies(n);
        println!(
            "{n:>8} {:>14.2} {:>14.2} {:>8.2} {awake:>6}",
            off * 1e6,
            affine * 1e6,
            affine / off
        );
    }

    let mut series = Vec::new();
    println!("{:>8} {:>14}", "triangles", "query µs");
    for n in [8, 128, 2048, 32_768, 131_072] {
        let mesh = floor(n);
        let t = query_against(&mesh);
        println!("{:>8} {:>14.2}", mesh.indices().len(), t * 1e6);
        series.push((mesh.indices().len() as f64, t));
    }
    println!(
        "growth exponent in target triangles: {:.2} (0 = flat, logarithmic shows as near 0)",
        growth(&series)
    );
}
