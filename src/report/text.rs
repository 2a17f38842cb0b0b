//! The summary's sections on the time/frequency link (modal energies, contact over the
//! cycle, dynamic stability) and on the pseudo trajectories.

use crate::eigen::complex_modes::damping_ratio;
use crate::stages::link::Link;
use crate::stages::pseudo::{PseudoReport, CYCLES};

/// The modal energies' summary lines (nothing when not asked for).
pub fn fmt_modal_energy(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.modal_energy {
        let e = &r.energy;
        let i = e
            .times
            .partition_point(|&t| t < e.at)
            .min(e.times.len() - 1);
        writeln!(
            f,
            "modal energy at t = {:.4e} s: {:.3e} J in the {} real modes, which hold {:.1} % of the kinetic energy; largest:",
            e.at,
            e.total(i),
            e.energy.len(),
            100.0 * e.kinetic_in_basis[i] / e.kinetic[i]
        )?;
        for m in &e.ranked {
            writeln!(
                f,
                "    R{:<4} {:9.1} Hz {:6.1} % of the modal energy, oscillating by {:5.1} % over [{:.4e}, {:.4e}] s, amplitude growing at {:.0} 1/s over [{:.4e}, {:.4e}] s",
                m.mode + 1,
                r.frequencies_hz[m.mode],
                100.0 * m.share,
                100.0 * m.oscillation,
                e.window.0,
                e.window.1,
                m.growth_rate,
                e.growth_window.0,
                e.growth_window.1
            )?;
        }
    }
    Ok(())
}

/// The contact cycle's summary lines (nothing when not asked for).
pub fn fmt_contact_cycle(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.contact_cycle {
        let c = &r.cycle;
        writeln!(
            f,
            "contact over the last cycle ({} phases of {} asked, period {:.4e} s, from {:.4e} s):",
            c.times.len(),
            r.wanted_phases,
            c.period,
            c.times.first().copied().unwrap_or(f64::NAN)
        )?;
        for p in &c.pads {
            let (hi, lo) = p.extreme_phases;
            writeln!(
                f,
                "    {:26} largest stiffness {:.3e}..{:.3e} Pa/m (varies by {:.0} %), open {:.1} %, sticking {:.1} %, sliding {:.1} %",
                p.name,
                p.largest_stiffness[lo],
                p.largest_stiffness[hi],
                100.0 * p.variation,
                100.0 * p.fractions[0],
                100.0 * p.fractions[1],
                100.0 * p.fractions[2]
            )?;
        }
    }
    Ok(())
}

