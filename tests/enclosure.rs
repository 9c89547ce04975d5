//! Enclosure arithmetic tests: soundness on random expressions, convergence
//! order, the write-up's worked examples, and the typed domain errors.
//!
//! Every arithmetic (`Interval`, `Affine`, `Taylor2`, `Taylor3`) runs through
//! the same generic checks over `E: Enclosure`.

use affine_ccd::{Affine, CcdError, Enclosure, Interval, Taylor, Taylor2, Taylor3, TimeSpan};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

// ---------------------------------------------------------------------------
// Random expressions over τ
// ---------------------------------------------------------------------------

/// An expression in the time `τ`, built from every `Enclosure` operation.
#[derive(Clone, Debug)]
enum Expr {
    Time,
    Const(f64),
    /// A time-independent value somewhere in `[lo, hi]` (`from_interval`).
    Uncertain(f64, f64),
    /// A non-finite constant in the enclosure; a finite stand-in for the
    /// reference evaluation (the enclosure must hold the value it gives).
    NonFinite(f64, f64),
    Neg(Box<Expr>),
    Sqr(Box<Expr>),
    Sqrt(Box<Expr>),
    Recip(Box<Expr>),
    Abs(Box<Expr>),
    Sin(Box<Expr>),
    Cos(Box<Expr>),
    AddC(Box<Expr>, f64),
    SubC(Box<Expr>, f64),
    MulC(Box<Expr>, f64),
    /// `scale` by a factor somewhere in `[lo, hi]`.
    Scale(Box<Expr>, f64, f64),
    Widen(Box<Expr>, f64),
    Add(Box<Expr>, Box<Expr>),
    Sub(Box<Expr>, Box<Expr>),
    Mul(Box<Expr>, Box<Expr>),
    Min(Box<Expr>, Box<Expr>),
    Max(Box<Expr>, Box<Expr>),
    /// `Enclosure::dot` of the first three and the last three.
    Dot3(Box<[Expr; 6]>),
    /// `Enclosure::dot` of the first two and the last two.
    Dot2(Box<[Expr; 4]>),
    /// `Enclosure::dot_f64` with these numbers.
    Dot3C(Box<[Expr; 3]>, [f64; 3]),
}

use Expr::*;

/// Evaluate `x` in the arithmetic `E` over the node `span`. A domain error
/// (sqrt of a negative range, recip of a range holding zero) propagates.
fn eval<E: Enclosure>(x: &Expr, span: TimeSpan) -> Result<E, CcdError> {
    Ok(match x {
        Time => E::time(span),
        Const(c) => E::constant(*c),
        Uncertain(lo, hi) => E::from_interval(Interval::new(*lo, *hi)),
        NonFinite(bad, _) => E::constant(*bad),
        Neg(a) => -eval::<E>(a, span)?,
        Sqr(a) => eval::<E>(a, span)?.sqr(),
        Sqrt(a) => eval::<E>(a, span)?.sqrt()?,
        Recip(a) => eval::<E>(a, span)?.recip()?,
        Abs(a) => eval::<E>(a, span)?.abs(),
        Sin(a) => eval::<E>(a, span)?.sin(),
        Cos(a) => eval::<E>(a, span)?.cos(),
        AddC(a, c) => eval::<E>(a, span)? + *c,
        SubC(a, c) => eval::<E>(a, span)? - *c,
        MulC(a, c) => eval::<E>(a, span)? * *c,
        Scale(a, lo, hi) => eval::<E>(a, span)?.scale(Interval::new(*lo, *hi)),
        Widen(a, r) => eval::<E>(a, span)?.widen(*r),
        Add(a, b) => eval::<E>(a, span)? + eval::<E>(b, span)?,
        Sub(a, b) => eval::<E>(a, span)? - eval::<E>(b, span)?,
        Mul(a, b) => eval::<E>(a, span)? * eval::<E>(b, span)?,
        Min(a, b) => eval::<E>(a, span)?.min(eval::<E>(b, span)?),
        Max(a, b) => eval::<E>(a, span)?.max(eval::<E>(b, span)?),
        Dot3(v) => {
            let e = |k: usize| eval::<E>(&v[k], span);
            E::dot([e(0)?, e(1)?, e(2)?], [e(3)?, e(4)?, e(5)?])
        }
        Dot2(v) => {
            let e = |k: usize| eval::<E>(&v[k], span);
            E::dot([e(0)?, e(1)?], [e(2)?, e(3)?])
        }
        Dot3C(v, k) => {
            let e = |i: usize| eval::<E>(&v[i], span);
            E::dot_f64([e(0)?, e(1)?, e(2)?], *k)
        }
    })
}

/// `2⁻⁵³`, the unit roundoff.
const U: f64 = f64::EPSILON / 2.0;

