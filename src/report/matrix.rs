//! Writer of the noise matrix: /matrix in results.h5, matrix.csv (one row per point) and
//! matrix-modes.csv (one row per point and mode), the noise-dynamometer chart (squealing
//! points per 1/3-octave band), the squeal-propensity maps (frequency against each axis,
//! unstable modes coloured by Re(s)), the summary's lines and the report's section.

use std::fmt::Write as _;
use std::path::Path;

use super::WriteError;
use crate::io::figure::{padded, Figure, BLACK, BLUE, GREY};
use crate::io::results::ResultsFile;
use crate::matrix::analysis::{analyse, MatrixAnalysis};
use crate::matrix::point::Outcome;
use crate::measure::{greatest, largest, smallest};
use crate::stages::matrix::MatrixOutput;

/// A matrix run (or merge) with its statistics.
#[derive(Debug, Clone)]
pub struct MatrixReport {
    pub run: MatrixOutput,
    pub analysis: MatrixAnalysis,
}

impl MatrixReport {
    pub fn of(run: MatrixOutput) -> Self {
        let analysis = analyse(&run.points, &run.axes, run.sampling, run.margin);
        MatrixReport { run, analysis }
    }

    /// "pressure_bar = 12.5, mu = 0.41".
    fn describe(&self, values: &[f64]) -> String {
        let parts: Vec<String> = self
            .run
            .axes
            .iter()
            .zip(values)
            .map(|(a, v)| format!("{} = {}", a.name(), number(*v)))
            .collect();
        parts.join(", ")
    }

    /// The answer line: how much of the matrix squeals, where in frequency, where in the
    /// operating range, and what drives it.
    pub fn answer_line(&self) -> String {
        let a = &self.analysis;
        let mut line = format!(
            "noise matrix: {} of {} operating points squeal ({:.1} %)",
            a.squealing,
            a.solved,
            percent(a.squealing, a.solved)
        );
        if let Some(b) = a.most_frequent_band() {
            let _ = write!(
                line,
                "; most often in the {} Hz band ({} points",
                number(b.nominal),
                b.points
            );
            let inside: Vec<_> = a
                .modes
                .iter()
                .filter(|m| b.lower <= m.mean_frequency_hz && m.mean_frequency_hz < b.upper)
                .collect();
            if let Some(m) = inside.first() {
                let _ = write!(line, ", {} at {}", m.name, m.points);
            }
            line.push(')');
        }
        if let Some(r) = &a.worst_region {
            let cell = bounds_text(r);
            let _ = write!(
                line,
                "; worst region {} ({} of {} points)",
                cell.join(" x "),
                r.squealing,
                r.points
            );
        }
        if let Some((axis, s)) = a.driver() {
            let _ = write!(
                line,
                "; driven by {} (first-order index {s:.2} of the largest Re(s))",
                axis.name()
            );
        }
        if let Some((level, p, m)) = super::matrix_saturation::loudest(&self.run) {
            let name = m
                .label
                .map_or("an unpaired mode".to_string(), |l| format!("C{l}"));
            let _ = write!(
                line,
                "; loudest predicted {level:.1} dB(A) at point {} ({name} at {:.0} Hz, alpha_sat {:.2e} m)",
                p.index + 1,
                m.frequency_hz,
                m.alpha_sat.unwrap_or(f64::NAN)
            );
        }
        if a.failed > 0 {
            let _ = write!(line, "; {} points failed", a.failed);
        }
        line
    }

