//! End-to-end runs of the `squeal` binary under mpirun (2 ranks when mpirun is available):
//! the default scene completes and writes its results; bad input gives a non-zero exit and a
//! message that names the file and the key, without hanging any rank.

use squeal::measure::nan_max;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

#[path = "support/launch.rs"]
mod launch;
#[path = "support/paraview.rs"]
mod paraview;
#[path = "support/report_numbers.rs"]
mod report_numbers;

fn squeal() -> &'static str {
    env!("CARGO_BIN_EXE_squeal")
}

/// Runs `squeal args...` on `ranks` ranks in `cwd`; a run that outlives the deadline is killed
/// (mpirun and its ranks) and fails the test, never hangs it.
fn mpirun(ranks: usize, args: &[&str], cwd: &Path) -> Output {
    let deadline = Duration::from_secs(600);
    let run = launch::squeal_run(ranks, args, cwd, &[], deadline);
    let Some(status) = run.status else {
        panic!(
            "squeal {args:?} on {ranks} ranks still ran after {} s: killed\n{}\n{}",
            deadline.as_secs(),
            run.stdout,
            run.stderr
        );
    };
    Output {
        status,
        stdout: run.stdout.into_bytes(),
        stderr: run.stderr.into_bytes(),
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("squeal-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn scene_file(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("jobs")
            .join(name),
    )
    .unwrap()
}

fn default_scene() -> String {
    scene_file("default.toml")
}

fn disc_ring_scene() -> String {
    scene_file("disc-ring-modes.toml")
}

#[test]
fn default_scene_runs_end_to_end_on_two_ranks_with_its_report_and_labelled_figures() {
    let dir = scratch("default");
    let out = mpirun(2, &["run"], &dir);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "stdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Only rank 0 prints: the header appears once; the summary leads with the answer.
    assert_eq!(stdout.matches("squeal 0.").count(), 1, "{stdout}");
    let answer = stdout.split("answer:").nth(1).expect("an answer block");
    let answer: Vec<&str> = answer
        .lines()
        .skip(1)
        .take_while(|l| l.starts_with("    "))
        .collect();
    check_verdict(answer[0].trim());
    assert!(
        answer.iter().any(|l| l.contains("unstable complex modes")),
        "{answer:?}"
    );
    assert!(
        answer.iter().any(|l| l.contains("transient (")),
        "{answer:?}"
    );
    assert!(
        answer
            .iter()
            .any(|l| l.contains("saturation amplitude predicted")),
        "{answer:?}"
    );
    assert!(answer.last().unwrap().contains("report.html"), "{answer:?}");
    // Solver diagnostics stay off the console: in transient.log and the report.
    assert!(!stdout.contains("stalled with"), "{stdout}");
    let summary = std::fs::read_to_string(dir.join("results/summary.txt")).expect("summary.txt");
    assert!(
        summary.starts_with("answer:\n    squeals: yes"),
        "{summary}"
    );
    assert!(summary.contains("timings (s):"), "{summary}");
    for needle in [
        "real modes",
        "complex modes",
        "limit cycle",
        "timings",
        "mesh quality",
    ] {
        assert!(stdout.contains(needle), "{needle} missing:\n{stdout}");
    }
    for f in [
        "results/results.h5",
        "results/results.xdmf",
        "results/model.png",
        "results/report.html",
    ] {
        let p = dir.join(f);
        assert!(
            p.metadata().map(|m| m.len() > 0).unwrap_or(false),
            "{} missing",
            p.display()
        );
    }
    let results = dir.join("results");
    check_paraview(&results);
    // Every row of the real modes (60 x 3 values), the complex modes (60 modes and the 4
    // unstable again, 3 values each), the dynamic stability (5 headline modes, 10 values
    // each), the pseudo trajectory (1 mode, 6 values), the ~22 stage timings and the
    // verdict's three figures.
    let compared = report_numbers::check_report_numbers(&results);
    assert!(
        compared >= 3 * 60 + 3 * 64 + 5 * 10 + 6 + 20 + 3,
        "{compared} values compared"
    );
    // The verdict's mode has its picture in the report.
    let html = std::fs::read_to_string(results.join("report.html")).unwrap();
    assert!(
        results.join("mode_shape_projected_C35.png").is_file()
            && html.contains("(mode_shape_projected_C35.png)"),
        "no picture of C35's shape in the report"
    );
    check_growth_into_saturation(&results);
    check_growing_mode_along_the_cycle(&results);
    check_report(&results, &default_scene());
    // Contact maps (4), stability diagram, torque, spectrogram, limit cycle, modal energy,
    // contact cycle (2), dynamic stability (2), pseudo trajectory (2).
    check_figures(&results, 15);
}

#[test]
fn real_modes_scene_reports_only_its_stages() {
    let dir = scratch("real-modes");
    let scene = scene_file("brake-real-modes.toml").replace("count = 50", "count = 12");
    std::fs::write(dir.join("scene.toml"), &scene).unwrap();
    let out = mpirun(2, &["run", "scene.toml"], &dir);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("rigid-body mode"), "{stdout}");
    let results = dir.join("results-real-modes");
    check_report(&results, &scene);
    check_figures(&results, 0);
}

