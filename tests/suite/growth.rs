//! The time/frequency link on the small brake (DESIGN.md §2b): the self-excited growth of the
//! transient is the most unstable complex mode of the same preloaded model.
//!
//! Reference: the full-route complex modes (SLEPc PEP on the 6k brake, backward errors
//! ~1e-14): C35, 2,912 Hz, Re(s) = 348 1/s, the largest below 6 kHz (C29, 2,537 Hz, 110 1/s
//! next). The joints' traction is Coulomb-limited (mu p tanh(k_c |delta| / p)): the
//! abutments carry part of the static torque near that limit, which softens their stick and
//! their gap coupling; with an unlimited elastic stick the largest was C48, 4,758 Hz,
//! 2,157 1/s. The transient (reduced on 100 modes, 2 us steps, 15,000 steps, 1 nm kick along
//! real mode 2) is fitted by `[post.limit_cycle]` on its torque envelope between the
//! envelope's minimum and 30 % of its final value, about two decades: asserted within 10 %
//! of Re(s) (the fit mixes in the slower unstable mode and the kick's decaying content during
//! the first decade; measured 355 1/s at 2,910 Hz, 2.1 %). The 2-rank run's torque is
//! compared with the 1-rank run's over the whole growth phase. The Jacobian is factorized by
//! MUMPS in single precision (`jacobian_factor = "single"`; the default scene's per-rank LU is
//! exercised by the command-line test): the growth, the modal energies, the pseudo
//! trajectory's comparison and the 1-vs-2-rank agreement hold with their bounds unchanged.

use super::TestResult;
use squeal::la::Petsc;
use squeal::measure::nan_max;

use super::common::{rel, say};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "small_brake_transient_grows_at_the_rate_of_its_unstable_complex_mode",
        growth_matches_complex_mode,
    )]
}

