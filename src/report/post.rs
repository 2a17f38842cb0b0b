//! Writers of the trajectory analyses: /post/limit_cycle and limit_cycle.png.

use std::path::Path;

use super::WriteError;
use crate::io::figure::{padded, Figure, BLUE, GREY, RED};
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::stages::post::LimitCycleReport;
use crate::time::transient::Transient;

/// # Collective
pub fn write_limit_cycle(
    petsc: &Petsc,
    file: &ResultsFile,
    report: &LimitCycleReport,
    tr: &Transient,
    output: &Path,
) -> Result<(), WriteError> {
    let g = "post/limit_cycle";
    let c = &report.cycle;
    let nan = f64::NAN;
    let numbers = [
        ("growth_rate_per_s", c.growth_rate.unwrap_or(nan)),
        ("growth_frequency_hz", c.growth_frequency.unwrap_or(nan)),
        (
            "growth_window_start_s",
            c.growth_window.map_or(nan, |w| w.0),
        ),
        ("growth_window_end_s", c.growth_window.map_or(nan, |w| w.1)),
        ("saturation_time_s", c.saturation_time.unwrap_or(nan)),
        ("saturated_amplitude_nm", c.saturated_amplitude),
        ("saturated_rms_nm", c.saturated_rms.unwrap_or(nan)),
        ("dominant_frequency_hz", c.dominant_frequency),
        ("period_s", c.period.unwrap_or(nan)),
        ("amplitude_variation", c.variation.unwrap_or(nan)),
        ("reached", f64::from(u8::from(c.reached))),
        (
            "predicted_growth_rate_per_s",
            report.predicted.as_ref().map_or(nan, |p| p.2),
        ),
        (
            "predicted_frequency_hz",
            report.predicted.as_ref().map_or(nan, |p| p.3),
        ),
    ];
    for (name, value) in numbers {
        file.set_number(g, name, value)?;
    }
    if let Some(phases) = &report.phase_costs {
        for (phase, p) in ["growth", "saturated"].iter().zip(phases) {
            for (what, value) in [
                ("simulated_s", p.simulated),
                ("steps", p.steps as f64),
                ("iterations", p.iterations as f64),
                ("wall_s", p.wall_seconds),
            ] {
                file.set_number(g, &format!("{phase}_{what}"), value)?;
            }
        }
    }
    file.set_text(g, "verdict", &c.verdict)?;
    if let Some((route, name, _, _)) = &report.predicted {
        file.set_text(
            g,
            "predicted_by",
            &format!("complex mode {name} ({route} route)"),
        )?;
    }
    file.write_table(&format!("{g}/cycle_start"), &c.cycle_starts, "s")?;
    file.write_table(&format!("{g}/peak_to_peak"), &c.amplitudes, "N m")?;
    let (et, ea): (Vec<f64>, Vec<f64>) = c.envelope.iter().copied().unzip();
    file.write_table(&format!("{g}/envelope_time"), &et, "s")?;
    file.write_table(&format!("{g}/envelope"), &ea, "N m (half peak-to-peak)")?;
    file.write_table(
        &format!("{g}/envelope_centre"),
        &c.envelope_centre,
        "N m ((max + min) / 2 per window)",
    )?;
    for (name, f) in &report.contact_fractions {
        let v = f.to_vec();
        file.write_table(
            &format!("{g}/contact/{name}"),
            &v,
            "fraction of the points open, sticking, slipping over the last cycles",
        )?;
    }
    if petsc.rank() == 0 {
        write_plot(report, tr, output)?;
    }
    Ok(())
}

/// limit_cycle.png: the braking torque (blue), its envelope (red: each window's max and
/// min) and the start of each detected cycle (grey ticks at the bottom).
fn write_plot(report: &LimitCycleReport, tr: &Transient, output: &Path) -> Result<(), WriteError> {
    let torque = tr.braking_torque();
    let (lo, hi) = torque
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let end = tr.time.last().copied().unwrap_or(1.0);
    let c = &report.cycle;
    let state = if c.reached {
        "limit cycle"
    } else if c.variation.is_some() {
        "saturated, not periodic"
    } else {
        "no cycle yet"
    };
    let title = match (c.growth_rate, report.predicted.as_ref()) {
        (Some(g), Some(p)) => format!(
            "torque: growth {g:.0} 1/s ({}: {:.0} 1/s), {:.0} Hz, {state}",
            p.1, p.2, c.dominant_frequency
        ),
        _ => format!("torque, {:.0} Hz, {state}", c.dominant_frequency),
    };
    let mut fig = Figure::new(
        1200,
        500,
        padded(0.0, end, 0.0),
        padded(lo, hi, 0.05),
        &title,
        "time (s)",
        "torque (N m)",
    );
    let points: Vec<(f64, f64)> = tr
        .time
        .iter()
        .copied()
        .zip(torque.iter().copied())
        .collect();
    fig.series(&points, BLUE, "braking torque");
    for sign in [1.0, -1.0] {
        let env: Vec<(f64, f64)> = c
            .envelope
            .iter()
            .zip(&c.envelope_centre)
            .map(|(&(t, a), &m)| (t, m + sign * a))
            .collect();
        if sign > 0.0 {
            fig.series(&env, RED, "envelope: max and min per 1.5 periods");
        } else {
            fig.line(&env, RED);
        }
    }
    let tick = lo + 0.02 * (hi - lo);
    fig.markers(c.cycle_starts.iter().map(|&t| (t, tick)).collect(), GREY, 3);
    if !c.cycle_starts.is_empty() {
        fig.legend(0, "start of a detected cycle", GREY);
    }
    let path = output.join("limit_cycle.png");
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}
