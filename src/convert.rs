//! Conversions between rapier/parry's glam `f32` types, parry3d-f64's
//! glam `f64` types and the `f64` nalgebra types of the core. `f32 → f64`
//! is exact; `f64 → f32` rounds.

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rapier3d::parry::math::{Pose, Vector};

/// A glam vector as an `f64` vector (exact).
pub fn vec_from_glam(v: Vector) -> Vector3<f64> {
    Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// A glam vector as an `f64` point (exact).
pub fn point_from_glam(v: Vector) -> Point3<f64> {
    Point3::from(vec_from_glam(v))
}

/// A parry pose as an `f64` isometry. The quaternion is taken as it is
/// (the core normalises it in `f64`).
pub fn iso_from_pose(pose: &Pose) -> Isometry3<f64> {
    let q = pose.rotation;
    let rotation = UnitQuaternion::new_unchecked(Quaternion::new(
        f64::from(q.w),
        f64::from(q.x),
        f64::from(q.y),
        f64::from(q.z),
    ));
    Isometry3::from_parts(
        Translation3::from(vec_from_glam(pose.translation)),
        rotation,
    )
}

/// An `f64` vector as a glam vector (rounded to `f32`).
pub fn glam_from_vec(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

/// An `f64` isometry as a parry pose (rounded to `f32`).
pub fn pose_from_iso(iso: &Isometry3<f64>) -> Pose {
    let q = iso.rotation.quaternion();
    let rotation =
        rapier3d::parry::math::Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32)
            .normalize();
    Pose::from_parts(glam_from_vec(&iso.translation.vector), rotation)
}

/// An `f64` isometry as a parry3d-f64 pose (exact).
pub fn pose64_from_iso(iso: &Isometry3<f64>) -> parry3d_f64::math::Pose {
    let (q, t) = (iso.rotation.quaternion(), iso.translation.vector);
    parry3d_f64::math::Pose::from_parts(
        parry3d_f64::math::Vector::new(t.x, t.y, t.z),
        parry3d_f64::math::Rotation::from_xyzw(q.i, q.j, q.k, q.w),
    )
}