    /// The summary's lines.
    pub fn text(&self) -> String {
        let (r, a) = (&self.run, &self.analysis);
        let mut t = String::new();
        let ranges: Vec<String> = r
            .axes
            .iter()
            .enumerate()
            .map(|(d, x)| {
                let v = r.points.iter().map(|p| p.values[d]);
                let lo = smallest(v.clone());
                let hi = greatest(v);
                format!("{} {}-{}", x.name(), number(lo), number(hi))
            })
            .collect();
        let _ = writeln!(
            t,
            "noise matrix: {} of {} points ({:?}, slice {}, {} from the journal) over {}",
            r.points.len(),
            r.total,
            r.sampling,
            r.slice,
            r.resumed,
            ranges.join(", ")
        );
        let _ = writeln!(
            t,
            "  solved {}, failed {}; squealing {} ({:.1} % of those solved; unstable: damping ratio < -{:.0e})",
            a.solved,
            a.failed,
            a.squealing,
            percent(a.squealing, a.solved),
            r.margin
        );
        let solved: Vec<_> = r.points.iter().filter_map(|p| p.solved()).collect();
        if !solved.is_empty() {
            let n = solved.len() as f64;
            let mean = |f: &dyn Fn(&crate::matrix::point::SolvedPoint) -> f64| {
                solved.iter().map(|s| f(s)).sum::<f64>() / n
            };
            let _ = writeln!(
                t,
                "  per point: statics {:.3} s ({:.1} Newton iterations, {:.1} LU factorizations taking {:.3} s, {:.1} solves with them taking {:.3} s), complex modes {:.3} s; {} cold restarts",
                mean(&|s| s.seconds_statics),
                mean(&|s| s.newton_iterations as f64),
                mean(&|s| s.factorizations as f64),
                mean(&|s| s.seconds_factorizing),
                mean(&|s| s.factor_solves as f64),
                mean(&|s| s.seconds_solving),
                mean(&|s| s.seconds_modes),
                solved.iter().filter(|s| s.cold_restart).count()
            );
        }
        let failed: Vec<f64> = r
            .points
            .iter()
            .filter_map(|p| match p.outcome {
                Outcome::Failed { seconds, .. } => Some(seconds),
                Outcome::Solved(_) => None,
            })
            .collect();
        if !failed.is_empty() {
            let _ = writeln!(
                t,
                "  per failed point: {:.3} s",
                failed.iter().sum::<f64>() / failed.len() as f64
            );
        }
        if let Some(e) = crate::matrix::check::reduced_error(&r.points, r.margin) {
            let _ = writeln!(t, "  {}", reduced_error_text(&e));
        }
        if let Some(line) = super::matrix_saturation::text(r) {
            let _ = writeln!(t, "  {line}");
        }
        let mut bands = a.bands.clone();
        bands.sort_by_key(|b| std::cmp::Reverse(b.points));
        let list: Vec<String> = bands
            .iter()
            .take(6)
            .map(|b| format!("{} Hz ({})", number(b.nominal), b.points))
            .collect();
        if !list.is_empty() {
            let _ = writeln!(
                t,
                "  squealing points per 1/3-octave band: {}",
                list.join(", ")
            );
        }
        let list: Vec<String> = a
            .modes
            .iter()
            .take(6)
            .map(|m| {
                format!(
                    "{} {:.0} Hz at {} (Re(s) up to {:.1} 1/s)",
                    m.name, m.mean_frequency_hz, m.points, m.largest_real_part
                )
            })
            .collect();
        if !list.is_empty() {
            let _ = writeln!(t, "  modes unstable most often: {}", list.join(", "));
        }
        let list: Vec<String> = a
            .sensitivity
            .iter()
            .map(|(x, s)| format!("{} {s:.2}", x.name()))
            .collect();
        let _ = writeln!(
            t,
            "  first-order sensitivity index of the largest Re(s): {}",
            list.join(", ")
        );
        if let Some(w) = &a.worst_region {
            let cell = bounds_text(w);
            let _ = writeln!(t, "  worst region (thirds of the most influential ranges): {}: {} of {} points squeal", cell.join(", "), w.squealing, w.points);
        }
        for p in &r.points {
            if let Outcome::Failed { reason, .. } = &p.outcome {
                let _ = writeln!(
                    t,
                    "  failed: point {} ({}): {reason}",
                    p.index + 1,
                    self.describe(&p.values)
                );
            }
        }
        t
    }
}

