//! Mode-coupling flutter of a 2-DOF mass on a moving belt (the minimal model of Hoffmann,
//! Fischer, Cornelsen & Gaul, Mech. Res. Commun. 29 (2002) 197-205: a mass on two skewed
//! springs, pressed on a belt, friction coupling the normal motion into the tangential one),
//! here with squeal's exponential normal law, so that the growth saturates by separation.
//!
//! Unit mass, x along the belt, y its normal (gap = y), springs K_s = [[2, -0.2], [-0.2, 1]],
//! damping C = 0.1 I, normal force N(y) = N0 exp(-lambda y) with N0 = lambda = 1, preload F0
//! (constant, towards the belt), friction mu N tanh((V - x') / eps) (squeal's Coulomb law),
//! mu = 0.5, belt speed V = 100 (the mass always slides forward). Static state: y = 0,
//! x = mu N0 / 2, F0 = N0 + 0.2 x.
//!
//! Linearized there (k_c = lambda N0 = 1; the friction's speed derivative vanishes at V/eps):
//! s^2 + c s + kappa = 0 with kappa the eigenvalues of K_t = [[2, -0.2 + mu k_c], [-0.2, 1 + k_c]]
//! = 2 +- i sqrt(0.06): a flutter pair s = -c/2 +- sqrt(c^2/4 - kappa), Re(s) = 0.03661,
//! Im(s) = 1.41466 (computed below in complex arithmetic). Verified:
//! - the growth rate of the linear phase (least squares of ln(peaks of y) from t = 60, where
//!   the stable pair has decayed below 1e-4 of the unstable one, while y < 0.03, where the
//!   exponential's quadratic term shifts the rate by less than 1e-3): within 2e-3 of Re(s),
//!   and the frequency within 1e-3 of Im(s) (average-acceleration Newmark: relative period
//!   error (w h)^2 / 12 = 7e-5 at h = 0.02);
//! - the limit cycle is bounded and closed: the peak-to-peak of y over the last 10 cycles
//!   varies by less than 1e-3 (a quasi-periodic or growing orbit would not);
//! - the contact opens on part of the cycle (N < 1 % of N0, squeal's open criterion);
//! - the energy balance over the last 10 cycles: the friction's work W_f equals the damping's
//!   dissipation D up to the energy change E_end - E_start between the cycles' ends (grid
//!   points next to maxima of y), which must be below 1e-3 D (a closed cycle). Average-
//!   acceleration Newmark conserves the discrete energy exactly: with dq = h (v0 + v1) / 2,
//!   dq . (mean of the equation of motion at both ends) is the change of kinetic and spring
//!   energy, so E_end - E_start - (W_f - D) is only the trapezoidal error of the contact
//!   potential, bounded per step by |dy|^3 / 12 max |N''| (N'' = lambda^2 N) and asserted so;
//! - against fine-step references (h = 0.04, 0.02, 0.01): the cycle's amplitude and period
//!   converge at second order (the differences of successive halvings shrink by at least 3).

use super::TestResult;
use squeal::contact::law::{FrictionLaw, NormalLaw};
use squeal::la::Preallocation;
use squeal::la::{
    DirectSolver, Factorization, LaError, MatrixFormat, Operator, Petsc, SparseMatrix, Vector,
};
use squeal::measure::{nan_max, nan_min};
use squeal::time::adaptive::{AdaptiveNewmark, Adaptivity, Closures, Flow, StepControl};
use squeal::time::newmark::{
    initial_acceleration, jacobian, Damping, Jacobian, NewmarkSettings, State, StepReport,
    TimeError,
};

use squeal::post::limit_cycle::slope;

use super::common::{rel, say};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "hoffmann_mode_coupling_saturates_by_separation_with_balanced_energy",
        mode_coupling,
    )]
}

pub(super) const K_S: [[f64; 2]; 2] = [[2.0, -0.2], [-0.2, 1.0]];
pub(super) const C: f64 = 0.1;
pub(super) const MU: f64 = 0.5;
pub(super) const V: f64 = 100.0;
const N0: f64 = 1.0;
const LAMBDA: f64 = 1.0;
pub(super) const NORMAL: NormalLaw = NormalLaw::Exponential {
    p0: N0,
    lambda: LAMBDA,
    linear_below_gap: None,
};
pub(super) const FRICTION: FrictionLaw = FrictionLaw::Coulomb {
    mu: MU,
    slip_speed: 1e-3,
};

