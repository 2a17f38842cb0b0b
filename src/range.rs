//! A swept axis of a scene: a list of values, or `from`, `to` and `points` evenly spaced.
//! The `[sweep]` table and every axis of `[matrix.axes]` are written this way.

use crate::invalid::InvalidSetting;
use crate::measure::{greatest, smallest};
use serde::{Deserialize, Serialize};

/// One axis: a list of values, or `from`, `to` (and `points`, for a grid).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisRange {
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<usize>,
}

impl AxisRange {
    /// A listed axis.
    pub fn listed(values: Vec<f64>) -> Self {
        AxisRange {
            values,
            ..Default::default()
        }
    }

    /// `points` values evenly spaced from `from` to `to`.
    pub fn spaced(from: f64, to: f64, points: usize) -> Self {
        AxisRange {
            values: Vec::new(),
            from: Some(from),
            to: Some(to),
            points: Some(points),
        }
    }

    /// The grid values of this axis: the list when given, else `points` evenly spaced from
    /// `from` to `to` (one point when from = to); empty when neither is complete.
    pub fn values(&self) -> Vec<f64> {
        if !self.values.is_empty() {
            return self.values.clone();
        }
        match (self.from, self.to, self.points) {
            (Some(a), Some(b), Some(1)) if a == b => vec![a],
            (Some(a), Some(b), Some(n)) if n >= 2 => (0..n)
                .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The range sampled (smallest, largest value).
    pub fn range(&self) -> (f64, f64) {
        match (self.from, self.to) {
            (Some(a), Some(b)) => (smallest([a, b]), greatest([a, b])),
            _ => {
                let v = &self.values;
                (smallest(v.iter().copied()), greatest(v.iter().copied()))
            }
        }
    }

    /// The checks every axis shares, under the scene key `key`: a list or a range, not both;
    /// at most `max_points` points (checked before any value is made, so a huge count is
    /// never allocated).
    pub fn check_form(&self, key: &str, max_points: usize) -> Result<(), InvalidSetting> {
        let has_range = self.from.is_some() || self.to.is_some() || self.points.is_some();
        if !self.values.is_empty() && has_range {
            let detail = ": give either 'values' or 'from'/'to'/'points', not both";
            return Err(InvalidSetting::new(key, detail));
        }
        if let Some(n) = self.points.filter(|&n| n > max_points) {
            let detail = format!(" = {n}: at most {max_points} (each point is a solve)");
            return Err(InvalidSetting::new(format!("{key}.points"), detail));
        }
        Ok(())
    }

    /// The first listed value or range end that `admits` refuses.
    pub fn first_refused(&self, admits: impl Fn(f64) -> bool) -> Option<f64> {
        let ends = [self.from, self.to].into_iter().flatten();
        self.values
            .iter()
            .copied()
            .chain(ends)
            .find(|&v| !admits(v))
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn spaced_values_end_on_both_ends_and_a_single_point_needs_equal_ends() {
        let v = AxisRange::spaced(0.0, 0.5, 6).values();
        assert_eq!(v.len(), 6);
        assert_eq!(v[0], 0.0);
        assert!((v[5] - 0.5).abs() < 1e-15);
        assert_eq!(AxisRange::spaced(2.0, 2.0, 1).values(), vec![2.0]);
        assert!(AxisRange::spaced(1.0, 2.0, 1).values().is_empty());
        assert_eq!(AxisRange::listed(vec![3.0, 1.0]).range(), (1.0, 3.0));
    }

    #[test]
    fn a_list_and_a_range_together_and_too_many_points_are_refused_by_key() {
        let both = AxisRange {
            values: vec![1.0],
            points: Some(3),
            ..Default::default()
        };
        assert_eq!(both.check_form("sweep", 10).unwrap_err().key, "sweep");
        let huge = AxisRange::spaced(0.0, 1.0, 1 << 40);
        assert_eq!(
            huge.check_form("sweep", 10).unwrap_err().key,
            "sweep.points"
        );
        let refused = AxisRange::listed(vec![0.1, f64::NAN]).first_refused(f64::is_finite);
        assert!(refused.is_some_and(f64::is_nan));
    }
}
