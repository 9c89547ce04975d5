//! Where a clamp puts a body: a hit is decided by the *true* contact (the
//! query at zero skin), so a shape whose motion never touches anything is
//! never clamped; the clamp then stands a little before the contact, far
//! enough for `f32` poses and close enough that the next step's contact
//! normal is the true one (a skin earlier, on a grazing path, it is steeply
//! inclined and the next step's contact takes the approach speed away).

use crate::motion::Motion;
use crate::query::Toi;
use crate::solve::RootStatus;
use rapier3d::parry::shape::Shape;

/// Share of the skin a clamp backs off from the true contact: the clamped
/// pair ends between 0 and about `BACKOFF·skin` (plus the query's ε of
/// travel) apart, well inside the band that counts as touching at the next
/// step's start, so the next step hands the pair to rapier's contacts
/// rather than clamping it again at once.
pub(crate) const BACKOFF: f64 = 0.1;

/// Bound on how far the pair's points move relative to each other over the
/// whole step, metres.
pub(crate) fn pair_travel(s1: &dyn Shape, m1: &Motion, s2: &dyn Shape, m2: &Motion) -> f64 {
    let radius = |s: &dyn Shape| {
        let b = s.compute_local_bounding_sphere();
        b.center.length() as f64 + b.radius as f64
    };
    m1.travel_bound(radius(s1)) + m2.travel_bound(radius(s2))
}

/// A hit at the true contact moved back along the motion by `back` metres
/// of relative travel (`travel` over the whole step), never before `from`.
/// The shapes are apart at every time before a true-contact hit, so the
/// pose there is sound; it is at most `back` (plus the query's ε) from the
/// contact.
pub(crate) fn back_off(mut toi: Toi, travel: f64, back: f64, from: f64) -> Toi {
    if toi.status == RootStatus::InitiallyTouching || travel <= 0.0 || !travel.is_finite() {
        return toi;
    }
    let tau = (toi.fraction - back / travel).max(from).min(toi.fraction);
    if toi.fraction > 0.0 {
        toi.time *= tau / toi.fraction;
    }
    toi.fraction = tau;
    toi
}
