//! report.html: the run in one self-contained page a brake engineer reads top to bottom (the
//! answer, the model, the static state, real and complex modes, the transient and its link
//! with the complex modes, and every stage's time against its accuracy figure). Figures are
//! the run's PNGs embedded as data URIs, the style is inline: the file opens anywhere, offline,
//! and can be mailed on its own. A section appears only when its stage ran.

use crate::measure::nan_max;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine as _;

use crate::report::answer::answer_lines;
use crate::report::summary::{Part, RunSummary};

/// One section of the report: its anchor, heading and HTML body.
pub struct Section {
    pub id: &'static str,
    pub title: String,
    pub body: String,
}

/// The report's section anchors, in order (tests compare them with the stages that ran).
pub const SECTION_IDS: [&str; 17] = [
    "answer",
    "model",
    "static-state",
    "real-modes",
    "complex-modes",
    "sweep",
    "noise-matrix",
    "reduction",
    "transient",
    "modal-energy",
    "contact-cycle",
    "dynamic-stability",
    "pseudo-trajectories",
    "how-loud",
    "diagnostics",
    "run",
    "scene",
];

const STYLE: &str = "body{font-family:sans-serif;max-width:1250px;margin:2em auto;padding:0 1em;color:#222;line-height:1.4}\
h1{border-bottom:3px solid #c0392b}h2{border-bottom:1px solid #ccc;margin-top:2em}\
nav a{margin-right:1em}figure{margin:1em 0}img{max-width:100%;border:1px solid #ddd}\
figcaption{font-size:90%;color:#555}pre{background:#f6f6f6;padding:.7em;white-space:pre-wrap;overflow-wrap:anywhere;font-size:85%}\
table{border-collapse:collapse;font-size:90%;margin:.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}\
th{background:#eee}td:first-child,th:first-child{text-align:left}.answer li{margin:.3em 0}.verdict{font-size:125%;font-weight:bold}dt{font-weight:bold;margin-top:.4em}\
.unstable{color:#c0392b;font-weight:bold}details{margin:.5em 0}summary{cursor:pointer}\
.maps figure{display:inline-block;width:49%;vertical-align:top;margin:.3em 0}\
#model img{max-width:760px}.run td:nth-child(3){text-align:left}";

/// Writes `output/report.html` for the run `summary` describes; returns its path.
pub fn write_report(
    summary: &RunSummary,
    scene_text: &str,
    output: &Path,
) -> std::io::Result<PathBuf> {
    let sections: Vec<(&str, String, String)> = sections(summary, scene_text, output)?
        .into_iter()
        .map(|s| (s.id, s.title, s.body))
        .collect();
    let intro = format!(
        "{} DOF; results in <code>{}</code> (results.h5 with results.xdmf for ParaView).",
        summary.dofs,
        escape(&output.display().to_string())
    );
    let path = output.join("report.html");
    std::fs::write(&path, page(output, &intro, &sections))?;
    Ok(path)
}

/// A whole page: title, the intro paragraph (HTML), a navigation bar, the sections (anchor,
/// heading, HTML body).
pub(crate) fn page(output: &Path, intro: &str, sections: &[(&str, String, String)]) -> String {
    let mut html = String::new();
    html.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    let _ = write!(
        html,
        "<title>squeal report: {}</title><style>{STYLE}</style></head><body>",
        escape(&output.display().to_string())
    );
    let _ = write!(
        html,
        "<h1>squeal: friction-induced instability analysis</h1><p>{intro}</p><nav>"
    );
    for (id, title, _) in sections {
        let _ = write!(html, "<a href=\"#{id}\">{}</a>", escape(title));
    }
    html.push_str("</nav>");
    for (id, title, body) in sections {
        let _ = writeln!(
            html,
            "<section id=\"{id}\"><h2>{}</h2>{body}</section>",
            escape(title)
        );
    }
    html.push_str("</body></html>\n");
    html
}