/// The dynamic stability's summary lines (nothing when not asked for).
pub fn fmt_dynamic_stability(link: &Link, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    if let Some(r) = &link.dynamic_stability {
        let s = &r.stability;
        let sampling = if r.states_per_period.is_nan() {
            "at the scene's times".to_string()
        } else if r.states_per_period + 0.5 < r.wanted_per_period as f64 {
            format!(
                "{:.1} per period, fewer than the {} wanted: lower 'transient.state_interval' ({:.1e} s) to {:.1e} s",
                r.states_per_period,
                r.wanted_per_period,
                r.state_interval,
                r.period / r.wanted_per_period as f64
            )
        } else {
            format!("{:.1} per period", r.states_per_period)
        };
        writeln!(
            f,
            "dynamic stability at {} states from {:.4e} to {:.4e} s ({sampling}; period {:.4e} s), {:.3} s per linearization; {} nominal modes tracked, {} lost on the way:",
            s.times.len(),
            s.times.first().copied().unwrap_or(f64::NAN),
            s.times.last().copied().unwrap_or(f64::NAN),
            r.period,
            s.seconds_per_point,
            s.followed,
            s.lost
        )?;
        if s.tracks.is_empty() {
            writeln!(
                f,
                "    no mode is unstable at the static state or along the run"
            )?;
        }
        for t in s.tracks.iter().filter(|t| t.headline(r.margin)) {
            let (fr, z) = (t.frequencies_hz(), t.damping_ratios());
            let range = |x: &[f64]| {
                x[1..]
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    })
            };
            let ((f0, f1), (z0, z1)) = (range(&fr), range(&z));
            let rest = if t.unstable_at_rest(r.margin) {
                "unstable"
            } else {
                "stable"
            };
            // Steps where the track's shape changed abruptly: its identity there is doubtful.
            let jumps = t.mac[1..]
                .iter()
                .filter(|&&m| m.is_nan() || m < 0.5)
                .count();
            let jumps = match jumps {
                0 => String::new(),
                n => format!("; MAC < 0.5 with the previous state at {n} states"),
            };
            // What the run did with it: its real mode's growth over the modal energies' span.
            let in_run = match (&link.modal_energy, t.dominant_real_mode) {
                (Some(m), Some(k)) => format!(
                    "; in the run its real mode R{} grows at {:.0} 1/s over [{:.4e}, {:.4e}] s",
                    k + 1,
                    m.energy.growth[k],
                    m.energy.growth_window.0,
                    m.energy.growth_window.1
                ),
                _ => String::new(),
            };
            writeln!(
                f,
                "    {:5} at rest {:.1} Hz, zeta {:.2e} ({rest}); along the run {:.1}..{:.1} Hz, zeta {:.2e}..{:.2e}, unstable {:.0} % of the time, mean zeta {:.2e}, mean Re(s) {:.1} 1/s, correlation of zeta with the torque {:.2}{jumps}{in_run}",
                t.name, fr[0], z[0], f0, f1, z0, z1,
                100.0 * t.unstable_fraction,
                t.mean_damping_ratio,
                t.mean_re_s,
                t.torque_correlation
            )?;
        }
        let flickering: Vec<_> = s.tracks.iter().filter(|t| !t.headline(r.margin)).collect();
        if let Some(most) = flickering
            .iter()
            .max_by(|a, b| a.unstable_fraction.total_cmp(&b.unstable_fraction))
        {
            writeln!(
                f,
                "    {} more modes, stable at rest and on average, are unstable for part of the time (longest: {} for {:.0} %; all in /post/dynamic_stability)",
                flickering.len(),
                most.name,
                100.0 * most.unstable_fraction
            )?;
        }
    }
    Ok(())
}

/// The summary's lines.
pub fn fmt_pseudo(r: &PseudoReport, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    use crate::post::pseudo_trajectory::Found;
    let Some(first) = r.studies.first() else {
        return writeln!(
            f,
            "pseudo trajectories: no complex mode is unstable at the static state (margin {:.1e})",
            r.margin
        );
    };
    let t = &first.trajectory;
    let (a0, a1) = (t.sweep[0].alpha, t.sweep[t.sweep.len() - 1].alpha);
    writeln!(
        f,
        "pseudo trajectories (alpha: the largest relative displacement at a contact point; swept {:.2e}..{:.2e} m, {} amplitudes x {} phases; static gap scale {:.3e} m):",
        a0,
        a1,
        t.sweep.len(),
        t.diagram.eigenvalue.len(),
        r.gap_scale
    )?;
    let show = |x: &Found| match x {
        Found::At { alpha, .. } => format!("{alpha:.3e} m"),
        Found::BelowRange => format!("below {a0:.2e} m"),
        Found::AboveRange => format!("above {a1:.2e} m (not reached)"),
    };
    for s in &r.studies {
        let t = &s.trajectory;
        let f_hz = crate::eigen::complex_modes::frequency_hz(t.nominal);
        let fr = t.diagram.frequencies_hz();
        let span = fr
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        write!(
            f,
            "    {:5} {:.1} Hz, zeta {:.2e}: alpha_crit {}, alpha_sat {} (there {:.1}..{:.1} Hz over the period); {} linearizations ({} between phases, where the tracking halved the step), {:.2} s ({:.2} s linearizing, {:.2} s near the pair, {:.2} s in {} full dense solves)",
            t.name,
            f_hz,
            damping_ratio(t.nominal),
            show(&t.alpha_crit),
            show(&t.alpha_sat),
            span.0,
            span.1,
            t.linearizations,
            t.cost.between_phases,
            t.seconds,
            t.cost.linearize_seconds,
            t.cost.near_shift_seconds,
            t.cost.dense_seconds,
            t.cost.dense_solves
        )?;
        if t.alpha_stable.alpha() != t.alpha_sat.alpha() {
            let above = match &t.alpha_stable {
                Found::AboveRange => format!("unstable on average again at {a1:.2e} m"),
                x => format!("stable on average for every alpha from {}", show(x)),
            };
            write!(
                f,
                "; the mean damping changes sign {} times on the grid: {above}",
                t.sign_changes
            )?;
        }
        let open: Vec<f64> = t
            .sweep
            .iter()
            .filter(|p| !p.closed)
            .map(|p| p.alpha)
            .collect();
        if let Some(&first) = open.first() {
            let sat_beyond = t.alpha_sat.alpha().is_some_and(|a| a > first);
            write!(
                f,
                "; at {} of {} amplitudes (the first {first:.2e} m{}) the pair followed over the period does not come back to its start: there the statistics depend on the phase where the period starts, and are not resolved (raise phases)",
                open.len(),
                t.sweep.len(),
                if sat_beyond { ", below alpha_sat" } else { "" }
            )?;
        }
        if let (Some(tr), Some(total)) = (&s.transient, r.transient_seconds) {
            let ratio = t.alpha_sat.alpha().map_or(f64::NAN, |a| a / tr.mean);
            write!(
                f,
                "; in the transient's last {CYCLES} periods (largest relative displacement {:.3e} m): the mode's fit {:.3e} m ({:.2e}..{:.2e}), holding {:.0} % of the contact motion, alpha_sat / that {ratio:.3}; {:.2} % of the transient's time",
                tr.largest,
                tr.mean,
                tr.min,
                tr.max,
                100.0 * tr.share,
                100.0 * t.seconds / total
            )?;
        }
        writeln!(f)?;
    }
    Ok(())
}

