//! Writer of the pseudo trajectories: /post/pseudo_trajectory/<mode> with
//! pseudo_amplitude_<mode>.png (the sweep against alpha) and pseudo_stability_<mode>.png (the
//! pseudo dynamic stability diagram at one amplitude).

use std::path::Path;

use super::WriteError;
use crate::io::figure::{padded, Figure, BLACK, BLUE, PALETTE, RED};
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::measure::{nan_max, nan_min};
use crate::post::pseudo_trajectory::{Found, Period};
use crate::stages::pseudo::{PseudoReport, PseudoStudy};

/// # Collective
pub fn write_pseudo(
    petsc: &Petsc,
    file: &ResultsFile,
    r: &PseudoReport,
    output: &Path,
) -> Result<(), WriteError> {
    let g = "post/pseudo_trajectory";
    file.set_number(g, "gap_scale_m", r.gap_scale)?;
    for s in &r.studies {
        write_study(file, g, s)?;
        if petsc.rank() == 0 {
            plot_amplitude(s, output)?;
            plot_stability(s, output)?;
        }
    }
    Ok(())
}

/// One figure per period.
fn values(periods: &[Period], f: &dyn Fn(&Period) -> f64) -> Vec<f64> {
    periods.iter().map(f).collect()
}

fn write_study(file: &ResultsFile, g: &str, s: &PseudoStudy) -> Result<(), WriteError> {
    let t = &s.trajectory;
    let m = format!("{g}/{}", t.name);
    let sweep = &t.sweep;
    let column = |f: &dyn Fn(&Period) -> f64| values(sweep, f);
    let span = |p: &Period, highest: bool| {
        let f = p.frequencies_hz().into_iter().filter(|x| x.is_finite());
        if highest {
            f.fold(f64::NEG_INFINITY, nan_max)
        } else {
            f.fold(f64::INFINITY, nan_min)
        }
    };
    let tables: [(&str, Vec<f64>, &str); 8] = [
        ("alpha", column(&|p| p.alpha), "m"),
        ("mean_damping_ratio", column(&|p| p.mean_damping_ratio), "1"),
        ("unstable_fraction", column(&|p| p.unstable_fraction), "1"),
        ("frequency_min", column(&|p| span(p, false)), "Hz"),
        ("frequency_max", column(&|p| span(p, true)), "Hz"),
        (
            "min_mac",
            column(&|p| p.min_mac),
            "MAC between successive phases",
        ),
        (
            "closed",
            column(&|p| f64::from(u8::from(p.closed))),
            "1 where the pair tracked over the period came back to its start, else 0",
        ),
        (
            "sample_status",
            sweep
                .iter()
                .flat_map(|p| p.sample.iter().map(|&x| f64::from(x)))
                .collect(),
            "0 open, 1 stick, 2 slide; alphas x phases, row-major",
        ),
    ];
    for (name, values, units) in tables {
        file.write_table(&format!("{m}/sweep/{name}"), &values, units)?;
    }
    let refined = |f: &dyn Fn(&Period) -> f64| values(&t.refinement, f);
    let refinement: [(&str, Vec<f64>, &str); 4] = [
        ("alpha", refined(&|p| p.alpha), "m"),
        (
            "mean_damping_ratio",
            refined(&|p| p.mean_damping_ratio),
            "1",
        ),
        ("unstable_fraction", refined(&|p| p.unstable_fraction), "1"),
        (
            "closed",
            refined(&|p| f64::from(u8::from(p.closed))),
            "1 where the pair tracked over the period came back to its start, else 0",
        ),
    ];
    for (name, values, units) in refinement {
        file.write_table(&format!("{m}/refinement/{name}"), &values, units)?;
    }
    let d = &t.diagram;
    let (re, im): (Vec<f64>, Vec<f64>) = d.eigenvalue.iter().copied().unzip();
    file.write_table(&format!("{m}/diagram/re_s"), &re, "1/s; per phase")?;
    file.write_table(&format!("{m}/diagram/im_s"), &im, "rad/s; per phase")?;
    file.set_number(&format!("{m}/diagram"), "alpha_m", d.alpha)?;
    let (psi_re, psi_im): (Vec<f64>, Vec<f64>) = t.psi.iter().copied().unzip();
    let note = "coordinates on the real modes (contact amplitude 1)";
    file.write_table(&format!("{m}/psi_re"), &psi_re, note)?;
    file.write_table(&format!("{m}/psi_im"), &psi_im, note)?;
    file.set_number(&m, "nominal_re_s", t.nominal.0)?;
    file.set_number(&m, "nominal_im_s", t.nominal.1)?;
    let value = |f: &Found| f.alpha().unwrap_or(f64::NAN);
    file.set_number(&m, "alpha_crit_m", value(&t.alpha_crit))?;
    file.set_number(&m, "alpha_sat_m", value(&t.alpha_sat))?;
    file.set_number(&m, "alpha_stable_m", value(&t.alpha_stable))?;
    file.set_number(&m, "sign_changes", t.sign_changes as f64)?;
    file.set_number(&m, "linearizations", t.linearizations as f64)?;
    file.set_number(&m, "between_phases", t.cost.between_phases as f64)?;
    file.set_number(&m, "solves", t.cost.solves as f64)?;
    file.set_number(&m, "dense_solves", t.cost.dense_solves as f64)?;
    file.set_number(&m, "linearize_seconds", t.cost.linearize_seconds)?;
    file.set_number(&m, "near_shift_seconds", t.cost.near_shift_seconds)?;
    file.set_number(&m, "dense_seconds", t.cost.dense_seconds)?;
    file.set_number(&m, "seconds", t.seconds)?;
    if let Some(tr) = &s.transient {
        file.set_number(&m, "transient_amplitude_mean_m", tr.mean)?;
        file.set_number(&m, "transient_amplitude_min_m", tr.min)?;
        file.set_number(&m, "transient_amplitude_max_m", tr.max)?;
        file.set_number(&m, "transient_share", tr.share)?;
        file.set_number(&m, "transient_largest_m", tr.largest)?;
        file.set_number(&m, "transient_window_start_s", tr.window.0)?;
        file.set_number(&m, "transient_window_end_s", tr.window.1)?;
        file.set_number(
            &m,
            "alpha_sat_over_transient",
            value(&t.alpha_sat) / tr.mean,
        )?;
    }
    Ok(())
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        })
}

