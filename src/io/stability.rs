//! The stability diagram: frequency against damping ratio of the complex modes, unstable modes
//! (negative damping ratio) in red and labelled with their names.

use std::path::Path;

use super::plot::{padded, Figure, BLACK, BLUE, RED};
use crate::eigen::complex_modes::ComplexMode;

/// Writes the diagram of `modes` as a PNG.
pub fn write_diagram(path: &Path, modes: &[ComplexMode], title: &str) -> std::io::Result<()> {
    let f = modes.iter().map(|m| m.frequency_hz);
    let z = modes.iter().map(|m| m.damping_ratio);
    let (f_min, f_max) = (0.0f64, f.fold(0.0f64, f64::max));
    let (z_min, z_max) = z.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let mut fig = Figure::new(
        1000,
        600,
        padded(f_min, f_max, 0.03),
        padded(z_min, z_max.max(1e-4), 0.08),
        title,
        "frequency (Hz)",
        "damping ratio",
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
