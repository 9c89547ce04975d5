//! The stage's calls to the time-of-impact query, counted: each adds what
//! it spent, hit or miss, to the step's report (`CcdReport::evaluations`,
//! and by family), so the profile shows the work of the searches that
//! found nothing too.

use super::report::CcdReport;
use crate::error::CcdError;
use crate::motion::Motion;
use crate::query::{Found, ManyToi, QueryOptions, ShapeMotion, Toi, lone_pair, with_query};
use rapier3d::parry::shape::Shape;

/// [`crate::query::time_of_impact`], counted. Every search runs on the
/// thread's query context, whose buffers are kept between calls (a fresh
/// context grows them anew on every search).
pub(crate) fn one(
    s1: &dyn Shape,
    m1: &Motion,
    s2: &dyn Shape,
    m2: &Motion,
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<Toi>, CcdError> {
    let (moving, target) = lone_pair(s1, m1, s2, m2);
    Ok(many(&moving, &target, opts, report)?.map(|hit| hit.toi))
}

/// [`crate::query::time_of_impact_many`], counted: [`found`] and the
/// hit's witness.
pub(crate) fn many(
    moving: &[ShapeMotion],
    targets: &[ShapeMotion],
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<ManyToi>, CcdError> {
    Ok(found(moving, targets, opts, report)?.map(|hit| hit.described(moving, targets)))
}

/// [`crate::query::Query::found`], counted: the hit without its witness.
pub(crate) fn found(
    moving: &[ShapeMotion],
    targets: &[ShapeMotion],
    opts: &QueryOptions,
    report: &mut CcdReport,
) -> Result<Option<Found>, CcdError> {
    with_query(|query| {
        let found = query.found(moving, targets, opts);
        report.count(query);
        found
    })
}
