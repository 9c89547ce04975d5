//! Shared helpers for the integration tests: a seeded random generator,
//! small statistics (a dozen lines; not worth a dependency) and a world
//! stepped by the stage or by rapier alone.
#![allow(dead_code)]

/// SplitMix64: tiny, seeded, good enough to spread test cases.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }

    /// A vector with each coordinate uniform in `[-r, r)`.
    pub fn vector(&mut self, r: f64) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }

    /// A uniformly random unit quaternion.
    pub fn rotation(&mut self) -> nalgebra::UnitQuaternion<f64> {
        loop {
            let q = nalgebra::Quaternion::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let n = q.norm();
            if n > 0.1 && n <= 1.0 {
                return nalgebra::UnitQuaternion::new_normalize(q);
            }
        }
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// The `q`-quantile (0..=1) of the values (sorted copy).
pub fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let i = ((v.len() - 1) as f64 * q).round() as usize;
    v[i]
}

/// A world stepped by the affine-ccd stage (`stage` is `Some`) or by rapier
/// alone, its own CCD as the world's parameters say.
pub struct Run {
    pub world: rapier3d::prelude::PhysicsWorld,
    pub stage: Option<affine_ccd::rapier::AffineCcd>,
}

impl Run {
    /// The stage with `config`, installed into `world`.
    pub fn affine(
        mut world: rapier3d::prelude::PhysicsWorld,
        config: affine_ccd::rapier::CcdConfig,
    ) -> Run {
        let stage = affine_ccd::rapier::AffineCcd::new(config);
        stage.install(&mut world);
        Run {
            world,
            stage: Some(stage),
        }
    }

    pub fn rapier(world: rapier3d::prelude::PhysicsWorld) -> Run {
        Run { world, stage: None }
    }

    pub fn step(&mut self) {
        match &mut self.stage {
            Some(stage) => {
                stage.step(&mut self.world);
            }
            None => self.world.step(),
        }
    }

    /// Whether the stage's last report skips `body` for a non-finite state
    /// (`false` for rapier alone).
    pub fn reported_non_finite(&self, body: rapier3d::prelude::RigidBodyHandle) -> bool {
        self.stage.as_ref().is_some_and(|stage| {
            stage
                .report()
                .skipped
                .iter()
                .any(|s| s.body == body && s.reason == affine_ccd::rapier::SkipReason::NonFinite)
        })
    }
}

/// Asserts that bodies `a` of `ours` and `b` of `theirs` (in pairs) have
/// bit-identical poses after step `step`.
pub fn assert_same_poses(
    step: usize,
    ours: &Run,
    a: &[rapier3d::prelude::RigidBodyHandle],
    theirs: &Run,
    b: &[rapier3d::prelude::RigidBodyHandle],
) {
    for (ha, hb) in a.iter().zip(b) {
        let (pa, pb) = (
            ours.world.bodies[*ha].position(),
            theirs.world.bodies[*hb].position(),
        );
        assert!(
            pa.translation.to_array().map(f32::to_bits)
                == pb.translation.to_array().map(f32::to_bits)
                && pa.rotation.to_array().map(f32::to_bits)
                    == pb.rotation.to_array().map(f32::to_bits),
            "step {step}: poses differ: {pa:?} with the stage, {pb:?} without"
        );
    }
}

/// An `f64` isometry as a parry3d-f64 pose (exact), for truths computed in
/// `f64`.
pub fn pose64(iso: &nalgebra::Isometry3<f64>) -> parry3d_f64::math::Pose {
    let (q, t) = (iso.rotation.quaternion(), iso.translation.vector);
    parry3d_f64::math::Pose::from_parts(
        parry3d_f64::math::Vector::new(t.x, t.y, t.z),
        parry3d_f64::math::Rotation::from_xyzw(q.i, q.j, q.k, q.w),
    )
}
