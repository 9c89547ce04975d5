//! Elementary functions and restriction for the polynomial arithmetics
//! ([`Affine`](super::Affine), [`Taylor`](super::Taylor)), written once over
//! the [`Enclosure`] operations.
//!
//! A function `f` of an enclosure `x` is expanded about a point `x0` of its
//! range: `f(x) = Σ_{k≤n} f⁽ᵏ⁾(x0)/k!·δᵏ + R` with `δ = x − x0` and the
//! Lagrange remainder `|R| ≤ sup|f⁽ⁿ⁺¹⁾|/(n+1)!·|δ|ⁿ⁺¹`, the sup taken over the
//! range of `x`. The coefficients are enclosed as intervals and `n` is the
//! arithmetic's degree: higher terms would be folded into the error term by
//! the multiplications anyway.

use super::rounding::add_up;
use super::{Enclosure, Interval, TimeSpan};
use crate::CcdError;

/// `Σ coefs[k]·δᵏ ± rem·|δ|ⁿ⁺¹` with `δ = x − x0`, by Horner's rule.
fn expand<E: Enclosure>(x: E, x0: f64, coefs: &[Interval], rem: Interval) -> E {
    let delta = x - x0;
    expand_about(delta, delta.range().mag(), coefs, rem)
}

/// [`expand`] with `δ = x − x0` and its largest magnitude `dmax` given.
fn expand_about<E: Enclosure>(delta: E, dmax: f64, coefs: &[Interval], rem: Interval) -> E {
    let n = coefs.len() - 1;
    let mut acc = E::from_interval(coefs[n]);
    for k in (0..n).rev() {
        acc = acc * delta + E::from_interval(coefs[k]);
    }
    let dmax = Interval::point(dmax);
    let mut tail = rem;
    for _ in 0..=n {
        tail *= dmax;
    }
    acc.widen(tail.hi)
}

/// Of two enclosures of the same value, the `series` unless its range is more
/// than twice as wide as the time-independent `fallback`'s.
///
/// This used to keep whichever range was narrower. For a monotone function
/// of a narrow argument the fallback (the interval of the exact range, up to
/// rounding) is never wider than the series, so the series was always dropped
/// and with it the value's dependence on the time symbol: in
/// `sin(3τ+1)·τ² − √(τ+2) + 1/(τ+1.5)` nothing cancelled any more and affine
/// and Taylor arithmetic fell to first order, like intervals (caught by the
/// convergence test in `tests/enclosure.rs`). The series' excess width
/// shrinks with the node, so any factor above 1 keeps it on small nodes; 2
/// still falls back where the series says little (a range near a pole).
pub(crate) fn prefer_series<E: Enclosure>(series: E, fallback: E) -> E {
    if series.range().width() <= 2.0 * fallback.range().width() {
        series
    } else {
        fallback
    }
}

/// `1/k!` enclosed (k! itself is exact in f64 for the small k used here).
fn inv_factorial(k: usize) -> Interval {
    let factorial = (1..=k).fold(1.0, |f, i| f * i as f64);
    inv(factorial)
}

/// `1/x` enclosed, for a non-zero constant `x`.
fn inv(x: f64) -> Interval {
    Interval::point(x).recip().unwrap_or(Interval::ENTIRE)
}

/// `(1/2 − (k − 1))/k`: the ratio of binom(1/2, k) to binom(1/2, k − 1).
fn half_binomial_ratio(k: usize) -> Interval {
    Interval::point(0.5 - (k - 1) as f64) * inv(k as f64)
}

/// `(sin x, cos x)` of any enclosure: the series about the range's
/// midpoint (sharing the midpoint, libm's values there and the powers of
/// `x − x0`), or `[−1, 1]` information alone when that is narrower.
pub(crate) fn sin_cos<E: Enclosure>(x: E) -> (E, E) {
    let range = x.range();
    if !range.is_bounded() || range.width() > 8.0 {
        // Beyond about a turn the series says less than |f| ≤ 1.
        let unit = E::from_interval(Interval::new(-1.0, 1.0));
        return (unit, unit);
    }
    let x0 = range.mid();
    let n = E::DEGREE.max(1);
    let (s, c) = x0.sin_cos();
    let (s, c) = (
        Interval::around(s, super::rounding::LIBM_SLACK),
        Interval::around(c, super::rounding::LIBM_SLACK),
    );
    // f(x0), f'(x0), f''(x0)/2!, …: derivatives cycle sin, cos, −sin, −cos.
    let mut sin_coefs = [Interval::point(0.0); 8];
    let mut cos_coefs = [Interval::point(0.0); 8];
    let sin_cycle = [s, c, -s, -c];
    let cos_cycle = [c, -s, -c, s];
    for k in 0..=n {
        sin_coefs[k] = sin_cycle[k % 4] * inv_factorial(k);
        cos_coefs[k] = cos_cycle[k % 4] * inv_factorial(k);
    }
    let delta = x - x0;
    let dmax = delta.range().mag();
    let sin = clamp_unit(expand_about(
        delta,
        dmax,
        &sin_coefs[..=n],
        inv_factorial(n + 1),
    ));
    let cos = clamp_unit(expand_about(
        delta,
        dmax,
        &cos_coefs[..=n],
        inv_factorial(n + 1),
    ));
    (sin, cos)
}

