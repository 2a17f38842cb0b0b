//! The `[transient]` table of a scene: step, length, start, output rates, Newton variant.

use crate::invalid::InvalidSetting;
use serde::{Deserialize, Serialize};

/// The `[transient]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransientSettings {
    /// Time step (s).
    #[serde(default = "default_step")]
    pub step: f64,
    /// Number of steps.
    pub steps: usize,
    /// Relative tolerance of the fixed-Jacobian iterations.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// What `tolerance` is relative to: `"total"` (default: the whole force on the model,
    /// max(|f|, |z|), the preload included) or `"vibration"` (the forces' departure from the
    /// static equilibrium, max(|f - K q_s|, |z - K q_s|): the residual then bounds the
    /// vibration's own relative error, however small the vibration is against the preload).
    /// (Not written when "total": restart fingerprints stay the same.)
    #[serde(default, skip_serializing_if = "ToleranceReference::is_total")]
    pub tolerance_reference: ToleranceReference,
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Earlier iterates the eliminated iteration (`eliminate_points`) combines by Anderson
    /// acceleration (the slow directions the fixed factor leaves after the elimination, no
    /// solve: `time::newmark::anderson`); 0: none. No effect without `eliminate_points`.
    #[serde(default = "default_anderson", skip_serializing_if = "is_zero")]
    pub anderson: usize,
    /// Also accept a step's iterate once the iteration's remaining error (estimated from the
    /// contraction of its last two moves) is below this fraction of Newmark's own local
    /// truncation error, (beta - 1/6) h^2 |a1 - a0| (`time::newmark::step_error`); 0
    /// (default): the residual `tolerance` alone.
    #[serde(default, skip_serializing_if = "is_zero_f64")]
    pub step_error_fraction: f64,
    /// The perturbation of the static state the run starts from (see [`Start`]).
    #[serde(default)]
    pub start: Start,
    /// `start = "mode"`: the real mode (1-based).
    #[serde(default = "default_mode")]
    pub mode: usize,
    /// `start = "mode"` or `"random"`: the largest nodal displacement of the kick (m).
    #[serde(default = "default_amplitude")]
    pub amplitude: f64,
    /// `start = "random"`: the seed of the modal coefficients.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// `start = "impulse"`: where and how much.
    #[serde(default)]
    pub impulse: Option<Impulse>,
    /// A failed step is halved (Jacobian refactorized) at most this many levels deep.
    #[serde(default = "default_max_cuts")]
    pub max_cuts: usize,
    /// Before cutting, rebuild the Jacobian with the contact tangent of the current state
    /// (normal and stick stiffness, friction damping of nearly sticking points).
    #[serde(default = "default_refresh")]
    pub refresh: bool,
    /// Where the fixed Jacobian's iterations stall, first update its factor at the contact
    /// points whose tangent changed most (Woodbury: one solve per iteration, one per new
    /// point, no factorization) and keep it updated for the next steps; false: the fixed
    /// factor, then a refreshed one (the behaviour before this key, for comparison).
    #[serde(default = "default_refresh")]
    pub update_factor: bool,
    /// Where the fixed Jacobian's iterations stall, eliminate the contact points whose tangent
    /// changed most, at most this many, at every iterate (a small nonlinear system over their
    /// unknowns, split into independent parts, each solved by Newton on one rank:
    /// `eliminate.rs`) before the fixed factor's correction, instead of updating the factor
    /// there; 0 (default): no elimination.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub eliminate_points: usize,
    /// `"modified"` (default): the fixed Jacobian; `"full"`: J rebuilt with the contact tangent
    /// at every iterate (the reference the fixed-Jacobian iterations are checked against).
    #[serde(default)]
    pub newton: Newton,
    /// Displacement and velocity states go to transient.h5 every this much simulated time
    /// (s; 0: none). Default 1e-5 s (100 kHz).
    #[serde(default = "default_state_interval")]
    pub state_interval: f64,
    /// A checkpoint (checkpoint.h5, for `squeal run --restart`) every this many steps, and at
    /// the end or the failure of the run (0: never).
    #[serde(default = "default_checkpoint_every")]
    pub checkpoint_every: usize,
    /// End the run this many cycles after the braking torque saturated (the limit-cycle
    /// analysis' detector, applied to the run so far every [`SATURATION_CHECK_EVERY`] steps);
    /// `steps` stays the upper bound. None: run all `steps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_after_saturation: Option<usize>,
    /// Sensor points by name: displacement, velocity and acceleration (x, y, z) of the node
    /// nearest to each position (m) at every step.
    #[serde(default)]
    pub sensors: std::collections::BTreeMap<String, [f64; 3]>,
    /// Where the stepping Jacobian is factorized: `"auto"` (default: `"per-rank"` up to
    /// [`PER_RANK_MAX_UNKNOWNS`] unknowns, else `"distributed"`), `"distributed"` (MUMPS over
    /// all ranks), `"per-rank"` (the whole J on every rank, PETSc's sequential LU: no
    /// communication inside a solve; for a reduced model's small J, solved ~10^5 times) or
    /// `"single"` (MUMPS over all ranks in single precision: half the factor's bytes per solve,
    /// the residual in double precision, judged with the linear force recomputed by products
    /// wherever the solves' rounding could matter: `time::newmark`'s carried.rs).
    /// (Not written when "auto": the restart fingerprint of checkpoints written before this
    /// key existed stays the same.)
    #[serde(default, skip_serializing_if = "JacobianFactor::is_auto")]
    pub jacobian_factor: JacobianFactor,
    /// The contact tangent of the first J, at the static state: `"consistent"` (default: the
    /// normal and stick stiffness, the friction's coupling and its damping through
    /// gamma / (beta h); unsymmetric, LU; the tangent the complex modes see, so in the growth
    /// the residual after one correction is of second order in the amplitude) or `"mock"`
    /// (the normal and stick stiffness alone, the paper's mock contact stiffness: symmetric,
    /// Cholesky). (Not written when "consistent": restart
    /// fingerprints stay the same.)
    #[serde(default, skip_serializing_if = "FirstJacobian::is_consistent")]
    pub first_jacobian: FirstJacobian,
    /// Upper frequency of the spectrogram plot (Hz).
    #[serde(default = "default_spectrogram_max_hz")]
    pub spectrogram_max_hz: f64,
}

