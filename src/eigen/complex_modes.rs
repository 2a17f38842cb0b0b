//! Complex modes `(s^2 M + s C + K) psi = 0` of a tangent state, by two routes that must agree:
//!
//! - **full**: SLEPc's PEP (TOAR, shift-and-invert with MUMPS LU) on the full unsymmetric
//!   quadratic problem in real arithmetic; complex eigenvalues come as conjugate pairs.
//! - **projected**: on the M-orthonormal real modes Phi of the symmetric reference tangent
//!   K_s = K0 + K_c + K_stick (Phi^T K_s Phi = diag(omega^2), Phi^T M Phi = I), the reduced
//!   problem `(s^2 I + s C_p + K_p) y = 0` is dense and solved through its companion matrix by
//!   LAPACK. Contact enters only through the observation rows: Phi^T (sum of point terms) Phi =
//!   P_a^T diag(g) P_b with P_a = C_a Phi (points x modes), so a new tangent state (another mu,
//!   pressure, speed, law) is re-projected in O(points x modes^2), without touching the full
//!   matrices. That makes sweeps cheap.
//!
//! Both routes report frequency Im(s)/2pi, damping ratio -Re(s)/|s| and the backward error of
//! every eigenpair on the full model, ||(s^2 M + s C + K) psi|| / ((|s|^2 ||M|| + |s| ||C|| +
//! ||K||) ||psi||) (infinity norms of the matrices, 2-norm of the vectors; PEP's definition).

use crate::invalid::InvalidSetting;
use crate::la::DenseError;
use crate::measure::nan_max;
use std::f64::consts::PI;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::contact::kernel::Channel;
use crate::la::lapack;
use crate::la::{solve_quadratic, LaError, Petsc, QuadraticOptions, SparseMatrix, Vector};

/// Which route(s) to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Route {
    #[default]
    Projected,
    Full,
    /// Both, with the projected-vs-full comparison in the results.
    Both,
}

/// The `[complex_modes]` table of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComplexModeSettings {
    #[serde(default)]
    pub method: Route,
    /// Full route: modes (one per conjugate pair) nearest s = 0. Default: as many as real
    /// modes, else 20.
    #[serde(default)]
    pub count: Option<usize>,
    /// Keep the modes below this frequency (Hz); the full route then widens its search until
    /// it has every eigenvalue with |s| below 2 pi f_max x 1.1, and reports those in the band
    /// inside that disc (heavily damped eigenvalues with |Re(s)| beyond it are left out).
    #[serde(default)]
    pub f_max_hz: Option<f64>,
    /// Full route: PEP convergence tolerance.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// A mode is reported unstable when its damping ratio is below -instability_margin
    /// (round-off puts the undamped modes of a friction-free model at |zeta| ~ 1e-12).
    #[serde(default = "default_margin")]
    pub instability_margin: f64,
}

fn default_tolerance() -> f64 {
    1e-10
}
fn default_margin() -> f64 {
    1e-6
}

impl Default for ComplexModeSettings {
    fn default() -> Self {
        ComplexModeSettings {
            method: Route::default(),
            count: None,
            f_max_hz: None,
            tolerance: default_tolerance(),
            instability_margin: default_margin(),
        }
    }
}

impl ComplexModeSettings {
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if self.count == Some(0) {
            return Err(InvalidSetting::new(
                "complex_modes.count",
                " must be at least 1",
            ));
        }
        if let Some(f) = self.f_max_hz {
            if !(f > 0.0 && f.is_finite()) {
                return Err(InvalidSetting::new(
                    "complex_modes.f_max_hz",
                    format!(" = {f}: must be a positive frequency"),
                ));
            }
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1e-2) {
            return Err(InvalidSetting::new(
                "complex_modes.tolerance",
                format!(" = {}: must be in (0, 0.01)", self.tolerance),
            ));
        }
        if !(self.instability_margin >= 0.0 && self.instability_margin < 0.1) {
            return Err(InvalidSetting::new(
                "complex_modes.instability_margin",
                format!(" = {}: must be in [0, 0.1)", self.instability_margin),
            ));
        }
        Ok(())
    }
}

/// The `[damping]` table: Rayleigh damping C = alpha M + beta K0, plus modal damping
/// C_m = M Phi diag(2 zeta omega_i) Phi^T M over the real modes whose frequency lies in
/// `modal_band_hz` (M-orthonormal Phi: each of those modes gets the damping ratio
/// `modal_ratio` on top of Rayleigh's, the others none).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingSettings {
    #[serde(default)]
    pub rayleigh_alpha: f64,
    #[serde(default)]
    pub rayleigh_beta: f64,
    #[serde(default)]
    pub modal_ratio: f64,
    #[serde(default)]
    pub modal_band_hz: Option<[f64; 2]>,
}

