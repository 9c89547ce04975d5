//! Enclosure arithmetic over one time variable.
//!
//! Every value here is a *set* that contains the true value of some quantity
//! for every time τ of a node `[lo, hi]` of the step. Within one node all
//! enclosures share one local time symbol `e ∈ [−1, 1]` with
//! `τ = m + h·e` (see [`TimeSpan::center_radius`]), so dependencies on time
//! cancel: in affine or Taylor arithmetic `τ − τ` is exactly zero.
//!
//! Three arithmetics implement [`Enclosure`], so that a distance function is
//! written once and evaluated in any of them:
//! - [`Interval`]: a lower and an upper bound, the write-up's baseline. It
//!   forgets dependencies: `x − x²` over `x ∈ [0, 1]` gives `[−1, 1]`.
//! - [`Affine`]: `x0 + x1·e ± r`, docs/design.md §1. Excess width shrinks with the
//!   square of the node width; the default.
//! - [`Taylor`]`<K>`: a polynomial of degree `K − 1` in `e` plus `± r`.
//!   [`Taylor2`] and [`Taylor3`] are the degrees 2 and 3.
//!
//! ## Rounding
//!
//! Rust on stable has no portable way to switch the FPU's rounding mode, so
//! soundness under rounding is kept in two ways (docs/design.md §8):
//! - [`Interval`] rounds every computed bound outward by one ulp with
//!   `f64::next_down` / `f64::next_up`. A correctly rounded `+ − × ÷ sqrt` is
//!   within half an ulp of the truth, so one ulp outward always contains it.
//! - [`Affine`] and [`Taylor`] compute their coefficients rounded to nearest
//!   and add a bound on each rounding error to their error term `r`
//!   (`rounding::err`: `2⁻⁵²·|x| + 2⁻¹⁰⁷⁴` per rounded result), summing
//!   those bounds with upward rounding. Cheaper than outward intervals per
//!   coefficient and just as sound.
//! - libm's `sin` and `cos` are not correctly rounded (glibc stays within one
//!   ulp); their results are widened by `rounding::LIBM_SLACK`, eight ulps
//!   of 1, see there.
//!
//! NaN never escapes as a bound: an operation whose bound would be NaN gives
//! the whole real line, which no caller can mistake for "apart".

mod affine;
mod interval;
pub(crate) mod rounding;
pub(crate) mod series;
mod taylor;

pub use affine::Affine;
pub use interval::Interval;
pub use taylor::{Taylor, Taylor2, Taylor3};

use crate::CcdError;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Which enclosure arithmetic a query runs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Arithmetic {
    /// Plain intervals: the write-up's baseline.
    Interval,
    /// Affine forms over the time symbol (the default: best speed/accuracy
    /// on the calibration set of docs/accuracy.md).
    #[default]
    Affine,
    /// Taylor models of degree 2.
    Taylor2,
    /// Taylor models of degree 3.
    Taylor3,
}

impl Arithmetic {
    /// Every kind, for comparisons.
    pub const ALL: [Arithmetic; 4] = [
        Arithmetic::Interval,
        Arithmetic::Affine,
        Arithmetic::Taylor2,
        Arithmetic::Taylor3,
    ];

    /// A short lowercase name, for tables and command lines.
    pub fn name(self) -> &'static str {
        match self {
            Arithmetic::Interval => "interval",
            Arithmetic::Affine => "affine",
            Arithmetic::Taylor2 => "taylor2",
            Arithmetic::Taylor3 => "taylor3",
        }
    }

    /// Runs `task` in this arithmetic: the one place that maps an
    /// [`Arithmetic`] value to its enclosure type.
    pub fn dispatch<T: InArithmetic>(self, task: T) -> T::Output {
        match self {
            Arithmetic::Interval => task.run::<Interval>(),
            Arithmetic::Affine => task.run::<Affine>(),
            Arithmetic::Taylor2 => task.run::<Taylor2>(),
            Arithmetic::Taylor3 => task.run::<Taylor3>(),
        }
    }
}

/// Work written once over the arithmetic, run in the one a caller chose
/// with [`Arithmetic::dispatch`].
pub trait InArithmetic {
    type Output;
    fn run<E: Enclosure>(self) -> Self::Output;
}

/// A node of the step: the closed set of time fractions `lo ≤ τ ≤ hi`,
/// with `0 ≤ lo ≤ hi ≤ 1` in the solver (any finite pair is accepted here).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeSpan {
    pub lo: f64,
    pub hi: f64,
}

impl TimeSpan {
    /// The whole step, `τ ∈ [0, 1]`.
    pub const STEP: TimeSpan = TimeSpan { lo: 0.0, hi: 1.0 };

