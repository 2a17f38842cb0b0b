//! Writer of a parameter sweep: /sweep, sweep.csv and the coalescence plots.

use std::path::Path;

use super::WriteError;
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::stages::sweep::SweepOutput;

/// Writes a sweep: /sweep tables (parameter values; per track frequency, damping ratio, real
/// part, MAC; NaN where a track is lost), `sweep.csv`, and the plots `sweep_frequency.png`
/// and `sweep_real_part.png` (the coalescence picture; unstable points in red).
///
/// # Collective
pub fn write_sweep(
    petsc: &Petsc,
    file: &ResultsFile,
    sw: &SweepOutput,
    output: &Path,
) -> Result<(), WriteError> {
    use crate::eigen::complex_modes::{damping_ratio, frequency_hz};
    file.write_table("sweep/values", &sw.values, sw.parameter.name())?;
    file.set_text("sweep", "parameter", sw.parameter.name())?;
    let per_point =
        |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..sw.values.len()).map(f).collect() };
    file.write_table(
        "sweep/unstable_modes",
        &per_point(&|i| sw.unstable[i] as f64),
        "1",
    )?;
    file.write_table("sweep/statics_seconds", &sw.statics_seconds, "s")?;
    file.write_table("sweep/modal_seconds", &sw.modal_seconds, "s")?;
    file.write_table(
        "sweep/newton_iterations",
        &per_point(&|i| sw.newton_iterations[i] as f64),
        "1",
    )?;
    let nan = f64::NAN;
    for (t, track) in sw.tracks.tracks.iter().enumerate() {
        let col = |f: &dyn Fn((f64, f64), f64) -> f64| -> Vec<f64> {
            track
                .iter()
                .map(|p| p.map_or(nan, |(s, m)| f(s, m)))
                .collect()
        };
        let g = format!("sweep/tracks/track_{:04}", t + 1);
        file.write_table(
            &format!("{g}/frequency"),
            &col(&|s, _| frequency_hz(s)),
            "Hz",
        )?;
        file.write_table(
            &format!("{g}/damping_ratio"),
            &col(&|s, _| damping_ratio(s)),
            "1",
        )?;
        file.write_table(&format!("{g}/real_part"), &col(&|s, _| s.0), "1/s")?;
        file.write_table(&format!("{g}/mac"), &col(&|_, m| m), "1")?;
    }
    if petsc.rank() != 0 {
        return Ok(());
    }
    let mut text = format!(
        "{},track,frequency_hz,damping_ratio,re_s,im_s,mac\n",
        sw.parameter.name()
    );
    for (t, track) in sw.tracks.tracks.iter().enumerate() {
        for (i, p) in track.iter().enumerate() {
            if let Some((s, m)) = p {
                text.push_str(&format!(
                    "{},{},{:.10e},{:.10e},{:.10e},{:.10e},{:.6}\n",
                    sw.values[i],
                    t + 1,
                    frequency_hz(*s),
                    damping_ratio(*s),
                    s.0,
                    s.1,
                    m
                ));
            }
        }
    }
    let path = output.join("sweep.csv");
    std::fs::write(&path, text).map_err(|source| WriteError::Io {
        path: path.clone(),
        source,
    })?;
    for (name, y_of, y_label) in [
        ("sweep_frequency.png", 0usize, "frequency (Hz)"),
        ("sweep_real_part.png", 1, "Re(s) (1/s)"),
    ] {
        let path = output.join(name);
        crate::report::stability::write_sweep_plot(
            &path,
            &sw.values,
            &sw.tracks,
            y_of == 1,
            sw.margin,
            sw.parameter.label(),
            y_label,
        )
        .map_err(|source| WriteError::Io { path, source })?;
    }
    Ok(())
}
