//! Interval arithmetic: the write-up's baseline (its section 3).
//!
//! Every bound is rounded outward by one ulp, so the result always contains
//! the exact result of the real operation on any values inside the operands.

use super::rounding::{LIBM_SLACK, down, up};
use super::{Arithmetic, Enclosure, TimeSpan};
use crate::CcdError;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The closed set `lo ≤ x ≤ hi`. Bounds may be infinite; never NaN
/// (constructors turn NaN into the whole line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// The whole real line: what we know of a value that is not known.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// The set between `a` and `b`, whichever is larger; NaN gives
    /// [`Interval::ENTIRE`].
    pub fn new(a: f64, b: f64) -> Interval {
        if a.is_nan() || b.is_nan() {
            Interval::ENTIRE
        } else if a <= b {
            Interval { lo: a, hi: b }
        } else {
            Interval { lo: b, hi: a }
        }
    }

    /// The single number `x`.
    pub fn point(x: f64) -> Interval {
        Interval::new(x, x)
    }

    /// `[c − r, c + r]`, rounded outward.
    pub fn around(c: f64, r: f64) -> Interval {
        Interval::new(down(c - r), up(c + r))
    }

    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    pub fn mid(&self) -> f64 {
        self.lo + 0.5 * (self.hi - self.lo)
    }

    /// The largest absolute value in the set.
    pub fn mag(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// The smallest interval holding both.
    pub fn hull(&self, other: Interval) -> Interval {
        Interval::new(self.lo.min(other.lo), self.hi.max(other.hi))
    }

    /// Both bounds finite.
    pub fn is_bounded(&self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// Outward-rounded interval from two computed bounds.
    fn outward(lo: f64, hi: f64) -> Interval {
        Interval::new(down(lo), up(hi))
    }
}

impl Add for Interval {
    type Output = Interval;
    fn add(self, o: Interval) -> Interval {
        Interval::outward(self.lo + o.lo, self.hi + o.hi)
    }
}

impl Sub for Interval {
    type Output = Interval;
    fn sub(self, o: Interval) -> Interval {
        Interval::outward(self.lo - o.hi, self.hi - o.lo)
    }
}

impl Mul for Interval {
    type Output = Interval;
    fn mul(self, o: Interval) -> Interval {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        if p.iter().any(|x| x.is_nan()) {
            // 0·∞: the operands are unbounded, so is the product.
            return Interval::ENTIRE;
        }
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::outward(lo, hi)
    }
}

impl Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

// The scalar operators take the scalar through `Enclosure::constant`, like
// `Affine` and `Taylor` do, so that a non-finite scalar means "unknown" (the
// whole line). With `Interval::point`, `τ + ∞` was `[f64::MAX, ∞]`, a range a
// caller would read as "far apart" (caught by the non-finite test in
// `tests/enclosure.rs`).
impl Add<f64> for Interval {
    type Output = Interval;
    fn add(self, c: f64) -> Interval {
        self + <Interval as Enclosure>::constant(c)
    }
}

impl Sub<f64> for Interval {
    type Output = Interval;
    fn sub(self, c: f64) -> Interval {
        self - <Interval as Enclosure>::constant(c)
    }
}

impl Mul<f64> for Interval {
    type Output = Interval;
    fn mul(self, c: f64) -> Interval {
        self * <Interval as Enclosure>::constant(c)
    }
}

impl AddAssign for Interval {
    fn add_assign(&mut self, o: Interval) {
        *self = *self + o;
    }
}

impl SubAssign for Interval {
    fn sub_assign(&mut self, o: Interval) {
        *self = *self - o;
    }
}

impl MulAssign for Interval {
    fn mul_assign(&mut self, o: Interval) {
        *self = *self * o;
    }
}

impl num_traits::Zero for Interval {
    fn zero() -> Interval {
        Interval::point(0.0)
    }
    fn is_zero(&self) -> bool {
        self.lo == 0.0 && self.hi == 0.0
    }
}

impl num_traits::One for Interval {
    fn one() -> Interval {
        Interval::point(1.0)
    }
}

/// The range of `f` (sin or cos) over `[lo, hi]`, where `f` peaks at
/// `peak + 2kπ` and bottoms at `peak + π + 2kπ`. Extremes that lie inside the
/// interval, or within a rounding tolerance of it, contribute ±1 exactly;
/// taking one in that is not quite inside only widens the result (sound).
fn trig_range(x: Interval, f: fn(f64) -> f64, peak: f64) -> Interval {
    // Beyond 2⁵⁰ the spacing of floats exceeds the period's resolution.
    if !x.is_bounded() || x.width() >= TAU || x.mag() > 1.0e15 {
        return Interval { lo: -1.0, hi: 1.0 };
    }
    let tol = 1.0e-9 * (1.0 + x.mag());
    // Is some `base + 2kπ` within [lo − tol, hi + tol]?
    let hits = |base: f64| {
        let k = ((x.lo - tol - base) / TAU).ceil();
        base + k * TAU <= x.hi + tol
    };
    let (fa, fb) = (f(x.lo), f(x.hi));
    let mut lo = fa.min(fb) - LIBM_SLACK;
    let mut hi = fa.max(fb) + LIBM_SLACK;
    if hits(peak) {
        hi = 1.0;
    }
    if hits(peak + PI) {
        lo = -1.0;
    }
    Interval::new(lo.max(-1.0), hi.min(1.0))
}

impl Enclosure for Interval {
    const KIND: Arithmetic = Arithmetic::Interval;
    const DEGREE: usize = 0;

    fn exact_value(&self) -> Option<f64> {
        (self.lo == self.hi).then_some(self.lo)
    }

    fn constant(c: f64) -> Interval {
        if c.is_finite() {
            Interval::point(c)
        } else {
            Interval::ENTIRE
        }
    }

    fn from_interval(iv: Interval) -> Interval {
        iv
    }

    fn time(span: TimeSpan) -> Interval {
        Interval::new(span.lo, span.hi)
    }

    fn range(&self) -> Interval {
        *self
    }

    fn linear_lower(&self) -> (f64, f64) {
        (self.lo, 0.0)
    }

    fn linear_upper(&self) -> (f64, f64) {
        (self.hi, 0.0)
    }

    fn widen(self, radius: f64) -> Interval {
        Interval::outward(self.lo - radius, self.hi + radius)
    }

    fn scale(self, factor: Interval) -> Interval {
        self * factor
    }

    fn sqr(self) -> Interval {
        let (a, b) = (self.lo * self.lo, self.hi * self.hi);
        if self.lo <= 0.0 && self.hi >= 0.0 {
            Interval::new(0.0, up(a.max(b)))
        } else {
            Interval::new(down(a.min(b)).max(0.0), up(a.max(b)))
        }
    }

    fn abs(self) -> Interval {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Interval::new(0.0, self.mag())
        }
    }

    fn min(self, o: Interval) -> Interval {
        Interval::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }

    fn max(self, o: Interval) -> Interval {
        Interval::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }

    fn sqrt(self) -> Result<Interval, CcdError> {
        if self.hi < 0.0 {
            return Err(CcdError::Domain {
                operation: "sqrt",
                lo: self.lo,
                hi: self.hi,
            });
        }
        let lo = down(self.lo.max(0.0).sqrt()).max(0.0);
        Ok(Interval::new(lo, up(self.hi.sqrt())))
    }

    fn recip(self) -> Result<Interval, CcdError> {
        if self.lo <= 0.0 && self.hi >= 0.0 {
            return Err(CcdError::Domain {
                operation: "recip",
                lo: self.lo,
                hi: self.hi,
            });
        }
        Ok(Interval::outward(1.0 / self.hi, 1.0 / self.lo))
    }

    fn sin(self) -> Interval {
        trig_range(self, f64::sin, FRAC_PI_2)
    }

    fn cos(self) -> Interval {
        trig_range(self, f64::cos, 0.0)
    }

    fn restrict(self, _from: TimeSpan, _to: TimeSpan) -> Interval {
        self
    }
}