/// The plain f64 value of `x` at `τ` and a running bound on its rounding
/// error (first order plus the cross terms; libm sin/cos taken as 2 ulps).
/// `None` where the value is not finite or the reference is too badly
/// conditioned to say anything (recip of a value within its error of 0).
/// `sqrt` is the clamped root `√max(x, 0)`, which is what the enclosures
/// compute (see `Enclosure::sqrt`).
fn reference(x: &Expr, t: f64) -> Option<(f64, f64)> {
    let (v, e) = match x {
        Time => (t, 0.0),
        Const(c) => (*c, 0.0),
        Uncertain(lo, hi) => (Interval::new(*lo, *hi).mid(), 0.0),
        NonFinite(_, stand_in) => (*stand_in, 0.0),
        Neg(a) => {
            let (v, e) = reference(a, t)?;
            (-v, e)
        }
        Sqr(a) => {
            let (v, e) = reference(a, t)?;
            let p = v * v;
            (p, 2.0 * v.abs() * e + e * e + U * p.abs())
        }
        Sqrt(a) => {
            let (v, e) = reference(a, t)?;
            let r = v.max(0.0).sqrt();
            // |√x − √y| ≤ min(√|x − y|, |x − y| / √max(x, y)).
            let prop = if v > 0.0 {
                (e / v.sqrt()).min(e.sqrt())
            } else {
                e.sqrt()
            };
            (r, prop + U * r)
        }
        Recip(a) => {
            let (v, e) = reference(a, t)?;
            if v.abs() <= 2.0 * e || v == 0.0 {
                return None;
            }
            let r = 1.0 / v;
            (r, e / ((v.abs() - e) * v.abs()) + U * r.abs())
        }
        Abs(a) => {
            let (v, e) = reference(a, t)?;
            (v.abs(), e)
        }
        Sin(a) => {
            let (v, e) = reference(a, t)?;
            (v.sin(), e + 4.0 * U)
        }
        Cos(a) => {
            let (v, e) = reference(a, t)?;
            (v.cos(), e + 4.0 * U)
        }
        AddC(a, c) => {
            let (v, e) = reference(a, t)?;
            let s = v + c;
            (s, e + U * s.abs())
        }
        SubC(a, c) => {
            let (v, e) = reference(a, t)?;
            let s = v - c;
            (s, e + U * s.abs())
        }
        MulC(a, c) => {
            let (v, e) = reference(a, t)?;
            let p = v * c;
            (p, e * c.abs() + U * p.abs())
        }
        Scale(a, lo, hi) => {
            let (v, e) = reference(a, t)?;
            let f = Interval::new(*lo, *hi).mid();
            let p = v * f;
            (p, e * f.abs() + U * p.abs())
        }
        Widen(a, _) => reference(a, t)?,
        // A sum of three products, each as `Mul` accounts it, then two
        // rounded additions.
        Dot3(..) | Dot2(..) => {
            let (left, right): (Vec<&Expr>, Vec<&Expr>) = match x {
                Dot3(v) => (v[..3].iter().collect(), v[3..].iter().collect()),
                Dot2(v) => (v[..2].iter().collect(), v[2..].iter().collect()),
                _ => unreachable!(),
            };
            let mut sum = (0.0, 0.0);
            for (a, b) in left.into_iter().zip(right) {
                let (va, ea) = reference(a, t)?;
                let (vb, eb) = reference(b, t)?;
                let p = va * vb;
                let s = sum.0 + p;
                sum = (
                    s,
                    sum.1 + va.abs() * eb + vb.abs() * ea + ea * eb + U * p.abs() + U * s.abs(),
                );
            }
            sum
        }
        Dot3C(v, c) => {
            let mut sum = (0.0, 0.0);
            for k in 0..3 {
                let (va, ea) = reference(&v[k], t)?;
                let p = va * c[k];
                let s = sum.0 + p;
                sum = (s, sum.1 + ea * c[k].abs() + U * p.abs() + U * s.abs());
            }
            sum
        }
        Add(a, b) | Sub(a, b) | Mul(a, b) | Min(a, b) | Max(a, b) => {
            let (va, ea) = reference(a, t)?;
            let (vb, eb) = reference(b, t)?;
            match x {
                Add(..) => {
                    let s = va + vb;
                    (s, ea + eb + U * s.abs())
                }
                Sub(..) => {
                    let s = va - vb;
                    (s, ea + eb + U * s.abs())
                }
                Mul(..) => {
                    let p = va * vb;
                    (p, va.abs() * eb + vb.abs() * ea + ea * eb + U * p.abs())
                }
                Min(..) => (va.min(vb), ea.max(eb)),
                _ => (va.max(vb), ea.max(eb)),
            }
        }
    };
    (v.is_finite() && e.is_finite()).then_some((v, e))
}

/// Constants: mostly moderate, some exact special values, a few large.
fn scalar() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -3.0..3.0f64,
        1 => prop_oneof![Just(0.0), Just(1.0), Just(-1.0), Just(0.5)],
        1 => -100.0..100.0f64,
    ]
}

fn leaf() -> impl Strategy<Value = Expr> {
    prop_oneof![
        4 => Just(Time),
        3 => scalar().prop_map(Const),
        1 => (scalar(), 0.0..0.5f64).prop_map(|(c, r)| Uncertain(c - r, c + r)),
    ]
}