/// sin or cos (`cosine = true`) of any enclosure.
pub(crate) fn trig<E: Enclosure>(x: E, cosine: bool) -> E {
    let (s, c) = sin_cos(x);
    if cosine { c } else { s }
}

/// A sine or cosine enclosure, or `[−1, 1]`'s part of its range when the
/// series overshoots that much.
pub(crate) fn clamp_unit<E: Enclosure>(series: E) -> E {
    let range = series.range();
    if range.lo < -1.0 || range.hi > 1.0 {
        let bounded = Interval::new(range.lo.max(-1.0), range.hi.min(1.0));
        prefer_series(series, E::from_interval(bounded))
    } else {
        series
    }
}

/// `√x`; see [`Enclosure::sqrt`] for the domain rule.
pub(crate) fn sqrt<E: Enclosure>(x: E) -> Result<E, CcdError> {
    let range = x.range();
    let whole = range.sqrt()?;
    if range.lo <= 0.0 || !range.is_bounded() {
        // No series about a point near zero: the range's own root.
        return Ok(E::from_interval(whole));
    }
    let x0 = range.mid();
    let n = E::DEGREE.max(1);
    // coef_k = binom(1/2, k)·x0^(1/2 − k), built from coef_{k−1}.
    let inv_x0 = Interval::point(x0).recip()?;
    let mut coefs = [Interval::point(0.0); 8];
    coefs[0] = Interval::point(x0).sqrt()?;
    for k in 1..=n {
        coefs[k] = coefs[k - 1] * half_binomial_ratio(k) * inv_x0;
    }
    // |binom(1/2, n+1)|·a^(1/2 − n − 1) at the range's low end a.
    let mut rem = Interval::point(range.lo).sqrt()?;
    let mut binom = Interval::point(1.0);
    let inv_a = Interval::point(range.lo).recip()?;
    for k in 1..=n + 1 {
        binom *= half_binomial_ratio(k);
        rem *= inv_a;
    }
    let rem = (binom * rem).abs();
    let series = expand(x, x0, &coefs[..=n], rem);
    Ok(prefer_series(series, E::from_interval(whole)))
}

/// `1/x`; a range holding zero is a `Domain` error.
pub(crate) fn recip<E: Enclosure>(x: E) -> Result<E, CcdError> {
    let range = x.range();
    let whole = range.recip()?;
    if !range.is_bounded() {
        return Ok(E::from_interval(whole));
    }
    let x0 = range.mid();
    let n = E::DEGREE.max(1);
    // coef_k = (−1)^k / x0^(k+1).
    let inv_x0 = Interval::point(x0).recip()?;
    let mut coefs = [Interval::point(0.0); 8];
    coefs[0] = inv_x0;
    for k in 1..=n {
        coefs[k] = -(coefs[k - 1] * inv_x0);
    }
    // sup |x|^−(n+2) over the range: at the end nearest zero.
    let nearest = Interval::point(range.lo.abs().min(range.hi.abs())).recip()?;
    let mut rem = Interval::point(1.0);
    for _ in 0..n + 2 {
        rem *= nearest;
    }
    let series = expand(x, x0, &coefs[..=n], rem);
    Ok(prefer_series(series, E::from_interval(whole)))
}

/// The polynomial `Σ coefs[k]·eᵏ ± r` of node `from`, re-expressed in the
/// local symbol of its sub-node `to`, by Horner's rule in `E` itself:
/// `e = (τ − m)/h` with `τ` the time over `to`.
pub(crate) fn restrict_poly<E: Enclosure>(
    coefs: &[f64],
    r: f64,
    from: TimeSpan,
    to: TimeSpan,
) -> E {
    let (m, h) = from.center_radius();
    // `center_radius` rounds `h` up, so even a point node has `h > 0` (the
    // smallest subnormal) and `1/h` overflows to infinity: that used to give
    // the whole line for every restriction of a point node (caught by the
    // restrict property in `tests/enclosure.rs`). Any `h` whose reciprocal is
    // not finite takes the point-node branch.
    let inv_h = match Interval::point(h).recip() {
        Ok(inv_h) if inv_h.is_bounded() => inv_h,
        _ => {
            // A point node: the function is one (uncertain) value,
            // `c0 ± (Σ_{k≥1} |c_k| + r)` for every `e ∈ [−1, 1]`.
            let mag = coefs[1..].iter().fold(r, |m, c| add_up(m, c.abs()));
            return E::from_interval(Interval::around(coefs[0], mag));
        }
    };
    let e = (E::time(to) - m).scale(inv_h);
    let n = coefs.len() - 1;
    let mut acc = E::constant(coefs[n]);
    for k in (0..n).rev() {
        acc = acc * e + coefs[k];
    }
    acc.widen(r)
}
