//! The noise matrix (DESIGN.md §1 sweeps, issue "virtual noise dynamometer").
//!
//! - A matrix point is the scene run at that point's parameters: its static state (braking
//!   torque, normal force) equals the one a separate run of the scene with those parameters
//!   finds from the unloaded state, within what the static tolerance allows (1e-9 of the
//!   force residual; asserted 1e-6 relative in torque and force, a bound on the state's
//!   error for a contact tangent of condition <= 1e3 relative to the load); at the scene's own
//!   parameters its complex modes are the projected complex-modes stage's (same basis, same
//!   state: 1e-7 relative in s, as the sweep's nominal point) and each carries its own label.
//!   The other points' modes are compared with nothing independent here: the projected route
//!   is verified against the full one and the dense reference elsewhere in the suite.
//! - Slices merged (`--slice 1/2`, `2/2`, `squeal merge`) hold the same points as the
//!   unsliced run (parameters bit for bit, results to the static tolerance: the warm starts
//!   differ); a killed run resumed with `--restart` computes only the points its journal lacks
//!   and ends with the same results; a journal of another scene, or one that holds points
//!   without `--restart`, is refused with an error naming the file.
//! - 1 and 2 ranks agree (the points' torques and eigenvalues, to the static tolerance).
//! - A lining_modulus factor e is the scene with the lining's elastic constants times e: K0 +
//!   (e - 1) K_l is exactly the stiffness assembled from the scaled material (the element
//!   stiffness is linear in the constants, also the Hex8i's condensed one), so the static
//!   state at e = 0.8 equals a separate run of the scene with the scaled orthotropic lining
//!   (same bound as above, 1e-6).
//! - Reduced statics (`statics = "reduced"`, every point checked on the full model): at the
//!   nominal point the full static state lies in the superelement's span (the static shape is
//!   in its basis), so the superelement's Galerkin solution is it: 1e-6 as above. Elsewhere the
//!   basis holds the first-order change of the static state with each varied parameter, so
//!   the error is second order in the parameter's distance from the nominal value: halving
//!   the distance must divide it by at least 2^1.5 (rate >= 1.5; measured 1.9 in pressure, 2.2
//!   in lining stiffness on this brake), for pressure and lining stiffness alike.
//! - Saturated modes (`saturation_modes = 1`): at the scene's own parameters the point's most
//!   unstable mode, followed along its pseudo trajectory, is the one the pseudo-trajectory
//!   stage follows at the nominal state (same label), with the same alpha_sat and alpha_crit
//!   within the bisections' tolerance (1 % by default: both bisect the same bracket on states
//!   equal to the static tolerance) and the loudness stage's level at alpha_sat within
//!   20 log10(1.01) = 0.09 dB of it (asserted 0.1 dB). Route against route, not against a
//!   reference: the pseudo trajectory itself is verified on the 2-DOF model elsewhere.

use super::TestResult;
use std::path::{Path, PathBuf};

use squeal::io::matrix_journal::{self, JOURNAL};
use squeal::la::Petsc;
use squeal::matrix::point::PointResult;
use squeal::matrix::sample::Slice;
use squeal::measure::{exceeds, nan_max};
use squeal::pipeline::{RunOptions, RunSummary};

use super::common::{one_rank_values, rel, say, suite_dir};

pub fn tests() -> Vec<super::NamedTest> {
    vec![
        (
            "noise_matrix_points_equal_single_scene_runs_and_the_nominal_modes",
            points_equal_single_runs,
        ),
        (
            "noise_matrix_slices_merge_to_the_whole_and_a_killed_run_resumes",
            slices_and_resume,
        ),
        (
            "noise_matrix_lining_modulus_is_the_scaled_material_and_superelement_statics_converge_quadratically",
            lining_and_superelement,
        ),
        (
            "noise_matrix_saturation_at_the_nominal_point_is_the_pseudo_trajectory_and_loudness_stages",
            saturation_at_the_nominal_point,
        ),
    ]
}

/// The small brake with a 30-mode basis.
fn brake(pressure_bar: f64, mu: f64) -> String {
    format!(
        "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = {pressure_bar:?}\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = {mu:?}, slip_speed = 1.0e-2 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = 30\n\
         [complex_modes]\nmethod = \"projected\"\n"
    )
}

