//! Writers of the time/frequency link: /post/modal_energy with modal_energy.png, and
//! /post/dynamic_stability with dynamic_stability.png and dynamic_stability_time.png.

use crate::measure::nan_max;
use std::path::Path;

use super::WriteError;
use crate::fem::dofmap::DofMap;
use crate::io::figure::{padded, Figure, BLACK, BLUE, GREY, PALETTE, RED};
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::post::contact_cycle::{ContactCycle, PadCycle};
use crate::post::dynamic_stability::TrackedMode;
use crate::report::contact_map::{map_figure, plane_map, MapContext};
use crate::stages::link::{ContactCycleReport, DynamicStabilityReport, Link, ModalEnergyReport};

/// # Collective
pub fn write_link(
    petsc: &Petsc,
    file: &ResultsFile,
    link: &Link,
    maps: Option<MapContext>,
    dofs: Option<&DofMap>,
    output: &Path,
) -> Result<(), WriteError> {
    if let Some(r) = &link.contact_cycle {
        write_contact_cycle(file, r)?;
        if let (Some(maps), 0) = (maps, petsc.rank()) {
            for pad in &r.cycle.pads {
                plot_contact_cycle(r, pad, maps, output)?;
            }
        }
    }
    if let Some(r) = &link.modal_energy {
        write_modal_energy(file, r)?;
        if petsc.rank() == 0 {
            plot_modal_energy(r, output)?;
        }
    }
    if let Some(r) = &link.dynamic_stability {
        write_dynamic_stability(file, r)?;
        if let Some(dofs) = dofs {
            for shape in &r.shapes {
                for (part, values) in ["re", "im"].iter().zip(&shape.parts) {
                    let name = format!("{}_{part}", shape.dataset);
                    file.write_nodal(&name, dofs, values, "m")?;
                }
            }
        }
        if petsc.rank() == 0 {
            plot_stability_diagram(r, output)?;
            plot_stability_in_time(r, output)?;
        }
    }
    Ok(())
}

fn write_modal_energy(file: &ResultsFile, r: &ModalEnergyReport) -> Result<(), WriteError> {
    let g = "post/modal_energy";
    let e = &r.energy;
    file.write_table(&format!("{g}/time"), &e.times, "s")?;
    let numbers: Vec<f64> = (1..=e.energy.len()).map(|k| k as f64).collect();
    file.write_table(&format!("{g}/mode"), &numbers, "real mode number")?;
    file.write_table(&format!("{g}/frequency"), &r.frequencies_hz, "Hz")?;
    let flat: Vec<f64> = e.energy.iter().flatten().copied().collect();
    file.write_table(
        &format!("{g}/energy"),
        &flat,
        "J; mode-major: mode k's energy at every stored time, then mode k+1's",
    )?;
    file.write_table(&format!("{g}/kinetic_energy"), &e.kinetic, "J")?;
    file.write_table(
        &format!("{g}/kinetic_energy_in_basis"),
        &e.kinetic_in_basis,
        "J",
    )?;
    let column = |f: &dyn Fn(&crate::post::modal_energy::RankedMode) -> f64| -> Vec<f64> {
        e.ranked.iter().map(f).collect()
    };
    let ranked = [
        ("mode", column(&|m| (m.mode + 1) as f64), "real mode number"),
        ("energy", column(&|m| m.energy), "J"),
        (
            "share",
            column(&|m| m.share),
            "of the sum of the modal energies",
        ),
        (
            "oscillation",
            column(&|m| m.oscillation),
            "half peak-to-peak over the mean, over the window",
        ),
        (
            "growth_rate",
            column(&|m| m.growth_rate),
            "1/s, the amplitude's, over the growth window",
        ),
    ];
    for (name, values, units) in ranked {
        file.write_table(&format!("{g}/ranked/{name}"), &values, units)?;
    }
    file.set_number(g, "ranking_time_s", e.at)?;
    file.set_number(g, "window_start_s", e.window.0)?;
    file.set_number(g, "window_end_s", e.window.1)?;
    file.write_table(
        &format!("{g}/growth_rate"),
        &e.growth,
        "1/s; per mode, its amplitude's: half the least-squares slope of ln E over the growth window",
    )?;
    file.set_number(g, "growth_window_start_s", e.growth_window.0)?;
    file.set_number(g, "growth_window_end_s", e.growth_window.1)?;
    Ok(())
}

