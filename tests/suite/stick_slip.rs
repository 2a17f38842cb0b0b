//! Stick-slip of a mass on a moving belt (the classical friction oscillator; e.g. Popp &
//! Stelter, Phil. Trans. R. Soc. A 332 (1990) 89-105): mass m on a spring k to the ground,
//! pressed with N on a belt moving at V, friction with a static coefficient mu_s above the
//! kinetic mu_k.
//!
//! Closed form for the unregularized law: the mass sticks to the belt (v = V) until the
//! spring force reaches mu_s N (x_s = mu_s N / k), then slips on an arc of the harmonic
//! oscillator centred at x_k = mu_k N / k, radius A = sqrt(d^2 + (V/w)^2) with d = x_s - x_k
//! and w = sqrt(k/m), until v = V again at x = x_k - d; so
//!   T = (pi + 2 atan2(V/w, d)) / w + 2 d / V,   peak-to-peak of x = 2 A.
//! With m = k = N = 1, V = 0.5, mu_s = 0.4, mu_k = 0.25: T = 6.30027, 2A = 1.04403.
//!
//! The run uses squeal's regularized Stribeck law (mu(w) = mu_k + (mu_s - mu_k) e^{-|w|/c},
//! times (2/pi) atan(w / eps)) through the adaptive Newmark integrator with its Newton-Krylov
//! fallback. The law tends to the discontinuous one when c -> 0 and eps / c -> 0 (its peak
//! is below mu_s by O(eps / c), its sliding value above mu_k by O(c)): here eps is quartered
//! and c = sqrt(eps) / 2 halved per level, so the errors of the period and of the amplitude
//! must shrink, asserted by at least a factor 1.5 per level, and be below 2 % at the finest
//! (eps = 6.25e-4). The step h = 1e-3 resolves the band crossings (the sliding speed crosses
//! eps in about eps / |x''| = 4e-3 s at the slip onset).

use super::TestResult;
use squeal::contact::law::FrictionLaw;
use squeal::la::{DirectSolver, Factorization, Petsc, Vector};
use squeal::time::adaptive::{AdaptiveNewmark, Adaptivity, Closures, Flow, StepControl};
use squeal::time::newmark::{
    initial_acceleration, Damping, NewmarkSettings, State, StepReport, TimeError,
};

use super::common::{rel, say};
use super::time_integration::{one_dof_jacobian, one_dof_state, tridiagonal};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "popp_stelter_belt_stick_slip_converges_to_the_coulomb_cycle",
        belt_stick_slip,
    )]
}

const V: f64 = 0.5;
const MU_S: f64 = 0.4;
const MU_K: f64 = 0.25;

/// The closed-form period and peak-to-peak amplitude (m = k = N = 1).
fn closed_form() -> (f64, f64) {
    let d = MU_S - MU_K;
    let theta = V.atan2(d);
    (
        (std::f64::consts::PI + 2.0 * theta) + 2.0 * d / V,
        2.0 * (d * d + V * V).sqrt(),
    )
}

fn belt_stick_slip(petsc: &Petsc) -> TestResult {
    let (period, amplitude) = closed_form();
    let mut errors = Vec::new();
    let mut fine = (0.0, 0.0);
    for eps in [1e-2, 2.5e-3, 6.25e-4] {
        let (p, a, control) = run(petsc, eps, 1e-3, false)?;
        say(
            petsc,
            &format!(
                "eps {eps:.1e}: period {p:.5} (closed form {period:.5}, {:.2e}), peak-to-peak {a:.5} ({amplitude:.5}, {:.2e}); {} steps, {} refreshes, {} Newton-Krylov and {} full-Newton retries, {} cuts",
                rel(p, period),
                rel(a, amplitude),
                control.steps,
                control.refreshes,
                control.krylov_retries,
                control.full_newton_retries,
                control.cuts
            ),
        );
        errors.push((rel(p, period), rel(a, amplitude)));
        fine = (p, a);
    }
    for w in errors.windows(2) {
        let shrinks = |a: f64, b: f64| a.is_finite() && b.is_finite() && b * 1.5 <= a;
        if !shrinks(w[0].0, w[1].0) || !shrinks(w[0].1, w[1].1) {
            return Err(format!("errors do not shrink with the regularization: {errors:?}").into());
        }
    }
    let finest = errors[errors.len() - 1];
    if !(finest.0 < 0.02 && finest.1 < 0.02) {
        return Err(format!("finest regularization: errors {finest:?} above 2 %").into());
    }
    // The same law with a 4x longer step and Jacobians that never carry the friction: its
    // slope through gamma / (beta h) (about 400 N s/m x 500 1/s) matches the inertia term
    // m / (beta h^2), so the factorized J alone cannot converge where the mass sticks (refresh
    // does not help: it has no friction either); the steps must go through on the consistent
    // tangent (Newton-Krylov: GMRES with that J as preconditioner), to the same cycle as the
    // fine step (the Newmark error (w h)^2 / 12 = 1.3e-6 is negligible here): asserted 1e-3
    // of the period and of the amplitude of the h = 1e-3 run at the same eps.
    let (p, a, control) = run(petsc, 6.25e-4, 4e-3, true)?;
    say(
        petsc,
        &format!(
            "h = 4e-3: period {p:.5} ({:.2e}), peak-to-peak {a:.5} ({:.2e}); {} refreshes, {} Newton-Krylov and {} full-Newton retries, {} cuts",
            rel(p, period),
            rel(a, amplitude),
            control.refreshes,
            control.krylov_retries,
            control.full_newton_retries,
            control.cuts
        ),
    );
    let (p_fine, a_fine) = fine;
    if control.krylov_retries == 0 || !(rel(p, p_fine) < 1e-3 && rel(a, a_fine) < 1e-3) {
        return Err(format!(
            "h = 4e-3: {} Newton-Krylov retries, period {p} vs {p_fine}, amplitude {a} vs {a_fine}",
            control.krylov_retries
        )
        .into());
    }
    Ok(())
}