impl DampingSettings {
    /// Modal damping is asked for.
    pub fn has_modal(&self) -> bool {
        self.modal_ratio > 0.0
    }

    /// 2 zeta omega for a mode of circular frequency `omega` (rad/s): the modal damping's
    /// coefficient, zero outside the band.
    pub fn modal_coefficient(&self, omega: f64) -> f64 {
        match self.modal_band_hz {
            Some([low, high]) if self.has_modal() => {
                let f = omega / (2.0 * std::f64::consts::PI);
                if f >= low && f <= high {
                    2.0 * self.modal_ratio * omega
                } else {
                    0.0
                }
            }
            _ => 0.0,
        }
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        if !(self.modal_ratio >= 0.0 && self.modal_ratio < 1.0) {
            return Err(InvalidSetting::new(
                "damping.modal_ratio",
                format!(
                    " = {}: must be in [0, 1) (a damping ratio, e.g. 0.01)",
                    self.modal_ratio
                ),
            ));
        }
        match self.modal_band_hz {
            Some([low, high]) if !(low >= 0.0 && high > low && high.is_finite()) => {
                return Err(InvalidSetting::new(
                    "damping.modal_band_hz",
                    format!(" = [{low}, {high}]: must be [low, high] in Hz with 0 <= low < high"),
                ));
            }
            None if self.has_modal() => {
                return Err(InvalidSetting::new(
                    "damping.modal_ratio",
                    " needs 'damping.modal_band_hz' = [low, high] (Hz): the modes it damps",
                ));
            }
            _ => {}
        }
        for (key, v) in [
            ("rayleigh_alpha", self.rayleigh_alpha),
            ("rayleigh_beta", self.rayleigh_beta),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(InvalidSetting::new(
                    format!("damping.{key}"),
                    format!(" = {v}: must be a finite non-negative number"),
                ));
            }
        }
        Ok(())
    }
}

/// One complex mode.
#[derive(Debug, Clone, PartialEq)]
pub struct ComplexMode {
    /// Cj, numbered by ascending frequency.
    pub name: String,
    /// s = re + i im (1/s), the member of its conjugate pair with im >= 0.
    pub eigenvalue: (f64, f64),
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    /// On the full model (see the module comment).
    pub backward_error: f64,
    pub unstable: bool,
    /// Index (0-based) of the real mode with the largest participation, when known.
    pub dominant_real_mode: Option<usize>,
    /// Of an unstable mode on a mesh model: each element block's share of its kinetic
    /// energy, largest first (`stages::motion`); empty otherwise.
    pub motion: Vec<(String, f64)>,
}

/// Complex modes of one route, ascending in frequency.
pub struct ComplexModes<'p> {
    pub route: Route,
    pub modes: Vec<ComplexMode>,
    /// Real and imaginary parts of each shape (unit M-norm for the projected route).
    pub shapes: Vec<(Vector<'p>, Vector<'p>)>,
    /// Real modes in the projection basis (projected route), 0 for the full route.
    pub basis: usize,
    /// Whole route, and its eigen-solve alone (dense companion or PEP; the rest is shape
    /// expansion and backward errors on the full model).
    pub seconds: f64,
    pub solve_seconds: f64,
}

pub fn damping_ratio(s: (f64, f64)) -> f64 {
    let r = s.0.hypot(s.1);
    if r == 0.0 {
        0.0
    } else {
        -s.0 / r
    }
}

pub fn frequency_hz(s: (f64, f64)) -> f64 {
    s.1 / (2.0 * PI)
}

/// The full model's quadratic operators, for the full route and for residuals.
pub struct Operators<'a, 'p> {
    pub k: &'a SparseMatrix<'p>,
    pub c: &'a SparseMatrix<'p>,
    pub m: &'a SparseMatrix<'p>,
    norms: [f64; 3],
}

impl<'a, 'p> Operators<'a, 'p> {
    /// # Collective
    pub fn new(
        k: &'a SparseMatrix<'p>,
        c: &'a SparseMatrix<'p>,
        m: &'a SparseMatrix<'p>,
    ) -> Result<Self, LaError> {
        let norms = [k.norm_infinity()?, c.norm_infinity()?, m.norm_infinity()?];
        Ok(Operators { k, c, m, norms })
    }