fn save(fig: &Figure, output: &Path, name: &str) -> Result<(), WriteError> {
    let path = output.join(name);
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}

/// modal_energy.png: the ranked modes' energies against time, log scale, labelled with mode
/// and frequency (rank 0 writes it).
pub fn plot_modal_energy(r: &ModalEnergyReport, output: &Path) -> Result<(), WriteError> {
    let e = &r.energy;
    let log = |x: f64| x.max(1e-300).log10();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for m in &e.ranked {
        for &v in &e.energy[m.mode] {
            if v > 0.0 {
                lo = lo.min(log(v));
                hi = hi.max(log(v));
            }
        }
    }
    // Twelve decades below the largest are enough to see the growth.
    let lo = lo.max(hi - 12.0);
    let end = e.times.last().copied().unwrap_or(1.0);
    let mut fig = Figure::new(
        1200,
        600,
        padded(e.times[0], end, 0.0),
        padded(lo, hi, 0.05),
        &format!(
            "modal energies: the {} largest at {:.4} s",
            e.ranked.len(),
            e.at
        ),
        "time (s)",
        "modal energy (J)",
    )
    .log_y();
    for (k, m) in e.ranked.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let points: Vec<(f64, f64)> = e
            .times
            .iter()
            .zip(&e.energy[m.mode])
            .filter(|(_, &v)| v > 0.0)
            .map(|(&t, &v)| (t, log(v).max(lo)))
            .collect();
        let label = format!(
            "R{} {:.0} Hz: {:.1} %",
            m.mode + 1,
            r.frequencies_hz[m.mode],
            100.0 * m.share
        );
        fig.series(&points, c, &label);
    }
    save(&fig, output, "modal_energy.png")
}

fn write_dynamic_stability(
    file: &ResultsFile,
    r: &DynamicStabilityReport,
) -> Result<(), WriteError> {
    let g = "post/dynamic_stability";
    let s = &r.stability;
    file.write_table(&format!("{g}/time"), &s.times, "s")?;
    file.write_table(&format!("{g}/braking_torque"), &s.torque, "N m")?;
    file.set_number(g, "period_s", r.period)?;
    file.set_number(g, "seconds_per_linearization", s.seconds_per_point)?;
    file.set_number(g, "tracks_followed", s.followed as f64)?;
    file.set_number(g, "tracks_lost", s.lost as f64)?;
    for t in &s.tracks {
        let m = format!("{g}/modes/{}", t.name);
        let (re, im): (Vec<f64>, Vec<f64>) = t.eigenvalue.iter().copied().unzip();
        let note = "at the static state, then at every time";
        file.write_table(&format!("{m}/re_s"), &re, &format!("1/s; {note}"))?;
        file.write_table(&format!("{m}/im_s"), &im, &format!("rad/s; {note}"))?;
        file.write_table(&format!("{m}/frequency"), &t.frequencies_hz(), "Hz")?;
        file.write_table(&format!("{m}/damping_ratio"), &t.damping_ratios(), "1")?;
        file.write_table(&format!("{m}/mac"), &t.mac, "MAC with the previous point")?;
        file.set_number(&m, "unstable_fraction", t.unstable_fraction)?;
        file.set_number(&m, "mean_damping_ratio", t.mean_damping_ratio)?;
        file.set_number(&m, "torque_correlation", t.torque_correlation)?;
        file.set_number(&m, "mean_re_s", t.mean_re_s)?;
        if let Some(k) = t.dominant_real_mode {
            file.set_number(&m, "dominant_real_mode", (k + 1) as f64)?;
        }
    }
    Ok(())
}

