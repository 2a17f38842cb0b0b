//! What a matrix point found: its parameters, and its complex modes or why it failed. These
//! records are the journal's lines (`crate::io::matrix_journal`), so a killed run resumes and
//! slices merge from them alone.

use serde::{Deserialize, Serialize};

use crate::eigen::complex_modes::{damping_ratio, frequency_hz, Complex};

/// A complex mode at a point, labelled by the nominal mode it continues (by MAC).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointMode {
    /// C<label> of the nominal state's projected complex modes (1-based), when paired.
    pub label: Option<usize>,
    /// Re(s) (1/s).
    pub re: f64,
    /// Im(s) (rad/s).
    pub im: f64,
    /// MAC with the nominal mode it continues (0 when unpaired).
    pub mac: f64,
}

impl PointMode {
    pub fn s(&self) -> Complex {
        (self.re, self.im)
    }

    pub fn frequency_hz(&self) -> f64 {
        frequency_hz(self.s())
    }

    pub fn damping_ratio(&self) -> f64 {
        damping_ratio(self.s())
    }

    /// "C12" or "new" (no nominal mode continues into it).
    pub fn name(&self) -> String {
        self.label.map_or_else(|| "new".into(), |l| format!("C{l}"))
    }
}

/// A point's static state and complex modes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolvedPoint {
    /// The complex modes (below the complex modes' f_max when set), by frequency.
    pub modes: Vec<PointMode>,
    /// Braking torque of the static state (N m), summed over the interfaces.
    pub braking_torque: f64,
    /// Normal contact force of the static state (N), summed over the interfaces.
    pub normal_force: f64,
    /// Newton iterations of the static state.
    pub newton_iterations: usize,
    /// LU factorizations of the static state.
    pub factorizations: usize,
    /// The warm start failed and the static state was solved from the unloaded state.
    pub cold_restart: bool,
    pub seconds_statics: f64,
    /// Of which in LU factorizations.
    #[serde(default)]
    pub seconds_factorizing: f64,
    /// Solves with the LU factors (corrections and GMRES iterations), and their seconds.
    #[serde(default)]
    pub factor_solves: usize,
    #[serde(default)]
    pub seconds_solving: f64,
    pub seconds_modes: f64,
    /// With the reduced statics at a checked point: the same point on the full model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub full_check: Option<FullCheck>,
    /// With `matrix.saturation_modes`: the pseudo-trajectory study of the most unstable
    /// modes, the largest Re(s) first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub saturation: Vec<ModeSaturation>,
}

/// An unstable mode of a point followed along its pseudo trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeSaturation {
    /// The nominal mode it continues (as its [`PointMode`]), its frequency (Hz) and Re(s).
    pub label: Option<usize>,
    pub frequency_hz: f64,
    pub re: f64,
    /// Contact amplitudes (m) where the mean damping over a period turns negative and back
    /// positive (None: outside the swept range).
    pub alpha_crit: Option<f64>,
    pub alpha_sat: Option<f64>,
    /// A-weighted sound power level (dB re 1 pW) at alpha_sat, with [post.loudness].
    pub level_db_a: Option<f64>,
    pub seconds: f64,
    /// Why the study failed (then the amplitudes and the level are None).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// A point of a reduced-statics matrix solved again on the full model: the reduced route's
/// error there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FullCheck {
    /// |T q_r - q| / |q|: the reduced static displacement, recovered, against the full one
    /// (NaN when the full solve failed).
    pub displacement_error: f64,
    /// Braking torque (N m) and normal force (N) of the full static state.
    pub braking_torque: f64,
    pub normal_force: f64,
    /// The full static state's complex modes, labelled as the point's.
    pub modes: Vec<PointMode>,
    pub seconds: f64,
    /// Why the full solve failed (then the other fields are NaN or empty).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl FullCheck {
    /// The largest Re(s) of the full state's modes (NaN when it failed).
    pub fn largest_real_part(&self) -> f64 {
        if self.failure.is_some() || self.modes.is_empty() {
            return f64::NAN;
        }
        crate::measure::greatest(self.modes.iter().map(|m| m.re))
    }
}

/// A point's outcome.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Outcome {
    Solved(SolvedPoint),
    /// Recorded, and the matrix goes on.
    Failed {
        reason: String,
        /// What the attempt cost (0 in journals written before this was recorded).
        #[serde(default)]
        seconds: f64,
    },
}

/// One operating point of the matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// Index among all the matrix' points (from 0).
    pub index: usize,
    /// The axes' values (the order of `MatrixSettings::axis_list`).
    pub values: Vec<f64>,
    pub outcome: Outcome,
}

impl PointResult {
    pub fn solved(&self) -> Option<&SolvedPoint> {
        match &self.outcome {
            Outcome::Solved(s) => Some(s),
            Outcome::Failed { .. } => None,
        }
    }

    /// The modes unstable beyond `margin` (damping ratio < -margin).
    pub fn unstable(&self, margin: f64) -> impl Iterator<Item = &PointMode> {
        self.solved()
            .into_iter()
            .flat_map(|s| s.modes.iter())
            .filter(move |m| m.damping_ratio() < -margin)
    }

    /// The largest Re(s) of the point's modes (NaN for a failed point): the squeal
    /// propensity, positive where a mode is unstable.
    pub fn largest_real_part(&self) -> f64 {
        self.solved().map_or(f64::NAN, |s| {
            crate::measure::greatest(s.modes.iter().map(|m| m.re))
        })
    }
}