fn run(petsc: &Petsc, text: &str, name: &str, options: &RunOptions) -> TestResult<RunSummary> {
    let scene = squeal::scene::Scene::parse(text, name)?;
    let out = suite_dir().join(name);
    Ok(squeal::pipeline::run_with(
        petsc,
        &scene,
        text,
        Path::new("."),
        &out,
        &[],
        options,
    )?)
}

/// A fresh output directory (a journal left by an earlier suite run would be refused).
fn fresh(petsc: &Petsc, name: &str) -> PathBuf {
    let dir = suite_dir().join(name);
    if petsc.rank() == 0 {
        let _ = std::fs::remove_dir_all(&dir);
    }
    squeal::parallel::barrier(petsc.world());
    dir
}

fn points(summary: &RunSummary) -> TestResult<Vec<PointResult>> {
    Ok(summary
        .matrix
        .as_ref()
        .ok_or("no matrix in the summary")?
        .run
        .points
        .clone())
}

/// Every point's figures on this many ranks against those stored by the 1-rank run: torque
/// and normal force relative, eigenvalues relative to |s| (a Re(s) near zero has no relative
/// accuracy of its own); bound 1e-6, the static tolerance's.
fn agrees_with_one_rank(petsc: &Petsc, name: &str, pts: &[PointResult]) -> TestResult {
    let per_point: Vec<Vec<f64>> = pts.iter().map(figures).collect::<Result<_, _>>()?;
    let all = per_point.concat();
    let Some(one) = one_rank_values(petsc, name, &all)? else {
        return Ok(());
    };
    if one.len() != all.len() {
        return Err(format!("{} figures on 1 rank, {} here", one.len(), all.len()).into());
    }
    let mut d = 0.0f64;
    let mut at = 0;
    for x in &per_point {
        let y = &one[at..at + x.len()];
        d = nan_max(d, nan_max(rel(x[0], y[0]), rel(x[1], y[1])));
        for k in (2..x.len()).step_by(2) {
            let scale = y[k].hypot(y[k + 1]);
            d = nan_max(d, (x[k] - y[k]).hypot(x[k + 1] - y[k + 1]) / scale);
        }
        at += x.len();
    }
    say(petsc, &format!("1 vs {} ranks: {d:.1e}", petsc.size()));
    if exceeds(d, 1e-6) {
        return Err(format!("1 vs {} ranks differ by {d:e}", petsc.size()).into());
    }
    Ok(())
}

/// Torque, normal force and every eigenvalue of a solved point, in order.
fn figures(p: &PointResult) -> TestResult<Vec<f64>> {
    let s = p
        .solved()
        .ok_or(format!("point {} failed: {:?}", p.index + 1, p.outcome))?;
    let mut v = vec![s.braking_torque, s.normal_force];
    v.extend(s.modes.iter().flat_map(|m| [m.re, m.im]));
    Ok(v)
}

/// Largest relative difference of two points' figures (eigenvalues relative to |s|).
fn difference(a: &PointResult, b: &PointResult) -> TestResult<f64> {
    let (x, y) = (figures(a)?, figures(b)?);
    if x.len() != y.len() {
        return Err(format!(
            "point {}: {} against {} figures",
            a.index + 1,
            x.len(),
            y.len()
        )
        .into());
    }
    let mut worst = nan_max(rel(x[0], y[0]), rel(x[1], y[1]));
    for k in (2..x.len()).step_by(2) {
        let scale = y[k].hypot(y[k + 1]);
        worst = nan_max(worst, (x[k] - y[k]).hypot(x[k + 1] - y[k + 1]) / scale);
    }
    Ok(worst)
}

