//! The noise matrix' saturated modes (`matrix.saturation_modes`): /matrix/saturation in
//! results.h5, matrix-saturation.csv (one row per point and followed mode), the summary's line
//! and the chart of the points' predicted levels in 10 dB(A) classes.

use std::fmt::Write as _;
use std::path::Path;

use super::WriteError;
use crate::io::figure::Figure;
use crate::io::results::ResultsFile;
use crate::matrix::point::{ModeSaturation, PointResult};
use crate::measure::greatest;
use crate::stages::matrix::MatrixOutput;

/// Every followed mode with its point.
fn studies(run: &MatrixOutput) -> Vec<(&PointResult, &ModeSaturation)> {
    run.points
        .iter()
        .flat_map(|p| {
            p.solved()
                .into_iter()
                .flat_map(move |s| s.saturation.iter().map(move |m| (p, m)))
        })
        .collect()
}

/// /matrix/saturation: one row per point and followed mode (NaN where not found).
pub fn write_h5(file: &ResultsFile, run: &MatrixOutput) -> Result<(), WriteError> {
    let rows = studies(run);
    if rows.is_empty() {
        return Ok(());
    }
    let g = "matrix/saturation";
    let column = |f: &dyn Fn(&PointResult, &ModeSaturation) -> f64| -> Vec<f64> {
        rows.iter().map(|&(p, m)| f(p, m)).collect()
    };
    let nan = f64::NAN;
    file.write_table(&format!("{g}/point"), &column(&|p, _| p.index as f64), "1")?;
    let label = column(&|_, m| m.label.map_or(0.0, |l| l as f64));
    file.write_table(&format!("{g}/label"), &label, "1 (C<label>; 0: unpaired)")?;
    file.write_table(
        &format!("{g}/frequency"),
        &column(&|_, m| m.frequency_hz),
        "Hz",
    )?;
    file.write_table(&format!("{g}/real_part"), &column(&|_, m| m.re), "1/s")?;
    let crit = column(&|_, m| m.alpha_crit.unwrap_or(nan));
    file.write_table(&format!("{g}/alpha_crit"), &crit, "m")?;
    let sat = column(&|_, m| m.alpha_sat.unwrap_or(nan));
    file.write_table(&format!("{g}/alpha_sat"), &sat, "m")?;
    let level = column(&|_, m| m.level_db_a.unwrap_or(nan));
    file.write_table(&format!("{g}/level_a"), &level, "dB(A) re 1 pW")?;
    file.write_table(&format!("{g}/seconds"), &column(&|_, m| m.seconds), "s")?;
    Ok(())
}

/// matrix-saturation.csv (None when no mode was followed).
pub fn csv(run: &MatrixOutput) -> Option<String> {
    let rows = studies(run);
    if rows.is_empty() {
        return None;
    }
    let names: Vec<&str> = run.axes.iter().map(|a| a.name()).collect();
    let mut out = format!(
        "point,{},mode,frequency_hz,re_s,alpha_crit_m,alpha_sat_m,level_db_a,seconds,failure\n",
        names.join(",")
    );
    let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6e}"));
    for (p, m) in rows {
        let values: Vec<String> = p.values.iter().map(|v| format!("{v:.10e}")).collect();
        let _ = writeln!(
            out,
            "{},{},{},{:.6e},{:.6e},{},{},{},{:.3},\"{}\"",
            p.index + 1,
            values.join(","),
            m.label.map_or("unpaired".to_string(), |l| format!("C{l}")),
            m.frequency_hz,
            m.re,
            optional(m.alpha_crit),
            optional(m.alpha_sat),
            m.level_db_a.map_or(String::new(), |v| format!("{v:.2}")),
            m.seconds,
            m.failure.as_deref().unwrap_or("").replace('"', "'")
        );
    }
    Some(out)
}

/// The loudest predicted level over the points: (dB(A), point, mode).
pub fn loudest(run: &MatrixOutput) -> Option<(f64, &PointResult, &ModeSaturation)> {
    studies(run)
        .into_iter()
        .filter_map(|(p, m)| m.level_db_a.map(|l| (l, p, m)))
        .max_by(|a, b| a.0.total_cmp(&b.0))
}

/// The summary's line: how many were followed, where they saturate, the loudest point.
pub fn text(run: &MatrixOutput) -> Option<String> {
    let rows = studies(run);
    if rows.is_empty() {
        return None;
    }
    let sat: Vec<f64> = rows.iter().filter_map(|(_, m)| m.alpha_sat).collect();
    let failed = rows.iter().filter(|(_, m)| m.failure.is_some()).count();
    let seconds = rows.iter().map(|(_, m)| m.seconds).sum::<f64>() / rows.len() as f64;
    let mut t = format!(
        "saturation: {} modes followed at {} points ({:.1} s each), alpha_sat found for {}",
        rows.len(),
        run.points
            .iter()
            .filter(|p| p.solved().is_some_and(|s| !s.saturation.is_empty()))
            .count(),
        seconds,
        sat.len()
    );
    if !sat.is_empty() {
        let mut sorted = sat.clone();
        sorted.sort_by(f64::total_cmp);
        let _ = write!(t, " (median {:.3e} m)", sorted[sorted.len() / 2]);
    }
    if let Some((level, p, m)) = loudest(run) {
        let name = m
            .label
            .map_or("an unpaired mode".to_string(), |l| format!("C{l}"));
        let _ = write!(
            t,
            "; loudest {level:.1} dB(A) at point {} ({name}, {:.1} Hz)",
            p.index + 1,
            m.frequency_hz
        );
    }
    if failed > 0 {
        let _ = write!(t, "; {failed} studies failed");
    }
    Some(t)
}

/// Each point's loudest predicted level (dB(A)), over the points that have one.
fn point_levels(run: &MatrixOutput) -> Vec<f64> {
    run.points
        .iter()
        .filter_map(|p| p.solved())
        .filter_map(|s| {
            let levels = s.saturation.iter().filter_map(|m| m.level_db_a);
            let loudest = greatest(levels);
            loudest.is_finite().then_some(loudest)
        })
        .collect()
}

/// Width of a level class (dB).
const CLASS: f64 = 10.0;

/// matrix_levels.png: the points per 10 dB(A) class of their loudest predicted level (false
/// when no point has a level).
pub fn plot_levels(run: &MatrixOutput, output: &Path) -> Result<bool, WriteError> {
    let levels = point_levels(run);
    if levels.is_empty() {
        return Ok(false);
    }
    let lo = (crate::measure::smallest(levels.iter().copied()) / CLASS).floor() * CLASS;
    let hi = (greatest(levels.iter().copied()) / CLASS).floor() * CLASS + CLASS;
    let classes = ((hi - lo) / CLASS).round() as usize;
    let mut counts = vec![0usize; classes];
    for l in &levels {
        let k = (((l - lo) / CLASS).floor() as usize).min(classes - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(1) as f64;
    let title = format!(
        "noise matrix: squealing points per level class ({} points with a predicted level)",
        levels.len()
    );
    let mut fig = Figure::new(
        1000,
        520,
        (lo, hi),
        (0.0, top * 1.12),
        &title,
        "loudest predicted sound power level at alpha_sat, dB(A) re 1 pW",
        "points",
    );
    for (k, &n) in counts.iter().enumerate() {
        let class = (lo + k as f64 * CLASS, lo + (k + 1) as f64 * CLASS);
        super::matrix::bar(&mut fig, class, n);
    }
    let path = output.join("matrix_levels.png");
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })?;
    Ok(true)
}