    pub fn new(lo: f64, hi: f64) -> TimeSpan {
        TimeSpan { lo, hi }
    }

    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// The centre `m` and half-width `h` of the local symbol:
    /// `τ = m + h·e`, `e ∈ [−1, 1]`. `h` is rounded up so that the real set
    /// `[m − h, m + h]` contains `[lo, hi]` whatever the rounding of `m`.
    pub fn center_radius(&self) -> (f64, f64) {
        let m = self.lo + 0.5 * (self.hi - self.lo);
        let h = rounding::up(self.hi - m).max(rounding::up(m - self.lo));
        (m, h.max(0.0))
    }

    /// The span's time values as an interval.
    pub fn interval(&self) -> Interval {
        Interval::new(self.lo, self.hi)
    }
}

/// An enclosure of a real function of time over one node.
///
/// Implemented by [`Interval`], [`Affine`] and [`Taylor`]. All operations are
/// sound: the result contains the true result for every time in the node,
/// float rounding included. The arithmetic operators (`+ − ×` among
/// enclosures and with `f64`) come as trait bounds so that generic code reads
/// as formulas; the `num_traits` `Zero`/`One` bounds let nalgebra's vectors and
/// matrices hold enclosures.
pub trait Enclosure:
    Copy
    + Debug
    + PartialEq
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + num_traits::Zero
    + num_traits::One
{
    /// Which arithmetic this is.
    const KIND: Arithmetic;

    /// The degree of the polynomial part in the time symbol (0, 1, 2, 3).
    const DEGREE: usize;

    /// A number known exactly (a non-finite `c` gives the whole line).
    fn constant(c: f64) -> Self;

    /// Some value in `iv`, independent of time.
    fn from_interval(iv: Interval) -> Self;

    /// The value, when this enclosure is one exact number at every time
    /// (a frame that does not turn has an exact rotation): products with
    /// it can then take the cheaper `f64` forms. `None` when unsure.
    fn exact_value(&self) -> Option<f64> {
        None
    }

    /// The time fraction `τ` itself over the node `span`.
    fn time(span: TimeSpan) -> Self;

    /// Bounds on every value the enclosure may take.
    fn range(&self) -> Interval;

    /// `(a, b)` such that the enclosed function is `≥ a + b·e` for every
    /// `e ∈ [−1, 1]` (the local symbol). Used to clip nodes (docs/design.md §6).
    /// Intervals give `(lo, 0)`.
    fn linear_lower(&self) -> (f64, f64);

    /// `(a, b)` such that the enclosed function is `≤ a + b·e` for every
    /// `e ∈ [−1, 1]`: where this is `≤ 0` the function surely is too. The
    /// solver uses it to find a time by which a pair surely touches.
    /// Intervals give `(hi, 0)`.
    fn linear_upper(&self) -> (f64, f64);

    /// `(c, s, r)` such that the enclosed function lies within
    /// `c + s·e ± r` for every `e ∈ [−1, 1]`: by default the line midway
    /// between [`Self::linear_lower`] and [`Self::linear_upper`]. An affine
    /// form is such a line already, and gives its own parts.
    #[inline]
    fn line(&self) -> (f64, f64, f64) {
        middle_line(self.linear_lower(), self.linear_upper())
    }

    /// An enclosure of any function that lies between the lines `lower`
    /// and `upper` (each `(a, b)` for `a + b·e`) at every `e ∈ [−1, 1]`.
    /// By default the range between them; forms with a slope keep the
    /// middle line's.
    fn between(lower: (f64, f64), upper: (f64, f64)) -> Self {
        Self::from_interval(Interval::new(
            rounding::down(lower.0 - lower.1.abs()),
            rounding::up(upper.0 + upper.1.abs()),
        ))
    }

    /// The enclosure widened by `± radius` (`radius ≥ 0`).
    fn widen(self, radius: f64) -> Self;

    /// Multiply by an uncertain, time-independent factor.
    fn scale(self, factor: Interval) -> Self;

    /// `x²`, tighter than `x·x` in every arithmetic.
    fn sqr(self) -> Self;

    /// The absolute value.
    fn abs(self) -> Self;

    /// The pointwise minimum.
    fn min(self, other: Self) -> Self;

    /// The pointwise maximum.
    fn max(self, other: Self) -> Self;

    /// `√x`. The value is assumed non-negative where it is evaluated (a
    /// squared norm, say): a range reaching below zero is clamped to its
    /// non-negative part; a range entirely below zero is a `Domain` error.
    fn sqrt(self) -> Result<Self, CcdError>;

    /// `1/x`; a range containing zero is a `Domain` error.
    fn recip(self) -> Result<Self, CcdError>;

    /// `sin x`, valid for any argument range.
    fn sin(self) -> Self;

    /// `cos x`, valid for any argument range.
    fn cos(self) -> Self;

    /// `self·a + other·b + k` for numbers `a`, `b`, `k`, widened by
    /// `slack`: the rotation series' entry with its prepared error (an
    /// arithmetic may fuse it into one rounding bound).
    fn scaled_sum(self, a: f64, other: Self, b: f64, k: f64, slack: f64) -> Self {
        (self * a + other * b + k).widen(slack)
    }

    /// `Σ xᵢ·yᵢ`: the dot product of two enclosed vectors (`N ≤ 16`), the
    /// inner step of every pose product and separating axis (an arithmetic
    /// may fuse it into one rounding bound).
    fn dot<const N: usize>(x: [Self; N], y: [Self; N]) -> Self {
        let mut sum = Self::zero();
        for (k, (a, b)) in x.into_iter().zip(y).enumerate() {
            sum = if k == 0 { a * b } else { sum + a * b };
        }
        sum
    }

    /// `Σ xᵢ·kᵢ` for numbers `kᵢ` (`N ≤ 16`): an enclosed vector against a
    /// fixed one (an arithmetic may fuse it into one rounding bound).
    fn dot_f64<const N: usize>(x: [Self; N], k: [f64; N]) -> Self {
        let mut sum = Self::zero();
        for (i, (a, k)) in x.into_iter().zip(k).enumerate() {
            sum = if i == 0 { a * k } else { sum + a * k };
        }
        sum
    }

    /// `(sin x, cos x)` together, sharing their expansion point.
    fn sin_cos(self) -> (Self, Self) {
        series::sin_cos(self)
    }

    /// The same function restricted to the sub-node `to` of the node `from`
    /// it was computed on (`to ⊆ from`): its local symbol becomes `to`'s.
    /// Intervals do not depend on the symbol and come back unchanged.
    fn restrict(self, from: TimeSpan, to: TimeSpan) -> Self;
}

