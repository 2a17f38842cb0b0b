//! Parameter sweeps of the complex modes: the scene's `[sweep]` (friction coefficient, brake
//! pressure, disc speed, exponential-law p0 or lambda), and mode tracking across the points
//! by MAC so every track is one physical mode (the coalescence picture).

use crate::invalid::InvalidSetting;
use crate::range::AxisRange;
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
/// Written flat in the scene (`parameter = "mu"`, `from = 0.2`, ...), read through
/// `SweepTable` so that unknown keys are still refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SweepTable", into = "SweepTable")]
pub struct SweepSettings {
    pub parameter: SweepParameter,
    pub range: AxisRange,
}

/// The scene's flat form of `SweepSettings` (serde's `flatten` cannot be combined with
/// `deny_unknown_fields`).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepTable {
    parameter: SweepParameter,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    values: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    from: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    to: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    points: Option<usize>,
}

impl From<SweepTable> for SweepSettings {
    fn from(t: SweepTable) -> Self {
        let range = AxisRange {
            values: t.values,
            from: t.from,
            to: t.to,
            points: t.points,
        };
        SweepSettings {
            parameter: t.parameter,
            range,
        }
    }
}

impl From<SweepSettings> for SweepTable {
    fn from(s: SweepSettings) -> Self {
        let r = s.range;
        SweepTable {
            parameter: s.parameter,
            values: r.values,
            from: r.from,
            to: r.to,
            points: r.points,
        }
    }
}

impl SweepSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        self.range.check_form("sweep", MAX_SWEEP_POINTS)?;
        if self.values().is_empty() {
            return Err(InvalidSetting::new(
                "sweep",
                ": give 'values = [...]' or 'from', 'to' and 'points' (at least 2)",
            ));
        }
        let admits = |v: f64| {
            v.is_finite()
                && match self.parameter {
                    SweepParameter::Mu => v >= 0.0,
                    _ => v > 0.0,
                }
        };
        if let Some(v) = self.range.first_refused(admits) {
            let sign = if self.parameter == SweepParameter::Mu {
                "non-negative"
            } else {
                "positive"
            };
            let detail = format!(
                ": {v} is not a valid {} (finite, {sign})",
                self.parameter.name()
            );
            return Err(InvalidSetting::new("sweep.values", detail));
        }
        Ok(())
    }

    pub fn values(&self) -> Vec<f64> {
        self.range.values()
    }
}

/// The most points a sweep takes from `from`/`to`/`points`.
pub const MAX_SWEEP_POINTS: usize = 1 << 16;

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
            range: AxisRange::spaced(0.0, 0.5, 1 << 40),
        };
        let e = s.validate().unwrap_err();
        assert_eq!(e.key, "sweep.points");
    }

    #[test]
    fn values_from_range_and_validation_names_the_key() {
        let s = SweepSettings {
            parameter: SweepParameter::Mu,
            range: AxisRange::spaced(0.0, 0.5, 6),
        };
        assert_eq!(s.values().len(), 6);
        assert!((s.values()[5] - 0.5).abs() < 1e-15);
        s.validate().unwrap();
        let bad = SweepSettings {
            range: AxisRange::listed(vec![0.1, f64::NAN]),
            ..s
        };
        assert_eq!(bad.validate().unwrap_err().key, "sweep.values");
    }
}