/// Frequency against damping ratio of the tracked modes, points coloured by time (dark:
/// first, bright: last); the static state's modes as black rings.
fn plot_stability_diagram(r: &DynamicStabilityReport, output: &Path) -> Result<(), WriteError> {
    let s = &r.stability;
    let tracks = shown(r);
    let (mut f, mut z) = (Vec::new(), Vec::new());
    for t in &tracks {
        f.extend(t.frequencies_hz().into_iter().filter(|x| x.is_finite()));
        z.extend(t.damping_ratios().into_iter().filter(|x| x.is_finite()));
    }
    let range = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    };
    let (z0, z1) = percentile_range(&z);
    let (f0, f1) = range(&f);
    let frequencies = padded(f0, f1, 0.08);
    let mut fig = Figure::new(
        1000,
        700,
        padded(z0.min(0.0), z1.max(0.0), 0.08),
        frequencies,
        &format!(
            "dynamic stability: {} modes along {} states (damping axis: 1st-99th percentile)",
            tracks.len(),
            s.times.len()
        ),
        "damping ratio, unstable below 0 (1)",
        "frequency (Hz)",
    )
    .colour_bar(
        "time (s)",
        (s.times[0], *s.times.last().unwrap_or(&s.times[0])),
    );
    fig.vline(0.0, RED, Some("stability boundary"));
    for t in &tracks {
        let (fr, zr) = (t.frequencies_hz(), t.damping_ratios());
        let points: Vec<(f64, f64)> = zr[1..]
            .iter()
            .copied()
            .zip(fr[1..].iter().copied())
            .collect();
        fig.valued(points, s.times.clone(), 3);
    }
    // The nominal modes and their names over every track's points.
    for (k, t) in tracks.iter().enumerate() {
        let (fr, zr) = (t.frequencies_hz(), t.damping_ratios());
        fig.marker(zr[0], fr[0], BLACK, 5);
        fig.label(zr[0], fr[0], &t.name, BLACK, k % 2 == 1);
    }
    fig.legend(0, "nominal mode at the static state", BLACK);
    save(&fig, output, "dynamic_stability.png")
}

/// Frequency and damping ratio of the tracked modes against time, the braking torque
/// underneath (three panels on one time axis).
fn plot_stability_in_time(r: &DynamicStabilityReport, output: &Path) -> Result<(), WriteError> {
    let s = &r.stability;
    let tracks = shown(r);
    let (t0, t1) = (s.times[0], *s.times.last().unwrap_or(&s.times[0]));
    let x = padded(t0, t1, 0.0);
    let finite = |v: Vec<f64>| v.into_iter().filter(|x| x.is_finite()).collect::<Vec<_>>();
    let span = |v: &[f64]| {
        v.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    };
    let mut panels = Vec::new();
    for (title, label, pick) in [
        (
            "tracked modes along the run: frequency",
            "frequency (Hz)",
            0usize,
        ),
        (
            "damping ratio (< 0: unstable; axis: 1st-99th percentile)",
            "damping ratio (1)",
            1,
        ),
    ] {
        let values = |t: &TrackedMode| {
            let v = if pick == 0 {
                t.frequencies_hz()
            } else {
                t.damping_ratios()
            };
            v[1..].to_vec()
        };
        let all: Vec<f64> = tracks.iter().flat_map(|t| finite(values(t))).collect();
        let (lo, hi) = if pick == 0 {
            span(&all)
        } else {
            percentile_range(&all)
        };
        let mut fig = Figure::new(1200, 330, x, padded(lo, hi, 0.08), title, "time (s)", label);
        if pick == 1 {
            fig.hline(0.0, RED);
        }
        for (k, t) in tracks.iter().enumerate() {
            let c = PALETTE[k % PALETTE.len()];
            let points: Vec<(f64, f64)> = s.times.iter().copied().zip(values(t)).collect();
            fig.series(&points, c, &t.name);
            fig.markers(points, c, 2);
        }
        panels.push(fig);
    }
    let (lo, hi) = span(&s.torque);
    let mut torque = Figure::new(
        1200,
        260,
        x,
        padded(lo, hi, 0.08),
        "braking torque",
        "time (s)",
        "torque (N m)",
    );
    let points: Vec<(f64, f64)> = s
        .times
        .iter()
        .copied()
        .zip(s.torque.iter().copied())
        .collect();
    torque.line(&points, BLUE);
    torque.markers(points, GREY, 2);
    panels.push(torque);
    let path = output.join("dynamic_stability_time.png");
    Figure::save_column(&panels.iter().collect::<Vec<_>>(), &path)
        .map_err(|source| WriteError::Io { path, source })
}

/// The tracks the plots show: the headline ones (unstable at rest or on average), at most as
/// many as the palette has colours.
fn shown(r: &DynamicStabilityReport) -> Vec<&TrackedMode> {
    r.stability
        .tracks
        .iter()
        .filter(|t| t.headline(r.margin))
        .take(PALETTE.len())
        .collect()
}

