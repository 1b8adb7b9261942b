//! What every factorization here does with a pivot: the one error type and the one rule
//! for a constraint that depends on those eliminated before it.
//!
//! A chain's tridiagonal system has no dependent edge, so a pivot near zero there is an
//! error ([`usable`]). A tree's or graph's system (SPD, `sparse`) and
//! the contact Newton's quasi-definite one (`supernodal`) can hold
//! edges that are exact combinations of others (a braced square in 2D): such an edge's
//! pivot is zero up to round-off, and its unknown is dropped (its multiplier is zero),
//! so a consistent set of redundant constraints is still met by the others.

/// A pivot below this fraction of its scale marks a dependent constraint.
pub const DEPENDENT_PIVOT: f64 = 1e-10;

/// A zero or non-finite pivot met at `row` (or one of the wrong sign where the matrix
/// fixes it): the system is singular, for example an edge of zero length whose
/// constraint has no direction, or not quasi-definite in the order given (a bug in the
/// caller's numbering, or values that overflowed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SingularPivot {
    /// The row (unknown, in elimination order) where elimination broke down.
    pub row: usize,
}

/// What to do with a pivot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pivot {
    /// Divide by it.
    Keep,
    /// Its constraint depends on earlier ones: drop its unknown.
    Drop,
    /// Not finite, or of the wrong sign where nothing may be dropped: an error.
    Fail,
}

/// A pivot of a chain's system: finite and not zero against its row's `scale`.
#[inline]
pub fn usable(pivot: f64, scale: f64) -> bool {
    pivot.abs() > 1e-14 * scale && pivot.abs() < f64::INFINITY
}

/// A pivot of a symmetric positive definite system whose unknowns are all constraints:
/// `scale` is its unknown's original diagonal.
#[inline]
pub fn positive_definite(pivot: f64, scale: f64) -> Pivot {
    if !pivot.is_finite() {
        Pivot::Fail
    } else if pivot <= DEPENDENT_PIVOT * scale || pivot <= 0.0 {
        Pivot::Drop
    } else {
        Pivot::Keep
    }
}

/// A pivot of a quasi-definite system: positive for a particle's unknown, negative for
/// a constraint's (`negative`), which alone may be dropped. `scale` is the unknown's
/// natural pivot size.
#[inline]
pub fn quasi_definite(pivot: f64, scale: f64, negative: bool) -> Pivot {
    let wrong_sign = if negative { pivot >= 0.0 } else { pivot <= 0.0 };
    if negative && (pivot.abs() <= DEPENDENT_PIVOT * scale || wrong_sign) {
        Pivot::Drop
    } else if wrong_sign || !pivot.is_finite() {
        Pivot::Fail
    } else {
        Pivot::Keep
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pivot_is_kept_dropped_or_an_error_by_its_size_and_sign() {
        assert_eq!(positive_definite(1.0, 1.0), Pivot::Keep);
        assert_eq!(positive_definite(1e-12, 1.0), Pivot::Drop);
        assert_eq!(positive_definite(-1.0, 1.0), Pivot::Drop);
        assert_eq!(positive_definite(f64::NAN, 1.0), Pivot::Fail);
        assert_eq!(quasi_definite(-1.0, 1.0, true), Pivot::Keep);
        assert_eq!(quasi_definite(-1e-12, 1.0, true), Pivot::Drop);
        assert_eq!(quasi_definite(1.0, 1.0, true), Pivot::Drop);
        assert_eq!(quasi_definite(-1.0, 1.0, false), Pivot::Fail);
        assert_eq!(quasi_definite(f64::INFINITY, 1.0, false), Pivot::Fail);
        assert_eq!(quasi_definite(f64::NAN, 1.0, true), Pivot::Fail);
        assert!(usable(1.0, 1.0) && !usable(1e-15, 1.0) && !usable(f64::INFINITY, 1.0));
    }
}
