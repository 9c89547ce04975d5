//! Affine forms over the one time symbol: `x0 + x1·e ± r` (docs/design.md §1).
//!
//! This is the write-up's section 6 with its one flaw mended: the write-up
//! keeps a single error term and adds `|x1|·|y1|` to it on each product. Here
//! the product's `x1·y1·e²` term, with `e² ∈ [0, 1]`, moves `x1·y1/2` into the
//! centre and only `|x1·y1|/2` into the error term, and the error terms'
//! cross products with the operands are accounted for in full, so the form
//! is sound and its excess width falls with the square of the node width.

use super::rounding::{LIBM_SLACK, bound, down, up};
use super::{Arithmetic, Enclosure, Interval, TimeSpan, series};
use crate::CcdError;
use std::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// `c + s·e ± r` for the node's local symbol `e ∈ [−1, 1]`, `r ≥ 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Centre.
    pub c: f64,
    /// Slope on the local time symbol.
    pub s: f64,
    /// Error radius: every nonlinear and rounding error so far.
    pub r: f64,
}

impl Affine {
    /// Nothing known: the whole real line.
    pub const ENTIRE: Affine = Affine {
        c: 0.0,
        s: 0.0,
        r: f64::INFINITY,
    };

    /// A form with the given parts; non-finite parts give [`Affine::ENTIRE`].
    /// One test of their sum stands for three: a NaN or an infinity in any
    /// part makes it NaN or infinite. (A sum that overflows while the parts
    /// do not, beyond 1e308 m, also gives the whole line: sound, and no
    /// scene gets there.) `r` is never negative here: every operation
    /// builds it from magnitudes (or NaN, caught). Every operation ends
    /// here, so this is the hottest branch of the arithmetic.
    #[inline]
    fn checked(c: f64, s: f64, r: f64) -> Affine {
        if (c + s + r).is_finite() {
            Affine { c, s, r }
        } else {
            Affine::ENTIRE
        }
    }
}

impl Add for Affine {
    type Output = Affine;
    #[inline]
    fn add(self, o: Affine) -> Affine {
        let c = self.c + o.c;
        let s = self.s + o.s;
        // Each rounded result x is off by at most 2⁻⁵²·|x| (plus underflow).
        let r = bound(self.r + o.r + (c.abs() + s.abs()) * f64::EPSILON);
        Affine::checked(c, s, r)
    }
}

impl Sub for Affine {
    type Output = Affine;
    #[inline]
    fn sub(self, o: Affine) -> Affine {
        self + (-o)
    }
}

impl Mul for Affine {
    type Output = Affine;
    #[inline]
    fn mul(self, o: Affine) -> Affine {
        // (a0 + a1 e)(b0 + b1 e) = a0 b0 + (a0 b1 + a1 b0) e + a1 b1 e²,
        // e² = ½ + ½(2e² − 1) with 2e² − 1 ∈ [−1, 1].
        let c00 = self.c * o.c;
        let half11 = 0.5 * (self.s * o.s);
        let c = c00 + half11;
        let (p01, p10) = (self.c * o.s, self.s * o.c);
        let s = p01 + p10;
        let rounding =
            (c00.abs() + half11.abs() + c.abs() + p01.abs() + p10.abs() + s.abs()) * f64::EPSILON;
        let cross =
            (self.c.abs() + self.s.abs()) * o.r + (o.c.abs() + o.s.abs()) * self.r + self.r * o.r;
        let r = bound(half11.abs() + cross + rounding);
        Affine::checked(c, s, r)
    }
}

impl Neg for Affine {
    type Output = Affine;
    #[inline]
    fn neg(self) -> Affine {
        Affine {
            c: -self.c,
            s: -self.s,
            r: self.r,
        }
    }
}

impl Add<f64> for Affine {
    type Output = Affine;
    #[inline]
    fn add(self, k: f64) -> Affine {
        let c = self.c + k;
        Affine::checked(c, self.s, bound(self.r + c.abs() * f64::EPSILON))
    }
}

impl Sub<f64> for Affine {
    type Output = Affine;
    #[inline]
    fn sub(self, k: f64) -> Affine {
        self + (-k)
    }
}