/// How the transient leaves the static state (the growth of unstable modes needs a seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Start {
    /// Displaced along one real mode shape (`mode`, `amplitude`).
    #[default]
    Mode,
    /// Displaced along a random combination of every computed real mode: coefficients
    /// uniform in [-1, 1] from `seed` (the same on any number of ranks), scaled to
    /// `amplitude`. Smooth (modal) rather than a per-DOF noise, whose strain energy would sit
    /// in the mesh's highest frequencies.
    Random,
    /// At rest at the static state, hit by an impulse (`[transient.impulse]`): v0 = M^-1 I.
    Impulse,
}

/// A force impulse at the node nearest to `point`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Impulse {
    /// Position (m).
    pub point: [f64; 3],
    /// Impulse vector (N s).
    pub value: [f64; 3],
}

/// Coefficients uniform in [-1, 1] (splitmix64: one definition, identical on every platform
/// and rank count).
pub fn random_coefficients(seed: u64, n: usize) -> Vec<f64> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            // 53 random bits to [0, 1), then to [-1, 1).
            2.0 * ((z >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        })
        .collect()
}

fn default_seed() -> u64 {
    1
}

fn default_spectrogram_max_hz() -> f64 {
    20_000.0
}

fn default_state_interval() -> f64 {
    1e-5
}
fn default_checkpoint_every() -> usize {
    10_000
}

/// Where the stepping Jacobian is factorized (see `TransientSettings::jacobian_factor`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JacobianFactor {
    #[default]
    Auto,
    Distributed,
    PerRank,
    /// MUMPS over all ranks in single precision (libsmumps): half the bytes per solve; the
    /// iteration's residual stays in double precision.
    Single,
}

/// `jacobian_factor = "auto"` factorizes J on every rank up to this many unknowns (faster
/// solves at ~2k unknowns: benches/decisions-results.md, "per-rank-factor"); the factor's
/// memory is then on every rank and its factorization is not parallel, so larger reduced
/// models stay with MUMPS unless a scene asks.
pub const PER_RANK_MAX_UNKNOWNS: usize = 10_000;