fn points_equal_single_runs(petsc: &Petsc) -> TestResult {
    let matrix = "[matrix]\nsampling = \"grid\"\n[matrix.axes]\n\
                  pressure_bar = { values = [10.0, 20.0] }\nmu = { values = [0.3, 0.4] }\n";
    fresh(petsc, "matrix-grid");
    let summary = run(
        petsc,
        &(brake(20.0, 0.4) + matrix),
        "matrix-grid",
        &RunOptions::default(),
    )?;
    let pts = points(&summary)?;
    if pts.len() != 4 {
        return Err(format!("{} points, expected the 2 x 2 grid", pts.len()).into());
    }
    // The nominal point (20 bar, mu 0.4) is the last of the grid (the last axis fastest).
    let nominal = &summary
        .complex
        .first()
        .ok_or("no projected complex modes")?
        .modes;
    let at = pts[3].solved().ok_or("the nominal point failed")?;
    if pts[3].values != [20.0, 0.4] || at.modes.len() != nominal.len() {
        return Err(format!(
            "nominal point {:?} with {} modes, the stage has {}",
            pts[3].values,
            at.modes.len(),
            nominal.len()
        )
        .into());
    }
    let mut worst_mode = 0.0f64;
    for (k, (m, n)) in at.modes.iter().zip(nominal).enumerate() {
        let s = n.eigenvalue;
        worst_mode = nan_max(worst_mode, (m.re - s.0).hypot(m.im - s.1) / s.0.hypot(s.1));
        if m.label != Some(k + 1) || m.mac.is_nan() || m.mac <= 0.999 {
            return Err(format!(
                "nominal point: mode {} labelled {:?} with MAC {}",
                k + 1,
                m.label,
                m.mac
            )
            .into());
        }
    }
    // The other points against runs of the scene at their parameters (statics from zero).
    let mut worst_static = 0.0f64;
    for p in &pts[..3] {
        let (pressure, mu) = (p.values[0], p.values[1]);
        let name = format!("matrix-single-{pressure}-{mu}");
        let single = run(
            petsc,
            &brake(pressure, mu).replace(
                "[real_modes]\ncount = 30\n[complex_modes]\nmethod = \"projected\"\n",
                "",
            ),
            &name,
            &RunOptions::default(),
        )?;
        let st = single.statics.as_ref().ok_or("no static summary")?;
        let torque: f64 = st.interfaces.iter().map(|(_, i)| i.torque).sum();
        let normal: f64 = st.interfaces.iter().map(|(_, i)| i.normal_force).sum();
        let s = p.solved().ok_or(format!("point {:?} failed", p.values))?;
        worst_static = nan_max(
            worst_static,
            nan_max(rel(s.braking_torque, torque), rel(s.normal_force, normal)),
        );
        say(petsc, &format!("pressure {pressure} bar, mu {mu}: torque {:.6} N m (single run {torque:.6}), {} unstable modes", s.braking_torque, p.unstable(1e-4).count()));
    }
    say(petsc, &format!("nominal point's modes against the stage: {worst_mode:.1e}; static states against single runs: {worst_static:.1e}"));
    if exceeds(worst_mode, 1e-7) || exceeds(worst_static, 1e-6) {
        return Err(format!("nominal modes off by {worst_mode:e} (bound 1e-7), static states by {worst_static:e} (bound 1e-6)").into());
    }
    agrees_with_one_rank(petsc, "noise-matrix-grid", &pts)
}