/// The loudness section: per mode (loudest first) L_W and L_W(A) at alpha_sat and per 1 um,
/// microphones, the transient's last cycles.
pub fn fmt_loudness(
    r: &crate::stages::loudness::LoudnessReport,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    use crate::post::loudness::{a_weighting, power_level};
    writeln!(
        f,
        "how loud: equivalent radiated power (radiation efficiency 1) of the exterior of {} ({} faces, {:.4e} m^2; air {} kg/m^3, {} m/s)",
        r.components.join(", "),
        r.faces,
        r.area,
        r.density,
        r.sound_speed
    )?;
    for m in &r.modes {
        let a = a_weighting(m.frequency_hz);
        let per_unit = power_level(m.power_per_unit);
        write!(
            f,
            "    {:<5} {:8.1} Hz  Re(s) {:7.1} 1/s  at 1 um: L_W {:6.1} dB, L_W(A) {:6.1} dB(A)",
            m.name,
            m.frequency_hz,
            m.growth,
            per_unit,
            per_unit + a
        )?;
        match (m.alpha_sat, m.power_at_sat) {
            (Some(alpha), Some(p)) => write!(
                f,
                "; at alpha_sat {:.3e} m: {:.3e} W, L_W {:.1} dB, L_W(A) {:.1} dB(A)",
                alpha,
                p,
                power_level(p),
                power_level(p) + a
            )?,
            _ => write!(f, "; no alpha_sat (none found, or no pseudo trajectory of this mode): ranked per unit amplitude")?,
        }
        for (name, unit, sat) in &m.microphones {
            write!(f, "; at {name}: {unit:.1} dB per 1 um")?;
            if let Some(l) = sat {
                write!(f, ", {l:.1} dB at alpha_sat")?;
            }
        }
        writeln!(f)?;
    }
    if let Some(t) = &r.transient {
        write!(
            f,
            "    transient, last cycles [{:.4e}, {:.4e}] s ({} stored states): mean ERP {:.3e} W, L_W {:.1} dB, L_W(A) {:.1} dB(A)",
            t.window.0,
            t.window.1,
            t.states,
            t.mean_power,
            power_level(t.mean_power),
            t.level_a()
        )?;
        if let Some((band, p)) = t.dominant_band() {
            write!(
                f,
                "; loudest 1/3-octave band {} Hz ({:.1} dB)",
                band.nominal,
                power_level(*p)
            )?;
        }
        for (name, plain, weighted) in &t.microphones {
            write!(f, "; at {name}: {plain:.1} dB, {weighted:.1} dB(A)")?;
        }
        writeln!(f)?;
    }
    Ok(())
}