/// What the transient's residual tolerance is relative to (`[transient] tolerance_reference`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToleranceReference {
    /// The whole force, max(|f|, |z|).
    #[default]
    Total,
    /// The departure of f and z from the static equilibrium's force.
    Vibration,
}

impl ToleranceReference {
    fn is_total(&self) -> bool {
        *self == ToleranceReference::Total
    }
}

/// The contact tangent of the transient's first Jacobian (at the static state).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FirstJacobian {
    /// The consistent tangent, friction coupling and damping included (LU).
    #[default]
    Consistent,
    /// Normal and stick stiffness (symmetric: Cholesky).
    Mock,
}

impl FirstJacobian {
    fn is_consistent(&self) -> bool {
        *self == FirstJacobian::Consistent
    }
}

impl JacobianFactor {
    fn is_auto(&self) -> bool {
        *self == JacobianFactor::Auto
    }

    /// Per rank or distributed, for a J of `unknowns` rows.
    pub fn per_rank(self, unknowns: usize) -> bool {
        self.resolve(unknowns) == JacobianFactor::PerRank
    }

    /// The factor for a J of `unknowns` rows ("auto" resolved).
    pub fn resolve(self, unknowns: usize) -> JacobianFactor {
        match self {
            JacobianFactor::Auto if unknowns <= PER_RANK_MAX_UNKNOWNS => JacobianFactor::PerRank,
            JacobianFactor::Auto => JacobianFactor::Distributed,
            other => other,
        }
    }
}

/// The Newton variant of the transient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Newton {
    #[default]
    Modified,
    Full,
}

fn default_refresh() -> bool {
    true
}

fn default_max_cuts() -> usize {
    6
}

fn default_step() -> f64 {
    1e-6
}
fn default_tolerance() -> f64 {
    1e-8
}
fn default_max_iterations() -> usize {
    30
}
fn is_zero(n: &usize) -> bool {
    *n == 0
}
fn is_zero_f64(x: &f64) -> bool {
    *x == 0.0
}
fn default_anderson() -> usize {
    0
}
/// More earlier iterates than this cost more in dot products than a step could gain.
pub const MAX_ANDERSON: usize = 20;
/// The elimination's subproblem (4-6 unknowns per point) is factored sparse and solved on
/// every rank: beyond this many points (the 600k brake has ~9,100) it is no longer local.
pub const MAX_ELIMINATED_POINTS: usize = 4096;
fn default_mode() -> usize {
    1
}
fn default_amplitude() -> f64 {
    1e-7
}

/// Steps between two checks of `stop_after_saturation` (the detector reads the whole torque
/// record: ~1 ms per check at 10^5 steps, once per 500 steps).
pub const SATURATION_CHECK_EVERY: usize = 500;