fn slices_and_resume(petsc: &Petsc) -> TestResult {
    let matrix = "[matrix]\nsampling = \"sobol\"\npoints = 8\nseed = 5\n[matrix.axes]\n\
                  pressure_bar = { from = 10.0, to = 30.0 }\ndisc_speed = { from = 2.0, to = 12.0 }\n";
    let text = brake(20.0, 0.4) + matrix;
    let whole_dir = fresh(petsc, "matrix-whole");
    let whole = points(&run(petsc, &text, "matrix-whole", &RunOptions::default())?)?;
    let mut slice_dirs = Vec::new();
    for k in 1..=2 {
        let name = format!("matrix-slice-{k}");
        slice_dirs.push(fresh(petsc, &name));
        let options = RunOptions {
            slice: Slice { index: k, count: 2 },
            ..Default::default()
        };
        let part = points(&run(petsc, &text, &name, &options)?)?;
        let expected = Slice { index: k, count: 2 }.range(8);
        if part.iter().map(|p| p.index).collect::<Vec<_>>() != expected.clone().collect::<Vec<_>>()
        {
            return Err(format!(
                "slice {k}/2 computed {:?}",
                part.iter().map(|p| p.index).collect::<Vec<_>>()
            )
            .into());
        }
    }
    let merged_dir = fresh(petsc, "matrix-merged");
    let merged =
        squeal::pipeline::merge::merge(petsc.world(), &slice_dirs, &merged_dir, Slice::WHOLE)?;
    let worst_merge = compare(&whole, &merged.run.points)?;

    // A run killed after 3 points (its journal cut in the 4th line), resumed.
    let resumed_dir = fresh(petsc, "matrix-resumed");
    if petsc.rank() == 0 {
        std::fs::create_dir_all(&resumed_dir)?;
        let full = std::fs::read_to_string(whole_dir.join(JOURNAL))?;
        let lines: Vec<&str> = full.lines().collect();
        let cut = format!(
            "{}\n{}",
            lines[..4].join("\n"),
            &lines[4][..lines[4].len() / 2]
        );
        std::fs::write(resumed_dir.join(JOURNAL), cut)?;
    }
    squeal::parallel::barrier(petsc.world());
    let journal = matrix_journal::read(&resumed_dir.join(JOURNAL))?;
    let kept: Vec<usize> = journal.points.iter().map(|p| p.index).collect();
    let refused = run(petsc, &text, "matrix-resumed", &RunOptions::default());
    match refused {
        Err(e) if e.to_string().contains("--restart") && e.to_string().contains(JOURNAL) => {}
        other => {
            return Err(format!(
                "a journal with points, no --restart: {:?}",
                other.map(|_| "ran")
            )
            .into())
        }
    }
    let restart = RunOptions {
        restart: true,
        ..Default::default()
    };
    let summary = run(petsc, &text, "matrix-resumed", &restart)?;
    let report = summary.matrix.as_ref().ok_or("no matrix")?;
    if report.run.resumed != 3 || kept.len() != 3 || report.run.points.len() != 8 {
        return Err(format!(
            "resumed {} (journal kept {kept:?}), {} points in all",
            report.run.resumed,
            report.run.points.len()
        )
        .into());
    }
    // The resumed points are the journal's, bit for bit (timings aside: each rank measures
    // its own, the journal holds rank 0's).
    for p in report.run.points.iter().filter(|p| kept.contains(&p.index)) {
        let w = whole
            .iter()
            .find(|w| w.index == p.index)
            .ok_or("a resumed point not in the whole run")?;
        if figures(p)? != figures(w)? || p.values != w.values {
            return Err(format!("resumed point {} changed", p.index + 1).into());
        }
    }
    let worst_resume = compare(&whole, &report.run.points)?;
    let journal = matrix_journal::read(&resumed_dir.join(JOURNAL))?;
    if journal.points.len() != 8 || journal.truncated {
        return Err(format!(
            "the resumed journal holds {} points (cut: {})",
            journal.points.len(),
            journal.truncated
        )
        .into());
    }
    // Another scene (another seed) on this journal: refused, naming the file.
    let other = text.replace("seed = 5", "seed = 6");
    match run(petsc, &other, "matrix-resumed", &restart) {
        Err(e) if e.to_string().contains("another scene") && e.to_string().contains(JOURNAL) => {}
        other => {
            return Err(format!("restart with another scene: {:?}", other.map(|_| "ran")).into())
        }
    }
    say(
        petsc,
        &format!("merged slices vs whole: {worst_merge:.1e}; resumed vs whole: {worst_resume:.1e}"),
    );
    Ok(())
}

/// The same points (indices, parameters bit for bit, labels) with results within 1e-6
/// relative (torque, force, eigenvalues); returns the largest difference.
fn compare(whole: &[PointResult], other: &[PointResult]) -> TestResult<f64> {
    if whole.len() != other.len() {
        return Err(format!("{} points against {}", other.len(), whole.len()).into());
    }
    let mut worst = 0.0f64;
    for (a, b) in whole.iter().zip(other) {
        if a.index != b.index || a.values != b.values {
            return Err(format!(
                "point {} {:?} against {} {:?}",
                b.index + 1,
                b.values,
                a.index + 1,
                a.values
            )
            .into());
        }
        let d = difference(b, a)?;
        let (sa, sb) = (a.solved().ok_or("failed")?, b.solved().ok_or("failed")?);
        let labels = |s: &squeal::matrix::point::SolvedPoint| {
            s.modes.iter().map(|m| m.label).collect::<Vec<_>>()
        };
        if labels(sa) != labels(sb) {
            return Err(format!("point {}: labels differ", a.index + 1).into());
        }
        worst = nan_max(worst, d);
    }
    if exceeds(worst, 1e-6) {
        return Err(format!("results differ by {worst:e} (bound 1e-6)").into());
    }
    Ok(worst)
}