/// The default scene's verdict names whether it squeals, the frequency, the mode, the
/// components that move most and the level: "squeals: yes, 2.91 kHz, mode C35 (the most
/// unstable of 4), disc, piston and inner backplate moving most, 124.5 dB(A) sound power from
/// the saturated vibration".
/// The numbers are the growth check's (C35 grows in the transient) and the loudness suite's
/// business; here the line must carry each part, in an engineer's units.
fn check_verdict(verdict: &str) {
    assert!(verdict.starts_with("squeals: yes, "), "{verdict}");
    // The number written just before a unit ("2.91 kHz").
    let before = |unit: &str| -> Option<f64> {
        let head = verdict.split(unit).next()?;
        head.rsplit(' ').next()?.parse().ok()
    };
    let kilohertz = before(" kHz");
    assert!(
        kilohertz.is_some_and(|f| (0.5..20.0).contains(&f)),
        "no frequency in kHz: {verdict}"
    );
    assert!(verdict.contains(", mode C"), "no mode: {verdict}");
    assert!(
        verdict.contains("disc") && verdict.contains("moving most"),
        "no components: {verdict}"
    );
    let level = before(" dB(A)");
    assert!(
        level.is_some_and(|l| l.is_finite() && (60.0..160.0).contains(&l)),
        "no level in dB(A): {verdict}"
    );
}

/// The report's sections, in order: one per stage the scene asked for, no other.
fn expected_sections(scene: &str) -> Vec<&'static str> {
    let v: toml::Value = toml::from_str(scene).unwrap();
    let has = |key: &str| v.get(key).is_some();
    let post = |key: &str| v.get("post").and_then(|p| p.get(key)).is_some() && has("transient");
    let mut out = vec!["answer", "model"];
    for (asked, id) in [
        (has("statics"), "static-state"),
        (has("real_modes"), "real-modes"),
        (has("complex_modes"), "complex-modes"),
        (has("sweep"), "sweep"),
        (has("reduction"), "reduction"),
        (has("transient"), "transient"),
        (post("modal_energy"), "modal-energy"),
        (post("contact_cycle"), "contact-cycle"),
        (post("dynamic_stability"), "dynamic-stability"),
        (
            v.get("post")
                .and_then(|p| p.get("pseudo_trajectory"))
                .is_some(),
            "pseudo-trajectories",
        ),
        (
            v.get("post").and_then(|p| p.get("loudness")).is_some(),
            "how-loud",
        ),
    ] {
        if asked {
            out.push(id);
        }
    }
    if has("transient") {
        out.push("diagnostics");
    }
    out.extend(["run", "scene"]);
    out
}

