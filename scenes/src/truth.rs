//! Ground truth by dense sampling: the reference the tests, the benches and
//! the accuracy report compare every method against.
//!
//! The exact motion ([`Trajectory::pose_at`]) is sampled at many instants,
//! parry's own `distance` query is asked at each (in parry's `f32`), and
//! the first sample within the skin is refined by bisection. Sampling can
//! miss a contact shorter than one sample interval; tests that need the
//! truth to be exact choose set-ups whose contacts last longer.

use affine_ccd::convert::pose_from_iso;
use affine_ccd::error::CcdError;
use affine_ccd::motion::Trajectory;
use rapier3d::parry::query;
use rapier3d::parry::shape::Shape;

/// What dense sampling says of one pair over the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// The first fraction of the step at which the shapes come within the
    /// skin, refined by bisection; `None` when no sample does.
    pub first_contact: Option<f64>,
    /// The smallest sampled distance between the shapes (metres).
    pub min_distance: f64,
}

/// Bisection steps refining a contact found between two samples: 2⁻⁴⁰ of a
/// sample interval is far below the f32 noise of parry's distance.
const REFINE_STEPS: usize = 40;

/// Sample the pair's distance at `samples + 1` evenly spaced instants of the
/// step and refine the first one within `skin` metres.
pub fn sample<M1: Trajectory, M2: Trajectory>(
    shape1: &dyn Shape,
    motion1: &M1,
    shape2: &dyn Shape,
    motion2: &M2,
    skin: f64,
    samples: usize,
) -> Result<Truth, CcdError> {
    let distance = |t: f64| -> Result<f64, CcdError> {
        let (p1, p2) = (
            pose_from_iso(&motion1.pose_at(t)),
            pose_from_iso(&motion2.pose_at(t)),
        );
        query::distance(&p1, shape1, &p2, shape2)
            .map(|d| f64::from(d.distance))
            .map_err(|_| CcdError::Unsupported {
                what: format!(
                    "parry distance for {:?} against {:?}",
                    shape1.shape_type(),
                    shape2.shape_type()
                ),
            })
    };
    let samples = samples.max(1);
    let mut min_distance = f64::INFINITY;
    let mut first_contact = None;
    let mut previous = 0.0;
    for i in 0..=samples {
        let t = i as f64 / samples as f64;
        let d = distance(t)?;
        min_distance = min_distance.min(d);
        if first_contact.is_none() && d <= skin {
            let (mut lo, mut hi) = (previous, t);
            if i > 0 {
                for _ in 0..REFINE_STEPS {
                    let mid = 0.5 * (lo + hi);
                    if distance(mid)? <= skin {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
            }
            first_contact = Some(if i == 0 { 0.0 } else { hi });
        }
        previous = t;
    }
    Ok(Truth {
        first_contact,
        min_distance,
    })
}
