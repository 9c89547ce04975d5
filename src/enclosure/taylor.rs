//! Taylor models: a polynomial of degree `K − 1` in the node's time symbol
//! plus a symmetric error term, docs/design.md §2.
//!
//! Products are truncated at degree `K − 1`; each dropped term `c·eᵏ` is
//! bounded over `e ∈ [−1, 1]` (even `k`: `c/2 ± |c|/2`, odd: `±|c|`) and
//! moved into the centre and the error term. Degree 1 would be [`Affine`]
//! (which has its own, faster type).
//!
//! [`Affine`]: super::Affine

use super::rounding::{add_up, down, err, mul_up, up};
use super::{Arithmetic, Enclosure, Interval, TimeSpan, series};
use crate::CcdError;
use std::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// `Σ_{k<K} c[k]·eᵏ ± r` for the node's local symbol `e ∈ [−1, 1]`.
/// `K` is the number of coefficients, from 2 to 8.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Taylor<const K: usize> {
    /// Coefficients of `e⁰ … e^(K−1)`.
    pub c: [f64; K],
    /// Error radius, `≥ 0`.
    pub r: f64,
}

/// Taylor models of degree 2.
pub type Taylor2 = Taylor<3>;
/// Taylor models of degree 3.
pub type Taylor3 = Taylor<4>;

impl<const K: usize> Taylor<K> {
    /// Products fold at most `2K − 2` degrees; 8 coefficients is plenty.
    const SUPPORTED: () = assert!(K >= 2 && K <= 8, "Taylor<K> needs 2 <= K <= 8");

    /// Nothing known: the whole real line.
    pub const ENTIRE: Taylor<K> = Taylor {
        c: [0.0; K],
        r: f64::INFINITY,
    };

    /// A model with the given parts; non-finite parts give the whole line.
    /// One test of their sum stands for one per part (a NaN or an infinity
    /// in any makes it NaN or infinite; one that overflows while the parts
    /// do not gives the whole line too, soundly), as in `Affine`.
    #[inline]
    fn checked(c: [f64; K], r: f64) -> Taylor<K> {
        #[allow(clippy::let_unit_value)]
        let _ = Self::SUPPORTED;
        if r >= 0.0 && (c.iter().sum::<f64>() + r).is_finite() {
            Taylor { c, r }
        } else {
            Taylor::ENTIRE
        }
    }

    /// `Σ|c[k]|` rounded up: the largest magnitude of the polynomial part.
    fn poly_mag(&self) -> f64 {
        self.c.iter().fold(0.0, |m, x| add_up(m, x.abs()))
    }

    /// Bounds of `c[k]·eᵏ` over `e ∈ [−1, 1]`, `k ≥ 1`.
    fn term_bounds(k: usize, coef: f64) -> (f64, f64) {
        if k % 2 == 0 {
            (coef.min(0.0), coef.max(0.0))
        } else {
            (-coef.abs(), coef.abs())
        }
    }

    /// True when the polynomial part is monotone on `[−1, 1]`:
    /// `|c1| > Σ_{k≥2} k·|c[k]|` bounds `|p'(e)|` away from zero.
    fn is_monotone(&self) -> bool {
        let higher = (2..K).fold(0.0, |m, k| add_up(m, mul_up(k as f64, self.c[k].abs())));
        self.c[1].abs() > higher
    }

    /// The polynomial part at `e = ±1`, enclosed.
    fn at_end(&self, e: f64) -> Interval {
        let mut acc = Interval::point(self.c[K - 1]);
        for k in (0..K - 1).rev() {
            acc = acc * Interval::point(e) + Interval::point(self.c[k]);
        }
        acc
    }

    /// `c0 + Σ_{k≥1} bounds(c[k]·eᵏ)`: each term bounded on its own.
    fn term_range(&self) -> Interval {
        let (mut lo, mut hi) = (self.c[0], self.c[0]);
        for k in 1..K {
            let (a, b) = Self::term_bounds(k, self.c[k]);
            lo = down(lo + a);
            hi = up(hi + b);
        }
        Interval::new(lo, hi)
    }

