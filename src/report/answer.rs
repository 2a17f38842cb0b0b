//! The answer of a run in a few lines, ahead of everything else in the summary and the report:
//! which complex modes are unstable, whether the transient reached a limit cycle (frequency,
//! amplitude), the predicted saturation amplitude, and where the report is.

use super::summary::RunSummary;
use crate::post::pseudo_trajectory::Found;

/// How many unstable modes the answer names (the rest are in the tables).
const NAMED: usize = 6;

/// The answer's lines (without indentation), the report's path last.
pub fn answer_lines(s: &RunSummary) -> Vec<String> {
    let mut lines = Vec::new();
    if let Some(failure) = &s.failure {
        lines.push(format!(
            "the run stopped early: {failure}; what it computed before is below and in results.h5"
        ));
    }
    for c in &s.complex {
        let mut unstable: Vec<_> = c.modes.iter().filter(|m| m.unstable).collect();
        unstable.sort_by(|a, b| b.eigenvalue.0.total_cmp(&a.eigenvalue.0));
        if unstable.is_empty() {
            lines.push(format!(
                "complex modes ({}): no mode is unstable among {}",
                c.route,
                c.modes.len()
            ));
            continue;
        }
        let named: Vec<String> = unstable
            .iter()
            .take(NAMED)
            .map(|m| {
                format!(
                    "{} {:.1} Hz (zeta {:.2e}, Re(s) {:.0} 1/s)",
                    m.name, m.frequency_hz, m.damping_ratio, m.eigenvalue.0
                )
            })
            .collect();
        let more = unstable.len().saturating_sub(NAMED);
        lines.push(format!(
            "{} unstable complex mode{} ({}, most unstable first): {}{}",
            unstable.len(),
            if unstable.len() == 1 { "" } else { "s" },
            c.route,
            named.join("; "),
            if more > 0 {
                format!("; {more} more")
            } else {
                String::new()
            }
        ));
    }
    if let Some(m) = &s.matrix {
        lines.push(m.answer_line());
    }
    match (&s.limit_cycle, &s.transient) {
        (Some(r), _) => {
            let c = &r.cycle;
            let state = if c.reached {
                "reached its limit cycle"
            } else if c.variation.is_some() {
                "saturated into a bounded vibration that is not periodic"
            } else if c.saturation_time.is_some() {
                "saturated; too few cycles since to call it a limit cycle"
            } else {
                "did not saturate within the run"
            };
            let at = c
                .growth_frequency
                .map_or(String::new(), |hz| format!(" at {hz:.1} Hz"));
            let growth = match (c.growth_rate, &r.predicted) {
                (Some(g), Some(p)) => format!(
                    "; it grew at {g:.0} 1/s{at} (complex mode {}: Re(s) {:.0} 1/s at {:.1} Hz)",
                    p.1, p.2, p.3
                ),
                (Some(g), None) => format!("; it grew at {g:.0} 1/s{at}"),
                _ => String::new(),
            };
            let rms = c.saturated_rms.map_or(String::new(), |r| {
                format!(", RMS {r:.3e} N m over the last fifth")
            });
            lines.push(format!(
                "transient: {state}; at its end {:.1} Hz, braking-torque amplitude {:.3e} N m (half peak-to-peak){rms}{growth}",
                c.dominant_frequency, c.saturated_amplitude
            ));
        }
        (None, Some(t)) => lines.push(format!(
            "transient: {} steps to t = {:.4e} s (add [post.limit_cycle] to characterize it)",
            t.steps, t.simulated
        )),
        _ => {}
    }
    if let Some(p) = &s.pseudo {
        for study in &p.studies {
            let t = &study.trajectory;
            let predicted = match &t.alpha_sat {
                Found::At { alpha, .. } => format!("{alpha:.3e} m"),
                Found::BelowRange => "below the swept range".into(),
                Found::AboveRange => "above the swept range (not reached)".into(),
            };
            let against = study.transient.as_ref().map_or(String::new(), |tr| {
                format!(
                    "; the transient's last cycles: {:.3e} m of this mode, {:.3e} m of relative contact displacement in all",
                    tr.mean, tr.largest
                )
            });
            lines.push(format!(
                "predicted saturation amplitude of {} (pseudo trajectory): alpha_sat {predicted}{against}",
                t.name
            ));
        }
    }
    if let Some(l) = &s.loudness {
        lines.push(how_loud(l));
    }
    if lines.is_empty() && !s.frequencies_hz.is_empty() {
        let (lo, hi) = (
            s.frequencies_hz[0],
            s.frequencies_hz[s.frequencies_hz.len() - 1],
        );
        lines.push(format!(
            "{} real modes from {lo:.1} to {hi:.1} Hz; no stability analysis asked (the scene has no [complex_modes])",
            s.frequencies_hz.len()
        ));
    }
    lines.push(format!(
        "report: {}",
        s.output.join("report.html").display()
    ));
    lines
}

/// "how loud": the modes ranked by L_W(A) at alpha_sat (else per 1 um), the transient's level
/// and loudest band, and predicted against transient.
fn how_loud(l: &crate::stages::loudness::LoudnessReport) -> String {
    use crate::post::loudness::power_level;
    let named: Vec<String> = l
        .modes
        .iter()
        .take(NAMED)
        .map(|m| match m.power_at_sat {
            Some(_) => format!(
                "{} {:.1} Hz {:.1} dB(A) at alpha_sat",
                m.name,
                m.frequency_hz,
                m.level_a()
            ),
            None => format!(
                "{} {:.1} Hz {:.1} dB(A) per 1 um (no alpha_sat)",
                m.name,
                m.frequency_hz,
                m.level_a()
            ),
        })
        .collect();
    let mut line = String::from("how loud (sound power, ERP)");
    if !named.is_empty() {
        line += &format!(": {}", named.join("; "));
    }
    if let Some(t) = &l.transient {
        let band = t.dominant_band().map_or(String::new(), |(b, _)| {
            format!(", loudest band {} Hz", b.nominal)
        });
        line += &format!(
            "; the transient's last cycles {:.1} dB(A) (L_W {:.1} dB{band})",
            t.level_a(),
            power_level(t.mean_power)
        );
        if let Some(m) = l.modes.iter().find(|m| m.power_at_sat.is_some()) {
            line += &format!(
                "; predicted ({}) minus transient {:+.1} dB(A)",
                m.name,
                m.level_a() - t.level_a()
            );
        }
    }
    line
}