/// The sections of the stages that ran, in [`SECTION_IDS`] order.
pub fn sections(s: &RunSummary, scene_text: &str, output: &Path) -> std::io::Result<Vec<Section>> {
    let mut out = Vec::new();
    let mut add = |id: &'static str, title: &str, body: String| {
        out.push(Section {
            id,
            title: title.into(),
            body,
        })
    };
    add("answer", "The answer", answer_section(s));

    let mut body = figure(output, "model.png", "The model (components coloured).")?;
    body += &text(s, Part::Model);
    add("model", "Model", body);

    if let Some(st) = &s.statics {
        let mut body = text(s, Part::Statics) + "<div class=\"maps\">";
        for (name, _) in &st.interfaces {
            for (field, what) in [
                ("pressure", "contact pressure"),
                ("contact_stiffness", "contact stiffness"),
            ] {
                let file = format!("contact_{field}_{name}.png");
                body += &figure(output, &file, &format!("Static {what} on {name}."))?;
            }
        }
        body += "</div>";
        add(
            "static-state",
            "Static state: preload, contact, torque",
            body,
        );
    }
    if !s.frequencies_hz.is_empty() {
        add("real-modes", "Real modes", real_modes_table(s));
    }
    if !s.complex.is_empty() {
        let mut body = String::new();
        for c in &s.complex {
            let file = format!("stability_{}.png", c.route);
            let caption = format!(
                "Stability diagram, {} route: unstable modes in red.",
                c.route
            );
            body += &figure(output, &file, &caption)?;
            body += &complex_table(c);
            for m in c.modes.iter().filter(|m| m.unstable) {
                let file = format!("mode_shape_{}_{}.png", c.route, m.name);
                body += &figure(output, &file, &shape_caption(m))?;
            }
        }
        add(
            "complex-modes",
            "Complex modes: stability at the static state",
            body,
        );
    }
    if s.sweep.is_some() {
        let mut body = figure(
            output,
            "sweep_frequency.png",
            "Frequencies along the sweep.",
        )?;
        body += &figure(output, "sweep_real_part.png", "Real parts along the sweep.")?;
        body += &text(s, Part::Sweep);
        add("sweep", "Parameter sweep", body);
    }
    if let Some(m) = &s.matrix {
        let body = crate::report::matrix::html_section(m, output)?;
        add(
            "noise-matrix",
            "Noise matrix: squeal over the operating range",
            body,
        );
    }
    if s.reduction.is_some() {
        add("reduction", "Reduction", text(s, Part::Reduction));
    }
    time_sections(s, output, &mut out)?;
    let scene = format!(
        "<p>The scene as run, without its comments (the file itself keeps them).</p><pre>{}</pre>",
        escape(&without_comments(scene_text))
    );
    for (id, title, body) in [
        ("run", "Speed against accuracy", run_table(s)),
        ("scene", "Scene", scene),
    ] {
        let title = title.into();
        out.push(Section { id, title, body });
    }
    Ok(out)
}