/// The line midway between `lower` and `upper` (each `(a, b)` for
/// `a + b·e`) and how far either is from it over `e ∈ [−1, 1]` (at an end:
/// the lines are straight), rounded up to cover the roundings of all
/// three: `(centre, slope, radius)`.
#[inline]
pub(crate) fn middle_line(lower: (f64, f64), upper: (f64, f64)) -> (f64, f64, f64) {
    let c = 0.5 * (lower.0 + upper.0);
    let s = 0.5 * (lower.1 + upper.1);
    let half = 0.5 * ((upper.0 - lower.0) + (upper.1 - lower.1).abs());
    // Each of the three is off by at most three half-ulps of its terms,
    // whose sizes the parts bound: four ulps of them cover it.
    let r =
        rounding::bound(half.max(0.0) + (c.abs() + s.abs() + half.abs()) * (4.0 * f64::EPSILON));
    (c, s, r)
}

/// The least and the greatest of a few enclosures, each range taken once
/// (chaining [`Enclosure::min`] and [`Enclosure::max`] takes both
/// operands' ranges on every call: a dozen ranges for a box–triangle
/// axis). One below (above) all the others at every time of the node is
/// kept as it is, as `min`/`max` keep it; otherwise the bounds of the
/// least (greatest) value at any time.
pub(crate) fn least_greatest<E: Enclosure, const N: usize>(p: &[E; N]) -> (E, E) {
    let r = p.each_ref().map(|x| x.range());
    // The first lowest and the last highest (ranges are never NaN: plain
    // comparisons, where `total_cmp` took integer work on every pair).
    let (mut lowest, mut highest) = (0, 0);
    for (i, x) in r.iter().enumerate().skip(1) {
        if x.lo < r[lowest].lo {
            lowest = i;
        }
        if x.hi >= r[highest].hi {
            highest = i;
        }
    }
    let least = if (0..N).all(|j| j == lowest || r[lowest].hi <= r[j].lo) {
        p[lowest]
    } else {
        let hi = r.iter().map(|x| x.hi).fold(f64::INFINITY, f64::min);
        E::from_interval(Interval::new(r[lowest].lo, hi))
    };
    let greatest = if (0..N).all(|j| j == highest || r[highest].lo >= r[j].hi) {
        p[highest]
    } else {
        let lo = r.iter().map(|x| x.lo).fold(f64::NEG_INFINITY, f64::max);
        E::from_interval(Interval::new(lo, r[highest].hi))
    };
    (least, greatest)
}