/// The default scene's transient (the small brake reduced on 60 modes, 5 um kick, 32 ms) grows
/// as its most unstable complex mode predicts and saturates into a bounded vibration.
///
/// Reference: the complex-modes stage of the same run (C35, 2,910.6 Hz, Re(s) = 340 1/s; the
/// full route agrees to ~1e-4, tests/suite/growth.rs). Bounds: the growth rate fitted on the
/// torque's envelope within 10 % of Re(s) (the fit mixes in the slower unstable modes and the
/// kick's decaying content, as in the growth test; measured 331 1/s, 2.8 %); the growth
/// window's spectral peak within one frequency bin (1 / window length) of the mode's frequency
/// (measured 2,911.7 Hz); saturation found before the end with at least 10 cycles after it;
/// and bounded: over the saturated window the envelope stays below twice the saturated
/// amplitude, where growth at Re(s) would have multiplied it by exp(Re(s) x window) (asserted
/// above 4, so that the check can fail; measured 6.7, the envelope within 0.7-1.3 x).
/// Not asserted: a periodic limit cycle (32 ms ends in a modulated vibration whose
/// cycle-to-cycle amplitude varies by ~60 %; the summary says so).
/// The ParaView files refer to what results.h5 holds, and meshio reads the whole brake with
/// its static state and mode shapes, and the vibration's frames: the default `[output]`
/// asks for 4 periods at about 24 frames a period (fewer only if fewer states were stored).
fn check_paraview(results: &Path) {
    let refs = paraview::check_xdmf_references(results);
    let view = paraview::read_with_meshio(results);
    let file = hdf5::File::open(results.join("results.h5")).expect("results.h5 opens");
    let nodes = file.dataset("model/coordinates").unwrap().shape()[0];
    let elements = file.dataset("model/component_id").unwrap().shape()[0];
    let frames = file.dataset("vibration/time").unwrap().shape()[0];
    assert_eq!((view.points, view.cells), (nodes, elements), "{refs:?}");
    assert_eq!(view.frames, frames);
    assert!(
        (4 * 24 - 4..=4 * 24 + 8).contains(&frames),
        "{frames} frames"
    );
    // 60 real modes and 60 complex ones (re, im), the static displacement and pressure.
    assert!(view.fields >= 60 + 120 + 2, "{} nodal fields", view.fields);
    // A saturated brake vibration is micrometres to tens of micrometres (the default's
    // alpha_sat is 2e-5 m): a frame of zeros, or of millimetres, is a wrong recovery.
    assert!(
        view.peak > 1e-6 && view.peak < 1e-3,
        "peak vibration {} m",
        view.peak
    );
}

fn check_growth_into_saturation(results: &Path) {
    let file = hdf5::File::open(results.join("results.h5")).expect("results.h5 opens");
    let g = file.group("post/limit_cycle").expect("/post/limit_cycle");
    let number = |name: &str| -> f64 {
        g.attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .unwrap_or_else(|e| panic!("/post/limit_cycle {name}: {e}"))
    };
    let table = |name: &str| -> Vec<f64> {
        g.dataset(name)
            .and_then(|d| d.read_raw::<f64>())
            .unwrap_or_else(|e| panic!("/post/limit_cycle/{name}: {e}"))
    };
    let (growth, re) = (
        number("growth_rate_per_s"),
        number("predicted_growth_rate_per_s"),
    );
    let error = (growth - re).abs() / re.abs();
    assert!(
        error <= 0.1,
        "growth {growth} 1/s vs Re(s) {re} 1/s ({error:.2e})"
    );
    let (f_growth, f_mode) = (
        number("growth_frequency_hz"),
        number("predicted_frequency_hz"),
    );
    let bin = 1.0 / (number("growth_window_end_s") - number("growth_window_start_s"));
    assert!(
        (f_growth - f_mode).abs() <= bin,
        "growth at {f_growth} Hz vs the mode's {f_mode} Hz (bin {bin} Hz)"
    );
    let saturation = number("saturation_time_s");
    let envelope_time = table("envelope_time");
    let end = *envelope_time.last().expect("an envelope");
    assert!(
        saturation > 0.0 && saturation < end,
        "saturation at {saturation} s, end {end} s"
    );
    let cycles = table("peak_to_peak").len();
    assert!(cycles >= 10, "{cycles} cycles after saturation");
    let amplitude = number("saturated_amplitude_nm");
    let linear_factor = (re * (end - saturation)).exp();
    assert!(
        linear_factor > 4.0,
        "saturated window too short: {linear_factor}"
    );
    let saturated: Vec<f64> = envelope_time
        .iter()
        .zip(table("envelope"))
        .filter(|(t, _)| **t >= saturation)
        .map(|(_, a)| a)
        .collect();
    assert!(
        !saturated.is_empty() && saturated.iter().all(|a| a.is_finite()),
        "envelope after saturation: {saturated:?}"
    );
    let largest = saturated.iter().copied().fold(0.0, nan_max);
    assert!(
        amplitude > 0.0 && largest <= 2.0 * amplitude,
        "envelope up to {largest} N m after saturation vs saturated amplitude {amplitude} N m"
    );
}

