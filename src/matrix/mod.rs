//! The virtual noise dynamometer (`[matrix]`, DESIGN.md §1 "sweeps"): operating points over
//! brake pressure, disc speed, friction, the exponential law and temperature, a full grid or a
//! seeded Sobol sample; per point the static state and the projected complex modes. The
//! settings and the points here; the stage in `crate::stages::matrix`, the journal that makes
//! a run resumable and sliceable in `crate::io::matrix_journal`, the statistics of the results
//! in [`analysis`].

pub mod analysis;
pub mod check;
pub mod point;
pub mod sample;
pub mod saturation;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::eigen::sweep::SweepParameter;
use crate::invalid::InvalidSetting;
pub use crate::range::AxisRange;

/// A parameter of the operating point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    PressureBar,
    /// rad/s.
    DiscSpeed,
    /// Friction coefficient of the sliding interfaces.
    Mu,
    /// p0 of the exponential law (Pa).
    P0,
    /// lambda of the exponential law (1/m).
    Lambda,
    /// Lining temperature (deg C): sets mu and the lining's stiffness through
    /// `[matrix.temperature]`.
    Temperature,
    /// The lining blocks' elastic constants as a factor on the scene's (1 = the scene's
    /// lining; an orthotropic lining keeps its anisotropy).
    LiningModulus,
}

impl Axis {
    pub fn name(self) -> &'static str {
        match self {
            Axis::Temperature => "temperature",
            Axis::LiningModulus => "lining_modulus",
            other => other.as_sweep().expect("a law parameter").name(),
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Axis::Temperature => "lining temperature (deg C)",
            Axis::LiningModulus => "lining modulus (x the scene's)",
            other => other.as_sweep().expect("a law parameter").label(),
        }
    }

    /// The sweep parameter this axis sets directly (temperature sets mu through its table).
    pub fn as_sweep(self) -> Option<SweepParameter> {
        Some(match self {
            Axis::PressureBar => SweepParameter::PressureBar,
            Axis::DiscSpeed => SweepParameter::DiscSpeed,
            Axis::Mu => SweepParameter::Mu,
            Axis::P0 => SweepParameter::P0,
            Axis::Lambda => SweepParameter::Lambda,
            Axis::Temperature | Axis::LiningModulus => return None,
        })
    }

    /// Values an axis may take: mu and temperature (deg C above absolute zero) may be zero.
    fn admits(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Axis::Mu => v >= 0.0,
                Axis::Temperature => v > -273.15,
                // Also a lining_modulus factor must be positive (the default arm).
                _ => v > 0.0,
            }
    }
}

/// How the operating points are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Every combination of the axes' values (full factorial).
    #[default]
    Grid,
    /// `points` points of an Owen-scrambled Sobol sequence over the axes' ranges, from `seed`
    /// (space-filling: every axis' range is stratified, also in projections).
    Sobol,
}

/// The model a point's static state is solved on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StaticsModel {
    /// The full finite-element model (exact; a factorization of its tangent per few points).
    #[default]
    Full,
    /// The superelement of `[reduction]`: the kept contact zone whole, the rest on the real
    /// modes and the static shape. For large models: its tangent is a fraction of the full
    /// one's, and `full_checks` points are also solved on the full model to measure the error.
    Reduced,
}

impl StaticsModel {
    fn is_full(&self) -> bool {
        *self == StaticsModel::Full
    }
}

fn yes() -> bool {
    true
}

fn is_true(b: &bool) -> bool {
    *b
}

/// Points also solved on the full model when the reduced one solves the matrix, by default.
pub const DEFAULT_FULL_CHECKS: usize = 3;

/// Properties of the lining against temperature, interpolated linearly between the rows: the
/// friction coefficient mu(T), the lining's stiffness E_lining(T), or both.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureTable {
    /// deg C, increasing.
    pub celsius: Vec<f64>,
    /// Friction coefficient at each temperature (empty: mu stays the scene's).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mu: Vec<f64>,
    /// The lining's elastic constants at each temperature, as a factor on the scene's
    /// (empty: the lining stays the scene's).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lining_modulus: Vec<f64>,
}

/// Linear interpolation of `values` over the increasing `celsius` at `t`; None outside.
fn interpolate(celsius: &[f64], values: &[f64], t: f64) -> Option<f64> {
    let k = celsius.windows(2).position(|w| w[0] <= t && t <= w[1])?;
    let s = (t - celsius[k]) / (celsius[k + 1] - celsius[k]);
    Some(values[k] + s * (values[k + 1] - values[k]))
}

impl TemperatureTable {
    /// mu at `t` (deg C), linear between the rows; None outside the table or without a mu
    /// column.
    pub fn mu(&self, t: f64) -> Option<f64> {
        (!self.mu.is_empty())
            .then(|| interpolate(&self.celsius, &self.mu, t))
            .flatten()
    }