/// The sections of the transient and of the analyses of its states and of the pseudo
/// trajectories and loudness, in [`SECTION_IDS`] order, appended to `out`.
fn time_sections(s: &RunSummary, output: &Path, out: &mut Vec<Section>) -> std::io::Result<()> {
    let mut add = |id: &'static str, title: &str, body: String| {
        out.push(Section {
            id,
            title: title.into(),
            body,
        })
    };
    if s.transient.is_some() {
        let mut body = figure(output, "torque.png", "Braking torque.")?;
        body += &figure(
            output,
            "spectrogram.png",
            "Spectrogram of the signal that moves most.",
        )?;
        if s.limit_cycle.is_some() {
            let caption = "The torque, its envelope and the detected cycles.";
            body += &figure(output, "limit_cycle.png", caption)?;
        }
        body += &text(s, Part::Transient);
        body += &text(s, Part::LimitCycle);
        add("transient", "Transient: growth and limit cycle", body);
    }
    if s.link.modal_energy.is_some() {
        let mut body = figure(output, "modal_energy.png", "The largest modal energies.")?;
        body += &text(s, Part::ModalEnergy);
        add("modal-energy", "Modal energies along the run", body);
    }
    if let Some(r) = &s.link.contact_cycle {
        let mut body = String::new();
        for pad in &r.cycle.pads {
            let file = format!("contact_cycle_{}.png", pad.name);
            let caption = format!("Contact stiffness over the cycle on {}.", pad.name);
            body += &figure(output, &file, &caption)?;
        }
        body += &text(s, Part::ContactCycle);
        add("contact-cycle", "Contact state over the cycle", body);
    }
    if s.link.dynamic_stability.is_some() {
        let mut body = figure(
            output,
            "dynamic_stability.png",
            "Complex modes of the tangent along the cycle.",
        )?;
        let caption = "Frequency and damping of the tracked modes against time, torque below.";
        body += &figure(output, "dynamic_stability_time.png", caption)?;
        if let Some(r) = &s.link.dynamic_stability {
            body += &dynamic_stability_table(r, s.link.modal_energy.as_ref());
        }
        body += &text(s, Part::DynamicStability);
        add(
            "dynamic-stability",
            "Dynamic stability along the cycle",
            body,
        );
    }
    if let Some(p) = &s.pseudo {
        let mut body = String::new();
        for study in &p.studies {
            let name = &study.trajectory.name;
            let caption = format!("{name}: mean damping and contact state against the amplitude.");
            body += &figure(output, &format!("pseudo_amplitude_{name}.png"), &caption)?;
            let caption = format!("{name}: pseudo dynamic stability over one period.");
            body += &figure(output, &format!("pseudo_stability_{name}.png"), &caption)?;
        }
        body += &pseudo_table(p);
        body += &text(s, Part::Pseudo);
        add(
            "pseudo-trajectories",
            "Pseudo trajectories: predicted saturation",
            body,
        );
    }
    if let Some(l) = &s.loudness {
        add("how-loud", "How loud", loudness_section(s, l, output)?);
    }
    if s.transient.is_some() {
        add(
            "diagnostics",
            "Solver diagnostics",
            diagnostics(&output.join("transient.log"))?,
        );
    }
    Ok(())
}

/// The answer: the verdict, its detail (without the line that points at this report), and a
/// glossary of the words it uses.
fn answer_section(s: &RunSummary) -> String {
    let lines = answer_lines(s);
    let verdict = crate::report::answer::verdict(s);
    let items: String = lines
        .iter()
        .filter(|l| Some(*l) != verdict.as_ref() && !l.starts_with("files:"))
        .map(|l| format!("<li>{}</li>", escape(l)))
        .collect();
    let verdict = verdict.map_or(String::new(), |v| {
        format!("<p class=\"verdict\">{}</p>", escape(&v))
    });
    format!("{verdict}<ul class=\"answer\">{items}</ul>{GLOSSARY}")
}

/// The words of the answer, for a reader who does not solve eigenproblems every day.
const GLOSSARY: &str = "<details><summary>Glossary</summary><dl>\
<dt>complex mode</dt><dd>A vibration shape of the brake with friction, at the static state: \
its eigenvalue s = Re(s) + i 2 pi f gives its frequency f and how fast it grows (Re(s) > 0) \
or decays. Friction couples modes, so a mode can draw energy from the sliding: it is \
unstable. Complex modes over-predict squeal; the transient says which unstable modes really \
grow and where they saturate.</dd>\
<dt>growth rate, damping ratio</dt><dd>Re(s) in 1/s: the amplitude of an unstable mode grows \
as exp(Re(s) t) while the vibration is small. The damping ratio is zeta = -Re(s)/|s|: \
negative for an unstable mode.</dd>\
<dt>moving most</dt><dd>The components holding the largest shares of the mode's kinetic \
energy.</dd>\
<dt>transient, saturation</dt><dd>The nonlinear time response from the static state plus a \
small kick: an unstable mode grows until contact opening, stick-slip and the friction \
limit bound it (saturation); a limit cycle is a saturated vibration that repeats itself.</dd>\
<dt>alpha_sat, saturation amplitude</dt><dd>The relative displacement at the contact (gap \
and slip, m) at which the mode, followed over its own period (pseudo trajectory), is stable \
on average: the amplitude the complex mode alone predicts for its saturation.</dd>\
<dt>sound power, dB(A)</dt><dd>The power radiated by the components of [post.loudness] (default: the disc and the backplates) as an \
equivalent radiated power (every face radiating as a piston: an upper bound), \
L_W = 10 log10(P / 1 pW), A-weighted for the ear. A level at a microphone (sound pressure, \
dB re 20 uPa) is a different quantity: it falls with distance.</dd>\
</dl></details>";