/// The dynamic stability along the default scene's last two periods (DESIGN.md §2b, the
/// paper's fig. 10): the mode that grows (the most unstable complex mode, which the growth
/// check above matched with the transient) is unstable at the static state and, along the
/// saturated vibration, stable for part of the cycle: the contact state it grew from no longer
/// holds everywhere on the cycle. Measured: C35 unstable 25 % of the time (stable 75 %), mean
/// damping ratio -9.4e-4. Asserted: unstable at rest (zeta < 0 at the first point, which is
/// the static state), stable (zeta > 0) at one state at least, every value finite.
fn check_growing_mode_along_the_cycle(results: &Path) {
    let file = hdf5::File::open(results.join("results.h5")).expect("results.h5 opens");
    let predicted_by: String = file
        .group("post/limit_cycle")
        .and_then(|g| g.attr("predicted_by"))
        .and_then(|a| a.read_scalar::<hdf5::types::VarLenUnicode>())
        .map(|s| s.to_string())
        .expect("/post/limit_cycle predicted_by");
    // "complex mode C35 (projected route)"
    let name = predicted_by
        .split_whitespace()
        .nth(2)
        .expect("a mode name in predicted_by");
    let zeta: Vec<f64> = file
        .dataset(&format!(
            "post/dynamic_stability/modes/{name}/damping_ratio"
        ))
        .and_then(|d| d.read_raw::<f64>())
        .unwrap_or_else(|e| panic!("{name}'s damping ratio along the run: {e}"));
    assert!(
        zeta.len() > 2 && zeta.iter().all(|z| z.is_finite()),
        "{name}: {zeta:?}"
    );
    assert!(zeta[0] < 0.0, "{name} at rest: zeta {}", zeta[0]);
    let stable = zeta[1..].iter().filter(|&&z| z > 0.0).count();
    assert!(
        stable > 0,
        "{name} unstable at every one of the {} states along the cycle",
        zeta.len() - 1
    );
}

/// report.html is one file that references nothing outside itself, every embedded figure
/// decodes as a PNG, and its sections are those of the stages the scene ran.
fn check_report(results: &Path, scene: &str) {
    let html = std::fs::read_to_string(results.join("report.html")).unwrap();
    let sections: Vec<&str> = html
        .split("<section id=\"")
        .skip(1)
        .map(|s| &s[..s.find('"').unwrap()])
        .collect();
    assert_eq!(sections, expected_sections(scene));
    for outside in ["http://", "https://", "url(", "<link", "<script", "file:"] {
        assert!(!html.contains(outside), "the report references {outside}");
    }
    for href in html.split("href=\"").skip(1) {
        assert!(
            href.starts_with('#'),
            "a link outside the report: {}",
            &href[..40.min(href.len())]
        );
    }
    let mut figures = 0;
    for src in html.split("src=\"").skip(1) {
        let data = src
            .strip_prefix("data:image/png;base64,")
            .unwrap_or_else(|| panic!("an image outside the report: {}", &src[..40]));
        let data = &data[..data.find('"').unwrap()];
        use base64::Engine as _;
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(data)
            .unwrap();
        let mut reader = png::Decoder::new(&bytes[..]).read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size()];
        let frame = reader.next_frame(&mut pixels).unwrap();
        assert!(frame.width >= 300 && frame.height >= 200);
        figures += 1;
    }
    assert!(figures >= 1, "no figure in the report");
    assert!(!html.contains("report.html"), "the report points at itself");
    let scene_section = html.split("<section id=\"scene\">").nth(1).unwrap();
    assert!(
        !scene_section
            .lines()
            .any(|l| l.trim_start().starts_with('#')),
        "the report's scene keeps its comments"
    );
}

/// The texts of an SVG written by plotters: (attributes, content) per <text> element.
fn svg_texts(svg: &str) -> Vec<(String, String)> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (attributes, rest) = t.split_once('>')?;
            let content = rest.split("</text>").next()?.trim();
            Some((attributes.to_string(), content.to_string()))
        })
        .collect()
}