impl Mul<f64> for Affine {
    type Output = Affine;
    #[inline]
    fn mul(self, k: f64) -> Affine {
        let (c, s) = (self.c * k, self.s * k);
        let r = bound(self.r * k.abs() + (c.abs() + s.abs()) * f64::EPSILON);
        Affine::checked(c, s, r)
    }
}

impl AddAssign for Affine {
    #[inline]
    fn add_assign(&mut self, o: Affine) {
        *self = *self + o;
    }
}

impl SubAssign for Affine {
    #[inline]
    fn sub_assign(&mut self, o: Affine) {
        *self = *self - o;
    }
}

impl MulAssign for Affine {
    #[inline]
    fn mul_assign(&mut self, o: Affine) {
        *self = *self * o;
    }
}

impl num_traits::Zero for Affine {
    fn zero() -> Affine {
        Affine::constant(0.0)
    }
    fn is_zero(&self) -> bool {
        self.c == 0.0 && self.s == 0.0 && self.r == 0.0
    }
}

impl num_traits::One for Affine {
    fn one() -> Affine {
        Affine::constant(1.0)
    }
}

impl Enclosure for Affine {
    const KIND: Arithmetic = Arithmetic::Affine;
    const DEGREE: usize = 1;

    #[inline]
    fn constant(c: f64) -> Affine {
        Affine::checked(c, 0.0, 0.0)
    }

    #[inline]
    fn exact_value(&self) -> Option<f64> {
        (self.s == 0.0 && self.r == 0.0).then_some(self.c)
    }

    #[inline]
    fn from_interval(iv: Interval) -> Affine {
        let c = iv.mid();
        let r = up(iv.hi - c).max(up(c - iv.lo));
        Affine::checked(c, 0.0, r)
    }

    #[inline]
    fn time(span: TimeSpan) -> Affine {
        let (m, h) = span.center_radius();
        Affine::checked(m, h, 0.0)
    }

    #[inline]
    fn range(&self) -> Interval {
        // Each end takes three roundings (the last one subtracting the
        // slack), each off by at most half an ulp of the terms' size:
        // four ulps of it, plus the smallest normal for underflow, cover
        // them. One multiply-add instead of four `next_up`s: this runs on
        // every axis of every node.
        let s = self.s.abs();
        let slack = (self.c.abs() + s + self.r) * (4.0 * f64::EPSILON) + f64::MIN_POSITIVE;
        let (lo, hi) = (self.c - s - self.r - slack, self.c + s + self.r + slack);
        // `lo ≤ hi` unless a part is NaN (a form built by hand: the
        // operations give the whole line instead): one comparison where
        // `Interval::new` took three.
        if lo <= hi {
            Interval { lo, hi }
        } else {
            Interval::ENTIRE
        }
    }

    #[inline]
    fn linear_lower(&self) -> (f64, f64) {
        (down(self.c - self.r), self.s)
    }

    #[inline]
    fn linear_upper(&self) -> (f64, f64) {
        (up(self.c + self.r), self.s)
    }

    #[inline]
    fn line(&self) -> (f64, f64, f64) {
        (self.c, self.s, self.r)
    }

    #[inline]
    fn between(lower: (f64, f64), upper: (f64, f64)) -> Affine {
        let (c, s, r) = super::middle_line(lower, upper);
        Affine::checked(c, s, r)
    }

    #[inline]
    fn widen(self, radius: f64) -> Affine {
        Affine::checked(self.c, self.s, bound(self.r + radius))
    }

    #[inline]
    fn scale(self, factor: Interval) -> Affine {
        // x·f = x·mid(f) + x·(f − mid(f)), the second part bounded by |x|·rad.
        let mid = factor.mid();
        let rad = (factor.hi - mid).max(mid - factor.lo);
        let mag = self.c.abs() + self.s.abs() + self.r;
        let (c, s) = (self.c * mid, self.s * mid);
        let r = bound(self.r * mid.abs() + (c.abs() + s.abs()) * f64::EPSILON + mag * rad);
        Affine::checked(c, s, r)
    }

    #[inline]
    fn sqr(self) -> Affine {
        let c00 = self.c * self.c;
        let half11 = 0.5 * (self.s * self.s);
        let c = c00 + half11;
        let s = 2.0 * (self.c * self.s);
        let rounding = (c00 + half11 + c.abs() + s.abs()) * f64::EPSILON;
        let cross = 2.0 * (self.c.abs() + self.s.abs()) * self.r + self.r * self.r;
        let r = bound(half11 + cross + rounding);
        Affine::checked(c, s, r)
    }

