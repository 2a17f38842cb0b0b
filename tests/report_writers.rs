//! The report wing's writers run without MPI on a stage output built here: the modal-energy
//! section of the summary and its figure, from two undamped oscillators whose energies are
//! known in closed form.
//!
//! Reference: a mode eta(t) = A sin(w t) of an undamped oscillator has the constant energy
//! E = (etadot^2 + w^2 eta^2) / 2 = A^2 w^2 / 2 at every instant; two such modes hold the
//! shares E_1 / (E_1 + E_2) and E_2 / (E_1 + E_2) of the modal energy, with no oscillation.

use std::fmt;

use squeal::post::modal_energy::{modal_energy, ModalEnergySettings, ModalSample};
use squeal::report::link::plot_modal_energy;
use squeal::report::text::fmt_modal_energy;
use squeal::stages::link::{Link, ModalEnergyReport};

/// The summary's modal-energy lines, as the report prints them.
struct Section<'a>(&'a Link);

impl fmt::Display for Section<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt_modal_energy(self.0, f)
    }
}

/// Two modes, 500 Hz with amplitude 2e-6 and 1,500 Hz with amplitude 1e-6 (mass-normalized
/// coordinates), sampled 400 times over 8 ms.
fn two_oscillators() -> ModalEnergyReport {
    let f = [500.0, 1500.0];
    let amplitude = [2e-6, 1e-6];
    let omega: Vec<f64> = f.iter().map(|f| 2.0 * std::f64::consts::PI * f).collect();
    let times: Vec<f64> = (0..400).map(|i| i as f64 * 2e-5).collect();
    let samples: Vec<ModalSample> = times
        .iter()
        .map(|&t| {
            let eta: Vec<f64> = (0..2)
                .map(|k| amplitude[k] * (omega[k] * t).sin())
                .collect();
            let eta_dot: Vec<f64> = (0..2)
                .map(|k| amplitude[k] * omega[k] * (omega[k] * t).cos())
                .collect();
            let kinetic = eta_dot.iter().map(|v| 0.5 * v * v).sum();
            ModalSample {
                eta,
                eta_dot,
                kinetic,
            }
        })
        .collect();
    let omega2: Vec<f64> = omega.iter().map(|w| w * w).collect();
    let settings = ModalEnergySettings::default();
    ModalEnergyReport {
        energy: modal_energy(&times, &samples, &omega2, &settings, 1.0 / f[0]),
        frequencies_hz: f.to_vec(),
    }
}

#[test]
fn modal_energy_section_and_figure_of_two_undamped_oscillators() {
    let report = two_oscillators();
    let omega = [
        2.0 * std::f64::consts::PI * 500.0,
        2.0 * std::f64::consts::PI * 1500.0,
    ];
    let exact = [
        0.5 * (2e-6 * omega[0]).powi(2),
        0.5 * (1e-6 * omega[1]).powi(2),
    ];
    let total = exact[0] + exact[1];
    let link = Link {
        modal_energy: Some(report),
        ..Link::default()
    };
    let text = Section(&link).to_string();
    // The 1,500 Hz mode holds 9/13 of the energy, the 500 Hz mode 4/13; the text rounds to
    // 0.1 %, so the printed shares must be those to that digit.
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(
        lines[0].contains(&format!("{total:.3e} J in the 2 real modes")),
        "{text}"
    );
    assert!(
        lines[0].contains("hold 100.0 % of the kinetic energy"),
        "{text}"
    );
    let share = |k: usize| format!("{:6.1} % of the modal energy", 100.0 * exact[k] / total);
    assert!(
        lines[1].starts_with("    R2") && lines[1].contains(&share(1)),
        "{text}"
    );
    assert!(
        lines[2].starts_with("    R1") && lines[2].contains(&share(0)),
        "{text}"
    );
    // Constant energies: no oscillation over the window (round-off of sin^2 + cos^2 only).
    assert!(lines[1].contains("oscillating by   0.0 %"), "{text}");

    let dir = std::env::temp_dir().join(format!("squeal-report-writers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    plot_modal_energy(link.modal_energy.as_ref().unwrap(), &dir).unwrap();
    let png = std::fs::read(dir.join("modal_energy.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "modal_energy.png is a PNG");
    std::fs::remove_dir_all(&dir).ok();
}
