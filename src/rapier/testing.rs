//! What the stage's tests share.

use crate::motion::Motion;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rapier3d::parry::shape::{Cuboid, TriMesh};
use rapier3d::prelude::Vector;

/// A small deterministic generator of test numbers (xorshift).
pub(crate) struct Numbers(pub u64);

impl Numbers {
    pub fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn vector(&mut self, size: f64) -> Vector3<f64> {
        Vector3::new(
            self.next(-size, size),
            self.next(-size, size),
            self.next(-size, size),
        )
    }
}

/// A body at `at`, turned by `turn`, with its centre of mass at its
/// origin, moving at `v` (m/s) and turning at `w` (rad/s) for `dt`
/// seconds.
pub(crate) fn flying(
    at: Vector3<f64>,
    turn: UnitQuaternion<f64>,
    v: Vector3<f64>,
    w: Vector3<f64>,
    dt: f64,
) -> Motion {
    Motion::from_velocities(
        Isometry3::from_parts(Translation3::from(at), turn),
        Point3::from(at),
        v,
        w,
        dt,
    )
    .expect("finite test motion")
}

/// A small mesh propeller (two crossed 1.7 m blades) and the fixed wall
/// box the mesh tests hold it against.
pub(crate) fn propeller_and_wall() -> (TriMesh, Cuboid) {
    (
        crate::query::cross_mesh(0.85, 0.05, 0.02),
        Cuboid::new(Vector::new(0.1, 1.5, 1.5)),
    )
}
