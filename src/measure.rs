//! Error measures that fail on NaN.
//!
//! `f64::max` and `f64::min` return the other operand when one is NaN, so a running maximum of
//! errors folded with `f64::max` (or `m = m.max(e)`) silently drops a NaN and a check on it
//! passes.
//! Every largest-error measure in the code and its tests goes through these instead; scripts/test
//! greps for the NaN-blind forms so they do not come back.

/// max(a, b), NaN when either operand is NaN.
pub fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// min(a, b), NaN when either operand is NaN.
pub fn nan_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

/// True when `value` exceeds `bound` or is NaN: the failing side of a check `value <= bound`.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // the negation is the point: NaN compares false
pub fn exceeds(value: f64, bound: f64) -> bool {
    !(value <= bound)
}

/// The largest of nonnegative measures (0 for none), NaN if any is NaN.
pub fn largest(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(0.0, nan_max)
}

/// The largest absolute value (0 for none), NaN if any is NaN.
pub fn largest_abs<'a>(values: impl IntoIterator<Item = &'a f64>) -> f64 {
    largest(values.into_iter().map(|x| x.abs()))
}

/// The smallest value (+inf for none), NaN if any is NaN.
pub fn smallest(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(f64::INFINITY, nan_min)
}

/// The largest value (-inf for none), NaN if any is NaN: for signed quantities.
pub fn greatest(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(f64::NEG_INFINITY, nan_max)
}

/// The largest |a_i - b_i|; NaN if any operand is NaN or the lengths differ.
pub fn max_abs_difference(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    largest(a.iter().zip(b).map(|(x, y)| (x - y).abs()))
}

/// The range (min, max) of the finite values, ignoring NaN and infinities on purpose: for the
/// axes of a figure, which must still be drawn when a series holds a non-finite value. `None`
/// when no value is finite.
pub fn finite_range<'a>(values: impl IntoIterator<Item = &'a f64>) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|x| x.is_finite())
        .fold(None, |r, &x| match r {
            None => Some((x, x)),
            Some((lo, hi)) => Some((if x < lo { x } else { lo }, if x > hi { x } else { hi })),
        })
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn a_nan_anywhere_makes_the_measure_nan() {
        for pos in 0..3 {
            let mut v = vec![1.0, 2.0, 3.0];
            v[pos] = f64::NAN;
            assert!(largest(v.iter().copied()).is_nan(), "NaN at {pos}");
            assert!(largest_abs(&v).is_nan());
            assert!(smallest(v.iter().copied()).is_nan());
            assert!(greatest(v.iter().copied()).is_nan());
        }
        // The broken pattern this replaces: a NaN followed by a finite value is lost.
        #[allow(clippy::disallowed_methods)] // the pattern shown to be broken
        let keep_nan_then_max = |m: f64, d: f64| match d.is_nan() {
            true => d,
            false => m.max(d),
        };
        let lost = [f64::NAN, 1.0].into_iter().fold(0.0, keep_nan_then_max);
        assert_eq!(lost, 1.0);
        assert!(largest([f64::NAN, 1.0]).is_nan());
        assert!(exceeds(f64::NAN, 1.0) && exceeds(2.0, 1.0) && !exceeds(1.0, 1.0));
    }

    #[test]
    fn finite_values_give_the_ordinary_extremes() {
        assert_eq!(largest([0.5, 3.0, 2.0]), 3.0);
        assert_eq!(largest_abs(&[-4.0, 3.0]), 4.0);
        assert_eq!(smallest([0.5, -3.0, 2.0]), -3.0);
        assert_eq!(greatest([-0.5, -3.0]), -0.5);
        assert_eq!(largest(std::iter::empty()), 0.0);
        assert_eq!(max_abs_difference(&[1.0, 2.0], &[1.5, 2.0]), 0.5);
        assert!(max_abs_difference(&[1.0], &[1.0, 2.0]).is_nan());
        assert_eq!(
            finite_range(&[f64::NAN, 2.0, -1.0, f64::INFINITY]),
            Some((-1.0, 2.0))
        );
        assert_eq!(finite_range(&[f64::NAN]), None);
    }
}
