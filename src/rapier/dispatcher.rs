//! `AffineDispatcher`: parry's query switchboard with the shape casts
//! answered by affine-ccd.
//!
//! Rapier 0.36's own CCD calls the dispatcher only for its fallback pairs
//! (cylinders, cones, custom shapes), so this does not take over CCD by
//! itself (that is the stage's job); it serves those pairs and the scene
//! queries (`cast_shape`, `cast_shape_nonlinear`) soundly. Everything else
//! answers `Unsupported`: chain it with parry's `DefaultQueryDispatcher`.

use crate::convert::{glam_from_vec, iso_from_pose, vec_from_glam};
use crate::enclosure::TimeSpan;
use crate::motion::{Motion, Trajectory};
use crate::query::{QueryOptions, Toi, time_of_impact};
use crate::solve::RootStatus;
use nalgebra::{Isometry3, Point3, Vector3};
use rapier3d::math::{Pose, Real, Vector};
use rapier3d::parry::query::details::{NormalConstraints, ShapeCastOptions};
use rapier3d::parry::query::{
    ClosestPoints, Contact, ContactManifold, ContactManifoldsWorkspace, DefaultQueryDispatcher,
    NonlinearRigidMotion, PersistentQueryDispatcher, QueryDispatcher, QueryDispatcherChain,
    ShapeCastHit, ShapeCastStatus, ShapeDistance, ShapeIntersection, Unsupported,
};
use rapier3d::parry::shape::Shape;

/// Answers `cast_shapes` and `cast_shapes_nonlinear` with affine-ccd.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AffineDispatcher {
    /// `skin` and `time_range` are set per query from the cast's
    /// arguments; the rest is used as given.
    pub options: QueryOptions,
}

impl AffineDispatcher {
    pub fn new(options: QueryOptions) -> AffineDispatcher {
        AffineDispatcher { options }
    }

    /// This dispatcher, falling back to parry's for everything it does
    /// not answer: what `NarrowPhase::set_query_dispatcher` wants.
    pub fn chained(self) -> QueryDispatcherChain<AffineDispatcher, DefaultQueryDispatcher> {
        self.chain(DefaultQueryDispatcher)
    }

    /// One cast over `[0, dt]` seconds; witnesses and normals come back
    /// in the shapes' local frames, as parry's `ShapeCastHit` wants.
    fn cast(
        &self,
        g1: &dyn Shape,
        m1: &Motion,
        g2: &dyn Shape,
        m2: &Motion,
        skin: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        let opts = QueryOptions {
            skin: skin as f64,
            time_range: TimeSpan::STEP,
            ..self.options
        };
        let toi = time_of_impact(g1, m1, g2, m2, &opts).map_err(|_| Unsupported)?;
        let Some(toi) = toi else {
            return Ok(None);
        };
        if toi.status == RootStatus::InitiallyTouching && !stop_at_penetration {
            // Parry then looks for the time the shapes start to approach;
            // let it keep that meaning.
            return Err(Unsupported);
        }
        Ok(Some(hit_in_local_frames(&toi, m1, m2)))
    }
}

fn hit_in_local_frames(toi: &Toi, m1: &Motion, m2: &Motion) -> ShapeCastHit {
    let (p1, p2) = (m1.pose_at(toi.fraction), m2.pose_at(toi.fraction));
    let local =
        |p: &Isometry3<f64>, w: &Point3<f64>| glam_from_vec(&p.inverse_transform_point(w).coords);
    let n1 = p1.inverse_transform_vector(&toi.normal1);
    let n2 = p2.inverse_transform_vector(&-toi.normal1);
    ShapeCastHit {
        time_of_impact: toi.time as Real,
        witness1: local(&p1, &toi.witness1),
        witness2: local(&p2, &toi.witness2),
        normal1: glam_from_vec(&n1),
        normal2: glam_from_vec(&n2),
        status: match toi.status {
            RootStatus::Hit => ShapeCastStatus::Converged,
            RootStatus::InitiallyTouching => ShapeCastStatus::PenetratingOrWithinTargetDist,
            RootStatus::BudgetExhausted | RootStatus::Separated => ShapeCastStatus::OutOfIterations,
        },
        subshape1: 0,
        subshape2: 0,
    }
}

