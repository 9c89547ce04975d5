//! Soak test of the rapier stage: fast spinning bodies of every shape kind,
//! with restitution, in a closed box of thin walls. After every step no
//! body may have left the box and no pose may be non-finite, and no body
//! is held at its start for more than a few steps in a row.
//!
//! A short run (with and without substeps) and a long one (300 bodies,
//! 10,000 steps): `cargo test --release --test soak -- --nocapture` prints
//! their clamps and longest holds.

use affine_ccd::rapier::{AffineCcd, CcdConfig};
use rapier3d::prelude::*;
use std::collections::{HashMap, HashSet};

/// Half the inner size of the box, metres.
const HALF: f32 = 5.0;
/// Half the thickness of its walls, metres.
const WALL: f32 = 0.05;

/// SplitMix64, seeded.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn vector(&mut self, r: f32) -> Vector {
        Vector::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
}

/// A small shape of kind `k` (every kind the stage sweeps).
fn shape(k: usize, rng: &mut Rng) -> SharedShape {
    let s = rng.range(0.08, 0.25);
    match k % 9 {
        0 => SharedShape::ball(s),
        1 => SharedShape::cuboid(s, 0.3 * s, 0.6 * s),
        2 => SharedShape::capsule_y(s, 0.4 * s),
        3 => SharedShape::cylinder(s, 0.5 * s),
        4 => SharedShape::cone(s, 0.6 * s),
        5 => SharedShape::round_cuboid(s, 0.2 * s, 0.5 * s, 0.02),
        6 => {
            let points: Vec<Vector> = (0..10).map(|_| rng.vector(s)).collect();
            SharedShape::convex_hull(&points).unwrap_or_else(|| SharedShape::ball(s))
        }
        7 => SharedShape::compound(vec![
            (
                Pose::from_translation(Vector::new(-s, 0.0, 0.0)),
                SharedShape::ball(0.5 * s),
            ),
            (
                Pose::from_translation(Vector::new(s, 0.0, 0.0)),
                SharedShape::cuboid(0.4 * s, 0.4 * s, 0.4 * s),
            ),
        ]),
        _ => {
            // A thin triangle-mesh plate.
            let v = vec![
                Vector::new(-s, 0.0, -s),
                Vector::new(s, 0.0, -s),
                Vector::new(s, 0.0, s),
                Vector::new(-s, 0.0, s),
            ];
            SharedShape::trimesh(v, vec![[0, 1, 2], [0, 2, 3]]).expect("a valid plate")
        }
    }
}

fn closed_box(world: &mut PhysicsWorld) {
    let walls = world.insert_body(RigidBodyBuilder::fixed());
    let o = HALF + WALL;
    let big = HALF + 2.0 * WALL;
    for (center, half) in [
        (Vector::new(o, 0.0, 0.0), Vector::new(WALL, big, big)),
        (Vector::new(-o, 0.0, 0.0), Vector::new(WALL, big, big)),
        (Vector::new(0.0, o, 0.0), Vector::new(big, WALL, big)),
        (Vector::new(0.0, -o, 0.0), Vector::new(big, WALL, big)),
        (Vector::new(0.0, 0.0, o), Vector::new(big, big, WALL)),
        (Vector::new(0.0, 0.0, -o), Vector::new(big, big, WALL)),
    ] {
        world.insert_collider(
            ColliderBuilder::cuboid(half.x, half.y, half.z)
                .translation(center)
                .restitution(0.9),
            Some(walls),
        );
    }
}

