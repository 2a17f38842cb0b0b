//! The answer of a run, ahead of everything else in the summary, summary.txt and the report:
//! a verdict in one line (does it squeal, at what frequency, which mode, which components move
//! most, how loud), then the detail in plain words: the unstable modes, what the transient did,
//! the predicted saturation amplitude, the levels in columns that compare, where the files are.
//! Solver diagnostics are not part of it (transient.log, the report's diagnostics).

use super::summary::{ComplexSummary, RunSummary};
use crate::eigen::complex_modes::ComplexMode;
use crate::post::loudness::power_level;
use crate::post::pseudo_trajectory::Found;
use crate::stages::loudness::LoudnessReport;

/// How many unstable modes the answer lists (the rest are in the tables).
const NAMED: usize = 6;

/// A frequency as an engineer says it: "2.91 kHz", "520 Hz".
pub fn hz(f: f64) -> String {
    // A rigid-body mode's round-off ("-0 Hz") reads as 0.
    let f = if f.abs() < 0.5 { 0.0 } else { f };
    if f >= 1000.0 {
        format!("{:.2} kHz", f / 1000.0)
    } else {
        format!("{f:.0} Hz")
    }
}

/// A length in micrometres, three significant digits.
fn um(x: f64) -> String {
    let v = x * 1e6;
    if v >= 100.0 {
        format!("{v:.0} um")
    } else if v >= 10.0 {
        format!("{v:.1} um")
    } else {
        format!("{v:.2} um")
    }
}

/// A block name in words ("outer_backplate" -> "outer backplate").
fn component(name: &str) -> String {
    name.replace('_', " ")
}

/// The blocks that carry most of a mode's motion: the largest shares until they hold two
/// thirds of it, at most three.
pub fn moving_most(motion: &[(String, f64)]) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let mut held = 0.0;
    for (name, share) in motion.iter().take(3) {
        if held >= 2.0 / 3.0 {
            break;
        }
        out.push((component(name), *share));
        held += share;
    }
    out
}