/// Parry's nonlinear motion from `t0` on, for `dt` seconds.
fn motion_from_parry(m: &NonlinearRigidMotion, t0: Real, dt: f64) -> Result<Motion, Unsupported> {
    let start = m.position_at_time(t0);
    let center = start.transform_point(m.local_center);
    Motion::from_velocities(
        iso_from_pose(&start),
        Point3::from(vec_from_glam(center)),
        vec_from_glam(m.linvel),
        vec_from_glam(m.angvel),
        dt,
    )
    .map_err(|_| Unsupported)
}

impl QueryDispatcher for AffineDispatcher {
    fn intersection_test(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
    ) -> Result<ShapeIntersection, Unsupported> {
        Err(Unsupported)
    }

    fn distance(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
    ) -> Result<ShapeDistance, Unsupported> {
        Err(Unsupported)
    }

    fn contact(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Real,
    ) -> Result<Option<Contact>, Unsupported> {
        Err(Unsupported)
    }

    fn closest_points(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Real,
    ) -> Result<ClosestPoints, Unsupported> {
        Err(Unsupported)
    }

    /// Shape 1 fixed at the origin, shape 2 at `pos12` translating at
    /// `local_vel12` (m/s, shape 1's frame) for `max_time_of_impact` s.
    fn cast_shapes(
        &self,
        pos12: &Pose,
        local_vel12: Vector,
        g1: &dyn Shape,
        g2: &dyn Shape,
        options: ShapeCastOptions,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        let dt = options.max_time_of_impact as f64;
        // An unbounded cast has no step to search: parry's answer stands.
        if !(dt > 0.0 && dt.is_finite() && dt < 1.0e6) {
            return Err(Unsupported);
        }
        let m1 = Motion::fixed(Isometry3::identity()).map_err(|_| Unsupported)?;
        let start2 = iso_from_pose(pos12);
        let m2 = Motion::from_velocities(
            start2,
            Point3::from(start2.translation.vector),
            vec_from_glam(local_vel12),
            Vector3::zeros(),
            dt,
        )
        .map_err(|_| Unsupported)?;
        let hit = self.cast(
            g1,
            &m1,
            g2,
            &m2,
            options.target_distance,
            options.stop_at_penetration,
        )?;
        // The fixed motion has no step length: time is fraction × dt.
        Ok(hit.map(|mut h| {
            h.time_of_impact = (h.time_of_impact as f64).min(dt) as Real;
            h
        }))
    }

    fn cast_shapes_nonlinear(
        &self,
        motion1: &NonlinearRigidMotion,
        g1: &dyn Shape,
        motion2: &NonlinearRigidMotion,
        g2: &dyn Shape,
        start_time: Real,
        end_time: Real,
        stop_at_penetration: bool,
    ) -> Result<Option<ShapeCastHit>, Unsupported> {
        let dt = end_time as f64 - start_time as f64;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(Unsupported);
        }
        let m1 = motion_from_parry(motion1, start_time, dt)?;
        let m2 = motion_from_parry(motion2, start_time, dt)?;
        let hit = self.cast(g1, &m1, g2, &m2, 0.0, stop_at_penetration)?;
        Ok(hit.map(|mut h| {
            h.time_of_impact += start_time;
            h
        }))
    }
}

impl<M, C> PersistentQueryDispatcher<M, C> for AffineDispatcher {
    fn contact_manifolds(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Real,
        _: &mut Vec<ContactManifold<M, C>>,
        _: &mut Option<ContactManifoldsWorkspace>,
    ) -> Result<(), Unsupported> {
        Err(Unsupported)
    }

    fn contact_manifold_convex_convex(
        &self,
        _: &Pose,
        _: &dyn Shape,
        _: &dyn Shape,
        _: Option<&dyn NormalConstraints>,
        _: Option<&dyn NormalConstraints>,
        _: Real,
        _: &mut ContactManifold<M, C>,
    ) -> Result<(), Unsupported> {
        Err(Unsupported)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::parry::shape::{Ball, Cuboid};

    #[test]
    fn a_ball_cast_at_a_box_hits_where_parry_does() {
        let d = AffineDispatcher::default();
        let (ball, cube) = (Ball::new(0.5), Cuboid::new(Vector::splat(0.5)));
        let pos12 = Pose::translation(5.0, 0.0, 0.0);
        let hit = d
            .cast_shapes(
                &pos12,
                Vector::new(-10.0, 0.0, 0.0),
                &ball,
                &cube,
                ShapeCastOptions::with_max_time_of_impact(1.0),
            )
            .unwrap()
            .unwrap();
        assert!(
            (hit.time_of_impact - 0.4).abs() < 1.0e-3,
            "toi {} s, expected 0.4 s",
            hit.time_of_impact
        );
    }
}