fn write_contact_cycle(file: &ResultsFile, r: &ContactCycleReport) -> Result<(), WriteError> {
    let g = "post/contact_cycle";
    let c = &r.cycle;
    file.write_table(&format!("{g}/time"), &c.times, "s")?;
    file.set_number(g, "period_s", c.period)?;
    let phase_major = "phase-major: every contact point (point-id order, as /static/contact) at the first phase, then the next";
    for (name, field, units) in [
        ("pressure", &c.pressure, "Pa"),
        ("contact_stiffness", &c.stiffness, "Pa/m"),
        ("status", &c.status, "0 open, 1 stick, 2 slip"),
    ] {
        let flat: Vec<f64> = field.iter().flatten().copied().collect();
        file.write_table(
            &format!("{g}/{name}"),
            &flat,
            &format!("{units}; {phase_major}"),
        )?;
        if name == "status" {
            continue;
        }
        let [lo, hi, variation] = ContactCycle::spread(field);
        file.write_table(&format!("{g}/{name}_min"), &lo, units)?;
        file.write_table(&format!("{g}/{name}_max"), &hi, units)?;
        file.write_table(
            &format!("{g}/{name}_variation"),
            &variation,
            "(max - min) / max over the phases",
        )?;
    }
    for p in &c.pads {
        let pad = format!("{g}/pads/{}", p.name);
        file.write_table(
            &format!("{pad}/largest_stiffness"),
            &p.largest_stiffness,
            "Pa/m, per phase",
        )?;
        file.set_number(&pad, "largest_stiffness_variation", p.variation)?;
        for (k, what) in ["open", "stick", "slip"].iter().enumerate() {
            file.set_number(&pad, &format!("{what}_fraction"), p.fractions[k])?;
        }
    }
    Ok(())
}

/// contact_cycle_<pad>.png: the contact stiffness at the phases where the pad's largest
/// stiffness is highest and lowest (one colour scale), and its variation over the cycle.
fn plot_contact_cycle(
    r: &ContactCycleReport,
    pad: &PadCycle,
    maps: MapContext,
    output: &Path,
) -> Result<(), WriteError> {
    let c = &r.cycle;
    let (hi, lo) = pad.extreme_phases;
    let [_, max, variation] = ContactCycle::spread(&c.stiffness);
    let Some(map) = plane_map(maps, pad.interface) else {
        return Ok(());
    };
    let top = map.cells.iter().map(|&(_, j)| max[j]).fold(0.0, nan_max);
    let stiffness = "contact stiffness (Pa/m)";
    let panels = [
        map_figure(
            &map,
            &c.stiffness[hi],
            (620, 560),
            &format!("{}: stiffest phase, t = {:.5} s", pad.name, c.times[hi]),
            stiffness,
            (0.0, top),
        ),
        map_figure(
            &map,
            &c.stiffness[lo],
            (620, 560),
            &format!("softest phase, t = {:.5} s", c.times[lo]),
            stiffness,
            (0.0, top),
        ),
        map_figure(
            &map,
            &variation,
            (620, 560),
            &format!(
                "variation over the {:.3} ms period (largest: {:.0} %)",
                1e3 * c.period,
                100.0 * pad.variation
            ),
            "(max - min) / max (1)",
            (0.0, 1.0),
        ),
    ];
    let path = output.join(format!("contact_cycle_{}.png", pad.name));
    Figure::save_row(&panels.iter().collect::<Vec<_>>(), &path)
        .map_err(|source| WriteError::Io { path, source })
}

/// The XDMF fields of the tracked modes' shapes (real and imaginary parts).
pub fn tracked_shape_fields(link: &Link) -> Vec<crate::io::xdmf::NodalField> {
    let Some(r) = &link.dynamic_stability else {
        return Vec::new();
    };
    r.shapes
        .iter()
        .flat_map(|s| {
            ["re", "im"].map(|part| {
                let label = format!("{} {part}", s.label);
                crate::io::xdmf::NodalField::vector(&label, &format!("{}_{part}", s.dataset))
            })
        })
        .collect()
}

/// The 1st to 99th percentile of the damping ratios, widened to hold 0: the moments a mode is
/// overdamped (zeta up to 1) would otherwise squeeze the rest against the stability boundary.
fn percentile_range(values: &[f64]) -> (f64, f64) {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (-1.0, 1.0);
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    (at(0.01).min(0.0), at(0.99).max(0.0))
}