pub(super) fn static_x() -> f64 {
    MU * NORMAL.eval(0.0).pressure / K_S[0][0]
}

pub(super) fn preload() -> f64 {
    NORMAL.eval(0.0).pressure - K_S[1][0] * static_x()
}

/// The flutter eigenvalue s (Re, Im) of the linearization at the static state.
pub(super) fn closed_form_eigenvalue() -> (f64, f64) {
    let kc = NORMAL.eval(0.0).stiffness;
    let kt = [
        [K_S[0][0], K_S[0][1] + MU * kc],
        [K_S[1][0], K_S[1][1] + kc],
    ];
    let half_trace = 0.5 * (kt[0][0] + kt[1][1]);
    let det = kt[0][0] * kt[1][1] - kt[0][1] * kt[1][0];
    let disc = half_trace * half_trace - det;
    assert!(disc < 0.0, "the parameters must give flutter");
    // kappa = half_trace + i sqrt(-disc); s = -c/2 + sqrt(c^2/4 - kappa).
    let (re, im) = complex_sqrt(0.25 * C * C - half_trace, -(-disc).sqrt());
    let (s1, s2) = ((-0.5 * C + re, im), (-0.5 * C - re, -im));
    if s1.0 > s2.0 {
        (s1.0, s1.1.abs())
    } else {
        (s2.0, s2.1.abs())
    }
}

fn complex_sqrt(a: f64, b: f64) -> (f64, f64) {
    let r = a.hypot(b);
    let re = (0.5 * (r + a)).sqrt();
    let im = (0.5 * (r - a)).sqrt().copysign(b);
    (re, im)
}

/// What one run recorded at every step.
#[derive(Default)]
pub(super) struct Record {
    pub(super) t: Vec<f64>,
    pub(super) q: Vec<[f64; 2]>,
    pub(super) v: Vec<[f64; 2]>,
    control: StepControl,
}