impl TransientSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        self.validate_stepping()?;
        self.validate_start_and_signals()
    }

    /// The step, its iterations and its end.
    fn validate_stepping(&self) -> Result<(), InvalidSetting> {
        if self.stop_after_saturation.is_some_and(|c| c < 2) {
            return Err(InvalidSetting::new(
                "transient.stop_after_saturation",
                " must be at least 2 (cycles after the saturation; leave it out to run all steps)",
            ));
        }
        if !(self.step > 0.0 && self.step.is_finite()) {
            return Err(InvalidSetting::new(
                "transient.step",
                format!(" = {}: must be a positive time step (s)", self.step),
            ));
        }
        if self.steps == 0 {
            return Err(InvalidSetting::new(
                "transient.steps",
                " must be at least 1",
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1e-2) {
            return Err(InvalidSetting::new(
                "transient.tolerance",
                format!(" = {}: must be in (0, 0.01)", self.tolerance),
            ));
        }
        if !(0.0..1.0).contains(&self.step_error_fraction) {
            return Err(InvalidSetting::new(
                "transient.step_error_fraction",
                format!(
                    " = {}: must be in [0, 1) (a fraction of the step's truncation error, e.g. \
                     0.1; 0: the residual tolerance alone)",
                    self.step_error_fraction
                ),
            ));
        }
        if self.anderson > MAX_ANDERSON {
            return Err(InvalidSetting::new(
                "transient.anderson",
                format!(
                    " = {}: at most {MAX_ANDERSON} earlier iterates (0: no acceleration)",
                    self.anderson
                ),
            ));
        }
        if self.eliminate_points > MAX_ELIMINATED_POINTS {
            return Err(InvalidSetting::new(
                "transient.eliminate_points",
                format!(
                    " = {}: at most {MAX_ELIMINATED_POINTS} points (0: no elimination)",
                    self.eliminate_points
                ),
            ));
        }
        Ok(())
    }

    /// The start (mode, amplitude, impulse) and what is recorded.
    fn validate_start_and_signals(&self) -> Result<(), InvalidSetting> {
        if self.mode == 0 {
            return Err(InvalidSetting::new(
                "transient.mode",
                " is 1-based: the first real mode is 1",
            ));
        }
        for (name, p) in &self.sensors {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(InvalidSetting::new(
                    format!("transient.sensors.{name}"),
                    ": the position must be three finite coordinates (m)",
                ));
            }
        }
        if self.spectrogram_max_hz.is_nan() || self.spectrogram_max_hz <= 0.0 {
            return Err(InvalidSetting::new(
                "transient.spectrogram_max_hz",
                " must be positive (Hz)",
            ));
        }
        if !(self.state_interval >= 0.0 && self.state_interval.is_finite()) {
            return Err(InvalidSetting::new(
                "transient.state_interval",
                format!(
                    " = {}: must be a time (s) >= 0 (0: no states)",
                    self.state_interval
                ),
            ));
        }
        if !self.amplitude.is_finite() {
            return Err(InvalidSetting::new(
                "transient.amplitude",
                " must be finite",
            ));
        }
        match (self.start, &self.impulse) {
            (Start::Impulse, None) => {
                return Err(InvalidSetting::new("transient.start", " = \"impulse\" needs [transient.impulse] with point = [x, y, z] (m) and value = [Ix, Iy, Iz] (N s)"))
            }
            (_, Some(i)) if i.point.iter().chain(&i.value).any(|x| !x.is_finite()) => {
                return Err(InvalidSetting::new("transient.impulse", ": point and value must be three finite numbers each"))
            }
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    fn settings(text: &str) -> TransientSettings {
        toml::from_str(text).expect("transient settings parse")
    }

    #[test]
    fn stop_after_saturation_needs_two_cycles_and_is_left_out_when_unset() {
        let err = settings("steps = 10\nstop_after_saturation = 1")
            .validate()
            .unwrap_err();
        assert_eq!(err.key, "transient.stop_after_saturation", "{err}");
        assert!(settings("steps = 10\nstop_after_saturation = 20")
            .validate()
            .is_ok());
        // Unset, it is not written: the restart fingerprints of older scenes stay the same.
        let text = toml::to_string(&settings("steps = 10")).unwrap();
        assert!(!text.contains("stop_after_saturation"), "{text}");
    }

    #[test]
    fn elimination_and_anderson_are_bounded_and_left_out_when_unset() {
        for (text, key) in [
            (
                "steps = 10\neliminate_points = 4097",
                "transient.eliminate_points",
            ),
            ("steps = 10\nanderson = 21", "transient.anderson"),
            (
                "steps = 10\nstep_error_fraction = 1.0",
                "transient.step_error_fraction",
            ),
            (
                "steps = 10\nstep_error_fraction = -0.1",
                "transient.step_error_fraction",
            ),
            (
                "steps = 10\nstep_error_fraction = nan",
                "transient.step_error_fraction",
            ),
        ] {
            let err = settings(text).validate().unwrap_err();
            assert_eq!(err.key, key, "{err}");
        }
        assert!(settings(
            "steps = 10\neliminate_points = 64\nanderson = 5\nstep_error_fraction = 0.1"
        )
        .validate()
        .is_ok());
        // Unset, they are not written: the restart fingerprints of older scenes stay the same.
        let text = toml::to_string(&settings("steps = 10")).unwrap();
        assert!(
            !text.contains("eliminate")
                && !text.contains("anderson")
                && !text.contains("step_error"),
            "{text}"
        );
    }

    #[test]
    fn impulse_start_without_an_impulse_names_the_key() {
        let err = settings("steps = 10\nstart = \"impulse\"")
            .validate()
            .unwrap_err();
        assert_eq!(err.key, "transient.start", "{err}");
        assert!(err.to_string().contains("transient.impulse"), "{err}");
        let ok = settings(
            "steps = 10\nstart = \"impulse\"\n[impulse]\npoint = [0.0, 0.0, 0.0]\nvalue = [0.0, 0.0, 1.0e-3]",
        );
        assert!(ok.validate().is_ok());
        let nan = settings(
            "steps = 10\nstart = \"impulse\"\n[impulse]\npoint = [0.0, nan, 0.0]\nvalue = [0.0, 0.0, 1.0]",
        );
        let nan = nan.validate().unwrap_err();
        assert!(nan.key == "transient.impulse" && nan.detail.contains("finite"));
        assert!(toml::from_str::<TransientSettings>("steps = 1\nstart = \"noise\"").is_err());
    }

    #[test]
    fn tolerance_is_against_the_whole_force_unless_the_scene_says_vibration() {
        let default = settings("steps = 1");
        assert_eq!(default.tolerance_reference, ToleranceReference::Total);
        // The default is not written: the restart fingerprints stay the same.
        assert!(!toml::to_string(&default)
            .unwrap()
            .contains("tolerance_reference"));
        let vibration = settings("steps = 1\ntolerance_reference = \"vibration\"");
        assert_eq!(vibration.tolerance_reference, ToleranceReference::Vibration);
        assert!(toml::to_string(&vibration)
            .unwrap()
            .contains("tolerance_reference = \"vibration\""));
        let err =
            toml::from_str::<TransientSettings>("steps = 1\ntolerance_reference = \"preload\"")
                .unwrap_err()
                .to_string();
        assert!(err.contains("total") && err.contains("vibration"), "{err}");
    }

    #[test]
    fn first_jacobian_is_the_consistent_tangent_unless_the_scene_says_mock() {
        let default = settings("steps = 1");
        assert_eq!(default.first_jacobian, FirstJacobian::Consistent);
        // The default is not written: the restart fingerprints stay the same.
        assert!(!toml::to_string(&default)
            .unwrap()
            .contains("first_jacobian"));
        let mock = settings("steps = 1\nfirst_jacobian = \"mock\"");
        assert_eq!(mock.first_jacobian, FirstJacobian::Mock);
        assert!(toml::to_string(&mock)
            .unwrap()
            .contains("first_jacobian = \"mock\""));
        let err = toml::from_str::<TransientSettings>("steps = 1\nfirst_jacobian = \"static\"")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("first_jacobian") || err.contains("consistent"),
            "{err}"
        );
    }

    #[test]
    fn jacobian_factor_is_per_rank_for_small_systems_unless_the_scene_says() {
        assert_eq!(settings("steps = 1").jacobian_factor, JacobianFactor::Auto);
        let auto = JacobianFactor::Auto;
        assert!(auto.per_rank(PER_RANK_MAX_UNKNOWNS) && !auto.per_rank(PER_RANK_MAX_UNKNOWNS + 1));
        let distributed = settings("steps = 1\njacobian_factor = \"distributed\"");
        assert!(!distributed.jacobian_factor.per_rank(10));
        let per_rank = settings("steps = 1\njacobian_factor = \"per-rank\"");
        assert!(per_rank.jacobian_factor.per_rank(1_000_000));
        assert!(
            toml::from_str::<TransientSettings>("steps = 1\njacobian_factor = \"mumps\"").is_err()
        );
        // "auto" is not written: the restart fingerprint of older checkpoints stays valid.
        assert!(!toml::to_string(&settings("steps = 1"))
            .unwrap()
            .contains("jacobian_factor"));
    }

    #[test]
    fn random_coefficients_are_seeded_uniform_and_reproducible() {
        let a = random_coefficients(7, 20_000);
        assert_eq!(a, random_coefficients(7, 20_000));
        assert_ne!(a[..10], random_coefficients(8, 10)[..]);
        assert!(a.iter().all(|x| (-1.0..1.0).contains(x)));
        // Uniform on [-1, 1): mean 0 and variance 1/3, to a few standard errors.
        let n = a.len() as f64;
        let mean = a.iter().sum::<f64>() / n;
        let variance = a.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        assert!(mean.abs() < 4.0 * (1.0f64 / 3.0 / n).sqrt(), "mean {mean}");
        assert!((variance - 1.0 / 3.0).abs() < 0.01, "variance {variance}");
    }
}