/// Runs `bodies` bodies for `steps` steps under the stage with `config`;
/// panics on the first body outside the box or non-finite pose, naming the
/// step and the body.
fn soak(bodies: usize, steps: usize, seed: u64, config: CcdConfig) {
    let mut rng = Rng(seed);
    let mut world = PhysicsWorld::default();
    let mut ccd = AffineCcd::new(config);
    ccd.install(&mut world);
    closed_box(&mut world);
    let mut handles = Vec::new();
    for i in 0..bodies {
        let body = RigidBodyBuilder::dynamic()
            .translation(rng.vector(HALF - 0.6))
            .linvel(rng.vector(40.0))
            .angvel(rng.vector(50.0))
            .ccd_enabled(true);
        let body = if i % 3 == 0 {
            body.allow_fast_rotation(true)
        } else {
            body
        };
        let handle = world.insert_body(body);
        world.insert_collider(
            ColliderBuilder::new(shape(i, &mut rng)).restitution(0.8),
            Some(handle),
        );
        handles.push(handle);
    }
    let (mut clamps, mut skipped) = (0, 0);
    // Steps in a row each body has been held at its start (a clamp within
    // 1e-3 of the step) while its velocity says it moves (faster than
    // 1 m/s or 1 rad/s, as the demo's "frozen" counts), and the longest
    // such run seen.
    let moves = |b: &RigidBody| b.linvel().length() > 1.0 || b.angvel().length() > 1.0;
    let mut held_for: HashMap<RigidBodyHandle, usize> = HashMap::new();
    let mut longest_hold = (0, None);
    for step in 0..steps {
        if step % 1000 == 0 && step > 0 {
            // Progress for the long run (shown with --nocapture).
            println!("step {step}: {clamps} clamps, {skipped} skipped body-steps so far");
        }
        let report = ccd.step(&mut world);
        clamps += report.clamps();
        skipped += report.skipped.len();
        let held: HashSet<RigidBodyHandle> = report
            .hits
            .iter()
            .filter(|h| h.fraction <= 1.0e-3 && moves(&world.bodies[h.body]))
            .map(|h| h.body)
            .collect();
        held_for.retain(|b, _| held.contains(b));
        for b in held {
            let run = held_for.entry(b).or_insert(0);
            *run += 1;
            if *run > longest_hold.0 {
                longest_hold = (*run, Some((b, step)));
            }
        }
        for (i, h) in handles.iter().enumerate() {
            let body = &world.bodies[*h];
            // The centre of mass, not the body's origin: a convex hull of
            // random points need not hold its origin (body 33 of the long
            // run rests against a wall with its origin 5 cm beyond the
            // wall's inner face and its centre of mass 8 cm inside).
            let p = body.center_of_mass();
            assert!(
                p.is_finite(),
                "step {step}: body {i} has a non-finite pose {p:?}"
            );
            // The centre of mass may touch the wall's inner face, not pass it.
            let limit = HALF + WALL;
            assert!(
                p.x.abs() < limit && p.y.abs() < limit && p.z.abs() < limit,
                "step {step}: body {i} ({:?}) left the box: {p:?}",
                world.colliders[body.colliders()[0]].shape().shape_type()
            );
        }
    }
    println!(
        "{bodies} bodies, {steps} steps: {clamps} clamps, {skipped} skipped body-steps; \
         longest hold at the start {} steps ({:?})",
        longest_hold.0, longest_hold.1
    );
    // A body held at its start step after step is frozen: the stage leaves
    // a pair it held to the contacts in the next step.
    assert!(
        longest_hold.0 <= MOST_HELD,
        "a body was held at its start {} steps in a row ({:?})",
        longest_hold.0,
        longest_hold.1
    );
}

/// The most steps in a row a moving body may be held at its start (a clamp
/// within 1e-3 of the step): once against one target, then against others.
const MOST_HELD: usize = 3;

#[test]
fn a_short_soak_keeps_every_body_in_the_box() {
    soak(60, 300, 1, CcdConfig::default());
}

#[test]
fn a_short_soak_with_substeps_keeps_every_body_in_the_box() {
    let config = CcdConfig {
        substeps: 4,
        ..CcdConfig::default()
    };
    soak(60, 300, 1, config);
}

/// 300 bodies for 10,000 steps (about 2 s in release: most fall asleep).
#[test]
fn a_long_soak_keeps_every_body_in_the_box() {
    // SOAK_BODIES / SOAK_STEPS / SOAK_SEED override the run (for bisecting a
    // failure on a shorter run); SOAK_SUBSTEPS sets `CcdConfig::substeps`.
    let env = |name: &str, default: u64| {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    soak(
        env("SOAK_BODIES", 300) as usize,
        env("SOAK_STEPS", 10_000) as usize,
        env("SOAK_SEED", 2),
        CcdConfig {
            substeps: env("SOAK_SUBSTEPS", 1) as u32,
            ..CcdConfig::default()
        },
    );
}
