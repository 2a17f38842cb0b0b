//! Writer of the loudness stage: /post/loudness (per mode, the transient's ERP over time and
//! its 1/3-octave bands, every dataset with units), loudness_modes.png (levels per mode) and
//! loudness_bands.png (the transient's last cycles in 1/3-octave bands).

use std::path::Path;

use super::WriteError;
use crate::io::figure::{padded, Figure, BLACK, BLUE, RED};
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::measure::finite_range;
use crate::post::loudness::{a_weighting, power_level};
use crate::stages::loudness::{LoudnessReport, UNIT_AMPLITUDE};

/// # Collective
pub fn write_loudness(
    petsc: &Petsc,
    file: &ResultsFile,
    r: &LoudnessReport,
    output: &Path,
) -> Result<(), WriteError> {
    let g = "post/loudness";
    file.set_text(g, "radiating_components", &r.components.join(", "))?;
    file.set_text(
        g,
        "model",
        "equivalent radiated power, radiation efficiency 1; microphone pressures by the Rayleigh integral with every face taken as baffled",
    )?;
    file.set_number(g, "radiating_area_m2", r.area)?;
    file.set_number(g, "air_density_kg_m3", r.density)?;
    file.set_number(g, "sound_speed_m_s", r.sound_speed)?;
    file.set_number(g, "unit_amplitude_m", UNIT_AMPLITUDE)?;
    let column = |f: &dyn Fn(&crate::stages::loudness::ModeLoudness) -> f64| -> Vec<f64> {
        r.modes.iter().map(f).collect()
    };
    let m = format!("{g}/modes");
    file.set_text(
        &m,
        "names",
        &r.modes
            .iter()
            .map(|m| m.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    )?;
    let tables: [(&str, Vec<f64>, &str); 7] = [
        ("frequency", column(&|m| m.frequency_hz), "Hz"),
        ("growth_rate", column(&|m| m.growth), "1/s (Re(s))"),
        (
            "alpha_sat",
            column(&|m| m.alpha_sat.unwrap_or(f64::NAN)),
            "m (NaN: none found)",
        ),
        (
            "power_per_unit_amplitude",
            column(&|m| m.power_per_unit),
            "W at 1 um of contact amplitude",
        ),
        (
            "power_at_alpha_sat",
            column(&|m| m.power_at_sat.unwrap_or(f64::NAN)),
            "W",
        ),
        (
            "level_at_alpha_sat",
            column(&|m| m.power_at_sat.map_or(f64::NAN, power_level)),
            "dB re 1 pW",
        ),
        (
            "a_level",
            column(&|m| m.level_a()),
            "dB(A) re 1 pW, at alpha_sat (else per unit amplitude)",
        ),
    ];
    for (name, values, units) in &tables {
        file.write_table(&format!("{m}/{name}"), values, units)?;
    }
    if let Some(first) = r.modes.first() {
        for (k, (name, _, _)) in first.microphones.iter().enumerate() {
            let per_unit = column(&|m| m.microphones[k].1);
            let at_sat = column(&|m| m.microphones[k].2.unwrap_or(f64::NAN));
            let p = format!("{m}/microphones/{name}");
            file.write_table(
                &format!("{p}/level_per_unit_amplitude"),
                &per_unit,
                "dB re 20 uPa at 1 um",
            )?;
            file.write_table(&format!("{p}/level_at_alpha_sat"), &at_sat, "dB re 20 uPa")?;
        }
    }
    if let Some(t) = &r.transient {
        let p = format!("{g}/transient");
        file.write_table(&format!("{p}/time"), &t.times, "s")?;
        file.write_table(&format!("{p}/power"), &t.power, "W (instantaneous ERP)")?;
        let centres: Vec<f64> = t.bands.iter().map(|b| b.0.centre).collect();
        let nominal: Vec<f64> = t.bands.iter().map(|b| b.0.nominal).collect();
        let powers: Vec<f64> = t.bands.iter().map(|b| b.1).collect();
        file.write_table(
            &format!("{p}/band_centre"),
            &centres,
            "Hz (1/3-octave, base 10)",
        )?;
        file.write_table(&format!("{p}/band_nominal"), &nominal, "Hz")?;
        file.write_table(
            &format!("{p}/band_power"),
            &powers,
            "W, mean over the window",
        )?;
        file.set_number(&p, "window_start_s", t.window.0)?;
        file.set_number(&p, "window_end_s", t.window.1)?;
        file.set_number(&p, "mean_power_w", t.mean_power)?;
        file.set_number(&p, "level_a_db", t.level_a())?;
        for (name, plain, weighted) in &t.microphones {
            let m = format!("{p}/microphones/{name}");
            file.set_number(&m, "level_db", *plain)?;
            file.set_number(&m, "level_a_db", *weighted)?;
        }
    }
    if petsc.rank() == 0 {
        if !r.modes.is_empty() {
            plot_modes(r, output)?;
        }
        if r.transient.as_ref().is_some_and(|t| t.states > 1) {
            plot_bands(r, output)?;
        }
    }
    Ok(())
}

fn save(fig: &Figure, output: &Path, name: &str) -> Result<(), WriteError> {
    let path = output.join(name);
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}

/// loudness_modes.png: L_W(A) of every mode against its frequency, as bars: at alpha_sat
/// (red) and per 1 um of contact amplitude (blue), each labelled with the mode's name.
fn plot_modes(r: &LoudnessReport, output: &Path) -> Result<(), WriteError> {
    let per_unit: Vec<f64> = r
        .modes
        .iter()
        .map(|m| power_level(m.power_per_unit) + a_weighting(m.frequency_hz))
        .collect();
    let at_sat: Vec<f64> = r
        .modes
        .iter()
        .map(|m| m.power_at_sat.map_or(f64::NAN, power_level) + a_weighting(m.frequency_hz))
        .collect();
    let (lo, hi) = finite_range(per_unit.iter().chain(&at_sat)).unwrap_or((0.0, 1.0));
    let frequencies: Vec<f64> = r.modes.iter().map(|m| m.frequency_hz).collect();
    let (f_lo, f_hi) = finite_range(&frequencies).unwrap_or((0.0, 1.0));
    // A span of at least 1 kHz, so a single mode's bars have a width to be seen.
    let centre = 0.5 * (f_lo + f_hi);
    let half = (0.5 * (f_hi - f_lo)).max(500.0) * 1.15;
    let width = 0.02 * half;
    let base = lo.min(0.0);
    let mut fig = Figure::new(
        1000,
        560,
        ((centre - half).max(0.0), centre + half),
        padded(base, hi, 0.08),
        "radiated sound power of the unstable modes: at alpha_sat (red), at 1 um of contact amplitude (blue)",
        "mode frequency (Hz)",
        "L_W(A) (dB(A) re 1 pW)",
    );
    for (k, m) in r.modes.iter().enumerate() {
        let f = m.frequency_hz;
        for (a, b, level, colour) in [
            (f - 2.0 * width, f - 0.2 * width, per_unit[k], BLUE),
            (f + 0.2 * width, f + 2.0 * width, at_sat[k], RED),
        ] {
            if level.is_finite() {
                fig.line(&[(a, base), (a, level), (b, level), (b, base)], colour);
            }
        }
        let top = if at_sat[k].is_finite() {
            at_sat[k]
        } else {
            per_unit[k]
        };
        fig.label(f, top, &m.name, BLACK, false);
    }
    save(&fig, output, "loudness_modes.png")
}

/// loudness_bands.png: the transient's last cycles in 1/3-octave bands, L_W and L_W(A).
fn plot_bands(r: &LoudnessReport, output: &Path) -> Result<(), WriteError> {
    let Some(t) = &r.transient else {
        return Ok(());
    };
    let level: Vec<(f64, f64)> = t
        .bands
        .iter()
        .filter(|b| b.1 > 0.0)
        .map(|b| (b.0.centre, power_level(b.1)))
        .collect();
    let weighted: Vec<(f64, f64)> = level
        .iter()
        .map(|&(f, l)| (f, l + a_weighting(f)))
        .collect();
    let (lo, hi) = finite_range(level.iter().chain(&weighted).map(|p| &p.1)).unwrap_or((0.0, 1.0));
    let mut fig = Figure::new(
        1000,
        560,
        (20f64.log10(), 20000f64.log10()),
        padded(lo.max(hi - 80.0), hi, 0.05),
        &format!(
            "transient, last cycles ({:.4}-{:.4} s): radiated power in 1/3-octave bands, L_W(A) {:.1} dB(A)",
            t.window.0,
            t.window.1,
            t.level_a()
        ),
        "band centre frequency (Hz)",
        "band power level (dB re 1 pW)",
    )
    .log_x();
    let log =
        |p: &[(f64, f64)]| -> Vec<(f64, f64)> { p.iter().map(|&(f, l)| (f.log10(), l)).collect() };
    fig.series(&log(&level), BLUE, "L_W");
    fig.series(&log(&weighted), RED, "L_W(A)");
    save(&fig, output, "loudness_bands.png")
}