/// The step control's changes during the transient (transient.log), at most 200 lines.
fn diagnostics(log: &Path) -> std::io::Result<String> {
    const SHOWN: usize = 200;
    let text = match std::fs::read_to_string(log) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e),
    };
    let lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() {
        return Ok(
            "<p>No step of the transient stalled: the fixed Jacobian converged every step.</p>"
                .into(),
        );
    }
    let more = lines.len().saturating_sub(SHOWN);
    let shown = lines[..lines.len().min(SHOWN)].join("\n");
    Ok(format!(
        "<p>Where the transient's fixed-Jacobian iterations stalled and how the step control \
         recovered (retried with an updated factor, refactorized, or cut the step): {} lines \
         of transient.log{}. These are solver events, not results: the answer holds only \
         converged steps.</p><details><summary>transient.log</summary><pre>{}</pre></details>",
        lines.len(),
        if more > 0 {
            format!(", the first {SHOWN} shown")
        } else {
            String::new()
        },
        escape(&shown)
    ))
}

/// The scene's text without its comment lines (the header's description is the file's).
fn without_comments(scene: &str) -> String {
    scene
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .collect::<Vec<_>>()
        .join("\n")
        .trim()
        .to_string()
}

/// A figure of the results folder embedded as a data URI, or nothing when the run did not
/// draw it (e.g. a spectrogram of a run too short for one).
pub(crate) fn figure(output: &Path, file: &str, caption: &str) -> std::io::Result<String> {
    let path = output.join(file);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(String::new()),
        Err(e) => return Err(e),
    };
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    Ok(format!(
        "<figure><img alt=\"{}\" src=\"data:image/png;base64,{data}\"><figcaption>{} ({})</figcaption></figure>",
        escape(caption),
        escape(caption),
        escape(file)
    ))
}

fn text(s: &RunSummary, part: Part) -> String {
    let t = s.part(part).to_string();
    if t.trim().is_empty() {
        String::new()
    } else {
        format!("<pre>{}</pre>", escape(&t))
    }
}

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn real_modes_table(s: &RunSummary) -> String {
    let f = &s.frequencies_hz;
    let mut t = format!(
        "<details><summary>{} real modes from {:.1} to {:.1} Hz, largest backward error {:.1e}</summary><table><tr><th>mode</th><th>frequency (Hz)</th><th>||K phi - w^2 M phi||</th><th>backward error</th><th></th></tr>",
        f.len(),
        f[0],
        f[f.len() - 1],
        s.backward_errors.iter().copied().fold(0.0f64, nan_max)
    );
    for (i, hz) in s.frequencies_hz.iter().enumerate() {
        let _ = write!(
            t,
            "<tr><td>R{}</td><td>{hz:.3}</td><td>{:.2e}</td><td>{:.2e}</td><td>{}</td></tr>",
            i + 1,
            s.residual_norms[i],
            s.backward_errors[i],
            if s.rigid[i] { "rigid-body mode" } else { "" }
        );
    }
    t + "</table></details>"
}

/// The caption of an unstable mode's picture: what it shows and which components move.
fn shape_caption(m: &crate::eigen::complex_modes::ComplexMode) -> String {
    let moving: Vec<String> = crate::report::answer::moving_most(&m.motion)
        .iter()
        .map(|(name, share)| format!("{} {:.0} %", name.replace('_', " "), 100.0 * share))
        .collect();
    let moving = match moving.is_empty() {
        true => String::new(),
        false => format!(
            " Moving most (share of its kinetic energy): {}.",
            moving.join(", ")
        ),
    };
    format!(
        "{} at {:.1} Hz (damping ratio {:.2e}): the brake deformed by the mode's shape at the phase where it moves most (exaggerated), coloured by the displacement's size from dark blue (still) to yellow (the largest 5 % of the nodes).{moving}",
        m.name, m.frequency_hz, m.damping_ratio
    )
}