fn expr() -> impl Strategy<Value = Expr> {
    leaf().prop_recursive(5, 40, 2, |inner| {
        let b = |e: Expr| Box::new(e);
        prop_oneof![
            inner.clone().prop_map(move |a| Neg(b(a))),
            inner.clone().prop_map(move |a| Sqr(b(a))),
            inner.clone().prop_map(move |a| Sqrt(b(a))),
            inner.clone().prop_map(move |a| Recip(b(a))),
            inner.clone().prop_map(move |a| Abs(b(a))),
            inner.clone().prop_map(move |a| Sin(b(a))),
            inner.clone().prop_map(move |a| Cos(b(a))),
            (inner.clone(), scalar()).prop_map(move |(a, c)| AddC(b(a), c)),
            (inner.clone(), scalar()).prop_map(move |(a, c)| SubC(b(a), c)),
            (inner.clone(), scalar()).prop_map(move |(a, c)| MulC(b(a), c)),
            (inner.clone(), scalar(), 0.0..0.5f64).prop_map(move |(a, c, r)| Scale(
                b(a),
                c - r,
                c + r
            )),
            (inner.clone(), 0.0..0.1f64).prop_map(move |(a, r)| Widen(b(a), r)),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Add(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Sub(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Mul(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Min(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| Max(b(x), b(y))),
            prop::array::uniform6(inner.clone()).prop_map(|v| Dot3(Box::new(v))),
            prop::array::uniform4(inner.clone()).prop_map(|v| Dot2(Box::new(v))),
            (
                prop::array::uniform3(inner.clone()),
                prop::array::uniform3(scalar())
            )
                .prop_map(|(v, k)| Dot3C(Box::new(v), k)),
        ]
    })
}

/// Replace the `k`-th constant leaf (counting cyclically; the time leaf if
/// there is no constant) by a non-finite one with the given finite stand-in.
fn poison(x: &Expr, k: usize, bad: f64, stand_in: f64) -> Expr {
    fn count(x: &Expr) -> usize {
        match x {
            Const(_) | Uncertain(..) | Time | NonFinite(..) => 1,
            Neg(a) | Sqr(a) | Sqrt(a) | Recip(a) | Abs(a) | Sin(a) | Cos(a) => count(a),
            AddC(a, _) | SubC(a, _) | MulC(a, _) | Scale(a, ..) | Widen(a, _) => count(a),
            Add(a, b) | Sub(a, b) | Mul(a, b) | Min(a, b) | Max(a, b) => count(a) + count(b),
            Dot3(v) => v.iter().map(count).sum(),
            Dot2(v) => v.iter().map(count).sum(),
            Dot3C(v, _) => v.iter().map(count).sum(),
        }
    }
    fn go(x: &Expr, k: &mut usize, bad: f64, stand_in: f64) -> Expr {
        let b = Box::new;
        match x {
            Const(_) | Uncertain(..) | Time | NonFinite(..) => {
                let hit = *k == 0;
                *k = k.wrapping_sub(1);
                if hit {
                    NonFinite(bad, stand_in)
                } else {
                    x.clone()
                }
            }
            Neg(a) => Neg(b(go(a, k, bad, stand_in))),
            Sqr(a) => Sqr(b(go(a, k, bad, stand_in))),
            Sqrt(a) => Sqrt(b(go(a, k, bad, stand_in))),
            Recip(a) => Recip(b(go(a, k, bad, stand_in))),
            Abs(a) => Abs(b(go(a, k, bad, stand_in))),
            Sin(a) => Sin(b(go(a, k, bad, stand_in))),
            Cos(a) => Cos(b(go(a, k, bad, stand_in))),
            AddC(a, c) => AddC(b(go(a, k, bad, stand_in)), *c),
            SubC(a, c) => SubC(b(go(a, k, bad, stand_in)), *c),
            MulC(a, c) => MulC(b(go(a, k, bad, stand_in)), *c),
            Scale(a, lo, hi) => Scale(b(go(a, k, bad, stand_in)), *lo, *hi),
            Widen(a, r) => Widen(b(go(a, k, bad, stand_in)), *r),
            Add(x, y) => Add(b(go(x, k, bad, stand_in)), b(go(y, k, bad, stand_in))),
            Sub(x, y) => Sub(b(go(x, k, bad, stand_in)), b(go(y, k, bad, stand_in))),
            Mul(x, y) => Mul(b(go(x, k, bad, stand_in)), b(go(y, k, bad, stand_in))),
            Min(x, y) => Min(b(go(x, k, bad, stand_in)), b(go(y, k, bad, stand_in))),
            Max(x, y) => Max(b(go(x, k, bad, stand_in)), b(go(y, k, bad, stand_in))),
            Dot3(v) => Dot3(Box::new(v.each_ref().map(|x| go(x, k, bad, stand_in)))),
            Dot2(v) => Dot2(Box::new(v.each_ref().map(|x| go(x, k, bad, stand_in)))),
            Dot3C(v, c) => Dot3C(Box::new(v.each_ref().map(|x| go(x, k, bad, stand_in))), *c),
        }
    }
    let mut k = k % count(x);
    go(x, &mut k, bad, stand_in)
}

// ---------------------------------------------------------------------------
// Random nodes and times
// ---------------------------------------------------------------------------

/// A node `[lo, hi] ⊆ [0, 1]`: points, tiny, generic, the whole step.
fn node() -> impl Strategy<Value = TimeSpan> {
    prop_oneof![
        2 => (0.0..=1.0f64).prop_map(|t| TimeSpan::new(t, t)),
        2 => (0.0..=1.0f64, -16.0..-5.0f64).prop_map(|(a, lw)| {
            let w = 10f64.powf(lw);
            let lo = a * (1.0 - w);
            TimeSpan::new(lo, (lo + w).min(1.0))
        }),
        4 => (0.0..=1.0f64, 0.0..=1.0f64).prop_map(|(a, b)| TimeSpan::new(a.min(b), a.max(b))),
        1 => prop_oneof![
            Just(TimeSpan::STEP),
            Just(TimeSpan::new(0.0, 0.0)),
            Just(TimeSpan::new(1.0, 1.0)),
            Just(TimeSpan::new(0.0, 0.5)),
        ],
    ]
}

/// A fraction of a node: its ends often, else anywhere.
fn fraction() -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 1 => Just(1.0), 4 => 0.0..=1.0f64]
}

/// The point `lo + f·(hi − lo)`, kept inside `span`.
fn at(span: TimeSpan, f: f64) -> f64 {
    (span.lo + f * (span.hi - span.lo)).clamp(span.lo, span.hi)
}

// ---------------------------------------------------------------------------
// The containment check, generic over the arithmetic
// ---------------------------------------------------------------------------

/// `enc` (computed for the node `span`) holds the value of `x` at `t ∈ span`:
/// its range meets the rigorous interval value at the point node `[t, t]`,
/// holds the plain f64 value up to that value's rounding error (plus 1e-12
/// relative), and its linear lower bound lies below the value.
fn check_holds<E: Enclosure>(
    x: &Expr,
    enc: &E,
    span: TimeSpan,
    t: f64,
) -> Result<(), TestCaseError> {
    let range = enc.range();
    prop_assert!(
        !range.lo.is_nan() && !range.hi.is_nan() && range.lo <= range.hi,
        "{:?}: bad range {:?} of {:?}",
        E::KIND,
        range,
        enc
    );
    let point = eval::<Interval>(x, TimeSpan::new(t, t));
    if let Ok(p) = point {
        prop_assert!(
            p.lo <= range.hi && range.lo <= p.hi,
            "{:?} on [{:e}, {:e}]: range [{:e}, {:e}] misses the point value [{:e}, {:e}] at τ = {:e}\n{:?}",
            E::KIND,
            span.lo,
            span.hi,
            range.lo,
            range.hi,
            p.lo,
            p.hi,
            t,
            enc
        );
        // Linear lower bound (for clipping): a + b·e ≤ f(τ), e = (τ − m)/h.
        let (a, b) = enc.linear_lower();
        prop_assert!(
            !a.is_nan() && !b.is_nan(),
            "{:?}: NaN linear bound",
            E::KIND
        );
        let (m, h) = span.center_radius();
        let e = if h > 0.0 {
            ((t - m) / h).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let lower = a + b * e;
        let slack = 1e-12 * (1.0 + a.abs() + b.abs());
        prop_assert!(
            lower - slack <= p.hi,
            "{:?}: linear lower bound {:e} + {:e}·e = {:e} above the value [{:e}, {:e}] at τ = {:e}",
            E::KIND,
            a,
            b,
            lower,
            p.lo,
            p.hi,
            t
        );
    }
    if let Some((v, err)) = reference(x, t) {
        let tol = 1e-12 * v.abs().max(1.0) + 4.0 * err;
        prop_assert!(
            range.lo - tol <= v && v <= range.hi + tol,
            "{:?} on [{:e}, {:e}]: range [{:e}, {:e}] misses f64 value {:e} (± {:e}) at τ = {:e}\n{:?}",
            E::KIND,
            span.lo,
            span.hi,
            range.lo,
            range.hi,
            v,
            tol,
            t,
            enc
        );
    }
    Ok(())
}

/// Evaluate `x` over `span` in `E` and check it at `t`. Domain errors are
/// allowed (they are conservative); panics are not.
fn check_expr<E: Enclosure>(x: &Expr, span: TimeSpan, t: f64) -> Result<(), TestCaseError> {
    match eval::<E>(x, span) {
        Ok(enc) => check_holds(x, &enc, span, t),
        Err(CcdError::Domain { .. }) => Ok(()),
        Err(other) => Err(TestCaseError::fail(format!("unexpected error {other:?}"))),
    }
}

/// Evaluate on `from`, restrict to `to ⊆ from`, check at `t ∈ to`.
fn check_restrict<E: Enclosure>(
    x: &Expr,
    from: TimeSpan,
    to: TimeSpan,
    t: f64,
) -> Result<(), TestCaseError> {
    match eval::<E>(x, from) {
        Ok(enc) => {
            let sub = enc.restrict(from, to);
            check_holds(x, &sub, to, t)?;
            // Restricting must not lose the information it started with
            // beyond a rounding-level amount when the sub-node is the node.
            if to == from && enc.range().is_bounded() {
                let (a, b) = (enc.range(), sub.range());
                let w = a.width();
                prop_assert!(
                    b.width() <= 2.0 * w + 1e-9 * (1.0 + a.mag()),
                    "{:?}: restrict to the same node widened {:?} to {:?}",
                    E::KIND,
                    a,
                    b
                );
            }
            Ok(())
        }
        Err(CcdError::Domain { .. }) => Ok(()),
        Err(other) => Err(TestCaseError::fail(format!("unexpected error {other:?}"))),
    }
}

fn sub_node() -> impl Strategy<Value = (TimeSpan, TimeSpan, f64)> {
    (node(), fraction(), fraction(), fraction()).prop_map(|(from, a, b, f)| {
        let to = TimeSpan::new(at(from, a.min(b)), at(from, a.max(b)));
        (from, to, at(to, f))
    })
}

fn non_finite() -> impl Strategy<Value = f64> {
    prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]
}

/// `cases` per property unless `PROPTEST_CASES` asks for another number
/// (for a long soak run).
fn config(cases: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(cases);
    ProptestConfig::with_cases(cases)
}

macro_rules! property_tests {
    ($($name:ident: $E:ty),* $(,)?) => {$(
        mod $name {
            use super::*;

            proptest! {
                #![proptest_config(config(2000))]

                #[test]
                fn holds_point_values(x in expr(), (span, f) in (node(), fraction())) {
                    check_expr::<$E>(&x, span, at(span, f))?;
                }

                #[test]
                fn restrict_holds_point_values(x in expr(), (from, to, t) in sub_node()) {
                    check_restrict::<$E>(&x, from, to, t)?;
                }

                #[test]
                fn non_finite_inputs_hold_everything(
                    x in expr(),
                    k in 0usize..64,
                    bad in non_finite(),
                    stand_in in scalar(),
                    (span, f) in (node(), fraction()),
                ) {
                    let x = poison(&x, k, bad, stand_in);
                    // No panic, no NaN bound, and the value for the finite
                    // stand-in of the poisoned leaf is held.
                    check_expr::<$E>(&x, span, at(span, f))?;
                }
            }

            #[test]
            fn non_finite_constants_are_entire() {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let c = <$E>::constant(bad);
                    let r = c.range();
                    assert!(
                        r.lo == f64::NEG_INFINITY && r.hi == f64::INFINITY,
                        "{:?}: constant({bad}) has range {r:?}",
                        <$E>::KIND
                    );
                    let t = <$E>::time(TimeSpan::new(0.25, 0.75));
                    for (what, y) in [
                        ("c + τ", c + t),
                        ("c − τ", c - t),
                        ("c · τ", c * t),
                        ("c · 0", c * 0.0),
                        ("τ + c", t + bad),
                        ("τ · c", t * bad),
                    ] {
                        let r = y.range();
                        assert!(
                            r.lo == f64::NEG_INFINITY && r.hi == f64::INFINITY,
                            "{:?}: {what} with {bad}: {r:?}",
                            <$E>::KIND
                        );
                    }
                    // min(c, τ) may be anything up to τ's top, max anything
                    // down from τ's bottom; c² anything non-negative.
                    let (min, max, sqr) = (c.min(t).range(), c.max(t).range(), c.sqr().range());
                    assert!(min.lo == f64::NEG_INFINITY && min.hi >= 0.75, "min: {min:?}");
                    assert!(max.lo <= 0.25 && max.hi == f64::INFINITY, "max: {max:?}");
                    assert!(sqr.lo <= 0.0 && sqr.hi == f64::INFINITY, "sqr: {sqr:?}");
                    let abs = c.abs().range();
                    assert!(abs.lo <= 0.0 && abs.hi == f64::INFINITY, "abs: {abs:?}");
                    for y in [c.sin(), c.cos()] {
                        let r = y.range();
                        assert!(r.lo <= -1.0 && r.hi >= 1.0, "{:?}: sin/cos of {bad}: {r:?}", <$E>::KIND);
                    }
                    // sqrt of the whole line is [0, ∞) (clamped) or an error.
                    if let Ok(s) = c.sqrt() {
                        let r = s.range();
                        assert!(r.lo <= 0.0 && r.hi == f64::INFINITY, "sqrt of {bad}: {r:?}");
                    }
                    // recip of the whole line: it holds zero, so an error.
                    assert!(
                        matches!(c.recip(), Err(CcdError::Domain { .. })),
                        "{:?}: recip of {bad}: {:?}",
                        <$E>::KIND,
                        c.recip()
                    );
                    let (a, b) = c.linear_lower();
                    assert!(a == f64::NEG_INFINITY && !b.is_nan(), "linear_lower of {bad}: {a}, {b}");
                }
            }
        }
    )*};
}