    /// The lining-modulus factor at `t` (deg C); None outside the table or without the column.
    pub fn lining_modulus(&self, t: f64) -> Option<f64> {
        (!self.lining_modulus.is_empty())
            .then(|| interpolate(&self.celsius, &self.lining_modulus, t))
            .flatten()
    }

    fn validate(&self) -> Result<(), InvalidSetting> {
        let key = "matrix.temperature";
        let rows = self.celsius.len();
        if rows < 2 {
            let detail = format!(": give at least 2 rows of 'celsius' (here {rows})");
            return Err(InvalidSetting::new(key, detail));
        }
        if self.mu.is_empty() && self.lining_modulus.is_empty() {
            let detail = ": give 'mu' or 'lining_modulus' (or both) at the 'celsius' rows";
            return Err(InvalidSetting::new(key, detail));
        }
        for (name, column) in [("mu", &self.mu), ("lining_modulus", &self.lining_modulus)] {
            if !column.is_empty() && column.len() != rows {
                let detail = format!(
                    ": '{name}' has {} values for {rows} rows of 'celsius'",
                    column.len()
                );
                return Err(InvalidSetting::new(key, detail));
            }
        }
        if !self.celsius.windows(2).all(|w| w[0] < w[1])
            || self.celsius.iter().any(|t| !t.is_finite())
        {
            let detail = ": 'celsius' must be finite and strictly increasing";
            return Err(InvalidSetting::new(key, detail));
        }
        if let Some(m) = self.mu.iter().find(|m| !(m.is_finite() && **m >= 0.0)) {
            let detail = format!(": mu = {m} is not a friction coefficient (finite, >= 0)");
            return Err(InvalidSetting::new(key, detail));
        }
        if let Some(e) = self
            .lining_modulus
            .iter()
            .find(|e| !(e.is_finite() && **e > 0.0))
        {
            let detail = format!(": lining_modulus = {e} is not a stiffness factor (finite, > 0)");
            return Err(InvalidSetting::new(key, detail));
        }
        Ok(())
    }
}

/// The `[matrix]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixSettings {
    #[serde(default)]
    pub sampling: Sampling,
    /// Number of points of a Sobol sample (a power of 2 stratifies best).
    #[serde(default)]
    pub points: Option<usize>,
    /// Seed of the Sobol sample's scrambling: the same seed, the same points.
    #[serde(default = "default_seed")]
    pub seed: u32,
    /// The axes (at least one); parameters not named keep the scene's value.
    pub axes: BTreeMap<Axis, AxisRange>,
    /// mu(T) of the sliding interfaces, for a temperature axis.
    #[serde(default)]
    pub temperature: Option<TemperatureTable>,
    /// The model each point's static state is solved on (not written when full, so the
    /// fingerprints of journals from before it stay).
    #[serde(default, skip_serializing_if = "StaticsModel::is_full")]
    pub statics: StaticsModel,
    /// With `statics = "reduced"`: this many points, spread over the matrix' indices, are
    /// solved on the full model too (static state and complex modes), and their difference is
    /// the reduced route's error in the report. Default 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub full_checks: Option<usize>,
    /// With `statics = "reduced"`: put the varied parameters' static shapes into the
    /// superelement's basis (default true; false for comparison).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub parameter_shapes: bool,
    /// The mesh blocks of the friction lining, whose stiffness a lining_modulus axis or
    /// column scales. Default: inner_lining and outer_lining (the brake model's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lining_blocks: Option<Vec<String>>,
    /// The most unstable modes (largest Re(s)) of each squealing point followed along a
    /// pseudo trajectory ([post.pseudo_trajectory]'s settings, else its defaults) to their
    /// saturation amplitude alpha_sat, and with [post.loudness] their A-weighted sound power
    /// level at alpha_sat. 0 (default): none. Each mode costs a sweep of linearizations.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub saturation_modes: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// The brake model's lining blocks.
pub const DEFAULT_LINING_BLOCKS: [&str; 2] = ["inner_lining", "outer_lining"];

fn default_seed() -> u32 {
    1
}

/// Largest sample: the Sobol sequence's index range.
pub const MAX_POINTS: usize = 1 << 16;

impl MatrixSettings {
    /// Whether some point scales the lining's stiffness (an axis, or the temperature table's
    /// column with a temperature axis).
    pub fn varies_lining(&self) -> bool {
        self.axes.contains_key(&Axis::LiningModulus)
            || (self.axes.contains_key(&Axis::Temperature)
                && self
                    .temperature
                    .as_ref()
                    .is_some_and(|t| !t.lining_modulus.is_empty()))
    }