    /// The polynomial part's range on `[−1, 1]` when it may turn there.
    ///
    /// Bounding each term on its own (`term_range`) overestimates by about
    /// `|c1| + |c2|`, which on a node holding a critical point of the function
    /// (a grazing contact) is of the order of the true width: Taylor models
    /// then converged no faster than affine forms there (order 2; caught by
    /// the convergence test in `tests/enclosure.rs`). For degree ≤ 3 the
    /// range is instead the hull of the values at the ends and over rigorous
    /// enclosures of the critical points (roots of `p′`, by the quadratic
    /// formula in interval arithmetic), exact up to rounding. Higher degrees
    /// keep the per-term bound.
    fn turning_range(&self) -> Interval {
        if K > 4 {
            return self.term_range();
        }
        let mut a = [0.0; 4];
        a[..K].copy_from_slice(&self.c);
        let mut range = self.at_end(-1.0).hull(self.at_end(1.0));
        for root in critical_points(a).into_iter().flatten() {
            let (lo, hi) = (root.lo.max(-1.0), root.hi.min(1.0));
            if lo <= hi {
                range = range.hull(cubic_over(a, Interval::new(lo, hi)));
            }
        }
        range
    }
}

/// `Σ a[k]·xᵏ` over the interval `x`, by Horner's rule.
fn horner(a: &[Interval], x: Interval) -> Interval {
    let mut acc = a[a.len() - 1];
    for &coef in a[..a.len() - 1].iter().rev() {
        acc = acc * x + coef;
    }
    acc
}

/// The cubic `Σ a[k]·eᵏ` over the (narrow) interval `x`, by the mean-value
/// form `p(mid) + p′(x)·(x − mid)`: near a critical point `p′` is small, so
/// the bound is far tighter than Horner's rule over `x`.
fn cubic_over(a: [f64; 4], x: Interval) -> Interval {
    let p = a.map(Interval::point);
    let mid = x.mid();
    let dp = [p[1], p[2] * 2.0, p[3] * 3.0];
    horner(&p, Interval::point(mid)) + horner(&dp, x) * (x - mid)
}

/// Enclosures of the real roots of `p′(e) = a1 + 2·a2·e + 3·a3·e²`, the
/// critical points of the cubic `Σ a[k]·eᵏ`. A root may be missing only if
/// it does not exist; an enclosure may be wide (even the whole line).
fn critical_points(a: [f64; 4]) -> [Option<Interval>; 2] {
    let div = |x: Interval, y: Interval| y.recip().ok().map(|inv| x * inv);
    let (a1, a2, a3) = (
        Interval::point(a[1]),
        Interval::point(a[2]),
        Interval::point(a[3]),
    );
    if a[3] == 0.0 {
        // Linear p′: one root −a1/(2·a2), none when p′ is constant.
        return [div(-a1, a2 * 2.0), None];
    }
    // Roots of 3a3·e² + 2a2·e + a1: with D = a2² − 3·a1·a3,
    // e = (−a2 ± √D)/(3a3), in the stable form q = −(a2 + sign(a2)·√D),
    // e1 = q/(3a3), e2 = a1/q.
    let disc = a2.sqr() - a1 * a3 * 3.0;
    let Ok(root_disc) = disc.sqrt() else {
        // D < 0: no real critical point, p is monotone.
        return [None, None];
    };
    let signed = if a[2] < 0.0 { -root_disc } else { root_disc };
    let q = -(a2 + signed);
    let three_a3 = a3 * 3.0;
    let e1 = div(q, three_a3);
    // If q may be zero, take the second root from the plain formula.
    let e2 = div(a1, q).or_else(|| div(-a2 - signed, three_a3));
    [e1, e2]
}