    #[inline]
    fn abs(self) -> Affine {
        let range = self.range();
        if range.lo >= 0.0 {
            self
        } else if range.hi <= 0.0 {
            -self
        } else {
            // The write-up's advice: |x| through its interval.
            Affine::from_interval(range.abs())
        }
    }

    #[inline]
    fn min(self, o: Affine) -> Affine {
        let (a, b) = (self.range(), o.range());
        if a.hi <= b.lo {
            self
        } else if b.hi <= a.lo {
            o
        } else {
            Affine::from_interval(a.min(b))
        }
    }

    #[inline]
    fn max(self, o: Affine) -> Affine {
        -((-self).min(-o))
    }

    /// The tangent at the centre, lowered by half the largest gap between
    /// it and the root over the range: `√` is concave, so on `[a, b]` it
    /// lies below its tangent at `c`, and the gap (convex) is widest at an
    /// end: `(√c − √a)²/(2√c)` or `(√b − √c)²/(2√c)`. A
    /// handful of `f64` operations and one rounding slack, where the
    /// generic series took interval products with outward rounding after
    /// each (a cylinder's or cone's support takes one root per node and
    /// axis).
    fn sqrt(self) -> Result<Affine, CcdError> {
        let range = self.range();
        let whole = range.sqrt()?;
        if range.lo.is_nan() || range.lo <= 0.0 || !range.is_bounded() {
            return Ok(Affine::from_interval(whole));
        }
        let root_c = self.c.sqrt();
        let slope = 0.5 / root_c;
        let gap = (root_c - range.lo.sqrt())
            .abs()
            .max((range.hi.sqrt() - root_c).abs())
            .powi(2)
            * slope;
        let (s, r) = (self.s * slope, self.r * slope);
        // Each quantity above is within a few ulps of its exact value
        // (the differences of roots within an ulp of the larger root, at
        // most `√c` plus the spread): sixteen ulps of their sum cover them
        // and the sums below.
        let slack = (root_c + s.abs() + r + gap) * (16.0 * f64::EPSILON) + f64::MIN_POSITIVE;
        let root = Affine::checked(root_c - 0.5 * gap, s, bound(r + 0.5 * gap + slack));
        Ok(series::prefer_series(root, Affine::from_interval(whole)))
    }

    fn recip(self) -> Result<Affine, CcdError> {
        series::recip(self)
    }

    /// One rounding bound for the whole expression instead of one per
    /// operation: the centre is a sum of three terms (two of them
    /// products) and the slope of two, each off by at most `γ₃ ≤ 2⁻⁵¹`
    /// times its terms' absolute sum.
    #[inline]
    fn scaled_sum(self, a: f64, other: Affine, b: f64, k: f64, slack: f64) -> Affine {
        let (ca, cb) = (self.c * a, other.c * b);
        let (sa, sb) = (self.s * a, other.s * b);
        let c = ca + cb + k;
        let s = sa + sb;
        let rounding = (ca.abs() + cb.abs() + k.abs() + sa.abs() + sb.abs()) * (2.0 * f64::EPSILON);
        let r = bound(self.r * a.abs() + other.r * b.abs() + rounding + slack);
        Affine::checked(c, s, r)
    }

    /// One rounding bound for the whole dot product instead of one per
    /// operation. The centre `Σ (cᵢc'ᵢ + ½sᵢs'ᵢ)` and the slope
    /// `Σ (cᵢs'ᵢ + sᵢc'ᵢ)` are sums of `2N` rounded products each, every
    /// product passing through at most `N + 1` roundings, so they are off
    /// by at most `γ_{N+1} < (N + 1)·ε` times their terms' absolute sum
    /// (`ε` the machine epsilon, `2u`); the error term gathers each
    /// product's `|½sᵢs'ᵢ|` (from `e² ∈ [0, 1]`) and its cross terms with
    /// the operands' error radii, as [`Mul`] does. For `N ≤ 16` the radius
    /// takes fewer than the 32 roundings [`bound`] allows.
    #[inline]
    fn dot<const N: usize>(x: [Affine; N], y: [Affine; N]) -> Affine {
        let (mut c, mut s) = (0.0, 0.0);
        let (mut terms, mut nonlinear) = (0.0, 0.0);
        for (a, b) in x.iter().zip(&y) {
            let c00 = a.c * b.c;
            let half11 = 0.5 * (a.s * b.s);
            let (p01, p10) = (a.c * b.s, a.s * b.c);
            c += c00 + half11;
            s += p01 + p10;
            terms += c00.abs() + half11.abs() + p01.abs() + p10.abs();
            nonlinear += half11.abs()
                + (a.c.abs() + a.s.abs()) * b.r
                + (b.c.abs() + b.s.abs()) * a.r
                + a.r * b.r;
        }
        let r = bound(nonlinear + terms * ((N as f64 + 1.0) * f64::EPSILON));
        Affine::checked(c, s, r)
    }

