//! Parameter sweeps of the complex modes: the scene's `[sweep]` (friction coefficient, brake
//! pressure, disc speed, exponential-law p0 or lambda), and mode tracking across the points
//! by MAC so every track is one physical mode (the coalescence picture).

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

pub use crate::contact::vary::LawMismatch;
use crate::contact::vary::{set_law_parameter, LawParameter};
use crate::contact::ResolvedInterface;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepParameter {
    /// Friction coefficient of the sliding interfaces.
    Mu,
    PressureBar,
    /// rad/s.
    DiscSpeed,
    /// p0 of the sliding interfaces' exponential law (Pa).
    P0,
    /// lambda of the sliding interfaces' exponential law (1/m).
    Lambda,
}

impl SweepParameter {
    pub fn name(self) -> &'static str {
        match self {
            SweepParameter::Mu => "mu",
            SweepParameter::PressureBar => "pressure_bar",
            SweepParameter::DiscSpeed => "disc_speed",
            SweepParameter::P0 => "p0",
            SweepParameter::Lambda => "lambda",
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            SweepParameter::Mu => "friction coefficient mu (1)",
            SweepParameter::PressureBar => "brake pressure (bar)",
            SweepParameter::DiscSpeed => "disc speed (rad/s)",
            SweepParameter::P0 => "p0 (Pa)",
            SweepParameter::Lambda => "lambda (1/m)",
        }
    }
}

/// The `[sweep]` table: a parameter and its values (a list, or `from`, `to`, `points`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSettings {
    pub parameter: SweepParameter,
    #[serde(default)]
    pub values: Vec<f64>,
    #[serde(default)]
    pub from: Option<f64>,
    #[serde(default)]
    pub to: Option<f64>,
    #[serde(default)]
    pub points: Option<usize>,
}

impl SweepSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        // Checked before the values are made: a huge count would be allocated first.
        if let Some(n) = self.points.filter(|&n| n > MAX_SWEEP_POINTS) {
            return Err(InvalidSetting::new(
                "sweep.points",
                format!(" = {n}: at most {MAX_SWEEP_POINTS} (each point re-solves the preload)"),
            ));
        }
        let values = self.values();
        if values.is_empty() {
            return Err(InvalidSetting::new(
                "sweep",
                ": give 'values = [...]' or 'from', 'to' and 'points' (at least 2)",
            ));
        }
        if !self.values.is_empty() && (self.from.is_some() || self.to.is_some()) {
            return Err(InvalidSetting::new(
                "sweep",
                ": give either 'values' or 'from'/'to'/'points', not both",
            ));
        }
        for v in &values {
            let ok = v.is_finite()
                && match self.parameter {
                    SweepParameter::Mu => *v >= 0.0,
                    _ => *v > 0.0,
                };
            if !ok {
                return Err(InvalidSetting::new(
                    "sweep.values",
                    format!(
                        ": {v} is not a valid {} (finite, {})",
                        self.parameter.name(),
                        if self.parameter == SweepParameter::Mu {
                            "non-negative"
                        } else {
                            "positive"
                        }
                    ),
                ));
            }
        }
        Ok(())
    }

    pub fn values(&self) -> Vec<f64> {
        listed_or_spaced(&self.values, self.from, self.to, self.points)
    }
}

/// The most points a sweep takes from `from`/`to`/`points`.
pub const MAX_SWEEP_POINTS: usize = 1 << 16;

/// The values of a swept axis: the list when given, else `points` evenly spaced from `from`
/// to `to` (one point when from = to); empty when neither is complete.
pub fn listed_or_spaced(
    values: &[f64],
    from: Option<f64>,
    to: Option<f64>,
    points: Option<usize>,
) -> Vec<f64> {
    if !values.is_empty() {
        return values.to_vec();
    }
    match (from, to, points) {
        (Some(a), Some(b), Some(1)) if a == b => vec![a],
        (Some(a), Some(b), Some(n)) if n >= 2 => (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect(),
        _ => Vec::new(),
    }
}

impl SweepParameter {
    /// The contact-law parameter this is (None: the pressure or the disc speed).
    pub fn law(self) -> Option<LawParameter> {
        match self {
            SweepParameter::Mu => Some(LawParameter::Mu),
            SweepParameter::P0 => Some(LawParameter::P0),
            SweepParameter::Lambda => Some(LawParameter::Lambda),
            SweepParameter::PressureBar | SweepParameter::DiscSpeed => None,
        }
    }
}

/// Sets a law parameter on the sliding interfaces (`contact::vary`); the pressure and the
/// disc speed are not laws and are left to the caller.
pub fn apply_to_laws(
    parameter: SweepParameter,
    value: f64,
    interfaces: &mut [ResolvedInterface],
) -> Result<(), LawMismatch> {
    match parameter.law() {
        Some(law) => set_law_parameter(law, value, interfaces),
        None => Ok(()),
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn a_huge_point_count_is_refused_before_it_is_allocated() {
        let s = SweepSettings {
            parameter: SweepParameter::Mu,
            values: Vec::new(),
            from: Some(0.0),
            to: Some(0.5),
            points: Some(1 << 40),
        };
        let e = s.validate().unwrap_err();
        assert_eq!(e.key, "sweep.points");
    }

    #[test]
    fn values_from_range_and_validation_names_the_key() {
        let s = SweepSettings {
            parameter: SweepParameter::Mu,
            values: Vec::new(),
            from: Some(0.0),
            to: Some(0.5),
            points: Some(6),
        };
        assert_eq!(s.values().len(), 6);
        assert!((s.values()[5] - 0.5).abs() < 1e-15);
        s.validate().unwrap();
        let bad = SweepSettings {
            values: vec![0.1, f64::NAN],
            from: None,
            to: None,
            points: None,
            ..s
        };
        assert_eq!(bad.validate().unwrap_err().key, "sweep.values");
    }
}