impl<const K: usize> Add for Taylor<K> {
    type Output = Taylor<K>;
    fn add(self, o: Taylor<K>) -> Taylor<K> {
        let mut c = [0.0; K];
        let mut r = add_up(self.r, o.r);
        for (k, ck) in c.iter_mut().enumerate() {
            *ck = self.c[k] + o.c[k];
            r = add_up(r, err(*ck));
        }
        Taylor::checked(c, r)
    }
}

impl<const K: usize> Sub for Taylor<K> {
    type Output = Taylor<K>;
    fn sub(self, o: Taylor<K>) -> Taylor<K> {
        self + (-o)
    }
}

impl<const K: usize> Mul for Taylor<K> {
    type Output = Taylor<K>;
    fn mul(self, o: Taylor<K>) -> Taylor<K> {
        // Full product into `full`, each product's and sum's rounding error
        // into `r`; then fold degrees ≥ K.
        let mut full = [0.0; 16];
        let mut r = 0.0;
        for i in 0..K {
            for j in 0..K {
                let p = self.c[i] * o.c[j];
                let sum = full[i + j] + p;
                r = add_up(r, add_up(err(p), err(sum)));
                full[i + j] = sum;
            }
        }
        let mut c = [0.0; K];
        c.copy_from_slice(&full[..K]);
        for (k, &coef) in full.iter().enumerate().take(2 * K - 1).skip(K) {
            if k % 2 == 0 {
                let half = 0.5 * coef;
                c[0] += half;
                r = add_up(r, add_up(half.abs(), err(c[0])));
            } else {
                r = add_up(r, coef.abs());
            }
        }
        let cross = add_up(
            add_up(mul_up(self.poly_mag(), o.r), mul_up(o.poly_mag(), self.r)),
            mul_up(self.r, o.r),
        );
        Taylor::checked(c, add_up(r, cross))
    }
}

impl<const K: usize> Neg for Taylor<K> {
    type Output = Taylor<K>;
    fn neg(self) -> Taylor<K> {
        Taylor {
            c: self.c.map(|x| -x),
            r: self.r,
        }
    }
}

impl<const K: usize> Add<f64> for Taylor<K> {
    type Output = Taylor<K>;
    fn add(self, k: f64) -> Taylor<K> {
        let mut c = self.c;
        c[0] += k;
        Taylor::checked(c, add_up(self.r, err(c[0])))
    }
}

impl<const K: usize> Sub<f64> for Taylor<K> {
    type Output = Taylor<K>;
    fn sub(self, k: f64) -> Taylor<K> {
        self + (-k)
    }
}

impl<const K: usize> Mul<f64> for Taylor<K> {
    type Output = Taylor<K>;
    fn mul(self, k: f64) -> Taylor<K> {
        let c = self.c.map(|x| x * k);
        let r = c
            .iter()
            .fold(mul_up(self.r, k.abs()), |r, x| add_up(r, err(*x)));
        Taylor::checked(c, r)
    }
}

impl<const K: usize> AddAssign for Taylor<K> {
    fn add_assign(&mut self, o: Taylor<K>) {
        *self = *self + o;
    }
}

impl<const K: usize> SubAssign for Taylor<K> {
    fn sub_assign(&mut self, o: Taylor<K>) {
        *self = *self - o;
    }
}

impl<const K: usize> MulAssign for Taylor<K> {
    fn mul_assign(&mut self, o: Taylor<K>) {
        *self = *self * o;
    }
}

impl<const K: usize> num_traits::Zero for Taylor<K> {
    fn zero() -> Taylor<K> {
        Taylor::constant(0.0)
    }
    fn is_zero(&self) -> bool {
        self.r == 0.0 && self.c.iter().all(|x| *x == 0.0)
    }
}

impl<const K: usize> num_traits::One for Taylor<K> {
    fn one() -> Taylor<K> {
        Taylor::constant(1.0)
    }
}