/// One run of 5 cycles; returns the period and peak-to-peak amplitude of the last cycle
/// (between maxima of x) and the step control.
fn run(
    petsc: &Petsc,
    eps: f64,
    step: f64,
    frictionless_jacobian: bool,
) -> TestResult<(f64, f64, StepControl)> {
    let law = FrictionLaw::Stribeck {
        mu_static: MU_S,
        mu_kinetic: MU_K,
        decay_speed: 0.5 * eps.sqrt(),
        slip_speed: eps,
    };
    let m = tridiagonal(petsc, &[1.0], &[])?;
    let k = tridiagonal(petsc, &[1.0], &[])?;
    let settings = NewmarkSettings {
        step,
        tolerance: 1e-10,
        max_iterations: 30,
        ..Default::default()
    };
    // f = N t(N, V - v): the belt drags the mass while it moves faster.
    let mut forces = |_t: f64, _q: &Vector, v: &Vector, f: &mut Vector| {
        let v = v.local()?.to_vec();
        let mut out = f.local_mut()?;
        for (o, v) in out.iter_mut().zip(v) {
            *o = law.traction(1.0, V - v).traction;
        }
        Ok(())
    };
    // The friction's tangent at a state: -df/dv = t'(w) through gamma / (beta h).
    let damping_at = |ns: &NewmarkSettings, s: &State| -> Result<f64, squeal::la::LaError> {
        let v = s.v.gather_all()?[0];
        Ok(ns.gamma / (ns.beta * ns.step) * law.traction(1.0, V - v).d_speed)
    };
    let mass = DirectSolver::factorize(petsc, &m, Factorization::Lu, "mass_")?;
    // Riding on the belt: the stick phase starts the cycle (from rest the mass would
    // oscillate about x_k without ever reaching the belt's speed, a pure-slip orbit).
    let mut state = one_dof_state(petsc, 0.0, V)?;
    initial_acceleration(&m, Damping::None, &k, &mut state, &mut forces, &mass)?;
    // The fixed J knows nothing of the friction (the sliding start has none); refreshed ones
    // carry it at their state, unless `frictionless_jacobian` (then only the linearization
    // does, and the Newton-Krylov retries must carry the steps).
    let mut factorize = |ns: &NewmarkSettings, at: Option<&State>, _retired| {
        let c = match at {
            Some(s) if !frictionless_jacobian => damping_at(ns, s)?,
            _ => 0.0,
        };
        one_dof_jacobian(petsc, ns, &m, &k, c, true)
    };
    let mut linearize = |ns: &NewmarkSettings, s: &State| {
        let c = damping_at(ns, s)?;
        let op = tridiagonal(petsc, &[c], &[])?;
        Ok(Box::new(op) as Box<dyn squeal::la::TangentChange + '_>)
    };
    let mut maxima = Vec::new();
    let mut extremes: Vec<f64> = Vec::new();
    let mut previous = (0.0, 0.0, 0.0);
    let mut on_step =
        |s: &State, _r: &StepReport, _c: &StepControl, _h: f64| -> Result<Flow, TimeError> {
            let x = s.q.gather_all().map_err(TimeError::La)?[0];
            let v = s.v.gather_all().map_err(TimeError::La)?[0];
            let (t0, x0, v0) = previous;
            if v0 > 0.0 && v <= 0.0 {
                maxima.push(t0 + (s.time - t0) * v0 / (v0 - v));
                extremes.push(squeal::measure::nan_max(x, x0));
            } else if v0 < 0.0 && v >= 0.0 {
                extremes.push(squeal::measure::nan_min(x, x0));
            }
            previous = (s.time, x, v);
            Ok(Flow::Continue)
        };
    let mut log = |_: &str| {};
    let mut control = StepControl::default();
    let (period, _) = closed_form();
    AdaptiveNewmark {
        settings,
        m: &m,
        c: Damping::None,
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
            log: &mut log,
        },
        &mut state,
        5.2 * period,
        &mut control,
    )?;
    let n = maxima.len();
    if n < 4 || extremes.len() < 4 {
        return Err(format!("eps {eps}: {n} maxima of x in 5 cycles").into());
    }
    let amplitude = (extremes[extremes.len() - 1] - extremes[extremes.len() - 2]).abs();
    Ok((maxima[n - 1] - maxima[n - 2], amplitude, control))
}