property_tests! {
    interval: Interval,
    affine: Affine,
    taylor2: Taylor2,
    taylor3: Taylor3,
}

// ---------------------------------------------------------------------------
// Convergence order
// ---------------------------------------------------------------------------

/// f(τ) = sin(3τ + 1)·τ² − √(τ + 2) + 1/(τ + 1.5).
fn smooth<E: Enclosure>(span: TimeSpan) -> E {
    let t = E::time(span);
    (t * 3.0 + 1.0).sin() * t.sqr() - (t + 2.0).sqrt().unwrap() + (t + 1.5).recip().unwrap()
}

fn smooth_f64(t: f64) -> f64 {
    (3.0 * t + 1.0).sin() * t * t - (t + 2.0).sqrt() + 1.0 / (t + 1.5)
}

/// The true range width of `f` over `span` by 10,001 samples.
fn sampled_width(f: fn(f64) -> f64, span: TimeSpan) -> f64 {
    let n = 10_000;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=n {
        let t = span.lo + (span.hi - span.lo) * (i as f64 / n as f64);
        let v = f(t);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    hi - lo
}

/// Least-squares slope of `log2 y` against `log2 x`.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.log2(), y.log2())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// Excess widths of `E` on nodes of width 2^-k, k in `ks`, centred at `t0`,
/// and the fitted order.
fn convergence<E: Enclosure>(
    enc: fn(TimeSpan) -> E,
    f: fn(f64) -> f64,
    t0: f64,
    ks: std::ops::RangeInclusive<i32>,
) -> (f64, Vec<(f64, f64)>) {
    let mut points = Vec::new();
    for k in ks {
        let w = 2f64.powi(-k);
        let span = TimeSpan::new(t0 - w / 2.0, t0 + w / 2.0);
        let excess = enc(span).range().width() - sampled_width(f, span);
        assert!(
            excess >= 0.0,
            "{:?}: negative excess {excess:e} at width {w:e}",
            E::KIND
        );
        points.push((w, excess));
    }
    (log_slope(&points), points)
}

fn report(kind: &str, order: f64, points: &[(f64, f64)]) {
    let table: Vec<String> = points
        .iter()
        .map(|(w, x)| format!("{w:.2e}:{x:.2e}"))
        .collect();
    println!(
        "{kind:>8}: order {order:.2}  (width:excess) {}",
        table.join(" ")
    );
}

#[test]
fn convergence_orders() {
    let t0 = 0.4;
    let (o, p) = convergence::<Interval>(smooth, smooth_f64, t0, 2..=10);
    report("interval", o, &p);
    let (o1, p1) = convergence::<Affine>(smooth, smooth_f64, t0, 2..=10);
    report("affine", o1, &p1);
    let (o2, p2) = convergence::<Taylor2>(smooth, smooth_f64, t0, 2..=10);
    report("taylor2", o2, &p2);
    let (o3, p3) = convergence::<Taylor3>(smooth, smooth_f64, t0, 2..=10);
    report("taylor3", o3, &p3);
    assert!((0.7..=1.4).contains(&o), "interval order {o:.3}: {p:?}");
    assert!(o1 > 1.6, "affine order {o1:.3}: {p1:?}");
    assert!(o2 > 2.5, "taylor2 order {o2:.3}: {p2:?}");
    assert!(o3 > 3.4, "taylor3 order {o3:.3}: {p3:?}");
}

/// g(τ) = sin(4τ) + τ²/2, which turns at τ* ≈ 0.41893 (4·cos 4τ* + τ* = 0).
fn turning<E: Enclosure>(span: TimeSpan) -> E {
    let t = E::time(span);
    (t * 4.0).sin() + t.sqr() * 0.5
}

fn turning_f64(t: f64) -> f64 {
    (4.0 * t).sin() + 0.5 * t * t
}

/// The same orders on nodes that hold a critical point of the function
/// (a grazing contact), off their centre: Taylor models used to fall to
/// order 2 there (their range bounded each term on its own).
#[test]
fn convergence_orders_at_a_critical_point() {
    let (mut a, mut b) = (0.3f64, 0.5f64);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if 4.0 * (4.0 * m).cos() + m > 0.0 {
            a = m
        } else {
            b = m
        }
    }
    let crit = 0.5 * (a + b);
    for offset in [0.0, 0.25, 0.45] {
        // Node centres at crit + offset·w: the critical point stays inside.
        let orders = [
            order_at::<Interval>(turning, crit, offset),
            order_at::<Affine>(turning, crit, offset),
            order_at::<Taylor2>(turning, crit, offset),
            order_at::<Taylor3>(turning, crit, offset),
        ];
        println!("critical point, node centre offset {offset}·w: orders {orders:.2?}");
        let [o, o1, o2, o3] = orders;
        assert!(
            (0.7..=1.4).contains(&o),
            "interval order {o:.3} at offset {offset}"
        );
        assert!(o1 > 1.6, "affine order {o1:.3} at offset {offset}");
        assert!(o2 > 2.5, "taylor2 order {o2:.3} at offset {offset}");
        assert!(o3 > 3.4, "taylor3 order {o3:.3} at offset {offset}");
    }
}