/// The small brake's orthotropic lining with every elastic constant times `e`.
fn scaled_lining(e: f64) -> String {
    let c = |v: f64| format!("{:?}", v * e);
    format!(
        "[model.materials.lining]\nname = \"pad lining x {e}\"\ndensity = 2500.0\n\
         elasticity = {{ model = \"orthotropic\", e1 = {}, e2 = {}, e3 = {}, nu12 = 0.25, nu13 = 0.1, nu23 = 0.1, g12 = {}, g13 = {}, g23 = {} }}\n",
        c(6e9),
        c(6e9),
        c(2e9),
        c(2.4e9),
        c(1.0e9),
        c(1.0e9)
    )
}

fn lining_and_superelement(petsc: &Petsc) -> TestResult {
    let matrix =
        "[reduction]\n[matrix]\nsampling = \"grid\"\nstatics = \"reduced\"\nfull_checks = 9\n\
                  [matrix.axes]\npressure_bar = { values = [20.0, 22.5, 25.0] }\n\
                  lining_modulus = { values = [0.8, 0.9, 1.0] }\n";
    fresh(petsc, "matrix-lining");
    let summary = run(
        petsc,
        &(brake(20.0, 0.4) + matrix),
        "matrix-lining",
        &RunOptions::default(),
    )?;
    let pts = points(&summary)?;
    // (displacement error, torque: reduced, full) at (pressure, lining).
    let at = |pressure: f64, lining: f64| -> TestResult<(f64, f64, f64)> {
        let p = pts
            .iter()
            .find(|p| p.values == [pressure, lining])
            .ok_or(format!("no point at {pressure} bar, lining x {lining}"))?;
        let s = p.solved().ok_or(format!("point {:?} failed", p.values))?;
        let c = s.full_check.as_ref().ok_or(format!(
            "point {:?} not checked on the full model",
            p.values
        ))?;
        if let Some(f) = &c.failure {
            return Err(format!("full check at {:?}: {f}", p.values).into());
        }
        Ok((c.displacement_error, s.braking_torque, c.braking_torque))
    };
    // The lining factor against the scaled material, on the full model.
    let single = run(
        petsc,
        &(brake(20.0, 0.4).replace(
            "[real_modes]\ncount = 30\n[complex_modes]\nmethod = \"projected\"\n",
            "",
        ) + &scaled_lining(0.8)),
        "matrix-lining-single",
        &RunOptions::default(),
    )?;
    let st = single.statics.as_ref().ok_or("no static summary")?;
    let torque: f64 = st.interfaces.iter().map(|(_, i)| i.torque).sum();
    let (_, _, full_at_08) = at(20.0, 0.8)?;
    let material = rel(full_at_08, torque);
    // The superelement at the nominal point, and its error's rate in each parameter.
    let (nominal, reduced_torque, full_torque) = at(20.0, 1.0)?;
    let nominal = nan_max(nominal, rel(reduced_torque, full_torque));
    let pressure = [at(22.5, 1.0)?.0, at(25.0, 1.0)?.0];
    let lining = [at(20.0, 0.9)?.0, at(20.0, 0.8)?.0];
    let rate = |e: [f64; 2]| (e[1] / e[0]).log2();
    let (rate_p, rate_l) = (rate(pressure), rate(lining));
    say(petsc, &format!("lining x 0.8 against the scaled material: {material:.1e}; superelement at the nominal point {nominal:.1e}; its error at +2.5/+5 bar {:.2e}/{:.2e} (rate {rate_p:.2}), at lining x 0.9/0.8 {:.2e}/{:.2e} (rate {rate_l:.2})", pressure[0], pressure[1], lining[0], lining[1]));
    if exceeds(material, 1e-6) || exceeds(nominal, 1e-6) {
        return Err(format!("lining factor vs scaled material {material:e} (bound 1e-6), superelement at the nominal point {nominal:e} (bound 1e-6)").into());
    }
    if !(rate_p >= 1.5 && rate_l >= 1.5) {
        return Err(format!("the superelement's static error converges at rate {rate_p} in pressure and {rate_l} in lining stiffness, below 1.5 (second order expected)").into());
    }
    agrees_with_one_rank(petsc, "noise-matrix-lining", &pts)
}