    /// Backward error of (s, xr + i xi) on the full model.
    ///
    /// # Collective
    pub fn backward_error(&self, s: (f64, f64), xr: &Vector, xi: &Vector) -> Result<f64, LaError> {
        // (s^2 M + s C + K) x with s^2 = (a, b), s = (c, d), x = xr + i xi:
        // real = a M xr - b M xi + c C xr - d C xi + K xr, imaginary likewise.
        let (re, im) = s;
        let (a, b) = (re * re - im * im, 2.0 * re * im);
        let mut tmp = xr.duplicate()?;
        let (mut rr, mut ri) = (xr.duplicate()?, xr.duplicate()?);
        self.k.mult(xr, &mut rr)?;
        self.k.mult(xi, &mut ri)?;
        for (op, cr, ci) in [(self.m, a, b), (self.c, re, im)] {
            op.mult(xr, &mut tmp)?;
            rr.axpy(cr, &tmp)?;
            ri.axpy(ci, &tmp)?;
            op.mult(xi, &mut tmp)?;
            rr.axpy(-ci, &tmp)?;
            ri.axpy(cr, &tmp)?;
        }
        let r = rr.norm2()?.hypot(ri.norm2()?);
        let x = xr.norm2()?.hypot(xi.norm2()?);
        let abs = re.hypot(im);
        let scale = abs * abs * self.norms[2] + abs * self.norms[1] + self.norms[0];
        Ok(if x > 0.0 && scale > 0.0 {
            r / (scale * x)
        } else {
            f64::INFINITY
        })
    }
}

/// Orders modes by frequency, names them and flags the unstable ones.
fn finish(
    mut modes: Vec<ComplexMode>,
    settings: &ComplexModeSettings,
) -> (Vec<ComplexMode>, Vec<usize>) {
    let mut order: Vec<usize> = (0..modes.len()).collect();
    order.sort_by(|&a, &b| {
        let (sa, sb) = (modes[a].eigenvalue, modes[b].eigenvalue);
        sa.1.total_cmp(&sb.1).then(sa.0.total_cmp(&sb.0))
    });
    let mut sorted: Vec<ComplexMode> = order.iter().map(|&i| modes[i].clone()).collect();
    for (j, m) in sorted.iter_mut().enumerate() {
        m.name = format!("C{}", j + 1);
        m.unstable = m.damping_ratio < -settings.instability_margin;
    }
    modes.clear();
    (sorted, order)
}

/// The real mode a complex mode's coordinates `y` (on the real modes) weigh most.
pub fn dominant_real_mode(y: &[Complex]) -> Option<usize> {
    y.iter()
        .map(|&(r, i)| r * r + i * i)
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

fn mode(s: (f64, f64), backward_error: f64, dominant: Option<usize>) -> ComplexMode {
    ComplexMode {
        name: String::new(),
        eigenvalue: s,
        frequency_hz: frequency_hz(s),
        damping_ratio: damping_ratio(s),
        backward_error,
        unstable: false,
        dominant_real_mode: dominant,
        motion: Vec::new(),
    }
}

/// The full route.
///
/// # Collective
pub fn full<'p>(
    petsc: &'p Petsc,
    ops: &Operators<'_, 'p>,
    settings: &ComplexModeSettings,
    default_count: usize,
) -> Result<ComplexModes<'p>, LaError> {
    let start = Instant::now();
    let mut nev = settings.count.unwrap_or(default_count).max(1);
    let wanted_radius = settings.f_max_hz.map(|f| 2.0 * PI * f * 1.1);
    let sol = loop {
        let opts = QuadraticOptions {
            count: 2 * nev,
            target: 0.0,
            tolerance: settings.tolerance,
            scale: true,
            prefix: "complex_".into(),
        };
        let sol = solve_quadratic(petsc, ops.k, ops.c, ops.m, &opts)?;
        // The eigenvalues nearest 0 come first: the requested ones cover the disc up to the
        // largest of them completely (the extra converged ones need not).
        let radius = sol
            .values
            .iter()
            .take(2 * nev)
            .map(|&(r, i)| r.hypot(i))
            .fold(0.0f64, nan_max);
        match wanted_radius {
            Some(w) if radius < w && nev < 4096 && sol.values.len() >= 2 * nev => {
                // Not every eigenvalue below f_max is in yet: widen the search.
                let grow = ((w / radius.max(1e-300)).powi(2) * nev as f64).ceil() as usize;
                nev = grow.clamp(2 * nev, 4 * nev);
            }
            _ => break sol,
        }
    };
    let solve_seconds = start.elapsed().as_secs_f64();
    let mut modes = Vec::new();
    let mut shapes = Vec::new();
    for (i, &(re, im)) in sol.values.iter().enumerate() {
        if im < 0.0 {
            continue;
        }
        if settings
            .f_max_hz
            .is_some_and(|f| frequency_hz((re, im)) > f)
        {
            continue;
        }
        // With a band: only the disc searched completely (heavily damped eigenvalues with
        // Im in the band but |s| beyond it would depend on the solver's settings).
        if wanted_radius.is_some_and(|w| re.hypot(im) > w) {
            continue;
        }
        let (xr, xi) = &sol.vectors[i];
        let eta = ops.backward_error((re, im), xr, xi)?;
        modes.push(mode((re, im), eta, None));
        shapes.push((xr.try_clone()?, xi.try_clone()?));
    }
    let (modes, order) = finish(modes, settings);
    let mut slots: Vec<Option<(Vector, Vector)>> = shapes.into_iter().map(Some).collect();
    let shapes = order
        .iter()
        .map(|&i| slots[i].take().expect("each shape once"))
        .collect();
    Ok(ComplexModes {
        route: Route::Full,
        modes,
        shapes,
        basis: 0,
        seconds: start.elapsed().as_secs_f64(),
        solve_seconds,
    })
}