fn mode_coupling(petsc: &Petsc) -> TestResult {
    let (sigma, omega) = closed_form_eigenvalue();
    // Linear phase, from a 1e-3 kick: peaks of y from t = 60 (the stable pair, decaying at
    // 0.137 + 0.037 relative to the unstable one, is below 1e-4 of it by then) while y stays
    // below 0.03.
    let growing = run(petsc, 0.02, 1e-3, 130.0)?;
    let linear: Vec<(f64, f64)> = maxima(&growing, 1)
        .into_iter()
        .filter(|&(t, y)| t > 60.0 && y < 0.03)
        .collect();
    if linear.len() < 5 {
        return Err(format!("{} peaks in the linear phase", linear.len()).into());
    }
    let growth = slope(&linear.iter().map(|&(t, y)| (t, y.ln())).collect::<Vec<_>>());
    let frequency = 2.0 * std::f64::consts::PI * (linear.len() - 1) as f64
        / (linear[linear.len() - 1].0 - linear[0].0);
    // The cycle, from a 2.0 kick (the contact opens at once; the growth phase is skipped): the
    // orbit settles at about 0.008 per unit time (measured: spread 2.5e-3 at t = 400 from a
    // 1e-3 kick, 2e-4 at t = 700).
    let end = 450.0;
    let settled = run(petsc, 0.02, 2.0, end)?;
    let cycle = LimitCycle::of(&settled)?;
    say(
        petsc,
        &format!(
            "2-DOF mode coupling: growth {growth:.5} (closed form {sigma:.5}, {:.1e}), frequency {frequency:.5} rad/s ({omega:.5}, {:.1e}); cycle: y peak-to-peak {:.5} (spread {:.1e} over 10 cycles), period {:.5}, open {:.1} % of the cycle; W_f {:.5}, D {:.5}, E_end - E_start {:.2e} (E_end - E_start - (W_f - D) = {:.2e}, bound {:.2e}); {} steps, {} refreshes, {} cuts",
            rel(growth, sigma),
            rel(frequency, omega),
            cycle.amplitude,
            cycle.spread,
            cycle.period,
            100.0 * cycle.open_fraction,
            cycle.friction_work,
            cycle.dissipation,
            cycle.energy_change,
            cycle.energy_change - (cycle.friction_work - cycle.dissipation),
            cycle.quadrature_bound,
            settled.control.steps,
            settled.control.refreshes,
            settled.control.cuts
        ),
    );
    if !(rel(growth, sigma) < 2e-3 && rel(frequency, omega) < 1e-3) {
        return Err(format!(
            "linear phase: growth {growth} vs {sigma}, frequency {frequency} vs {omega}"
        )
        .into());
    }
    // (NaN fails.)
    if cycle.spread.is_nan() || cycle.spread >= 1e-3 {
        return Err(format!("the cycle is not closed: spread {}", cycle.spread).into());
    }
    if cycle.open_fraction.is_nan() || cycle.open_fraction <= 0.0 {
        return Err("the contact never opens on the cycle".into());
    }
    let identity = cycle.energy_change - (cycle.friction_work - cycle.dissipation);
    if !(identity.abs() <= cycle.quadrature_bound
        && cycle.energy_change.abs() < 1e-3 * cycle.dissipation)
    {
        return Err(format!(
            "energy balance: W_f {} vs D {}, E_end - E_start {} (closed: below {}), identity error {identity:.3e} (bound {:.3e})",
            cycle.friction_work,
            cycle.dissipation,
            cycle.energy_change,
            1e-3 * cycle.dissipation,
            cycle.quadrature_bound
        ).into());
    }

    // Fine-step references: second-order convergence of the cycle's amplitude and period.
    // Pure arithmetic of a 2-DOF model (the 2-rank run above went through the distributed
    // path already): on one rank only, where it costs 4x less.
    if petsc.size() > 1 {
        return Ok(());
    }
    let coarse = LimitCycle::of(&run(petsc, 0.04, 2.0, end)?)?;
    let finest = LimitCycle::of(&run(petsc, 0.01, 2.0, end)?)?;
    let d_amplitude = [
        (coarse.amplitude - cycle.amplitude).abs(),
        (cycle.amplitude - finest.amplitude).abs(),
    ];
    let d_period = [
        (coarse.period - cycle.period).abs(),
        (cycle.period - finest.period).abs(),
    ];
    say(
        petsc,
        &format!(
            "h = 0.04 / 0.02 / 0.01: peak-to-peak {:.6} / {:.6} / {:.6} (differences {:.1e}, {:.1e}), period {:.6} / {:.6} / {:.6} ({:.1e}, {:.1e})",
            coarse.amplitude,
            cycle.amplitude,
            finest.amplitude,
            d_amplitude[0],
            d_amplitude[1],
            coarse.period,
            cycle.period,
            finest.period,
            d_period[0],
            d_period[1]
        ),
    );
    if !(d_amplitude[0] >= 3.0 * d_amplitude[1] && d_period[0] >= 3.0 * d_period[1]) {
        return Err(format!(
            "not second order: amplitude differences {d_amplitude:?}, period differences {d_period:?}"
        ).into());
    }
    Ok(())
}

/// The last 10 cycles of a run (between maxima of y).
struct LimitCycle {
    amplitude: f64,
    spread: f64,
    period: f64,
    open_fraction: f64,
    friction_work: f64,
    dissipation: f64,
    energy_change: f64,
    /// Sum over the steps of |dy|^3 / 12 max |N''| (the trapezoidal rule's error bound for
    /// the contact potential).
    quadrature_bound: f64,
}

