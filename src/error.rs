//! The one error type of the crate.
//!
//! Every public entry returns `Result<_, CcdError>` instead of panicking on bad
//! input: non-finite numbers, parameters out of range, shapes we cannot handle.

use std::fmt;

/// Why a query or an operation could not be answered.
#[derive(Clone, Debug, PartialEq)]
pub enum CcdError {
    /// An input number is NaN or infinite. `what` names the input.
    NonFinite { what: &'static str, value: f64 },
    /// A parameter is out of its allowed range. `what` names it, `expected`
    /// says the range.
    BadParameter {
        what: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// An enclosure operation is undefined on the range it was given
    /// (square root of a possibly negative value, reciprocal of a range that
    /// contains zero).
    Domain {
        operation: &'static str,
        lo: f64,
        hi: f64,
    },
    /// A shape kind (or pair of kinds) this crate does not handle.
    Unsupported { what: String },
}

impl fmt::Display for CcdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CcdError::NonFinite { what, value } => {
                write!(f, "{what} is not finite ({value})")
            }
            CcdError::BadParameter {
                what,
                value,
                expected,
            } => write!(f, "{what} = {value} is out of range: expected {expected}"),
            CcdError::Domain { operation, lo, hi } => {
                write!(f, "{operation} is undefined on [{lo}, {hi}]")
            }
            CcdError::Unsupported { what } => write!(f, "unsupported: {what}"),
        }
    }
}

impl std::error::Error for CcdError {}

/// `Ok(value)` when `value` is finite, else a `NonFinite` error naming it.
pub fn check_finite(what: &'static str, value: f64) -> Result<f64, CcdError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(CcdError::NonFinite { what, value })
    }
}