/// "disc and outer backplate" from the blocks that move most.
fn names_in_words(blocks: &[(String, f64)]) -> String {
    let names: Vec<&str> = blocks.iter().map(|(n, _)| n.as_str()).collect();
    match names.as_slice() {
        [] => String::new(),
        [one] => (*one).to_string(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// "disc 48 %, outer backplate 21 %".
fn shares_in_words(blocks: &[(String, f64)]) -> String {
    blocks
        .iter()
        .map(|(n, s)| format!("{n} {:.0} %", 100.0 * s))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The unstable modes of a route, most unstable (largest Re(s)) first.
fn unstable_of(c: &ComplexSummary) -> Vec<&ComplexMode> {
    let mut unstable: Vec<_> = c.modes.iter().filter(|m| m.unstable).collect();
    unstable.sort_by(|a, b| b.eigenvalue.0.total_cmp(&a.eigenvalue.0));
    unstable
}

/// The level of the verdict: the saturated vibration's, else the one predicted at a mode's
/// saturation amplitude.
fn verdict_level(l: Option<&LoudnessReport>, mode: &str) -> Option<String> {
    let l = l?;
    if let Some(t) = &l.transient {
        return Some(format!(
            "{:.1} dB(A) sound power from the saturated vibration",
            t.level_a()
        ));
    }
    let m = l
        .modes
        .iter()
        .find(|m| m.name == mode && m.power_at_sat.is_some())?;
    Some(format!(
        "{:.1} dB(A) sound power predicted at its saturation amplitude",
        m.level_a()
    ))
}

/// The verdict of a noise matrix: at how many of its operating points it squeals.
pub fn matrix_verdict(m: &crate::report::matrix::MatrixReport) -> String {
    let a = &m.analysis;
    let yes = if a.squealing > 0 { "yes" } else { "no" };
    format!(
        "squeals: {yes}, at {} of {} operating points of the noise matrix",
        a.squealing, a.solved
    )
}

/// The verdict: one line, "squeals: yes/likely/no, ..." (None when the scene asked no
/// stability question: real modes alone).
pub fn verdict(s: &RunSummary) -> Option<String> {
    if let Some(m) = &s.matrix {
        return Some(matrix_verdict(m));
    }
    let route = s.complex.first()?;
    let unstable = unstable_of(route);
    let Some(&first) = unstable.first() else {
        let below = route
            .modes
            .last()
            .map_or(String::new(), |m| format!(" up to {}", hz(m.frequency_hz)));
        return Some(format!(
            "squeals: no, none of the {} complex modes{below} is unstable at the static state",
            route.modes.len()
        ));
    };
    // The mode the transient saw grow, when there is one; else the most unstable.
    let named = s
        .limit_cycle
        .as_ref()
        .and_then(|r| r.predicted.as_ref())
        .and_then(|p| unstable.iter().find(|m| m.name == p.1).copied())
        .unwrap_or(first);
    let moving = moving_most(&named.motion);
    let moving = if moving.is_empty() {
        String::new()
    } else {
        format!(", {} moving most", names_in_words(&moving))
    };
    let level =
        verdict_level(s.loudness.as_ref(), &named.name).map_or(String::new(), |l| format!(", {l}"));
    let others = match unstable.len() {
        1 => String::new(),
        n => format!(" ({} of {n})", ordinal_of(&unstable, named)),
    };
    let at = format!(
        "{}, mode {}{others}{moving}",
        hz(named.frequency_hz),
        named.name
    );
    Some(match &s.limit_cycle {
        Some(r) => {
            let c = &r.cycle;
            match (c.growth_rate, c.saturation_time) {
                (Some(g), Some(_)) if g > 0.0 => {
                    let end = if (c.dominant_frequency - named.frequency_hz).abs()
                        > 0.05 * named.frequency_hz
                    {
                        format!(" (saturated near {})", hz(c.dominant_frequency))
                    } else {
                        String::new()
                    };
                    format!("squeals: yes, {at}{level}{end}")
                }
                (Some(g), None) if g > 0.0 => format!(
                    "squeals: yes, {at}: still growing at the end of the transient{level}"
                ),
                _ => format!(
                    "squeals: not in this transient: {at} is unstable at rest, but the vibration did not grow from its start"
                ),
            }
        }
        None => {
            let how = if s.transient.is_some() {
                "add [post.limit_cycle] to judge the transient"
            } else {
                "the complex modes over-predict: a transient decides"
            };
            format!("squeals: likely, {at}{level}; {how}")
        }
    })
}

/// "the most unstable", "the 2nd most unstable".
fn ordinal_of(unstable: &[&ComplexMode], mode: &ComplexMode) -> String {
    let i = unstable
        .iter()
        .position(|m| m.name == mode.name)
        .unwrap_or(0);
    match i {
        0 => "the most unstable".into(),
        1 => "the 2nd most unstable".into(),
        2 => "the 3rd most unstable".into(),
        i => format!("the {}th most unstable", i + 1),
    }
}

/// The answer's lines (without indentation): the verdict, then the detail, the files last.
pub fn answer_lines(s: &RunSummary) -> Vec<String> {
    let mut lines = Vec::new();
    match verdict(s) {
        Some(v) => lines.push(v),
        None if !s.frequencies_hz.is_empty() => {
            let (lo, hi) = (
                s.frequencies_hz[0],
                s.frequencies_hz[s.frequencies_hz.len() - 1],
            );
            lines.push(format!(
                "no verdict on squeal (the scene asks for no complex modes); {} real modes from {} to {}",
                s.frequencies_hz.len(),
                hz(lo),
                hz(hi)
            ));
        }
        None => {}
    }
    if let Some(failure) = &s.failure {
        lines.push(format!(
            "the run stopped early: {failure}; what it computed before is below and in results.h5"
        ));
    }
    for c in &s.complex {
        unstable_lines(c, &mut lines);
    }
    if let Some(m) = &s.matrix {
        lines.push(m.answer_line());
    }
    transient_line(s, &mut lines);
    pseudo_lines(s, &mut lines);
    if let Some(l) = &s.loudness {
        lines.push(how_loud(l));
    }
    lines.push(format!(
        "files: {} (this answer and the whole summary), {} (everything on one page), {}",
        s.output.join("summary.txt").display(),
        s.output.join("report.html").display(),
        s.output.join("results.h5").display(),
    ));
    lines
}

/// The unstable modes of a route: one line each, growth rate and damping ratio, what moves.
fn unstable_lines(c: &ComplexSummary, lines: &mut Vec<String>) {
    let unstable = unstable_of(c);
    if unstable.is_empty() {
        lines.push(format!(
            "complex modes ({} route): all {} stable",
            c.route,
            c.modes.len()
        ));
        return;
    }
    let basis = if c.basis > 0 {
        format!(" on {} real modes", c.basis)
    } else {
        String::new()
    };
    lines.push(format!(
        "{} unstable complex mode{} ({} route{basis}), most unstable first:",
        unstable.len(),
        if unstable.len() == 1 { "" } else { "s" },
        c.route
    ));
    for m in unstable.iter().take(NAMED) {
        let moving = moving_most(&m.motion);
        let moving = if moving.is_empty() {
            String::new()
        } else {
            format!("; moving: {}", shares_in_words(&moving))
        };
        lines.push(format!(
            "    {:<4} {:>9}  grows at {:>4.0} 1/s (damping ratio {:.2e}){moving}",
            m.name,
            hz(m.frequency_hz),
            m.eigenvalue.0,
            m.damping_ratio
        ));
    }
    if unstable.len() > NAMED {
        lines.push(format!(
            "    and {} more (complex_modes_*.csv)",
            unstable.len() - NAMED
        ));
    }
}

/// What the transient did, in words.
fn transient_line(s: &RunSummary, lines: &mut Vec<String>) {
    match (&s.limit_cycle, &s.transient) {
        (Some(r), t) => {
            let c = &r.cycle;
            let length = t.as_ref().map_or(String::new(), |t| {
                format!(" ({:.1} ms simulated)", 1e3 * t.simulated)
            });
            let growth = match (c.growth_rate, &r.predicted) {
                (Some(g), Some(p)) => format!(
                    "grew at {g:.0} 1/s{} ({} predicts {:.0} 1/s at {})",
                    c.growth_frequency
                        .map_or(String::new(), |f| format!(" at {}", hz(f))),
                    p.1,
                    p.2,
                    hz(p.3)
                ),
                (Some(g), None) => format!("grew at {g:.0} 1/s"),
                _ => "did not grow".into(),
            };
            let state = match (c.saturation_time, c.reached, c.variation) {
                (Some(t), true, _) => {
                    format!("saturated at {:.1} ms into a limit cycle", 1e3 * t)
                }
                (Some(t), false, Some(v)) => format!(
                    "saturated at {:.1} ms into a bounded vibration that is not periodic (its amplitude varies by {:.0} % over the last cycles)",
                    1e3 * t,
                    100.0 * v
                ),
                (Some(t), false, None) => format!(
                    "saturated at {:.1} ms (too few cycles since to call it a limit cycle)",
                    1e3 * t
                ),
                (None, _, _) => "did not saturate within the run".into(),
            };
            let torque = c.saturated_rms.map_or(String::new(), |rms| {
                format!(", RMS {rms:.0} N m over the last fifth")
            });
            lines.push(format!(
                "transient{length}: {growth}; {state}; at the end {}, braking-torque swing {:.0} N m (half peak-to-peak){torque}",
                hz(c.dominant_frequency),
                c.saturated_amplitude
            ));
        }
        (None, Some(t)) => lines.push(format!(
            "transient: {} steps to {:.1} ms (add [post.limit_cycle] to characterize it)",
            t.steps,
            1e3 * t.simulated
        )),
        _ => {}
    }
}

/// The saturation amplitude each pseudo trajectory predicts, beside the transient's.
fn pseudo_lines(s: &RunSummary, lines: &mut Vec<String>) {
    let Some(p) = &s.pseudo else { return };
    for study in &p.studies {
        let t = &study.trajectory;
        let predicted = match &t.alpha_sat {
            Found::At { alpha, .. } => format!("{} of relative contact displacement", um(*alpha)),
            Found::BelowRange => "below the smallest swept amplitude".into(),
            Found::AboveRange => {
                "none within the swept amplitudes (unstable on average up to the largest)".into()
            }
        };
        let against = match (&study.transient, &t.alpha_sat) {
            (Some(tr), Found::At { alpha, .. }) => format!(
                "; in the transient's last cycles {} holds {} ({:.2} of it predicted), the contact motion in all {}",
                t.name,
                um(tr.mean),
                alpha / tr.mean,
                um(tr.largest)
            ),
            (Some(tr), _) => format!(
                "; in the transient's last cycles {} holds {}",
                t.name,
                um(tr.mean)
            ),
            _ => String::new(),
        };
        lines.push(format!(
            "saturation amplitude predicted from {} alone (pseudo trajectory): {predicted}{against}",
            t.name
        ));
    }
}

/// "how loud": the saturated vibration's level, the levels predicted at alpha_sat, and every
/// unstable mode per 1 um of contact amplitude, each group in its own column (levels at
/// different amplitudes do not compare).
fn how_loud(l: &LoudnessReport) -> String {
    use crate::post::loudness::a_weighting;
    let mut parts = Vec::new();
    if let Some(t) = &l.transient {
        let band = t.dominant_band().map_or(String::new(), |(b, _)| {
            format!(", loudest 1/3-octave band {}", hz(b.nominal))
        });
        parts.push(format!(
            "the saturated vibration {:.1} dB(A) (L_W {:.1} dB{band})",
            t.level_a(),
            power_level(t.mean_power)
        ));
    }
    let at_sat: Vec<String> = l
        .modes
        .iter()
        .filter(|m| m.power_at_sat.is_some())
        .map(|m| format!("{} {:.1} dB(A)", m.name, m.level_a()))
        .collect();
    if !at_sat.is_empty() {
        parts.push(format!(
            "at the predicted saturation amplitude {}",
            at_sat.join(", ")
        ));
    }
    let mut per_unit: Vec<_> = l
        .modes
        .iter()
        .map(|m| {
            let level = power_level(m.power_per_unit) + a_weighting(m.frequency_hz);
            (m.name.as_str(), level)
        })
        .collect();
    per_unit.sort_by(|a, b| b.1.total_cmp(&a.1));
    if !per_unit.is_empty() {
        let list: Vec<String> = per_unit
            .iter()
            .take(NAMED)
            .map(|(n, level)| format!("{n} {level:.1}"))
            .collect();
        parts.push(format!(
            "per 1 um of contact amplitude (to rank the modes) {} dB(A)",
            list.join(", ")
        ));
    }
    format!(
        "how loud (A-weighted sound power, ERP of {}): {}",
        l.components
            .iter()
            .map(|c| component(c))
            .collect::<Vec<_>>()
            .join(", "),
        parts.join("; ")
    )
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn frequencies_read_as_an_engineer_says_them() {
        assert_eq!(hz(2910.55), "2.91 kHz");
        assert_eq!(hz(520.4), "520 Hz");
        assert_eq!(hz(-1e-9), "0 Hz");
        assert_eq!(um(2.148e-5), "21.5 um");
    }

    #[test]
    fn moving_most_stops_at_two_thirds_or_three_blocks() {
        let m = |v: &[(&str, f64)]| -> Vec<(String, f64)> {
            v.iter().map(|(n, s)| (n.to_string(), *s)).collect()
        };
        let one = moving_most(&m(&[("disc", 0.8), ("outer_lining", 0.1)]));
        assert_eq!(one.len(), 1);
        let two = moving_most(&m(&[
            ("disc", 0.5),
            ("outer_backplate", 0.3),
            ("caliper", 0.2),
        ]));
        assert_eq!(names_in_words(&two), "disc and outer backplate");
        let three = moving_most(&m(&[("a", 0.3), ("b", 0.2), ("c", 0.1), ("d", 0.1)]));
        assert_eq!(names_in_words(&three), "a, b and c");
    }
}