/// The fitted order of `E` on nodes of width 2^-2 … 2^-10 centred at
/// `t0 + offset·w`.
fn order_at<E: Enclosure>(enc: fn(TimeSpan) -> E, t0: f64, offset: f64) -> f64 {
    let points: Vec<(f64, f64)> = (2..=10)
        .map(|k| {
            let w = 2f64.powi(-k);
            let c = t0 + offset * w;
            let span = TimeSpan::new(c - w / 2.0, c + w / 2.0);
            let excess = enc(span).range().width() - sampled_width(turning_f64, span);
            assert!(
                excess >= 0.0,
                "{:?}: negative excess {excess:e} at width {w:e}",
                E::KIND
            );
            (w, excess)
        })
        .collect();
    log_slope(&points)
}

// ---------------------------------------------------------------------------
// Taylor range of a bare polynomial: sound and (degree ≤ 3) exact
// ---------------------------------------------------------------------------

fn coefficient() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1.0..1.0f64,
        1 => Just(0.0),
        1 => -1e-9..1e-9f64,
        1 => -1e3..1e3f64,
    ]
}

/// Coefficients of a cubic: random, or with a double critical point
/// (`c2² = 3·c1·c3`, the discriminant of `p′` zero up to rounding).
fn cubic() -> impl Strategy<Value = [f64; 4]> {
    prop_oneof![
        3 => [coefficient(), coefficient(), coefficient(), coefficient()],
        1 => (coefficient(), coefficient(), coefficient()).prop_map(|(c0, c2, c3)| {
            let c1 = if c3 == 0.0 { 0.0 } else { c2 * c2 / (3.0 * c3) };
            [c0, c1, c2, c3]
        }),
        1 => (coefficient(), -1.0..1.0f64, coefficient(), coefficient()).prop_map(|(c0, e, c2, c3)| {
            // A critical point at e (p′(e) = 0).
            [c0, -(2.0 * c2 * e + 3.0 * c3 * e * e), c2, c3]
        }),
    ]
}