    /// The lining blocks' names.
    pub fn lining_block_names(&self) -> Vec<String> {
        self.lining_blocks.clone().unwrap_or_else(|| {
            DEFAULT_LINING_BLOCKS
                .iter()
                .map(|b| b.to_string())
                .collect()
        })
    }

    /// The axes in their fixed order (the order of every point's values).
    pub fn axis_list(&self) -> Vec<Axis> {
        self.axes.keys().copied().collect()
    }

    /// The indices (among `total` points) also solved on the full model: `full_checks` of them,
    /// each in the middle of an equal share of the indices, so every slicing checks the same
    /// points. None with the full model.
    pub fn full_check_indices(&self, total: usize) -> Vec<usize> {
        if self.statics == StaticsModel::Full || total == 0 {
            return Vec::new();
        }
        let n = self.full_checks.unwrap_or(DEFAULT_FULL_CHECKS).min(total);
        let mut indices: Vec<usize> = (0..n)
            .map(|k| ((2 * k + 1) * total / (2 * n)).min(total - 1))
            .collect();
        indices.dedup();
        indices
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.axes.is_empty() {
            let detail = ": name at least one axis, e.g. [matrix.axes] pressure_bar = { from = 5.0, to = 40.0, points = 8 }";
            return Err(InvalidSetting::new("matrix.axes", detail));
        }
        for (&axis, range) in &self.axes {
            self.validate_axis(axis, range)?;
        }
        match (self.sampling, self.points) {
            (Sampling::Sobol, Some(n)) if (1..=MAX_POINTS).contains(&n) => {}
            (Sampling::Sobol, _) => {
                let detail = format!(": a Sobol sample needs 'points' from 1 to {MAX_POINTS}");
                return Err(InvalidSetting::new("matrix.points", detail));
            }
            (Sampling::Grid, Some(_)) => {
                let detail = ": a grid has the product of its axes' points; 'points' is for sampling = \"sobol\"";
                return Err(InvalidSetting::new("matrix.points", detail));
            }
            (Sampling::Grid, None) => {
                // Counted without making the values: a huge `points` would be allocated.
                let count: f64 = self
                    .axes
                    .values()
                    .map(|r| match r.values.len() {
                        0 => r.points.unwrap_or(0) as f64,
                        n => n as f64,
                    })
                    .product();
                if count > MAX_POINTS as f64 {
                    let detail = format!(
                        ": {count} grid points, more than {MAX_POINTS}: use sampling = \"sobol\""
                    );
                    return Err(InvalidSetting::new("matrix.axes", detail));
                }
            }
        }
        if self.full_checks.is_some() && self.statics == StaticsModel::Full {
            let detail = ": full checks measure the reduced statics' error: set statics = \"reduced\" or leave full_checks out";
            return Err(InvalidSetting::new("matrix.full_checks", detail));
        }
        let temperature = self.axes.contains_key(&Axis::Temperature);
        match (&self.temperature, temperature) {
            (None, true) => {
                let detail = ": a temperature axis needs the table [matrix.temperature] celsius = [...], mu = [...]";
                return Err(InvalidSetting::new("matrix.temperature", detail));
            }
            (Some(_), false) => {
                let detail = ": a temperature table without a temperature axis in [matrix.axes]";
                return Err(InvalidSetting::new("matrix.temperature", detail));
            }
            (Some(table), true) => {
                table.validate()?;
                if self.axes.contains_key(&Axis::Mu) && !table.mu.is_empty() {
                    let detail = ": temperature sets mu through its table: give either a mu axis or a mu column in [matrix.temperature]";
                    return Err(InvalidSetting::new("matrix.axes.mu", detail));
                }
                if self.axes.contains_key(&Axis::LiningModulus) && !table.lining_modulus.is_empty()
                {
                    let detail = ": temperature sets the lining's stiffness through its table: give either a lining_modulus axis or a lining_modulus column in [matrix.temperature]";
                    return Err(InvalidSetting::new("matrix.axes.lining_modulus", detail));
                }
                let (lo, hi) = self.axes[&Axis::Temperature].range();
                let (first, last) = (table.celsius[0], table.celsius[table.celsius.len() - 1]);
                if lo < first || hi > last {
                    let detail = format!(": the axis spans {lo} to {hi} deg C, the table only {first} to {last} (no extrapolation)");
                    return Err(InvalidSetting::new("matrix.axes.temperature", detail));
                }
            }
            (None, false) => {}
        }
        if let Some(blocks) = &self.lining_blocks {
            if !self.varies_lining() || blocks.is_empty() {
                let detail = ": names the lining blocks a lining_modulus axis (or temperature column) scales: give at least one block, and such an axis";
                return Err(InvalidSetting::new("matrix.lining_blocks", detail));
            }
        }
        Ok(())
    }

