//! Rounding helpers shared by the arithmetics (see the module docs of
//! [`crate::enclosure`] for why these and not a rounding-mode switch).

/// `x` moved one ulp towards +∞: an upper bound of any real that rounds to
/// `x` under round-to-nearest.
#[inline]
pub(crate) fn up(x: f64) -> f64 {
    x.next_up()
}

/// `x` moved one ulp towards −∞.
#[inline]
pub(crate) fn down(x: f64) -> f64 {
    x.next_down()
}

/// A bound on `|fl(z) − z|` given the computed `fl(z)` of one correctly
/// rounded operation: `u·|z| ≤ 2u·|fl(z)|` with `u = 2⁻⁵³`, plus the
/// smallest subnormal for results that underflow.
#[inline]
pub(crate) fn err(computed: f64) -> f64 {
    computed.abs() * f64::EPSILON + f64::from_bits(1)
}

/// `a + b` rounded up, for sums of non-negative error bounds.
#[inline]
pub(crate) fn add_up(a: f64, b: f64) -> f64 {
    up(a + b)
}

/// `a · b` rounded up, for products of non-negative error bounds.
#[inline]
pub(crate) fn mul_up(a: f64, b: f64) -> f64 {
    up(a * b)
}

/// How far libm's `sin`/`cos` may be from the truth, as an absolute bound.
/// glibc documents at most one ulp for them; results lie in `[−1, 1]` where
/// one ulp is at most `2⁻⁵³`. We allow eight ulps of 1 (`2⁻⁴⁹`) so that a
/// libm with a few ulps of error is still covered.
pub(crate) const LIBM_SLACK: f64 = 1.7763568394002505e-15; // 2^-49

/// `1 + 2⁻⁴⁷`: see [`bound`].
const BOUND_FACTOR: f64 = 1.0 + 1.0 / (1u64 << 47) as f64;

/// An upper bound of the exact value of a non-negative expression (sums
/// and products of non-negative terms) that was evaluated in plain
/// round-to-nearest with at most 32 roundings. Each rounding loses at most
/// a factor `1 − 2⁻⁵³`, so the computed value is at least
/// `exact·(1 − 2⁻⁵³)³²` ≥ `exact·(1 − 2⁻⁴⁸)`; multiplying by `1 + 2⁻⁴⁷`
/// (itself rounded once more) restores an upper bound, and the smallest
/// normal number covers any underflow on the way. One multiply and one add
/// instead of a `next_up` per operation: the affine forms' hot path.
#[inline]
pub(crate) fn bound(x: f64) -> f64 {
    x * BOUND_FACTOR + f64::MIN_POSITIVE
}