impl<const K: usize> Enclosure for Taylor<K> {
    const KIND: Arithmetic = match K {
        3 => Arithmetic::Taylor2,
        4 => Arithmetic::Taylor3,
        // Other degrees are usable but have no named kind; they report as
        // the nearest named one.
        2 => Arithmetic::Affine,
        _ => Arithmetic::Taylor3,
    };
    const DEGREE: usize = K - 1;

    fn constant(x: f64) -> Taylor<K> {
        let mut c = [0.0; K];
        c[0] = x;
        Taylor::checked(c, 0.0)
    }

    fn from_interval(iv: Interval) -> Taylor<K> {
        let mid = iv.mid();
        let mut c = [0.0; K];
        c[0] = mid;
        Taylor::checked(c, up(iv.hi - mid).max(up(mid - iv.lo)))
    }

    fn time(span: TimeSpan) -> Taylor<K> {
        let (m, h) = span.center_radius();
        let mut c = [0.0; K];
        c[0] = m;
        c[1] = h;
        Taylor::checked(c, 0.0)
    }

    fn range(&self) -> Interval {
        let poly = if self.is_monotone() {
            // Exact up to rounding: the values at the two ends.
            self.at_end(-1.0).hull(self.at_end(1.0))
        } else {
            // Both bounds are sound; keep their intersection.
            let (turning, terms) = (self.turning_range(), self.term_range());
            Interval::new(turning.lo.max(terms.lo), turning.hi.min(terms.hi))
        };
        Interval::new(down(poly.lo - self.r), up(poly.hi + self.r))
    }

    fn linear_lower(&self) -> (f64, f64) {
        let mut a = down(self.c[0] - self.r);
        for k in 2..K {
            a = down(a + Self::term_bounds(k, self.c[k]).0);
        }
        (a, self.c[1])
    }

    fn linear_upper(&self) -> (f64, f64) {
        let mut a = up(self.c[0] + self.r);
        for k in 2..K {
            a = up(a + Self::term_bounds(k, self.c[k]).1);
        }
        (a, self.c[1])
    }

    fn between(lower: (f64, f64), upper: (f64, f64)) -> Taylor<K> {
        let (c0, c1, r) = super::middle_line(lower, upper);
        let mut c = [0.0; K];
        c[0] = c0;
        c[1] = c1;
        Taylor::checked(c, r)
    }

    fn widen(self, radius: f64) -> Taylor<K> {
        Taylor::checked(self.c, add_up(self.r, radius))
    }

    fn scale(self, factor: Interval) -> Taylor<K> {
        let mid = factor.mid();
        let rad = up(factor.hi - mid).max(up(mid - factor.lo));
        (self * mid).widen(mul_up(self.range().mag(), rad))
    }

    fn sqr(self) -> Taylor<K> {
        self * self
    }

    fn abs(self) -> Taylor<K> {
        let range = self.range();
        if range.lo >= 0.0 {
            self
        } else if range.hi <= 0.0 {
            -self
        } else {
            Taylor::from_interval(range.abs())
        }
    }

    fn min(self, o: Taylor<K>) -> Taylor<K> {
        let (a, b) = (self.range(), o.range());
        if a.hi <= b.lo {
            self
        } else if b.hi <= a.lo {
            o
        } else {
            Taylor::from_interval(a.min(b))
        }
    }

    fn max(self, o: Taylor<K>) -> Taylor<K> {
        -((-self).min(-o))
    }

    fn sqrt(self) -> Result<Taylor<K>, CcdError> {
        series::sqrt(self)
    }

    fn recip(self) -> Result<Taylor<K>, CcdError> {
        series::recip(self)
    }

    fn sin(self) -> Taylor<K> {
        series::trig(self, false)
    }

    fn cos(self) -> Taylor<K> {
        series::trig(self, true)
    }

    fn restrict(self, from: TimeSpan, to: TimeSpan) -> Taylor<K> {
        series::restrict_poly(&self.c, self.r, from, to)
    }
}
