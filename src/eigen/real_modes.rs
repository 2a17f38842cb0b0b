//! Real modes (K phi = omega^2 M phi) with SLEPc shift-and-invert + MUMPS Cholesky.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::la::{
    EigenOptions, FactorizationReport, GeneralizedEigen, LaError, Petsc, SparseMatrix, Vector,
};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// What real modes to compute.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RealModeRequest {
    /// The N lowest modes (ignored when `f_max_hz` is set).
    #[serde(default = "default_count")]
    pub count: usize,
    /// All modes below this frequency (Hz), by spectrum slicing.
    #[serde(default)]
    pub f_max_hz: Option<f64>,
    /// Shift (Hz) of shift-and-invert; negative means sigma = -(2 pi f)^2, below zero, which a
    /// free-free body (singular K) needs. None: 0 when constrained, -1 Hz when free.
    #[serde(default)]
    pub shift_hz: Option<f64>,
    /// Modes below this frequency (Hz) are reported as rigid-body modes.
    #[serde(default = "default_rigid_below")]
    pub rigid_below_hz: f64,
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
}

fn default_count() -> usize {
    20
}
fn default_rigid_below() -> f64 {
    0.5
}
fn default_tolerance() -> f64 {
    1e-10
}

impl Default for RealModeRequest {
    fn default() -> Self {
        RealModeRequest {
            count: default_count(),
            f_max_hz: None,
            shift_hz: None,
            rigid_below_hz: default_rigid_below(),
            tolerance: default_tolerance(),
        }
    }
}

/// Real modes in ascending order, M-normalized.
pub struct RealModes<'p> {
    /// omega^2 (rad^2/s^2); slightly negative values are rigid-body modes in round-off.
    pub eigenvalues: Vec<f64>,
    pub frequencies_hz: Vec<f64>,
    pub shapes: Vec<Vector<'p>>,
    /// ||K phi - omega^2 M phi||_2 with phi^T M phi = 1.
    pub residual_norms: Vec<f64>,
    /// SLEPc's backward error ||r|| / ((||K|| + |lambda| ||M||) ||phi||).
    pub backward_errors: Vec<f64>,
    pub rigid: Vec<bool>,
    /// The frequency (Hz) below which a mode counts as rigid (`rigid_below_hz`).
    pub rigid_below_hz: f64,
    pub iterations: usize,
    pub factorization: Option<FactorizationReport>,
    pub seconds: f64,
}

/// Frequency in Hz of an eigenvalue omega^2 (negative round-off kept as a negative sign).
pub fn frequency_hz(eigenvalue: f64) -> f64 {
    eigenvalue.signum() * eigenvalue.abs().sqrt() / TWO_PI
}

/// Computes real modes of K phi = omega^2 M phi. `free_free`: K is singular (no constraint),
/// so the default shift goes below zero. `prefix` prefixes the solver's PETSc options.
///
/// # Collective
pub fn real_modes<'p>(
    petsc: &'p Petsc,
    stiffness: &SparseMatrix<'p>,
    mass: &SparseMatrix<'p>,
    free_free: bool,
    request: &RealModeRequest,
    prefix: &str,
) -> Result<RealModes<'p>, LaError> {
    let start = Instant::now();
    let shift_hz = request
        .shift_hz
        .unwrap_or(if free_free { -1.0 } else { 0.0 });
    let shift = shift_hz.signum() * (TWO_PI * shift_hz).powi(2);
    let opts = EigenOptions {
        count: request.count,
        max_eigenvalue: request.f_max_hz.map(|f| (TWO_PI * f).powi(2)),
        shift,
        ncv: None,
        tolerance: request.tolerance,
        prefix: prefix.to_string(),
    };
    let wanted = if request.f_max_hz.is_some() {
        0
    } else {
        request.count
    };
    let mut bar = crate::progress::Progress::new("real modes", wanted, petsc.rank());
    let mut report =
        |nconv: usize, its: usize| bar.update(nconv, &format!("converged (restart {its})"));
    let monitor: Option<&mut dyn FnMut(usize, usize)> =
        if wanted > 0 { Some(&mut report) } else { None };
    let sol = GeneralizedEigen::solve(petsc, stiffness, mass, true, &opts, monitor);
    bar.finish();
    let mut sol = sol?;
    // Residuals by our own products (two per mode) rather than EPSComputeError (which
    // repeats them): r = K x - lambda M x, backward error ||r|| / ((||K|| + |lambda| ||M||) ||x||)
    // with infinity norms, SLEPc's definition. The M-norm is checked and restored on the way.
    let norm_k = stiffness.norm_infinity()?;
    let norm_m = mass.norm_infinity()?;
    let mut residual_norms = Vec::with_capacity(sol.values.len());
    let mut backward_errors = Vec::with_capacity(sol.values.len());
    let mut kx = stiffness.new_vector()?;
    let mut mx = stiffness.new_vector()?;
    for (lambda, x) in sol.values.iter().zip(&mut sol.vectors) {
        mass.mult(x, &mut mx)?;
        let m_norm = mx.dot(x)?.sqrt();
        if m_norm > 0.0 && (m_norm - 1.0).abs() > 1e-12 {
            x.scale(1.0 / m_norm)?;
            mx.scale(1.0 / m_norm)?;
        }
        stiffness.mult(x, &mut kx)?;
        kx.axpy(-lambda, &mx)?;
        let r = kx.norm2()?;
        residual_norms.push(r);
        backward_errors.push(r / ((norm_k + lambda.abs() * norm_m) * x.norm2()?));
    }
    // NaN-aware: a NaN compares false with everything, so it is looked for explicitly.
    if let Some(k) = (0..sol.values.len())
        .find(|&k| !(sol.values[k].is_finite() && backward_errors[k].is_finite()))
    {
        return Err(LaError::NotFinite {
            what: "real modes: mode",
            index: k + 1,
            value: sol.values[k],
            backward_error: backward_errors[k],
        });
    }
    let frequencies_hz: Vec<f64> = sol.values.iter().map(|&l| frequency_hz(l)).collect();
    let rigid = frequencies_hz
        .iter()
        .map(|f| f.abs() < request.rigid_below_hz)
        .collect();
    Ok(RealModes {
        eigenvalues: sol.values,
        frequencies_hz,
        shapes: sol.vectors,
        residual_norms,
        backward_errors,
        rigid,
        rigid_below_hz: request.rigid_below_hz,
        iterations: sol.iterations,
        factorization: sol.factorization,
        seconds: start.elapsed().as_secs_f64(),
    })
}