fn complex_table(c: &crate::report::summary::ComplexSummary) -> String {
    let row = |m: &crate::eigen::complex_modes::ComplexMode| {
        format!(
            "<tr{}><td>{}</td><td>{:.2}</td><td>{:.3e}</td><td>{:.3e}</td><td>{}</td><td>{:.2e}</td></tr>",
            if m.unstable { " class=\"unstable\"" } else { "" },
            m.name,
            m.frequency_hz,
            m.damping_ratio,
            m.eigenvalue.0,
            m.dominant_real_mode.map_or(String::new(), |k| format!("R{}", k + 1)),
            m.backward_error
        )
    };
    let head = "<table><tr><th>mode</th><th>frequency (Hz)</th><th>damping ratio</th><th>Re(s) (1/s)</th><th>dominant real mode</th><th>backward error</th></tr>";
    let unstable: String = c.modes.iter().filter(|m| m.unstable).map(row).collect();
    let all: String = c.modes.iter().map(row).collect();
    let count = c.modes.iter().filter(|m| m.unstable).count();
    let basis = if c.basis > 0 {
        format!(", projected on {} real modes", c.basis)
    } else {
        String::new()
    };
    format!(
        "<p>{} route{basis}: {count} unstable of {} modes.</p>{head}{unstable}</table><details><summary>all {} modes</summary>{head}{all}</table></details>",
        c.route,
        c.modes.len(),
        c.modes.len()
    )
}

/// Every stage's time with the accuracy figure that goes with it.
fn run_table(s: &RunSummary) -> String {
    let accuracy = |stage: &str| -> String {
        let max = |v: &[f64]| v.iter().copied().fold(0.0f64, nan_max);
        match stage {
            "static preload" => s.statics.as_ref().map_or(String::new(), |st| {
                format!(
                    "residual {:.2e} N after {} Newton iterations",
                    st.final_residual, st.newton_iterations
                )
            }),
            "real modes" => format!(
                "largest backward error {:.1e} over {} modes",
                max(&s.backward_errors),
                s.backward_errors.len()
            ),
            "reduction" => s.reduction.as_ref().map_or(String::new(), |r| {
                format!(
                    "reduced vs full real modes {:.1e}, static state {:.1e}",
                    r.mode_error, r.static_error
                )
            }),
            "transient" => s.transient.as_ref().map_or(String::new(), |t| {
                format!(
                    "{} steps, {:.2} iterations per step, {} step cuts, every step converged",
                    t.steps, t.mean_iterations, t.cuts
                )
            }),
            other if other.starts_with("complex modes (") => s
                .complex
                .iter()
                .find(|c| other.contains(c.route))
                .map_or(String::new(), |c| {
                    let b: Vec<f64> = c.modes.iter().map(|m| m.backward_error).collect();
                    format!("largest backward error {:.1e}", max(&b))
                }),
            _ => String::new(),
        }
    };
    let mut t = String::from(
        "<table class=\"run\"><tr><th>stage</th><th>time (s)</th><th>accuracy</th></tr>",
    );
    for (name, secs) in &s.timings.stages {
        let _ = write!(
            t,
            "<tr><td>{}</td><td>{secs:.3}</td><td>{}</td></tr>",
            escape(name),
            escape(&accuracy(name))
        );
    }
    let total: f64 = s.timings.stages.iter().map(|(_, x)| x).sum();
    let _ = write!(
        t,
        "<tr><th>all stages</th><th>{total:.3}</th><th>peak memory per rank {:.1} MiB</th></tr></table>",
        s.peak_memory_per_rank / (1024.0 * 1024.0)
    );
    t
}