fn padded_pair((a, b): (f64, f64)) -> (f64, f64) {
    padded(a, b, 0.08)
}

/// A vertical line at data abscissa x, in the legend as `label`.
fn mark(fig: &mut Figure, x: f64, label: &str, c: [u8; 3]) {
    fig.vline(x, c, Some(label));
}

/// Mean damping ratio, unstable fraction, frequency span and the sample point's contact
/// status against log10 alpha, alpha_crit / alpha_sat / the transient's amplitude marked.
fn plot_amplitude(s: &PseudoStudy, output: &Path) -> Result<(), WriteError> {
    let t = &s.trajectory;
    let log: Vec<f64> = t.sweep.iter().map(|p| p.alpha.log10()).collect();
    let x = padded(log[0], log[log.len() - 1], 0.02);
    let marks = |fig: &mut Figure| {
        if let Some(a) = t.alpha_crit.alpha() {
            mark(fig, a.log10(), "alpha_crit", PALETTE[1]);
        }
        if let Some(a) = t.alpha_sat.alpha() {
            mark(fig, a.log10(), "alpha_sat", RED);
        }
        if let Some(a) = t
            .alpha_stable
            .alpha()
            .filter(|_| t.alpha_stable.alpha() != t.alpha_sat.alpha())
        {
            mark(fig, a.log10(), "stable above", PALETTE[4]);
        }
        if let Some(tr) = &s.transient {
            mark(fig, tr.mean.log10(), "transient", PALETTE[2]);
        }
    };
    let xl = "amplitude alpha: largest relative displacement at a contact point (m)";
    let f = |a: f64| format!("{a:.1}");
    let title = format!(
        "{} ({} Hz): pseudo trajectories, {} phases per period",
        t.name,
        f(crate::eigen::complex_modes::frequency_hz(t.nominal)),
        t.diagram.eigenvalue.len()
    );
    let zeta: Vec<f64> = t.sweep.iter().map(|p| p.mean_damping_ratio).collect();
    let refined = |f: fn(&Period) -> f64| -> Vec<(f64, f64)> {
        t.refinement
            .iter()
            .map(|p| (p.alpha.log10(), f(p)))
            .collect()
    };
    let refined_zeta = refined(|p| p.mean_damping_ratio);
    let all_zeta = || zeta.iter().copied().chain(refined_zeta.iter().map(|p| p.1));
    let yz = padded(range(all_zeta()).0, range(all_zeta()).1.max(0.0), 0.08);
    let mut damping = Figure::new(1200, 320, x, yz, &title, xl, "mean damping ratio (1)").log_x();
    damping.hline(0.0, BLACK);
    let points: Vec<(f64, f64)> = log.iter().copied().zip(zeta).collect();
    damping.line(&points, BLUE);
    // Where the pair followed over the period does not come back to its start: there the
    // statistics depend on where the period starts (not resolved by the phases).
    let open: Vec<(f64, f64)> = points
        .iter()
        .zip(&t.sweep)
        .filter(|(_, p)| !p.closed)
        .map(|(&xy, _)| xy)
        .collect();
    if !open.is_empty() {
        damping.markers(open, PALETTE[6], 5);
        damping.legend(0, "period not closed", PALETTE[6]);
    }
    for &(a, z) in &points {
        damping.marker(a, z, BLUE, 2);
    }
    // The bisections' periods: where the crossing was found, off the sweep's line.
    let bisected = "bisection periods";
    if !t.refinement.is_empty() {
        damping.markers(refined_zeta, PALETTE[5], 3);
        damping.legend(0, bisected, PALETTE[5]);
    }
    marks(&mut damping);

    let mut fraction = Figure::new(
        1200,
        260,
        x,
        (-0.05, 1.05),
        "fraction of the period the mode is unstable",
        xl,
        "fraction (1)",
    )
    .log_x();
    let points: Vec<(f64, f64)> = log
        .iter()
        .copied()
        .zip(t.sweep.iter().map(|p| p.unstable_fraction))
        .collect();
    fraction.line(&points, BLUE);
    if !t.refinement.is_empty() {
        fraction.markers(refined(|p| p.unstable_fraction), PALETTE[5], 3);
        fraction.legend(0, bisected, PALETTE[5]);
    }
    marks(&mut fraction);

    let lo: Vec<f64> = t
        .sweep
        .iter()
        .map(|p| range(p.frequencies_hz().into_iter()).0)
        .collect();
    let hi: Vec<f64> = t
        .sweep
        .iter()
        .map(|p| range(p.frequencies_hz().into_iter()).1)
        .collect();
    let yf = padded(
        range(lo.iter().copied()).0,
        range(hi.iter().copied()).1,
        0.08,
    );
    let mut frequency = Figure::new(
        1200,
        260,
        x,
        yf,
        "frequency over the period: lowest and highest",
        xl,
        "frequency (Hz)",
    )
    .log_x();
    for (series, c) in [(&lo, PALETTE[0]), (&hi, PALETTE[3])] {
        let points: Vec<(f64, f64)> = log.iter().copied().zip(series.iter().copied()).collect();
        frequency.line(&points, c);
    }
    marks(&mut frequency);

    let phases = t.diagram.eigenvalue.len();
    let mut status = Figure::new(
        1200,
        260,
        x,
        (0.0, 1.0),
        "contact state at the sample point over the period",
        xl,
        "phase / 2 pi (1)",
    )
    .log_x()
    .colour_bar("0 open, 1 stick, 2 slide", (0.0, 2.0));
    let values: Vec<f64> = t
        .sweep
        .iter()
        .flat_map(|p| p.sample.iter().map(|&v| f64::from(v)))
        .collect();
    let half = 0.5 * (log[1] - log[0]);
    status.cells(
        (t.sweep.len(), phases),
        values,
        (log[0] - half, log[log.len() - 1] + half),
        (0.0, 1.0),
    );
    let path = output.join(format!("pseudo_amplitude_{}.png", t.name));
    let panels = [&damping, &fraction, &frequency, &status];
    Figure::save_column(&panels, &path).map_err(|source| WriteError::Io { path, source })
}