fn growth_matches_complex_mode(petsc: &Petsc) -> TestResult {
    let text = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
        [contact]\ndisc_speed = 6.2832\n\
        [contact.sliding]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
        friction = { law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }\n\
        [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = 100\n\
        [complex_modes]\nmethod = \"both\"\nf_max_hz = 6000.0\n[reduction]\n\
        [transient]\nstep = 2.0e-6\nsteps = 15000\nmode = 2\namplitude = 1.0e-9\n\
        state_interval = 1.0e-4\njacobian_factor = \"single\"\n[post.limit_cycle]\n[post.modal_energy]\n\
        [post.pseudo_trajectory]\nmodes = [\"C35\"]\nalpha_range = [1.0e-8, 1.0e-3]\n\
        alphas = 11\nphases = 64\n";
    let scene = squeal::scene::Scene::parse(text, "growth")?;
    let out = super::common::suite_dir().join("growth");
    let run = squeal::pipeline::run(petsc, &scene, text, std::path::Path::new("."), &out, &[])?;
    let report = run.limit_cycle.as_ref().ok_or("no limit-cycle report")?;
    let growth = report.cycle.growth_rate.ok_or("no growth rate fitted")?;
    let (_, name, re, f) = report.predicted.clone().ok_or("no unstable complex mode")?;
    say(
        petsc,
        &format!(
            "transient growth {growth:.0} 1/s at {:.0} Hz; complex mode {name}: Re(s) {re:.0} 1/s at {f:.0} Hz ({:.1e})",
            report.cycle.dominant_frequency,
            rel(growth, re)
        ),
    );
    let error = rel(growth, re);
    if error.is_nan() || error >= 0.1 {
        return Err(format!("growth {growth} 1/s vs Re(s) {re} 1/s of {name} ({f} Hz)").into());
    }
    modal_energy_follows_the_mode(petsc, &run, &name, re)?;
    pseudo_trajectory_against_the_growth(petsc, &run)?;
    growth_same_on_one_and_two_ranks(petsc, &out)
}

/// The pseudo trajectory of C35 next to the same run (the comparison path: the stored
/// states' contact motion over the last 3 periods fitted by C35's contact shape, summed over
/// the ranks). The run ends in the linear growth, far below the saturation, so the ratio
/// alpha_sat / amplitude is large; what is asserted is what the issue asks of the brake:
/// finite and positive, a share of the contact motion in (0, 1], and the same on 1 and 2
/// ranks: the fitted amplitude to the torque's 1e-3; alpha_crit, alpha_sat and the mean
/// damping ratio at every swept amplitude to 1e-6 (of the largest |mean damping|). Until
/// psi's phase was fixed by the motion, only the amplitudes below alpha_crit agreed (one
/// suite run found a grid point's mean damping +1.4e-4 on 1 rank and -7.6e-3 on 2, and
/// alpha_sat 4.56e-6 against 1.58e-5 m): the two rank counts chose opposite signs of the
/// real modes, so their periods started half a period apart and followed other modes.
/// 64 phases over [1e-8, 1e-3] m: at 16 the pair's continuation is not resolved above 10 um
/// and the mean damping did not cross zero up to 1 mm (at 64: alpha_sat 22.8 um).
fn pseudo_trajectory_against_the_growth(
    petsc: &Petsc,
    run: &squeal::pipeline::RunSummary,
) -> TestResult {
    let p = run.pseudo.as_ref().ok_or("no pseudo trajectories")?;
    let study = p.studies.first().ok_or("no pseudo-trajectory study")?;
    let t = &study.trajectory;
    let tr = study
        .transient
        .as_ref()
        .ok_or("no transient amplitude next to the pseudo trajectory")?;
    let sat = t.alpha_sat.alpha().unwrap_or(f64::NAN);
    let crit = t.alpha_crit.alpha().unwrap_or(f64::NAN);
    let ratio = sat / tr.mean;
    say(
        petsc,
        &format!(
            "{}: alpha_crit {crit:.4e} m, alpha_sat {sat:.4e} m; the run's last 3 periods ({} states): largest relative displacement {:.3e} m, C35's fit {:.3e} m holding {:.0} % of the contact motion; alpha_sat / that {ratio:.3e}",
            t.name,
            tr.states,
            tr.largest,
            tr.mean,
            100.0 * tr.share
        ),
    );
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(ratio) && positive(crit) && tr.share > 0.0 && tr.share <= 1.0 + 1e-12) {
        return Err(format!(
            "alpha_sat {sat}, alpha_crit {crit}, amplitude {}, share {}",
            tr.mean, tr.share
        )
        .into());
    }
    let mut values = vec![tr.mean, crit, sat];
    values.extend(t.sweep.iter().map(|p| p.mean_damping_ratio));
    let Some(one) = super::common::one_rank_values(petsc, "growth-pseudo", &values)? else {
        return Ok(());
    };
    let rel = |k: usize| (one[k] - values[k]).abs() / one[k].abs();
    let zeta = super::common::max_scaled_difference(&one[3..], &values[3..]);
    say(
        petsc,
        &format!(
            "{} ranks vs 1: fitted amplitude {:.1e}, alpha_crit {:.1e}, alpha_sat {:.1e}, mean damping ratios {zeta:.1e}",
            petsc.size(),
            rel(0),
            rel(1),
            rel(2)
        ),
    );
    let bad = |d: f64, bound: f64| d.is_nan() || d > bound;
    if one.len() != values.len()
        || bad(rel(0), 1e-3)
        || bad(rel(1), 1e-6)
        || bad(rel(2), 1e-6)
        || bad(zeta, 1e-6)
    {
        return Err(format!("2 ranks vs 1: {one:?} vs {values:?}").into());
    }
    Ok(())
}

