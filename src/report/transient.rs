//! Writer of the transient: the run's figures under /transient_run (the signals and states are
//! in transient.h5, linked as /transient), `torque.png` and `spectrogram.png`.

use std::path::Path;

use super::WriteError;
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::post::spectrum::{spectrogram_db, spectrogram_signal};
use crate::time::transient::{Transient, TransientSettings};

/// # Collective
pub fn write_transient(
    petsc: &Petsc,
    file: &ResultsFile,
    tr: &Transient,
    settings: &TransientSettings,
    output: &Path,
) -> Result<(), WriteError> {
    file.link_external("transient", "transient.h5")?;
    let g = "transient_run";
    let numbers = [
        ("steps", tr.iterations.len().saturating_sub(1) as f64),
        ("simulated_time_s", tr.time.last().copied().unwrap_or(0.0)),
        ("step_cuts", tr.cuts as f64),
        ("jacobian_refreshes", tr.refreshes as f64),
        ("krylov_retries", tr.krylov_retries as f64),
        ("krylov_iterations", tr.krylov_iterations as f64),
        ("full_newton_retries", tr.full_newton_retries as f64),
        ("updated_factor_retries", tr.updated_retries as f64),
        (
            "nonlinear_eliminations",
            tr.eliminations.eliminations as f64,
        ),
        ("eliminated_points", tr.eliminations.points as f64),
        ("eliminated_unknowns", tr.eliminations.unknowns as f64),
        ("elimination_parts", tr.eliminations.parts as f64),
        (
            "elimination_largest_part_unknowns",
            tr.eliminations.largest_parts as f64,
        ),
        (
            "elimination_parts_on_kept_factors",
            tr.eliminations.parts_on_kept_factors as f64,
        ),
        (
            "elimination_local_iterations",
            tr.eliminations.local_iterations as f64,
        ),
        (
            "elimination_local_factorizations",
            tr.eliminations.local_factorizations as f64,
        ),
        (
            "elimination_dense_factorizations",
            tr.eliminations.dense_factorizations as f64,
        ),
        (
            "elimination_numeric_refactorizations",
            tr.eliminations.numeric_refactorizations as f64,
        ),
        ("elimination_factor_entries", tr.eliminations.factor_entries),
        ("seconds_eliminating", tr.eliminations.seconds),
        (
            "seconds_eliminating_ranking",
            tr.eliminations.seconds_ranking,
        ),
        (
            "seconds_eliminating_tangent",
            tr.eliminations.seconds_tangent,
        ),
        ("seconds_eliminating_blocks", tr.eliminations.seconds_blocks),
        (
            "seconds_eliminating_local_newton",
            tr.eliminations.seconds_local_newton,
        ),
        (
            "seconds_eliminating_local_newton_slowest_rank",
            tr.eliminations.seconds_local_newton_slowest,
        ),
        (
            "seconds_eliminating_factorizing",
            tr.eliminations.seconds_factorizing,
        ),
        (
            "seconds_eliminating_linear_change",
            tr.eliminations.seconds_linear_change,
        ),
        (
            "seconds_eliminating_combining",
            tr.eliminations.seconds_combining,
        ),
        ("elimination_worst_mismatch", tr.eliminations.worst_mismatch),
        ("failed_attempt_iterations", tr.failed_iterations as f64),
        ("failed_attempt_factor_solves", tr.failed_solves as f64),
        ("seconds_in_failed_attempts", tr.seconds_in_failed_attempts),
        ("seconds_recording", tr.seconds_recording),
        ("factorizations", tr.factorizations as f64),
        ("factor_entries", tr.factor_entries),
        ("states_written", tr.states as f64),
        ("seconds_stepping", tr.seconds_stepping),
        (
            "seconds_factorizing_jacobians_in_loop",
            tr.seconds_jacobians,
        ),
        (
            "seconds_assembling_jacobians",
            tr.seconds_assembling_jacobians,
        ),
        ("seconds_in_corrections", tr.seconds_solving),
        ("factor_solves", tr.factor_solves as f64),
        ("seconds_in_factor_solves", tr.seconds_in_factor_solves),
        ("seconds_in_forces", tr.seconds_in_forces),
        ("seconds_in_products", tr.seconds_in_products),
        ("iterations_run", tr.iterations_run as f64),
        ("steps_on_step_error", tr.steps_on_step_error as f64),
    ];
    // The counts and times are this process's (the summary prints rank 0's): an attribute
    // takes one value, so every rank writes rank 0's (the times differ between ranks).
    let mut values: Vec<f64> = numbers.iter().map(|&(_, v)| v).collect();
    crate::parallel::broadcast_f64s(petsc.world(), 0, &mut values);
    for ((name, _), value) in numbers.iter().zip(values) {
        file.set_number(g, name, value)?;
    }
    file.set_number(g, "static_residual_removed_n", tr.static_residual)?;
    if let Some(t) = tr.stopped_at_saturation {
        file.set_number(g, "stopped_at_saturation_s", t)?;
    }
    if let Some(t) = tr.resumed_at {
        file.set_number(g, "restarted_at_s", t)?;
    }
    if petsc.rank() == 0 {
        write_torque_plot(tr, output)?;
        write_spectrogram(tr, settings, output)?;
    }
    Ok(())
}

/// torque.png: the braking torque against time.
fn write_torque_plot(tr: &Transient, output: &Path) -> Result<(), WriteError> {
    use crate::io::figure::{padded, Figure, BLUE};
    let torque = tr.braking_torque();
    let (lo, hi) = torque
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let mut fig = Figure::new(
        1000,
        500,
        padded(0.0, tr.time.last().copied().unwrap_or(1.0), 0.0),
        padded(lo, hi, 0.05),
        "braking torque",
        "time (s)",
        "torque (N m)",
    );
    let points: Vec<(f64, f64)> = tr.time.iter().copied().zip(torque).collect();
    fig.line(&points, BLUE);
    let path = output.join("torque.png");
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}

/// spectrogram.png: the short-time spectrum (80 dB range) of the signal `post` chooses, on the
/// nominal step grid; nothing when the run is too short.
fn write_spectrogram(
    tr: &Transient,
    settings: &TransientSettings,
    output: &Path,
) -> Result<(), WriteError> {
    let (signal, what) = spectrogram_signal(tr);
    let Some(s) = spectrogram_db(
        &tr.time,
        &signal,
        tr.nominal_step,
        settings.spectrogram_max_hz,
    ) else {
        return Ok(());
    };
    let dt = s.column_width;
    let x = (s.first_time - 0.5 * dt, s.last_time + 0.5 * dt);
    let y = (0.0, s.rows as f64 * s.bin_hz);
    let mut fig = crate::io::figure::Figure::new(
        1000,
        500,
        x,
        y,
        &format!("spectrogram: {what}"),
        "time (s)",
        "frequency (Hz)",
    )
    .colour_bar("power spectral density (dB re largest)", (-80.0, 0.0));
    let relative: Vec<f64> = s.db.iter().map(|v| (v - s.top_db).max(-80.0)).collect();
    fig.cells(
        (s.columns, s.rows),
        relative,
        x,
        (y.0 - 0.5 * s.bin_hz, y.1 - 0.5 * s.bin_hz),
    );
    let path = output.join("spectrogram.png");
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}