    fn validate_axis(&self, axis: Axis, range: &AxisRange) -> Result<(), InvalidSetting> {
        let key = format!("matrix.axes.{}", axis.name());
        range.check_form(&key, MAX_POINTS)?;
        let usable = match self.sampling {
            Sampling::Grid => !range.values().is_empty(),
            Sampling::Sobol => range.from.is_some() && range.to.is_some() && range.points.is_none(),
        };
        if !usable {
            let detail = match self.sampling {
                Sampling::Grid => ": give 'values = [...]' or 'from', 'to' and 'points' (at least 2)",
                Sampling::Sobol => ": a Sobol sample draws from a range: give 'from' and 'to' (no 'points' or 'values')",
            };
            return Err(InvalidSetting::new(key, detail));
        }
        if let Some(v) = range.first_refused(|v| axis.admits(v)) {
            let detail = format!(
                ": {v} is not a valid {} ({})",
                axis.name(),
                match axis {
                    Axis::Mu => "finite, non-negative",
                    Axis::Temperature => "finite, above -273.15",
                    _ => "finite, positive",
                }
            );
            return Err(InvalidSetting::new(key, detail));
        }
        Ok(())
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn parse(text: &str) -> MatrixSettings {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn validation_names_the_key() {
        let ok =
            parse("sampling = \"sobol\"\npoints = 64\n[axes]\nmu = { from = 0.3, to = 0.6 }\n");
        ok.validate().unwrap();
        for (text, key) in [
            ("[axes]\n", "matrix.axes"),
            ("[axes]\nmu = { from = 0.3, to = 0.6 }\n", "matrix.axes.mu"),
            ("sampling = \"sobol\"\n[axes]\nmu = { from = 0.3, to = 0.6 }\n", "matrix.points"),
            ("[axes]\npressure_bar = { values = [10.0, -1.0] }\n", "matrix.axes.pressure_bar"),
            ("[axes]\ntemperature = { values = [20.0, 100.0] }\n", "matrix.temperature"),
            (
                "[axes]\ntemperature = { values = [20.0, 400.0] }\n[temperature]\ncelsius = [0.0, 300.0]\nmu = [0.4, 0.3]\n",
                "matrix.axes.temperature",
            ),
            (
                "[axes]\ntemperature = { values = [20.0] }\nmu = { values = [0.4] }\n[temperature]\ncelsius = [0.0, 300.0]\nmu = [0.4, 0.3]\n",
                "matrix.axes.mu",
            ),
            (
                "[axes]\ntemperature = { values = [20.0] }\n[temperature]\ncelsius = [0.0, 300.0]\n",
                "matrix.temperature",
            ),
            (
                "[axes]\ntemperature = { values = [20.0] }\n[temperature]\ncelsius = [0.0, 300.0]\nlining_modulus = [1.0, 0.0]\n",
                "matrix.temperature",
            ),
            (
                "[axes]\ntemperature = { values = [20.0] }\nlining_modulus = { values = [0.8] }\n[temperature]\ncelsius = [0.0, 300.0]\nlining_modulus = [1.0, 0.6]\n",
                "matrix.axes.lining_modulus",
            ),
            ("[axes]\nlining_modulus = { values = [0.5, -1.0] }\n", "matrix.axes.lining_modulus"),
            ("lining_blocks = [\"inner_lining\"]\n[axes]\nmu = { values = [0.4] }\n", "matrix.lining_blocks"),
            ("full_checks = 2\n[axes]\nmu = { values = [0.4] }\n", "matrix.full_checks"),
        ] {
            let err = parse(text).validate().unwrap_err();
            assert_eq!(err.key, key, "{text}");
        }
    }

    #[test]
    fn temperature_table_interpolates_inside_and_refuses_outside() {
        let t = TemperatureTable {
            celsius: vec![20.0, 100.0, 300.0],
            mu: vec![0.40, 0.44, 0.34],
            lining_modulus: vec![1.0, 0.9, 0.5],
        };
        assert!((t.mu(60.0).unwrap() - 0.42).abs() < 1e-15);
        assert!((t.mu(300.0).unwrap() - 0.34).abs() < 1e-15);
        assert_eq!(t.mu(301.0), None);
        assert!((t.lining_modulus(200.0).unwrap() - 0.7).abs() < 1e-15);
        assert_eq!(t.lining_modulus(19.0), None);
        let only_stiffness = TemperatureTable {
            mu: Vec::new(),
            ..t
        };
        assert_eq!(only_stiffness.mu(60.0), None);
        only_stiffness.validate().unwrap();
    }
}