/// A complex number as (re, im).
pub type Complex = (f64, f64);
/// An eigenvalue with its modal coordinates.
pub type DenseEigenpair = (Complex, Vec<Complex>);
/// Projected K, C and M (column-major).
pub type ProjectedOperators = (Vec<f64>, Vec<f64>, Vec<f64>);

/// Point terms `(coefficient, channel a, channel b)` of every local point.
pub type PointTerms = [Vec<(f64, Channel, Channel)>];

/// Projects the full operators on `shapes` by products (for models without contact
/// observation, e.g. user matrices): returns (K_p, C_p, M_p), column-major.
///
/// # Collective
pub fn project_operators(
    ops: &Operators,
    shapes: &[Vector],
) -> Result<ProjectedOperators, LaError> {
    let m = shapes.len();
    let mut out = [vec![0.0; m * m], vec![0.0; m * m], vec![0.0; m * m]];
    if m == 0 {
        let [k, c, mm] = out;
        return Ok((k, c, mm));
    }
    let mut y = shapes[0].duplicate()?;
    for (o, op) in out.iter_mut().zip([ops.k, ops.c, ops.m]) {
        for j in 0..m {
            op.mult(&shapes[j], &mut y)?;
            for i in 0..m {
                o[j * m + i] = shapes[i].dot(&y)?;
            }
        }
    }
    let [k, c, mm] = out;
    Ok((k, c, mm))
}

/// The companion matrix [[0, I], [-K_p, -C_p]] of `(s^2 I + s C_p + K_p) y = 0` (order 2m,
/// column-major), scaled by omega_r = sqrt(max |K_p,ii|) so its blocks are of order one
/// (LAPACK balances the rest); returned with omega_r (its eigenvalues times omega_r are s).
pub fn companion(m: usize, kp: &[f64], cp: &[f64]) -> (Vec<f64>, f64) {
    let n = 2 * m;
    let omega_r = (0..m)
        .map(|i| kp[i * m + i].abs())
        .fold(0.0f64, nan_max)
        .sqrt()
        .max(1e-300);
    let mut a = vec![0.0; n * n];
    for i in 0..m {
        a[(m + i) * n + i] = 1.0;
        for j in 0..m {
            a[j * n + m + i] = -kp[j * m + i] / (omega_r * omega_r);
            a[(m + j) * n + m + i] = -cp[j * m + i] / omega_r;
        }
    }
    (a, omega_r)
}

/// The coordinates y (unit 2-norm) of a companion eigenvector z = [y; s y], or None where
/// its y part vanishes.
pub fn coordinates(m: usize, z: &[(f64, f64)]) -> Option<Vec<(f64, f64)>> {
    let norm = z[..m]
        .iter()
        .map(|&(r, i)| r * r + i * i)
        .sum::<f64>()
        .sqrt();
    (norm > 0.0).then(|| z[..m].iter().map(|&(r, i)| (r / norm, i / norm)).collect())
}

/// Eigenpairs of `(s^2 I + s C_p + K_p) y = 0` (m x m, column-major) with Im(s) >= 0; y has
/// unit 2-norm. Solved on the scaled companion matrix ([`companion`]).
pub fn solve_dense(m: usize, kp: &[f64], cp: &[f64]) -> Result<Vec<DenseEigenpair>, DenseError> {
    let (a, omega_r) = companion(m, kp, cp);
    let e = lapack::eigen_general(2 * m, a)?;
    let mut out = Vec::new();
    for (j, &(re, im)) in e.values.iter().enumerate() {
        if im < 0.0 {
            continue;
        }
        if let Some(y) = coordinates(m, &e.vectors[j]) {
            out.push(((re * omega_r, im * omega_r), y));
        }
    }
    Ok(out)
}