fn font_size(attributes: &str) -> f64 {
    attributes
        .split("font-size=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.0)
}

/// Every plot the run wrote (PNG) has an SVG twin with a title (its largest text), a
/// horizontal and a vertical axis label with units in parentheses, and tick values. The
/// exceptions are pictures of the model, not plots: model.png and the mode shapes.
fn check_figures(results: &Path, at_least: usize) {
    let mut plots = 0;
    for entry in std::fs::read_dir(results).unwrap() {
        let png = entry.unwrap().path();
        let name = png.file_name().unwrap().to_string_lossy().to_string();
        let picture = name == "model.png" || name.starts_with("mode_shape_");
        if !name.ends_with(".png") || picture {
            continue;
        }
        let svg = std::fs::read_to_string(png.with_extension("svg"))
            .unwrap_or_else(|e| panic!("{name}: no SVG twin ({e})"));
        let texts = svg_texts(&svg);
        let largest = texts.iter().map(|t| font_size(&t.0)).fold(0.0, nan_max);
        let title: Vec<&str> = texts
            .iter()
            .filter(|t| font_size(&t.0) == largest && !t.1.is_empty())
            .map(|t| t.1.as_str())
            .collect();
        assert!(!title.is_empty(), "{name}: no title");
        let label = |rotated: bool| {
            texts.iter().any(|(a, c)| {
                a.contains("rotate(") == rotated
                    && font_size(a) < largest
                    && c.contains('(')
                    && c.ends_with(')')
            })
        };
        assert!(label(false), "{name}: no x-axis label with units");
        assert!(label(true), "{name}: no y-axis label with units");
        let ticks = texts.iter().filter(|t| t.1.parse::<f64>().is_ok()).count();
        assert!(ticks >= 4, "{name}: {ticks} tick values");
        plots += 1;
    }
    assert!(plots >= at_least, "{plots} plots in {}", results.display());
}

#[test]
fn print_default_scene_roundtrips() {
    let out = Command::new(squeal())
        .args(["scene", "--print-default"])
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout), default_scene());
}

fn expect_failure(name: &str, scene: &str, needles: &[&str]) {
    let dir = scratch(name);
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let out = mpirun(2, &["run", "scene.toml"], &dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // squeal's own error exit, not a crash (a signal or another code) after the message.
    assert_eq!(
        out.status.code(),
        Some(1),
        "{name}: exit status {}, not 1\n{stderr}",
        out.status
    );
    for n in needles {
        assert!(stderr.contains(n), "{name}: '{n}' not in:\n{stderr}");
    }
}

#[test]
fn negative_thickness_names_the_key() {
    expect_failure(
        "thickness",
        &default_scene().replace("disc_thickness = 0.028", "disc_thickness = -0.028"),
        &["scene.toml", "model.geometry.disc_thickness"],
    );
}

#[test]
fn unknown_key_names_the_key() {
    expect_failure(
        "unknown",
        &default_scene().replace("count = 60", "count = 60\nnumber = 3"),
        &["scene.toml", "number"],
    );
}

#[test]
fn missing_matrix_file_names_the_file() {
    let scene = "[model]\nsource = \"matrices\"\nstiffness = [{ file = \"K.mtx\" }]\nmass = [{ file = \"M.mtx\" }]\n[real_modes]\ncount = 4\n";
    expect_failure("missing", scene, &["K.mtx", "No such file"]);
}

#[test]
fn missing_node_set_names_the_sets() {
    expect_failure(
        "nodeset",
        &disc_ring_scene().replace("clamp = [\"inner\"]", "clamp = [\"hat\"]"),
        &["no node set 'hat'", "inner"],
    );
}

/// The frequencies of a summary printed by `squeal run`.
fn frequencies(stdout: &str) -> Vec<f64> {
    stdout
        .lines()
        .skip_while(|l| !l.starts_with("real modes:"))
        .skip(1)
        .map_while(|l| {
            let mut w = l.split_whitespace();
            w.next()?.parse::<usize>().ok()?;
            w.next()?.parse::<f64>().ok()
        })
        .collect()
}

#[test]
fn written_inp_reimported_gives_the_same_modes() {
    let dir = scratch("inp");
    let scene = disc_ring_scene()
        .replace(
            "directory = \"results\"",
            "directory = \"first\"\nwrite_inp = true",
        )
        .replace("cells = [8, 120, 4]", "cells = [3, 40, 2]")
        .replace("count = 30", "count = 8");
    std::fs::write(dir.join("generated.toml"), &scene).unwrap();
    let first = mpirun(2, &["run", "generated.toml"], &dir);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let imported = "[model]\nsource = \"abaqus\"\nfile = \"first/model.inp\"\n[real_modes]\ncount = 8\n[output]\ndirectory = \"second\"\n";
    std::fs::write(dir.join("imported.toml"), imported).unwrap();
    let second = mpirun(2, &["run", "imported.toml"], &dir);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    let (a, b) = (
        frequencies(&String::from_utf8_lossy(&first.stdout)),
        frequencies(&String::from_utf8_lossy(&second.stdout)),
    );
    assert_eq!(a.len(), 8, "{a:?}");
    assert_eq!(a, b, "generated and re-imported models differ");
}

/// The small brake's noise matrix (8 Sobol points, a 20-mode basis).
fn matrix_scene() -> String {
    let matrix = "[matrix]\nsampling = \"sobol\"\npoints = 8\nseed = 3\n[matrix.axes]\n\
                  pressure_bar = { from = 10.0, to = 30.0 }\nmu = { from = 0.3, to = 0.5 }\n";
    default_scene()
        .split("[reduction]")
        .next()
        .unwrap()
        .replace("count = 60", "count = 20")
        + matrix
}

/// The points' lines of a journal by index (a run writes them in the order it computes
/// them): (index, parameters) and their results as numbers.
fn journal_points(path: &Path) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut points: Vec<(u64, (String, Vec<f64>))> = text
        .lines()
        .skip(1)
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let solved = &v["outcome"];
            let mut numbers = vec![solved["braking_torque"].as_f64().unwrap()];
            for m in solved["modes"].as_array().unwrap() {
                numbers.push(m["re"].as_f64().unwrap());
                numbers.push(m["im"].as_f64().unwrap());
            }
            let index = v["index"].as_u64().unwrap();
            (index, (format!("{index} {}", v["values"]), numbers))
        })
        .collect();
    points.sort_by_key(|p| p.0);
    points.into_iter().map(|p| p.1).collect()
}