/// The reduced statics against the full model at the checked points, in one line.
fn reduced_error_text(e: &crate::matrix::check::ReducedError) -> String {
    let mut line = format!(
        "static state on the superelement vs the full model at {} points: displacement within {:.1e} (relative), braking torque {:.1e}, normal force {:.1e}; largest Re(s) within {:.2} 1/s (of up to {:.1}); frequencies of the unstable modes within {:.2e}; the same modes unstable at {} of {}",
        e.checked - e.failed,
        e.displacement,
        e.torque,
        e.normal_force,
        e.largest_real_part,
        e.real_part_scale,
        e.frequency,
        e.same_unstable,
        e.checked - e.failed
    );
    if e.failed > 0 {
        let _ = write!(line, "; the full solve failed at {}", e.failed);
    }
    line
}

/// "pressure_bar 5-16.667" per axis of a region.
fn bounds_text(r: &crate::matrix::analysis::Region) -> Vec<String> {
    r.bounds
        .iter()
        .map(|(x, lo, hi)| format!("{} {}-{}", x.name(), number(*lo), number(*hi)))
        .collect()
}

fn percent(part: usize, whole: usize) -> f64 {
    100.0 * part as f64 / whole.max(1) as f64
}

/// A parameter value in few characters (bar, rad/s, mu, Pa, 1/m, deg C alike).
fn number(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-2) {
        format!("{v:.3e}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Writes /matrix, and on rank 0 the CSVs and the figures.
///
/// # Collective
pub fn write_matrix(
    rank: i32,
    file: &ResultsFile,
    r: &MatrixReport,
    output: &Path,
) -> Result<(), WriteError> {
    let run = &r.run;
    let g = "matrix";
    let names: Vec<&str> = run.axes.iter().map(|a| a.name()).collect();
    file.set_text(g, "axes", &names.join(", "))?;
    file.set_text(g, "sampling", &format!("{:?}", run.sampling))?;
    file.set_text(g, "slice", &run.slice.to_string())?;
    file.set_number(g, "total_points", run.total as f64)?;
    file.set_number(g, "instability_margin", run.margin)?;
    let column = |f: &dyn Fn(&crate::matrix::point::PointResult) -> f64| -> Vec<f64> {
        run.points.iter().map(f).collect()
    };
    file.write_table(
        &format!("{g}/points/index"),
        &column(&|p| p.index as f64),
        "1",
    )?;
    for (d, a) in run.axes.iter().enumerate() {
        let unit = match a {
            crate::matrix::Axis::PressureBar => "bar",
            crate::matrix::Axis::DiscSpeed => "rad/s",
            crate::matrix::Axis::Mu => "1",
            crate::matrix::Axis::P0 => "Pa",
            crate::matrix::Axis::Lambda => "1/m",
            crate::matrix::Axis::Temperature => "degC",
            crate::matrix::Axis::LiningModulus => "1 (x the scene's lining)",
        };
        file.write_table(
            &format!("{g}/points/{}", a.name()),
            &column(&|p| p.values[d]),
            unit,
        )?;
    }
    file.write_table(
        &format!("{g}/points/solved"),
        &column(&|p| f64::from(u8::from(p.solved().is_some()))),
        "1",
    )?;
    file.write_table(
        &format!("{g}/points/largest_real_part"),
        &column(&|p| p.largest_real_part()),
        "1/s",
    )?;
    let margin = run.margin;
    file.write_table(
        &format!("{g}/points/unstable_modes"),
        &column(&|p| p.unstable(margin).count() as f64),
        "1",
    )?;
    let modes: Vec<(usize, &crate::matrix::point::PointMode)> = run
        .points
        .iter()
        .flat_map(|p| {
            p.solved()
                .into_iter()
                .flat_map(move |s| s.modes.iter().map(move |m| (p.index, m)))
        })
        .collect();
    let mode_column = |f: &dyn Fn(usize, &crate::matrix::point::PointMode) -> f64| -> Vec<f64> {
        modes.iter().map(|&(i, m)| f(i, m)).collect()
    };
    let m = format!("{g}/modes");
    file.write_table(&format!("{m}/point"), &mode_column(&|i, _| i as f64), "1")?;
    file.write_table(
        &format!("{m}/label"),
        &mode_column(&|_, m| m.label.map_or(0.0, |l| l as f64)),
        "1 (C<label>; 0: unpaired)",
    )?;
    file.write_table(
        &format!("{m}/frequency"),
        &mode_column(&|_, m| m.frequency_hz()),
        "Hz",
    )?;
    file.write_table(&format!("{m}/real_part"), &mode_column(&|_, m| m.re), "1/s")?;
    file.write_table(
        &format!("{m}/damping_ratio"),
        &mode_column(&|_, m| m.damping_ratio()),
        "1",
    )?;
    file.write_table(&format!("{m}/mac"), &mode_column(&|_, m| m.mac), "1")?;
    write_full_checks(file, run)?;
    super::matrix_saturation::write_h5(file, run)?;
    if rank == 0 {
        write_files(r, output)?;
    }
    Ok(())
}

/// /matrix/full_checks: the points of a reduced-statics matrix also solved on the full model,
/// with both routes' braking torque and largest Re(s).
fn write_full_checks(file: &ResultsFile, run: &MatrixOutput) -> Result<(), WriteError> {
    let checked: Vec<_> = run
        .points
        .iter()
        .filter_map(|p| {
            p.solved()
                .and_then(|s| s.full_check.as_ref().map(|c| (p, s, c)))
        })
        .collect();
    if checked.is_empty() {
        return Ok(());
    }
    let g = "matrix/full_checks";
    let column = |f: &dyn Fn(
        &crate::matrix::point::PointResult,
        &crate::matrix::point::SolvedPoint,
        &crate::matrix::point::FullCheck,
    ) -> f64|
     -> Vec<f64> { checked.iter().map(|&(p, s, c)| f(p, s, c)).collect() };
    file.write_table(
        &format!("{g}/point"),
        &column(&|p, _, _| p.index as f64),
        "1",
    )?;
    file.write_table(
        &format!("{g}/displacement_error"),
        &column(&|_, _, c| c.displacement_error),
        "1 (|T q_r - q| / |q|)",
    )?;
    file.write_table(
        &format!("{g}/braking_torque_reduced"),
        &column(&|_, s, _| s.braking_torque),
        "N m",
    )?;
    file.write_table(
        &format!("{g}/braking_torque_full"),
        &column(&|_, _, c| c.braking_torque),
        "N m",
    )?;
    file.write_table(
        &format!("{g}/largest_real_part_reduced"),
        &column(&|p, _, _| p.largest_real_part()),
        "1/s",
    )?;
    file.write_table(
        &format!("{g}/largest_real_part_full"),
        &column(&|_, _, c| c.largest_real_part()),
        "1/s",
    )?;
    file.write_table(
        &format!("{g}/seconds_full"),
        &column(&|_, _, c| c.seconds),
        "s",
    )?;
    Ok(())
}

/// The CSVs and figures (no MPI: `squeal merge` calls it too).
pub fn write_files(r: &MatrixReport, output: &Path) -> Result<(), WriteError> {
    write_csv(r, output)?;
    if let Some(text) = super::matrix_saturation::csv(&r.run) {
        write_text(&output.join("matrix-saturation.csv"), &text)?;
    }
    super::matrix_saturation::plot_levels(&r.run, output)?;
    plot_bands(r, output)?;
    for d in 0..r.run.axes.len() {
        plot_propensity(r, d, output)?;
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<(), WriteError> {
    std::fs::write(path, text).map_err(|source| WriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn write_csv(r: &MatrixReport, output: &Path) -> Result<(), WriteError> {
    let run = &r.run;
    let names: Vec<&str> = run.axes.iter().map(|a| a.name()).collect();
    let mut points = format!(
        "point,{},status,braking_torque_nm,unstable_modes,largest_re_s,most_unstable,most_unstable_hz,reason,full_displacement_error,full_braking_torque_nm,full_largest_re_s\n",
        names.join(",")
    );
    let mut modes = format!(
        "point,{},mode,frequency_hz,damping_ratio,re_s,im_s,mac\n",
        names.join(",")
    );
    for p in &run.points {
        let values: Vec<String> = p.values.iter().map(|v| format!("{v:.10e}")).collect();
        let values = values.join(",");
        match &p.outcome {
            Outcome::Solved(s) => {
                let worst = p.unstable(run.margin).max_by(|a, b| a.re.total_cmp(&b.re));
                // With reduced statics, where the point was also solved on the full model.
                let check = s.full_check.as_ref().map_or(",,".to_string(), |c| {
                    format!(
                        "{:.6e},{:.10e},{:.10e}",
                        c.displacement_error,
                        c.braking_torque,
                        c.largest_real_part()
                    )
                });
                let _ = writeln!(
                    points,
                    "{},{values},solved,{:.10e},{},{:.10e},{},{},,{check}",
                    p.index + 1,
                    s.braking_torque,
                    p.unstable(run.margin).count(),
                    p.largest_real_part(),
                    worst.map_or(String::new(), |m| m.name()),
                    worst.map_or(String::new(), |m| format!("{:.6e}", m.frequency_hz())),
                );
                for m in &s.modes {
                    let _ = writeln!(
                        modes,
                        "{},{values},{},{:.10e},{:.10e},{:.10e},{:.10e},{:.6}",
                        p.index + 1,
                        m.name(),
                        m.frequency_hz(),
                        m.damping_ratio(),
                        m.re,
                        m.im,
                        m.mac
                    );
                }
            }
            Outcome::Failed { reason, .. } => {
                let _ = writeln!(
                    points,
                    "{},{values},failed,,,,,,\"{}\",,,",
                    p.index + 1,
                    reason.replace('"', "'")
                );
            }
        }
    }
    write_text(&output.join("matrix.csv"), &points)?;
    write_text(&output.join("matrix-modes.csv"), &modes)
}

fn save(fig: &Figure, output: &Path, name: &str) -> Result<(), WriteError> {
    let path = output.join(name);
    fig.save(&path)
        .map_err(|source| WriteError::Io { path, source })
}

/// A bar of height `n` over [lo, hi] (a tenth inset on each side), its count above it.
pub(super) fn bar(fig: &mut Figure, (lo, hi): (f64, f64), n: usize) {
    let (inset, h) = (0.1 * (hi - lo), n as f64);
    let outline = [
        (lo + inset, 0.0),
        (lo + inset, h),
        (hi - inset, h),
        (hi - inset, 0.0),
    ];
    fig.line(&outline, BLUE);
    fig.label_centred(0.5 * (lo + hi), h, &n.to_string(), BLACK);
}

/// matrix_bands.png: squealing points per 1/3-octave band, as bars on a log frequency axis.
fn plot_bands(r: &MatrixReport, output: &Path) -> Result<(), WriteError> {
    let a = &r.analysis;
    let top = a.bands.iter().map(|b| b.points).max().unwrap_or(0).max(1) as f64;
    let title = format!(
        "noise matrix: squealing points per 1/3-octave band ({} of {} points squeal)",
        a.squealing, a.solved
    );
    let mut fig = Figure::new(
        1000,
        520,
        (100f64.log10(), 20000f64.log10()),
        (0.0, top * 1.12),
        &title,
        "band centre frequency (Hz)",
        "points with an unstable mode in the band",
    )
    .log_x();
    for b in &a.bands {
        bar(&mut fig, (b.lower.log10(), b.upper.log10()), b.points);
    }
    save(&fig, output, "matrix_bands.png")
}

/// Stable modes are drawn (grey) only up to this many markers: beyond, the picture is a grey
/// band and its SVG megabytes.
const MAX_STABLE_MARKERS: usize = 20_000;

/// matrix_<axis>.png: the squeal-propensity map of one axis: every unstable mode's frequency
/// against the axis' value, coloured by Re(s); stable modes grey when few enough.
fn plot_propensity(r: &MatrixReport, d: usize, output: &Path) -> Result<(), WriteError> {
    let run = &r.run;
    let axis = run.axes[d];
    let solved = || run.points.iter().filter_map(|p| p.solved().map(|s| (p, s)));
    let f_top = largest(solved().flat_map(|(_, s)| s.modes.iter().map(|m| m.frequency_hz())));
    let x = run.points.iter().map(|p| p.values[d]);
    let (lo, hi) = (smallest(x.clone()), greatest(x));
    let unstable: Vec<(f64, f64, f64)> = solved()
        .flat_map(|(p, _)| {
            p.unstable(run.margin)
                .map(move |m| (p.values[d], m.frequency_hz(), m.re))
        })
        .collect();
    let re_max = largest(unstable.iter().map(|u| u.2));
    let title = format!(
        "squeal propensity against {}: unstable modes coloured by Re(s)",
        axis.name()
    );
    let mut fig = Figure::new(
        1000,
        560,
        padded(lo, hi, 0.04),
        (0.0, f_top.max(1.0) * 1.03),
        &title,
        axis.label(),
        "frequency (Hz)",
    )
    .colour_bar("Re(s) (1/s)", (0.0, re_max.max(1e-9)));
    let stable: Vec<(f64, f64)> = solved()
        .flat_map(|(p, s)| {
            s.modes
                .iter()
                .filter(move |m| m.damping_ratio() >= -run.margin)
                .map(move |m| (p.values[d], m.frequency_hz()))
        })
        .collect();
    if stable.len() <= MAX_STABLE_MARKERS {
        fig.markers(stable, GREY, 1);
    }
    let (points, values): (Vec<(f64, f64)>, Vec<f64>) =
        unstable.into_iter().map(|(x, f, re)| ((x, f), re)).unzip();
    fig.valued(points, values, 3);
    save(&fig, output, &format!("matrix_{}.png", axis.name()))
}

/// The report's "Noise matrix" section body.
pub fn html_section(r: &MatrixReport, output: &Path) -> std::io::Result<String> {
    use crate::report::html::{escape, figure};
    let caption =
        "Noise-dynamometer chart: operating points with an unstable mode, per 1/3-octave band.";
    let mut body = figure(output, "matrix_bands.png", caption)?;
    if output.join("matrix_levels.png").exists() {
        let caption = "Squealing points per class of their loudest predicted sound power level: each point's most unstable modes followed along their pseudo trajectories to alpha_sat (matrix.saturation_modes).";
        body += &figure(output, "matrix_levels.png", caption)?;
    }
    for a in &r.run.axes {
        let caption = format!("Squeal propensity against {}: frequencies of the unstable modes (coloured by Re(s)) over the points; stable modes grey when there are at most 20,000.", a.label());
        body += &figure(output, &format!("matrix_{}.png", a.name()), &caption)?;
    }
    body += &format!("<pre>{}</pre>", escape(&r.text()));
    body += "<p>Every point: <code>matrix.csv</code>; every point's modes: <code>matrix-modes.csv</code>; both in <code>/matrix</code> of results.h5.</p>";
    if output.join("matrix-saturation.csv").exists() {
        body += "<p>The followed modes' alpha_crit, alpha_sat and levels: <code>matrix-saturation.csv</code>, <code>/matrix/saturation</code>.</p>";
    }
    Ok(body)
}

/// A report of the matrix alone (`squeal merge`): the answer, the matrix section, the scene.
pub fn write_standalone_report(
    r: &MatrixReport,
    scene_text: &str,
    output: &Path,
) -> std::io::Result<std::path::PathBuf> {
    use crate::report::html::{escape, page};
    let sections = vec![
        (
            "answer",
            "The answer".to_string(),
            format!(
                "<ul class=\"answer\"><li>{}</li></ul>",
                escape(&r.answer_line())
            ),
        ),
        (
            "noise-matrix",
            "Noise matrix: squeal over the operating range".to_string(),
            html_section(r, output)?,
        ),
        (
            "scene",
            "Scene".to_string(),
            format!("<pre>{}</pre>", escape(scene_text)),
        ),
    ];
    let intro = format!(
        "Merged noise matrix: {} of {} points; results in <code>{}</code>.",
        r.run.points.len(),
        r.run.total,
        escape(&output.display().to_string())
    );
    let path = output.join("report.html");
    std::fs::write(&path, page(output, &intro, &sections))?;
    Ok(path)
}