/// The headline modes of the dynamic stability: at rest, along the run, how long unstable,
/// the mean Re(s) and, with the modal energies, how fast the mode's real mode grew in the run.
fn dynamic_stability_table(
    r: &crate::stages::link::DynamicStabilityReport,
    energy: Option<&crate::stages::link::ModalEnergyReport>,
) -> String {
    use crate::eigen::complex_modes::{damping_ratio, frequency_hz};
    let growth_header = energy.map_or(String::new(), |e| {
        let (a, b) = e.energy.growth_window;
        format!("<th>its real mode's growth in the run, {a:.4} to {b:.4} s (1/s)</th>")
    });
    let mut t = format!(
        "<table><tr><th>mode</th><th>at rest (Hz)</th><th>damping ratio at rest</th><th>frequency along the run (Hz)</th><th>damping ratio along the run</th><th>unstable (% of the time)</th><th>mean damping ratio</th><th>mean Re(s) (1/s)</th>{growth_header}</tr>",
    );
    for m in r.stability.tracks.iter().filter(|m| m.headline(r.margin)) {
        let along = &m.eigenvalue[1..];
        let span = |f: &dyn Fn((f64, f64)) -> f64| {
            along
                .iter()
                .map(|&s| f(s))
                .filter(|x| x.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                })
        };
        let (f0, f1) = span(&frequency_hz);
        let (z0, z1) = span(&damping_ratio);
        let rest = m.eigenvalue[0];
        let growth = match (energy, m.dominant_real_mode) {
            (Some(e), Some(k)) => format!("<td>R{}: {:.0}</td>", k + 1, e.energy.growth[k]),
            (Some(_), None) => "<td></td>".to_string(),
            _ => String::new(),
        };
        let _ = write!(
            t,
            "<tr{}><td>{}</td><td>{:.1}</td><td>{:.2e}</td><td>{f0:.1} .. {f1:.1}</td><td>{z0:.2e} .. {z1:.2e}</td><td>{:.0}</td><td>{:.2e}</td><td>{:.1}</td>{growth}</tr>",
            if m.mean_damping_ratio < -r.margin { " class=\"unstable\"" } else { "" },
            m.name,
            frequency_hz(rest),
            damping_ratio(rest),
            100.0 * m.unstable_fraction,
            m.mean_damping_ratio,
            m.mean_re_s
        );
    }
    t + "</table>"
}

/// Per studied mode: the amplitudes the pseudo trajectory finds and the transient's.
fn pseudo_table(p: &crate::stages::pseudo::PseudoReport) -> String {
    use crate::post::pseudo_trajectory::Found;
    let show = |x: &Found| match x {
        Found::At { alpha, .. } => format!("{alpha:.3e}"),
        Found::BelowRange => "below the range".into(),
        Found::AboveRange => "above the range".into(),
    };
    let mut t = String::from(
        "<table><tr><th>mode</th><th>frequency (Hz)</th><th>damping ratio</th><th>alpha_crit (m)</th><th>alpha_sat (m)</th><th>in the transient (m)</th><th>alpha_sat / transient</th><th>cost (s)</th></tr>",
    );
    for study in &p.studies {
        let m = &study.trajectory;
        let (transient, ratio) =
            study
                .transient
                .as_ref()
                .map_or(("-".to_string(), "-".to_string()), |tr| {
                    let ratio = m.alpha_sat.alpha().map_or(f64::NAN, |a| a / tr.mean);
                    (format!("{:.3e}", tr.mean), format!("{ratio:.3}"))
                });
        let _ = write!(
            t,
            "<tr><td>{}</td><td>{:.1}</td><td>{:.2e}</td><td>{}</td><td>{}</td><td>{transient}</td><td>{ratio}</td><td>{:.1}</td></tr>",
            m.name,
            crate::eigen::complex_modes::frequency_hz(m.nominal),
            crate::eigen::complex_modes::damping_ratio(m.nominal),
            show(&m.alpha_crit),
            show(&m.alpha_sat),
            m.seconds
        );
    }
    t + "</table>"
}

/// The "How loud" section: the levels per mode, the transient's bands, the summary's lines.
fn loudness_section(
    s: &RunSummary,
    l: &crate::stages::loudness::LoudnessReport,
    output: &Path,
) -> std::io::Result<String> {
    let mut body = String::new();
    if !l.modes.is_empty() {
        let caption = "Radiated sound power level (A-weighted) of each unstable mode at its predicted saturation amplitude and at 1 um of contact amplitude.";
        body += &figure(output, "loudness_modes.png", caption)?;
    }
    if l.transient.is_some() {
        let caption = "The transient's last cycles: radiated power in 1/3-octave bands.";
        body += &figure(output, "loudness_bands.png", caption)?;
    }
    body += &text(s, Part::Loudness);
    Ok(body)
}