impl LimitCycle {
    fn of(r: &Record) -> TestResult<Self> {
        const CYCLES: usize = 10;
        let peaks = maxima_at(r, 1);
        if peaks.len() < CYCLES + 1 {
            return Err(format!("{} maxima of y", peaks.len()).into());
        }
        let last = &peaks[peaks.len() - CYCLES - 1..];
        let mut amplitudes = Vec::new();
        for w in last.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let min = r.q[lo..hi]
                .iter()
                .map(|q| q[1])
                .fold(f64::INFINITY, nan_min);
            amplitudes.push(nan_max(r.q[lo][1], r.q[hi][1]) - min);
        }
        let max = amplitudes.iter().copied().fold(f64::NEG_INFINITY, nan_max);
        let min = amplitudes.iter().copied().fold(f64::INFINITY, nan_min);
        let mean = amplitudes.iter().sum::<f64>() / CYCLES as f64;
        let (first, end) = (last[0], last[CYCLES]);
        let period = (interpolated_peak(r, end) - interpolated_peak(r, first)) / CYCLES as f64;
        let open = (first..end).filter(|&i| NORMAL.is_open(r.q[i][1])).count();
        let (mut friction_work, mut dissipation, mut quadrature_bound) = (0.0, 0.0, 0.0);
        for i in first..end {
            // N is largest at the lower y of the step.
            let dy = (r.q[i + 1][1] - r.q[i][1]).abs();
            let n_max = NORMAL.eval(nan_min(r.q[i][1], r.q[i + 1][1])).pressure;
            quadrature_bound += dy.powi(3) / 12.0 * LAMBDA * LAMBDA * n_max;
            let dq = [r.q[i + 1][0] - r.q[i][0], r.q[i + 1][1] - r.q[i][1]];
            let fx = 0.5 * (friction(r.q[i], r.v[i]) + friction(r.q[i + 1], r.v[i + 1]));
            friction_work += fx * dq[0];
            for (d, (a, b)) in dq.iter().zip(r.v[i].iter().zip(r.v[i + 1].iter())) {
                dissipation += C * 0.5 * (a + b) * d;
            }
        }
        Ok(LimitCycle {
            amplitude: mean,
            spread: (max - min) / mean,
            period,
            open_fraction: open as f64 / (end - first) as f64,
            friction_work,
            dissipation,
            energy_change: energy(r.q[end], r.v[end]) - energy(r.q[first], r.v[first]),
            quadrature_bound,
        })
    }
}

fn friction(q: [f64; 2], v: [f64; 2]) -> f64 {
    FRICTION
        .traction(NORMAL.eval(q[1]).pressure, V - v[0])
        .traction
}

/// Kinetic + spring + contact potential ((N0 / lambda) exp(-lambda y), whose -d/dy is N) +
/// the preload's potential F0 y (its force is -F0).
fn energy(q: [f64; 2], v: [f64; 2]) -> f64 {
    let spring =
        0.5 * (K_S[0][0] * q[0] * q[0] + 2.0 * K_S[0][1] * q[0] * q[1] + K_S[1][1] * q[1] * q[1]);
    let contact = NORMAL.eval(q[1]).pressure / LAMBDA;
    0.5 * (v[0] * v[0] + v[1] * v[1]) + spring + contact + preload() * q[1]
}

/// Indices of the local maxima of component `c` of q.
pub(super) fn maxima_at(r: &Record, c: usize) -> Vec<usize> {
    (1..r.q.len() - 1)
        .filter(|&i| r.q[i][c] > r.q[i - 1][c] && r.q[i][c] >= r.q[i + 1][c])
        .collect()
}

fn maxima(r: &Record, c: usize) -> Vec<(f64, f64)> {
    maxima_at(r, c)
        .into_iter()
        .map(|i| (interpolated_peak(r, i), r.q[i][c]))
        .collect()
}

/// The time of the maximum of y near sample i (where the velocity changes sign).
fn interpolated_peak(r: &Record, i: usize) -> f64 {
    let (v0, v1) = (r.v[i][1], r.v[i + 1][1]);
    if v0 > 0.0 && v1 <= 0.0 {
        r.t[i] + (r.t[i + 1] - r.t[i]) * v0 / (v0 - v1)
    } else {
        let (vm, v0) = (r.v[i - 1][1], r.v[i][1]);
        r.t[i - 1] + (r.t[i] - r.t[i - 1]) * vm / (vm - v0)
    }
}

/// A 2 x 2 matrix, row i on rank i (1 rank: both).
fn dense<'p>(petsc: &'p Petsc, a: [[f64; 2]; 2]) -> Result<SparseMatrix<'p>, LaError> {
    let rows = owned_rows(petsc);
    let p = Preallocation {
        diag: vec![2; rows.len()],
        off: vec![2; rows.len()],
        diag_upper: vec![2; rows.len()],
        off_upper: vec![2; rows.len()],
    };
    let mut m = SparseMatrix::new(petsc, MatrixFormat::Aij, 1, rows.len(), &p)?;
    for i in rows {
        m.add_values(&[i as i32], &[0, 1], &a[i])?;
    }
    m.assemble()?;
    Ok(m)
}

fn owned_rows(petsc: &Petsc) -> std::ops::Range<usize> {
    let (size, rank) = (petsc.size() as usize, petsc.rank() as usize);
    rank * 2 / size..(rank + 1) * 2 / size
}

fn vector<'p>(petsc: &'p Petsc, values: [f64; 2]) -> Result<Vector<'p>, LaError> {
    Vector::from_local(petsc, &values[owned_rows(petsc)])
}