/// The range of `p` holds `p(e)` for 2,001 sampled `e` (enclosed by interval
/// Horner at the point) and is no wider than the sampled range plus the
/// sampling error and rounding.
fn check_poly_range<const K: usize>(c: [f64; K]) -> Result<(), TestCaseError> {
    let p = Taylor::<K> { c, r: 0.0 };
    let range = p.range();
    let n = 2000;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=n {
        let e = -1.0 + 2.0 * (i as f64) / (n as f64);
        let mut v = Interval::point(c[K - 1]);
        for k in (0..K - 1).rev() {
            v = v * Interval::point(e) + Interval::point(c[k]);
        }
        prop_assert!(
            v.lo <= range.hi && range.lo <= v.hi,
            "Taylor<{K}> {c:?}: range {range:?} misses p({e}) ∈ {v:?}"
        );
        lo = lo.min(v.mid());
        hi = hi.max(v.mid());
    }
    let scale: f64 = c.iter().map(|x| x.abs()).sum();
    // Between samples (spacing 1e-3) p exceeds them by ≤ max|p″|·(5e-4)²/2
    // at each end of its range.
    let slack = (2.0 * c[2].abs() + if K > 3 { 6.0 * c[3].abs() } else { 0.0 }) * 2.6e-7
        + 1e-12 * scale
        + 1e-300;
    prop_assert!(
        range.width() <= (hi - lo) + slack,
        "Taylor<{K}> {c:?}: range {range:?} (width {:e}) vs sampled [{lo:e}, {hi:e}] (width {:e})",
        range.width(),
        hi - lo
    );
    Ok(())
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn taylor2_range_is_sound_and_exact(c in cubic()) {
        check_poly_range::<3>([c[0], c[1], c[2]])?;
    }

    #[test]
    fn taylor3_range_is_sound_and_exact(c in cubic()) {
        check_poly_range::<4>(c)?;
    }
}