    /// One rounding bound for the whole sum: centre and slope are sums of
    /// `N` rounded products each, off by at most `γ_N < (N + 1)·ε` times
    /// their terms' absolute sum; the error radii scale with `|kᵢ|`.
    #[inline]
    fn dot_f64<const N: usize>(x: [Affine; N], k: [f64; N]) -> Affine {
        let (mut c, mut s) = (0.0, 0.0);
        let (mut terms, mut radius) = (0.0, 0.0);
        for (a, &k) in x.iter().zip(&k) {
            let (ck, sk) = (a.c * k, a.s * k);
            c += ck;
            s += sk;
            terms += ck.abs() + sk.abs();
            radius += a.r * k.abs();
        }
        let r = bound(radius + terms * ((N as f64 + 1.0) * f64::EPSILON));
        Affine::checked(c, s, r)
    }

    fn sin(self) -> Affine {
        self.sin_cos().0
    }

    fn cos(self) -> Affine {
        self.sin_cos().1
    }

    /// The degree-one series about the centre, written out: the generic one
    /// (`series::sin_cos`) builds its coefficients as intervals, and this is
    /// the rotation series' inner step (a fifth of a turning pair's
    /// evaluation). With `δ = s·e ± r`, `sin(c + δ) = sin c + cos c·δ −
    /// sin ξ·δ²/2`: centre `sin c`, slope `cos c·s`, and in the error term
    /// `|cos c|·r`, `(|s| + r)²/2`, libm's error (on the centre and, times
    /// `|s|`, on the slope) and the slope's rounding. Likewise for `cos`.
    fn sin_cos(self) -> (Affine, Affine) {
        let reach = self.s.abs() + self.r;
        if reach.is_nan() || reach > 4.0 {
            // Beyond about a turn (or unbounded): the generic answer, `[−1, 1]`.
            return series::sin_cos(self);
        }
        let (sc, cc) = self.c.sin_cos();
        let common = 0.5 * (reach * reach) + LIBM_SLACK * (1.0 + self.s.abs());
        let sin_slope = cc * self.s;
        let cos_slope = -(sc * self.s);
        let sin_r =
            (cc.abs() + LIBM_SLACK).min(1.0) * self.r + common + sin_slope.abs() * f64::EPSILON;
        let cos_r =
            (sc.abs() + LIBM_SLACK).min(1.0) * self.r + common + cos_slope.abs() * f64::EPSILON;
        (
            series::clamp_unit(Affine::checked(sc, sin_slope, bound(sin_r))),
            series::clamp_unit(Affine::checked(cc, cos_slope, bound(cos_r))),
        )
    }

    fn restrict(self, from: TimeSpan, to: TimeSpan) -> Affine {
        series::restrict_poly(&[self.c, self.s], self.r, from, to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A number of any sign over most of the exponent range (zero too).
    fn number() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(0.0),
            (-1.0f64..1.0, -300i32..300).prop_map(|(m, e)| m * 2f64.powi(e)),
        ]
    }

    proptest! {
        /// The range holds the one rounded outward step by step (a `next_up`
        /// or `next_down` after each operation), which holds the exact ends.
        #[test]
        fn the_range_holds_the_step_by_step_outward_one(
            c in number(),
            s in number(),
            r in number().prop_map(f64::abs),
        ) {
            let x = Affine { c, s, r };
            let range = x.range();
            let s = s.abs();
            let (lo, hi) = (down(down(c - s) - r), up(up(c + s) + r));
            prop_assert!(range.lo <= lo && hi <= range.hi, "{range:?} vs [{lo}, {hi}] for {x:?}");
        }
    }
}