/// `--groups 2` on 2 ranks (each group one rank, half the points) merges into the same points
/// as one group of 2 ranks: parameters exactly, torques and eigenvalues to the static
/// tolerance (1e-6 relative; the warm starts differ); `squeal merge` of a folder without a
/// journal names it.
#[test]
fn noise_matrix_in_two_groups_equals_one_group() {
    let dir = scratch("matrix-groups");
    std::fs::write(dir.join("scene.toml"), matrix_scene()).unwrap();
    let one = mpirun(2, &["run", "scene.toml", "-o", "one"], &dir);
    let stdout = String::from_utf8_lossy(&one.stdout);
    assert!(
        one.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&one.stderr)
    );
    let two = mpirun(
        2,
        &["run", "scene.toml", "-o", "two", "--groups", "2"],
        &dir,
    );
    let stdout = String::from_utf8_lossy(&two.stdout);
    assert!(
        two.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&two.stderr)
    );
    assert!(stdout.contains("groups merged into two"), "{stdout}");
    assert!(
        !stdout.contains("group 2 of 2"),
        "only rank 0 prints:\n{stdout}"
    );
    assert!(dir.join("two/group-2-of-2/console.log").exists());
    let (a, b) = (
        journal_points(&dir.join("one/matrix-points.jsonl")),
        journal_points(&dir.join("two/matrix-points.jsonl")),
    );
    assert_eq!(a.len(), 8);
    let mut worst = 0.0f64;
    for ((ka, va), (kb, vb)) in a.iter().zip(&b) {
        assert_eq!(ka, kb);
        assert_eq!(va.len(), vb.len(), "{ka}");
        for (x, y) in va.iter().zip(vb) {
            worst = nan_max(worst, (x - y).abs() / nan_max(x.abs(), 1.0));
        }
    }
    assert!(worst <= 1e-6, "groups against one group: {worst:e}");
    let report = std::fs::read_to_string(dir.join("two/report.html")).unwrap();
    assert!(report.contains("noise-matrix") && report.contains("matrix_bands.png"));
    let out = mpirun(
        1,
        &["merge", "one/group-1-of-2", "--output", "merged"],
        &dir,
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("one/group-1-of-2") && stderr.contains("matrix-points.jsonl"),
        "{stderr}"
    );
}