// ---------------------------------------------------------------------------
// Rounding: one operation on floats holds the exact real result
// ---------------------------------------------------------------------------

/// `lo ≤ s + e ≤ hi` exactly, where `s + e` is an exact sum with `s` its
/// rounding to nearest (so `s + e` lies strictly inside `s`'s neighbours).
fn holds_exact(range: Interval, s: f64, e: f64) -> bool {
    (range.lo < s || (range.lo == s && e >= 0.0)) && (range.hi > s || (range.hi == s && e <= 0.0))
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// Floats over a wide range of exponents, away from overflow and underflow
/// (where the error-free transformations are no longer exact).
fn wide_float() -> impl Strategy<Value = f64> {
    (-1.0..1.0f64, -60i32..60).prop_map(|(m, x)| m * 2f64.powi(x))
}

fn check_rounding<E: Enclosure>(a: f64, b: f64, t: TimeSpan) -> Result<(), TestCaseError> {
    let (ca, cb) = (E::constant(a), E::constant(b));
    let cases = [
        ("a + b", (ca + cb).range(), two_sum(a, b)),
        ("a − b", (ca - cb).range(), two_sum(a, -b)),
        ("a · b", (ca * cb).range(), two_prod(a, b)),
        ("a + (f64) b", (ca + b).range(), two_sum(a, b)),
        ("a − (f64) b", (ca - b).range(), two_sum(a, -b)),
        ("a · (f64) b", (ca * b).range(), two_prod(a, b)),
        ("a²", ca.sqr().range(), two_prod(a, a)),
        ("τ(lo) · b", (E::time(t) * b).range(), two_prod(t.lo, b)),
        ("τ(hi) · b", (E::time(t) * b).range(), two_prod(t.hi, b)),
        ("τ(lo) + b", (E::time(t) + b).range(), two_sum(t.lo, b)),
        ("τ(hi) + b", (E::time(t) + b).range(), two_sum(t.hi, b)),
    ];
    for (what, range, (s, e)) in cases {
        prop_assert!(
            holds_exact(range, s, e),
            "{:?}: {what} with a = {a:e}, b = {b:e}, τ ∈ [{:e}, {:e}]: {range:?} misses {s:e} + {e:e}",
            E::KIND,
            t.lo,
            t.hi
        );
    }
    let x = a.abs();
    if x > 0.0 {
        // √x: the sign of fl(√x)² − x tells on which side of √x the float is.
        let s = x.sqrt();
        let side = s.mul_add(s, -x);
        let r = E::constant(x).sqrt().unwrap().range();
        let ok =
            (r.lo < s || (r.lo == s && side <= 0.0)) && (r.hi > s || (r.hi == s && side >= 0.0));
        prop_assert!(ok, "{:?}: sqrt({x:e}) = {r:?}, f64 {s:e}", E::KIND);
        // 1/x: the sign of fl(1/x)·x − 1.
        let q = 1.0 / x;
        let side = q.mul_add(x, -1.0);
        let r = E::constant(x).recip().unwrap().range();
        let ok =
            (r.lo < q || (r.lo == q && side <= 0.0)) && (r.hi > q || (r.hi == q && side >= 0.0));
        prop_assert!(ok, "{:?}: 1/{x:e} = {r:?}, f64 {q:e}", E::KIND);
    }
    Ok(())
}

fn unit_span() -> impl Strategy<Value = TimeSpan> {
    (0.0..=1.0f64, 0.0..=1.0f64).prop_map(|(a, b)| TimeSpan::new(a.min(b), a.max(b)))
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn rounding_is_enclosed(a in wide_float(), b in wide_float(), t in unit_span()) {
        check_rounding::<Interval>(a, b, t)?;
        check_rounding::<Affine>(a, b, t)?;
        check_rounding::<Taylor2>(a, b, t)?;
        check_rounding::<Taylor3>(a, b, t)?;
    }
}

// ---------------------------------------------------------------------------
// The write-up's examples
// ---------------------------------------------------------------------------

fn x_minus_x2<E: Enclosure>() -> Interval {
    let x = E::time(TimeSpan::STEP);
    (x - x * x).range()
}

#[test]
fn writeup_x_minus_x_squared() {
    let iv = x_minus_x2::<Interval>();
    assert!(
        iv.lo <= -1.0 && iv.hi >= 1.0 && iv.width() <= 2.0 + 1e-12,
        "interval: {iv:?}"
    );
    let af = x_minus_x2::<Affine>();
    assert!(
        af.lo <= 0.0 && af.hi >= 0.25 && af.width() <= 0.5,
        "affine: {af:?}"
    );
    for (kind, r) in [
        ("taylor2", x_minus_x2::<Taylor2>()),
        ("taylor3", x_minus_x2::<Taylor3>()),
    ] {
        assert!(
            r.lo <= 0.0 && r.hi >= 0.25 && r.width() <= 0.25 + 1e-9,
            "{kind}: {r:?}"
        );
    }
}

#[test]
fn writeup_sine_series() {
    // On [−1, 1] the local symbol e is τ itself.
    let span = TimeSpan::new(-1.0, 1.0);
    // (h is rounded up by one ulp: e = τ/(1 + 2⁻⁵²), harmless at 1e-10.)
    let (m, h) = span.center_radius();
    assert!(m == 0.0 && (h - 1.0).abs() <= 1e-15, "m = {m}, h = {h}");
    let s = (Taylor3::time(span) * 0.1 + 2.0).sin();
    // The write-up's numbers (signs corrected, docs/design.md §1), and the exact
    // Taylor coefficients f⁽ᵏ⁾(0)/k! of sin(2 + 0.1τ).
    let writeup = [
        0.909297426826,
        -0.0416146836547,
        -0.00454648713413,
        6.93578060913e-5,
    ];
    let exact = [
        2f64.sin(),
        0.1 * 2f64.cos(),
        -0.01 * 2f64.sin() / 2.0,
        -0.001 * 2f64.cos() / 6.0,
    ];
    for k in 0..4 {
        assert!(
            (s.c[k] - exact[k]).abs() <= 1e-10,
            "c[{k}] = {:e}, expected {:e}",
            s.c[k],
            exact[k]
        );
        assert!(
            (s.c[k] - writeup[k]).abs() <= 1e-10,
            "c[{k}] = {:e}, write-up {:e}",
            s.c[k],
            writeup[k]
        );
    }
    // The remainder must cover the dropped terms (from 0.1⁴·sin(2)/24 ≈
    // 3.8e-6 at e = ±1) and need not exceed the Lagrange bound 0.1⁴/4!.
    let mut dev: f64 = 0.0;
    for i in 0..=2000 {
        let e = -1.0 + i as f64 / 1000.0;
        let p = s.c[0] + e * (s.c[1] + e * (s.c[2] + e * s.c[3]));
        dev = dev.max(((2.0 + 0.1 * e).sin() - p).abs());
    }
    let lagrange = 1e-4 / 24.0;
    assert!(
        s.r >= dev && s.r <= lagrange * (1.0 + 1e-6) + 1e-12,
        "remainder {:e}: true deviation {dev:e}, Lagrange bound {lagrange:e}",
        s.r
    );
    println!(
        "sin(2 + 0.1τ): c = {:?}, r = {:e}, max deviation {dev:e}",
        s.c, s.r
    );
}

// ---------------------------------------------------------------------------
// Typed errors
// ---------------------------------------------------------------------------

fn domain_errors<E: Enclosure>() {
    let span = TimeSpan::new(0.25, 0.75);
    let t = E::time(span);
    let negative = t - 2.0; // [−1.75, −1.25]
    match negative.sqrt() {
        Err(CcdError::Domain { operation, lo, hi }) => {
            assert_eq!(operation, "sqrt");
            assert!(
                lo <= -1.75 && (-1.25..0.0).contains(&hi),
                "{:?}: [{lo}, {hi}]",
                E::KIND
            );
        }
        other => panic!("{:?}: sqrt of a negative range gave {other:?}", E::KIND),
    }
    assert!(matches!(
        E::constant(-1.0).sqrt(),
        Err(CcdError::Domain { .. })
    ));
    // A range reaching below zero is clamped, not an error.
    let straddle = t - 0.5;
    let root = straddle
        .sqrt()
        .expect("sqrt of a range reaching below zero is clamped");
    let r = root.range();
    // τ − 0.5 ∈ [−0.25, 0.25]: the root of its non-negative part, [0, 0.5].
    assert!(r.lo <= 0.0 && r.hi >= 0.5, "{:?}: {r:?}", E::KIND);
    // sqrt of exactly zero is zero.
    let z = E::constant(0.0).sqrt().expect("sqrt(0)").range();
    assert!(z.lo <= 0.0 && z.hi >= 0.0, "{:?}: sqrt(0) = {z:?}", E::KIND);

    for (what, x) in [
        ("τ − 0.5", straddle),
        ("0", E::constant(0.0)),
        ("[−1, 1]", E::from_interval(Interval::new(-1.0, 1.0))),
        ("τ − 0.25 (zero at the end)", t - 0.25),
    ] {
        match x.recip() {
            Err(CcdError::Domain { operation, lo, hi }) => {
                assert_eq!(operation, "recip");
                assert!(
                    lo <= 0.0 && hi >= 0.0,
                    "{:?}: recip of {what}: [{lo}, {hi}]",
                    E::KIND
                );
            }
            other => panic!("{:?}: recip of {what} gave {other:?}", E::KIND),
        }
    }
    // Defined cases succeed.
    let inv = (t + 1.0).recip().expect("recip of [1.25, 1.75]").range();
    assert!(
        inv.lo <= 1.0 / 1.75 && inv.hi >= 0.8,
        "{:?}: {inv:?}",
        E::KIND
    );
    let neg_inv = (-t).recip().expect("recip of [−0.75, −0.25]").range();
    assert!(
        neg_inv.lo <= -4.0 && neg_inv.hi >= -1.0 / 0.75,
        "{:?}: {neg_inv:?}",
        E::KIND
    );
}

#[test]
fn typed_domain_errors() {
    domain_errors::<Interval>();
    domain_errors::<Affine>();
    domain_errors::<Taylor2>();
    domain_errors::<Taylor3>();
}