/// The nonlinear forces' tangent -df/dq - gamma/(beta h) df/dv at a state.
fn tangent(ns: &NewmarkSettings, q: [f64; 2], v: [f64; 2]) -> [[f64; 2]; 2] {
    let n = NORMAL.eval(q[1]);
    let t = FRICTION.traction(n.pressure, V - v[0]);
    let c1 = ns.gamma / (ns.beta * ns.step);
    // f_x = t(N(y), V - x'), f_y = N(y) - F0.
    [
        [c1 * t.d_speed, t.d_pressure * n.stiffness],
        [0.0, n.stiffness],
    ]
}

pub(super) fn run(petsc: &Petsc, step: f64, kick: f64, end: f64) -> TestResult<Record> {
    let m = dense(petsc, [[1.0, 0.0], [0.0, 1.0]])?;
    let k = dense(petsc, K_S)?;
    let damping = Damping::Rayleigh {
        alpha: C,
        beta: 0.0,
    };
    let settings = NewmarkSettings {
        step,
        tolerance: 1e-10,
        max_iterations: 30,
        ..Default::default()
    };
    let f0 = preload();
    let mut forces = |_t: f64, q: &Vector, v: &Vector, f: &mut Vector| {
        let (q, v) = (q.gather_all()?, v.gather_all()?);
        let p = NORMAL.eval(q[1]).pressure;
        let all = [FRICTION.traction(p, V - v[0]).traction, p - f0];
        f.local_mut()?.copy_from_slice(&all[owned_rows(petsc)]);
        Ok(())
    };
    let pair = |s: &State| -> Result<([f64; 2], [f64; 2]), LaError> {
        let (q, v) = (s.q.gather_all()?, s.v.gather_all()?);
        Ok(([q[0], q[1]], [v[0], v[1]]))
    };
    let mut factorize = |ns: &NewmarkSettings, at: Option<&State>, _retired| {
        let (q, v) = match at {
            Some(s) => pair(s)?,
            None => ([static_x(), 0.0], [0.0; 2]),
        };
        let x = dense(petsc, tangent(ns, q, v))?;
        let j = jacobian(ns, &m, damping, &k, Some(&x))?;
        Ok(Jacobian {
            factor: DirectSolver::factorize(petsc, &j, Factorization::Lu, "time_")?,
            extra: Some(Box::new(x) as Box<dyn Operator + '_>),
            matrix: Some(j),
        })
    };
    let mut linearize = |ns: &NewmarkSettings, s: &State| {
        let (q, v) = pair(s)?;
        Ok(Box::new(dense(petsc, tangent(ns, q, v))?) as Box<dyn squeal::la::TangentChange + '_>)
    };
    // A kick in y from the static state.
    let mut state = State {
        time: 0.0,
        step: 0,
        q: vector(petsc, [static_x(), kick])?,
        v: vector(petsc, [0.0; 2])?,
        a: vector(petsc, [0.0; 2])?,
        linear: None,
    };
    let mass = DirectSolver::factorize(petsc, &m, Factorization::Lu, "mass_")?;
    initial_acceleration(&m, damping, &k, &mut state, &mut forces, &mass)?;
    let mut record = Record::default();
    let (q, v) = pair(&state)?;
    record.t.push(0.0);
    record.q.push(q);
    record.v.push(v);
    let mut on_step =
        |s: &State, _r: &StepReport, _c: &StepControl, _h: f64| -> Result<Flow, TimeError> {
            let (q, v) = pair(s)?;
            record.t.push(s.time);
            record.q.push(q);
            record.v.push(v);
            Ok(Flow::Continue)
        };
    let mut control = StepControl::default();
    AdaptiveNewmark {
        settings,
        m: &m,
        c: damping,
        k: &k,
        equilibrium: None,
        adaptivity: Adaptivity {
            max_cuts: 6,
            restore_after: 100,
            refresh: true,
            full_newton: false,
            update: true,
        },
    }
    .integrate(
        &mut Closures {
            forces: &mut forces,
            factorize: &mut factorize,
            linearize: Some(&mut linearize),
            on_step: &mut on_step,
            log: &mut |_: &str| {},
        },
        &mut state,
        end,
        &mut control,
    )
    .map_err(|e| format!("h = {step}: {e}"))?;
    record.control = control;
    Ok(record)
}
