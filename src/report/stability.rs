//! The stability diagram: frequency against damping ratio of the complex modes, unstable modes
//! (negative damping ratio) in red and labelled with their names.

use std::path::Path;

use crate::eigen::complex_modes::ComplexMode;
use crate::eigen::complex_modes::{damping_ratio, frequency_hz};
use crate::eigen::tracking::Tracks;
use crate::io::figure::{padded, Figure, BLACK, BLUE, PALETTE, RED};
use crate::measure::nan_max;

/// Writes the diagram of `modes` as a PNG.
pub fn write_diagram(path: &Path, modes: &[ComplexMode], title: &str) -> std::io::Result<()> {
    let f = modes
        .iter()
        .map(|m| m.frequency_hz)
        .filter(|x| x.is_finite());
    let z = modes.iter().map(|m| m.damping_ratio);
    let (f_min, f_max) = (0.0f64, f.fold(0.0f64, nan_max));
    let (z_min, z_max) = z.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let mut fig = Figure::new(
        1000,
        600,
        padded(f_min, f_max, 0.03),
        padded(z_min, z_max.max(1e-4), 0.08),
        title,
        "frequency (Hz)",
        "damping ratio (1)",
    );
    fig.hline(0.0, BLACK);
    for m in modes.iter().filter(|m| !m.unstable) {
        fig.marker(m.frequency_hz, m.damping_ratio, BLUE, 3);
    }
    // Alternate labels above and below so neighbours do not overwrite each other.
    for (i, m) in modes.iter().filter(|m| m.unstable).enumerate() {
        fig.marker(m.frequency_hz, m.damping_ratio, RED, 4);
        fig.label(
            m.frequency_hz,
            m.damping_ratio,
            &format!("{} {:.0} Hz", m.name, m.frequency_hz),
            RED,
            i % 2 == 1,
        );
    }
    let unstable = modes.iter().filter(|m| m.unstable).count();
    fig.legend(0, &format!("stable ({})", modes.len() - unstable), BLUE);
    fig.legend(1, &format!("unstable ({unstable})"), RED);
    fig.save(path)
}

/// A sweep plot: each track's frequency (or real part) against the parameter, one colour per
/// track, points where the mode is unstable marked red.
pub fn write_sweep_plot(
    path: &Path,
    values: &[f64],
    tracks: &Tracks,
    real_part: bool,
    margin: f64,
    x_label: &str,
    y_label: &str,
) -> std::io::Result<()> {
    let y = |s: (f64, f64)| if real_part { s.0 } else { frequency_hz(s) };
    let all = tracks.tracks.iter().flatten().flatten().map(|(s, _)| y(*s));
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (x_lo, x_hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let title = if real_part {
        "real part of the complex modes"
    } else {
        "frequency of the complex modes"
    };
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
    let mut fig = Figure::new(
        1000,
        600,
        padded(x_lo, x_hi, 0.02),
        padded(lo, hi, 0.05),
        title,
        x_label,
        y_label,
    );
    if real_part {
        fig.hline(0.0, BLACK);
    }
    for (t, track) in tracks.tracks.iter().enumerate() {
        let colour = PALETTE[t % PALETTE.len()];
        let pts: Vec<(f64, f64)> = track
            .iter()
            .zip(values)
            .filter_map(|(p, &x)| p.map(|(s, _)| (x, y(s))))
            .collect();
        fig.line(&pts, colour);
        for (p, &x) in track.iter().zip(values) {
            if let Some((s, _)) = p {
                let unstable = damping_ratio(*s) < -margin;
                fig.marker(
                    x,
                    y(*s),
                    if unstable { RED } else { colour },
                    if unstable { 3 } else { 1 },
                );
            }
        }
    }
    fig.legend(0, "unstable", RED);
    fig.save(path)
}