fn saturation_at_the_nominal_point(petsc: &Petsc) -> TestResult {
    // The pseudo-trajectory suite's brake (40 modes: C35, the most unstable, saturates in the
    // coarse sweep).
    let post = "[post.pseudo_trajectory]\nmost_unstable = 1\nalphas = 9\nphases = 16\n\
                [post.loudness]\n";
    let matrix = "[matrix]\nsampling = \"grid\"\nsaturation_modes = 1\n[matrix.axes]\n\
                  mu = { values = [0.4, 0.42] }\n";
    fresh(petsc, "matrix-saturation");
    let text = brake(20.0, 0.4).replace("count = 30", "count = 40") + post + matrix;
    let summary = run(petsc, &text, "matrix-saturation", &RunOptions::default())?;
    let pts = points(&summary)?;
    let at = pts[0].solved().ok_or("the nominal point failed")?;
    let sat = at
        .saturation
        .first()
        .ok_or("no saturated mode at the nominal point")?;
    if let Some(f) = &sat.failure {
        return Err(format!("the nominal point's study failed: {f}").into());
    }
    let study = summary
        .pseudo
        .as_ref()
        .and_then(|p| p.studies.first())
        .ok_or("no pseudo-trajectory study")?;
    let t = &study.trajectory;
    let label = sat.label.map(|l| format!("C{l}"));
    if label.as_deref() != Some(t.name.as_str()) {
        return Err(format!("the point followed {label:?}, the stage {}", t.name).into());
    }
    let (a, b) = (sat.alpha_sat, t.alpha_sat.alpha());
    let (Some(a), Some(b)) = (a, b) else {
        return Err(format!("alpha_sat: point {a:?}, stage {b:?}").into());
    };
    let crit = match (sat.alpha_crit, t.alpha_crit.alpha()) {
        (Some(x), Some(y)) => rel(x, y),
        (None, None) => 0.0,
        (x, y) => return Err(format!("alpha_crit: point {x:?}, stage {y:?}").into()),
    };
    let loud = summary.loudness.as_ref().ok_or("no loudness report")?;
    let stage_level = loud
        .modes
        .iter()
        .find(|m| m.name == t.name)
        .map(|m| m.level_a())
        .ok_or(format!("the loudness stage has no level of {}", t.name))?;
    let level = sat.level_db_a.ok_or("no level at the nominal point")?;
    let (d_sat, d_level) = (rel(a, b), (level - stage_level).abs());
    say(petsc, &format!("{}: alpha_sat {a:.4e} m (stage {b:.4e}, {d_sat:.1e}), alpha_crit {crit:.1e} apart, level {level:.2} dB(A) (stage {stage_level:.2}); the other point: {:?}", t.name, pts[1].solved().and_then(|s| s.saturation.first()).map(|m| (m.label, m.alpha_sat, m.level_db_a))));
    if exceeds(d_sat, 0.01) || exceeds(crit, 0.01) || exceeds(d_level, 0.1) {
        return Err(format!("alpha_sat {d_sat:e} and alpha_crit {crit:e} apart (bound 1 %), level {d_level:e} dB (bound 0.1 dB)").into());
    }
    let mine: Vec<f64> = pts
        .iter()
        .flat_map(|p| p.solved().into_iter().flat_map(|s| s.saturation.iter()))
        .flat_map(|m| {
            [
                m.alpha_sat.unwrap_or(f64::NAN),
                m.level_db_a.unwrap_or(f64::NAN),
            ]
        })
        .collect();
    let Some(one) = one_rank_values(petsc, "noise-matrix-saturation", &mine)? else {
        return Ok(());
    };
    let mut d = 0.0f64;
    for (k, (x, y)) in mine.iter().zip(&one).enumerate() {
        d = nan_max(
            d,
            if k % 2 == 0 {
                rel(*x, *y) / 0.01
            } else {
                (x - y).abs() / 0.1
            },
        );
    }
    say(
        petsc,
        &format!(
            "1 vs {} ranks: {d:.2} of the bounds (1 %, 0.1 dB)",
            petsc.size()
        ),
    );
    match mine.len() == one.len() && !exceeds(d, 1.0) {
        true => Ok(()),
        false => Err(format!(
            "1 vs {} ranks: {d} of the bounds, {} vs {} values",
            petsc.size(),
            mine.len(),
            one.len()
        )
        .into()),
    }
}