/// Frequency against damping ratio of the mode over one period at the diagram's amplitude,
/// coloured by phase; the nominal mode as a black dot (the paper's fig. 13).
fn plot_stability(s: &PseudoStudy, output: &Path) -> Result<(), WriteError> {
    let t = &s.trajectory;
    let d = &t.diagram;
    let (fr, zr) = (d.frequencies_hz(), d.damping_ratios());
    let nominal = (
        crate::eigen::complex_modes::damping_ratio(t.nominal),
        crate::eigen::complex_modes::frequency_hz(t.nominal),
    );
    let (z0, z1) = range(zr.iter().copied().chain([nominal.0, 0.0]));
    let (f0, f1) = padded_pair(range(fr.iter().copied().chain([nominal.1])));
    let mut fig = Figure::new(
        1000,
        700,
        padded(z0, z1, 0.08),
        (f0, f1),
        &format!(
            "{}: pseudo dynamic stability at alpha = {:.3e} m",
            t.name, d.alpha
        ),
        "damping ratio, unstable below 0 (1)",
        "frequency (Hz)",
    )
    .colour_bar("phase / 2 pi (1)", (0.0, 1.0));
    fig.vline(0.0, RED, Some("stability boundary"));
    let n = fr.len().max(1) as f64;
    let points: Vec<(f64, f64)> = zr.iter().copied().zip(fr.iter().copied()).collect();
    fig.valued(points, (0..fr.len()).map(|i| i as f64 / n).collect(), 4);
    fig.marker(nominal.0, nominal.1, BLACK, 6);
    fig.legend(0, "static state", BLACK);
    let path = output.join(format!("pseudo_stability_{}.png", t.name));
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}