/// psi = Phi y for complex coordinates y.
///
/// # Collective
pub fn expand<'p>(
    shapes: &[Vector<'p>],
    y: &[(f64, f64)],
) -> Result<(Vector<'p>, Vector<'p>), LaError> {
    let mut xr = shapes[0].duplicate()?;
    let mut xi = shapes[0].duplicate()?;
    xr.set_all(0.0)?;
    xi.set_all(0.0)?;
    for (phi, &(r, i)) in shapes.iter().zip(y) {
        xr.axpy(r, phi)?;
        xi.axpy(i, phi)?;
    }
    Ok((xr, xi))
}

/// The projected route from projected operators (M_p = I). With `ops`, each mode is expanded
/// to the full model and its backward error computed there (else NaN, for fast sweeps).
///
/// # Collective
pub fn projected<'p>(
    shapes: &[Vector<'p>],
    kp: &[f64],
    cp: &[f64],
    ops: Option<&Operators<'_, 'p>>,
    settings: &ComplexModeSettings,
) -> Result<ComplexModes<'p>, LaError> {
    let start = Instant::now();
    let m = shapes.len();
    let pairs = solve_dense(m, kp, cp)?;
    let solve_seconds = start.elapsed().as_secs_f64();
    let mut modes = Vec::new();
    let mut coords = Vec::new();
    for (s, y) in pairs {
        if settings.f_max_hz.is_some_and(|f| frequency_hz(s) > f) {
            continue;
        }
        modes.push(mode(s, f64::NAN, dominant_real_mode(&y)));
        coords.push(y);
    }
    let (mut modes, order) = finish(modes, settings);
    let mut shapes_out = Vec::new();
    if let Some(ops) = ops {
        for (mode, &i) in modes.iter_mut().zip(&order) {
            let (xr, xi) = expand(shapes, &coords[i])?;
            mode.backward_error = ops.backward_error(mode.eigenvalue, &xr, &xi)?;
            shapes_out.push((xr, xi));
        }
    }
    Ok(ComplexModes {
        route: Route::Projected,
        modes,
        shapes: shapes_out,
        basis: m,
        seconds: start.elapsed().as_secs_f64(),
        solve_seconds,
    })
}

/// Modal coordinates of the projected modes (for tracking), in the order of `modes`.
pub fn projected_coordinates(
    m: usize,
    kp: &[f64],
    cp: &[f64],
) -> Result<Vec<DenseEigenpair>, DenseError> {
    let mut pairs = solve_dense(m, kp, cp)?;
    pairs.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1).then(a.0 .0.total_cmp(&b.0 .0)));
    Ok(pairs)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn dense_route_finds_damped_oscillators_exactly() {
        // Uncoupled s^2 + c s + k: s = -c/2 +- i sqrt(k - c^2/4).
        let m = 3;
        let k = [4.0, 9.0e6, 16.0e10];
        let c = [0.1, 30.0, 2.0e3];
        let mut kp = vec![0.0; 9];
        let mut cp = vec![0.0; 9];
        for i in 0..m {
            kp[i * m + i] = k[i];
            cp[i * m + i] = c[i];
        }
        let pairs = solve_dense(m, &kp, &cp).unwrap();
        assert_eq!(pairs.len(), 3);
        for i in 0..m {
            let exact = (-c[i] / 2.0, (k[i] - c[i] * c[i] / 4.0).sqrt());
            let found = pairs
                .iter()
                .map(|p| p.0)
                .min_by(|a, b| {
                    let d = |s: &(f64, f64)| (s.0 - exact.0).hypot(s.1 - exact.1);
                    d(a).total_cmp(&d(b))
                })
                .unwrap();
            let err = (found.0 - exact.0).hypot(found.1 - exact.1) / exact.0.hypot(exact.1);
            assert!(
                err < 1e-12,
                "oscillator {i}: {found:?} vs {exact:?} ({err:e})"
            );
        }
    }

    #[test]
    fn damping_ratio_and_frequency() {
        let s = (-3.0, 4.0);
        assert!((damping_ratio(s) - 0.6).abs() < 1e-15);
        assert!((frequency_hz(s) - 4.0 / (2.0 * PI)).abs() < 1e-15);
    }
}
