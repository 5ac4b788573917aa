//! Range checks shared by the estimators' parameter tables (`mekf`, `pf`):
//! each table's error type converts from [`OutOfRange`].

/// A parameter that is NaN, infinite or outside its range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutOfRange {
    /// The field's name.
    pub name: &'static str,
    /// The value given.
    pub value: f64,
    /// The allowed range, in words.
    pub range: &'static str,
}

/// `lo <= value <= hi` (or `lo < value` when `open_low`), false for NaN.
pub fn in_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    open_low: bool,
    range: &'static str,
) -> Result<f64, OutOfRange> {
    let low_ok = if open_low { value > lo } else { value >= lo };
    if low_ok && value <= hi {
        Ok(value)
    } else {
        Err(OutOfRange { name, value, range })
    }
}

/// A value in [0, 1e6].
pub fn nonneg(name: &'static str, value: f64) -> Result<f64, OutOfRange> {
    in_range(name, value, 0.0, 1e6, false, "[0, 1e6]")
}

/// A value in (0, 1e6].
pub fn positive(name: &'static str, value: f64) -> Result<f64, OutOfRange> {
    in_range(name, value, 0.0, 1e6, true, "(0, 1e6]")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_and_nan() {
        assert_eq!(nonneg("a", 0.0), Ok(0.0));
        assert!(positive("a", 0.0).is_err());
        assert!(nonneg("a", f64::NAN).is_err());
        assert!(nonneg("a", 2e6).is_err());
        assert_eq!(in_range("a", 1.0, 0.0, 1.0, true, "(0, 1]"), Ok(1.0));
    }
}