/// 1 and 2 ranks over the growth phase: the 1-rank run keeps its braking torque, the 2-rank
/// run compares step by step, relative to the largest torque fluctuation. The growth is
/// linear, so a difference grows no faster than the vibration; what differs between rank
/// counts is the start: the static state is an equilibrium only to its Newton tolerance
/// (residual ~1.7e-6 N, rank-dependent), a second kick next to the 1 nm one, whose force is
/// ~w_2^2 x 1 nm x sqrt(modal mass) ~ 4e-3 N: a ratio ~4e-4, which the growth keeps.
/// Asserted 1e-3 (measured 1.0e-4 to 1.9e-4 in four runs).
fn growth_same_on_one_and_two_ranks(petsc: &Petsc, out: &std::path::Path) -> TestResult {
    let torque = hdf5::File::open(out.join("results.h5"))
        .and_then(|f| f.dataset("transient/braking_torque"))
        .and_then(|d| d.read_raw::<f64>())?;
    let Some(one) = super::common::one_rank_values(petsc, "growth-torque", &torque)? else {
        return Ok(());
    };
    let scale = one.iter().map(|x| (x - one[0]).abs()).fold(0.0, nan_max);
    let diff = one
        .iter()
        .zip(&torque)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f64, nan_max)
        / scale;
    say(
        petsc,
        &format!(
            "growth phase, {} ranks vs 1: torque differs by {diff:.1e} of its largest fluctuation ({scale:.3e} N m) over {} steps",
            petsc.size(),
            torque.len()
        ),
    );
    if diff.is_nan() || diff > 1e-3 {
        return Err(format!("torque differs from 1 rank by {diff:e} of {scale:e}").into());
    }
    Ok(())
}

/// The modal sensors of the same run: the real mode holding the most energy at the end is the
/// dominant real mode of the unstable complex mode (projected route, same name), and its
/// energy grows at 2 Re(s) (E ~ amplitude^2). Fitted over [10, 30] ms, once the slower
/// unstable modes (C29: 110 1/s) and the kick's decaying content are below a few percent of
/// C35's content; asserted within 5 % of 2 Re(s). Measured: R37 (34.7 % of the modal energy
/// at 30 ms) is C35's dominant real mode, its energy grows at 2 x 348 1/s (8.5e-4).
fn modal_energy_follows_the_mode(
    petsc: &Petsc,
    run: &squeal::pipeline::RunSummary,
    name: &str,
    re: f64,
) -> TestResult {
    let energy = &run
        .link
        .modal_energy
        .as_ref()
        .ok_or("no modal energy")?
        .energy;
    let projected = run
        .complex
        .iter()
        .find(|c| c.route == "projected")
        .ok_or("no projected complex modes")?;
    let mode = projected
        .modes
        .iter()
        .find(|m| m.name == name)
        .ok_or(format!("no projected {name}"))?;
    let dominant = mode.dominant_real_mode.ok_or("no dominant real mode")?;
    let top = energy.ranked.first().ok_or("no ranked mode")?;
    let points: Vec<(f64, f64)> = energy
        .times
        .iter()
        .zip(&energy.energy[top.mode])
        .filter(|(&t, &e)| (0.010..=0.030).contains(&t) && e > 0.0)
        .map(|(&t, &e)| (t, e.ln()))
        .collect();
    let rate = 0.5 * squeal::post::limit_cycle::slope(&points);
    say(
        petsc,
        &format!(
            "modal energy: R{} holds {:.1} % at the end (projected {name}: dominant R{}); its energy grows at 2 x {rate:.0} 1/s vs Re(s) {re:.0} 1/s ({:.1e})",
            top.mode + 1,
            100.0 * top.share,
            dominant + 1,
            rel(rate, re)
        ),
    );
    if top.mode != dominant || rel(rate, re).is_nan() || rel(rate, re) > 0.05 {
        return Err(format!(
            "top mode R{} (dominant of {name}: R{}), energy growth 2 x {rate} vs {re}",
            top.mode + 1,
            dominant + 1
        )
        .into());
    }
    Ok(())
}
