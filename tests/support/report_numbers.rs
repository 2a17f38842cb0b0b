//! report.html's numbers against results.h5, each to the precision it is printed with: the
//! verdict's frequency, mode and level, and every row of the real-mode, complex-mode,
//! dynamic-stability, pseudo-trajectory and timing tables.

use std::path::Path;

/// |printed - value| within half a unit of the printed last digit (plus round-off); false on
/// NaN.
fn agrees(printed: &str, value: f64) -> bool {
    let Ok(p) = printed.trim().parse::<f64>() else {
        return false;
    };
    let half_unit = match printed.split_once(['e', 'E']) {
        // d.ddde-x: half a unit of the mantissa's last digit, scaled by the exponent.
        Some((mantissa, exponent)) => {
            let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len());
            let exponent: i32 = exponent.parse().unwrap_or(0);
            0.5 * 10f64.powi(exponent - decimals as i32)
        }
        None => {
            let decimals = printed.trim().split_once('.').map_or(0, |(_, d)| d.len());
            0.5 * 10f64.powi(-(decimals as i32))
        }
    };
    (p - value).abs() <= half_unit * (1.0 + 1e-9) + 1e-12 * value.abs()
}

fn table(file: &hdf5::File, path: &str) -> Vec<f64> {
    file.dataset(path)
        .unwrap_or_else(|e| panic!("results.h5: {path}: {e}"))
        .read_raw::<f64>()
        .unwrap()
}

/// The cells of the table rows of `html` whose first cell is a mode name `C<k>`.
fn mode_rows(html: &str) -> Vec<Vec<String>> {
    html.split("<tr")
        .skip(1)
        .filter_map(|row| {
            let row = row.split("</tr>").next()?;
            let cells: Vec<String> = row
                .split("<td>")
                .skip(1)
                .map(|c| c.split("</td>").next().unwrap_or("").to_string())
                .collect();
            let first = cells.first()?;
            let is_mode = first.len() > 1
                && first.starts_with('C')
                && first[1..].chars().all(|c| c.is_ascii_digit());
            is_mode.then_some(cells)
        })
        .collect()
}

/// A table of the report: its header cells and its rows' cells (`<td>` and `<th>` alike).
struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<String>>,
}

fn cells(row: &str) -> Vec<String> {
    row.split("<t")
        .skip(1)
        .filter_map(|c| {
            let (tag, rest) = c.split_once('>')?;
            let is_cell = tag.starts_with('d') || tag.starts_with('h');
            let text = rest.split("</t").next().unwrap_or("");
            is_cell.then(|| text.to_string())
        })
        .collect()
}

fn tables(html: &str) -> Vec<Table> {
    html.split("<table")
        .skip(1)
        .map(|t| {
            let t = t.split("</table>").next().unwrap_or("");
            let mut rows = t.split("<tr").skip(1).map(|r| {
                let r = r.split_once('>').map_or("", |(_, rest)| rest);
                cells(r.split("</tr>").next().unwrap_or(""))
            });
            let headers = rows.next().unwrap_or_default();
            Table {
                headers,
                rows: rows.collect(),
            }
        })
        .collect()
}

/// The one table whose header starts with `first` and has a column `column`.
fn table_with<'t>(all: &'t [Table], first: &str, column: &str) -> &'t Table {
    let found: Vec<&Table> = all
        .iter()
        .filter(|t| t.headers.first().is_some_and(|h| h == first))
        .filter(|t| t.headers.iter().any(|h| h.starts_with(column)))
        .collect();
    assert_eq!(
        found.len(),
        1,
        "report.html: tables [{first}, .., {column}, ..]"
    );
    found[0]
}

fn attr(file: &hdf5::File, group: &str, name: &str) -> f64 {
    file.group(group)
        .and_then(|g| g.attr(name))
        .and_then(|a| a.read_scalar::<f64>())
        .unwrap_or_else(|e| panic!("results.h5: {group} @{name}: {e}"))
}

fn check(what: &str, printed: &str, value: f64) {
    assert!(
        agrees(printed, value),
        "report.html {what}: {printed}, results.h5 {value}"
    );
}

/// The real modes: frequency, residual and backward error of each.
fn check_real_modes(all: &[Table], file: &hdf5::File) -> usize {
    let t = table_with(all, "mode", "||K phi");
    let frequency = table(file, "modes/real/frequency");
    let residual = table(file, "modes/real/residual_norm");
    let backward = table(file, "modes/real/backward_error");
    for row in &t.rows {
        let i = mode_number(&row[0], 'R') - 1;
        check(&format!("{} frequency", row[0]), &row[1], frequency[i]);
        check(&format!("{} residual", row[0]), &row[2], residual[i]);
        check(&format!("{} backward error", row[0]), &row[3], backward[i]);
    }
    assert_eq!(t.rows.len(), frequency.len(), "a row per real mode");
    3 * t.rows.len()
}

fn mode_number(name: &str, letter: char) -> usize {
    name.strip_prefix(letter)
        .and_then(|k| k.parse().ok())
        .unwrap_or_else(|| panic!("{name}: not a mode name {letter}<k>"))
}

/// Smallest and largest finite value of `v`.
fn span(v: &[f64]) -> (f64, f64) {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    assert!(!finite.is_empty(), "no finite value");
    let lo = finite
        .iter()
        .copied()
        .fold(f64::INFINITY, |a, x| if x < a { x } else { a });
    let hi = finite
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, |a, x| if x > a { x } else { a });
    (lo, hi)
}

/// The dynamic stability's headline modes: at rest, the ranges along the run, the time
/// unstable, the means, and the growth of the mode's real mode in the run.
fn check_dynamic_stability(all: &[Table], file: &hdf5::File) -> usize {
    let t = table_with(all, "mode", "at rest (Hz)");
    let growth = table(file, "post/modal_energy/growth_rate");
    let energy_modes = table(file, "post/modal_energy/mode");
    let mut compared = 0;
    for row in &t.rows {
        let name = &row[0];
        let g = format!("post/dynamic_stability/modes/{name}");
        let frequency = table(file, &format!("{g}/frequency"));
        let zeta = table(file, &format!("{g}/damping_ratio"));
        check(&format!("{name} at rest"), &row[1], frequency[0]);
        check(&format!("{name} zeta at rest"), &row[2], zeta[0]);
        for (column, values) in [(3, &frequency), (4, &zeta)] {
            let (lo, hi) = span(&values[1..]);
            let (a, b) = row[column].split_once(" .. ").expect("a range a .. b");
            check(&format!("{name} lowest along the run"), a, lo);
            check(&format!("{name} highest along the run"), b, hi);
        }
        let fraction = attr(file, &g, "unstable_fraction");
        check(&format!("{name} unstable %"), &row[5], 100.0 * fraction);
        check(
            &format!("{name} mean zeta"),
            &row[6],
            attr(file, &g, "mean_damping_ratio"),
        );
        check(
            &format!("{name} mean Re(s)"),
            &row[7],
            attr(file, &g, "mean_re_s"),
        );
        compared += 9;
        if let Some((real, rate)) = row.get(8).and_then(|c| c.split_once(": ")) {
            let k = mode_number(real, 'R');
            assert_eq!(
                attr(file, &g, "dominant_real_mode"),
                k as f64,
                "{name}'s real mode"
            );
            let i = energy_modes
                .iter()
                .position(|&m| m == k as f64)
                .expect("R<k> in the energies");
            check(&format!("{name} growth of {real}"), rate, growth[i]);
            compared += 1;
        }
    }
    assert!(
        !t.rows.is_empty(),
        "headline modes of the dynamic stability"
    );
    compared
}

/// The pseudo trajectories: per studied mode, its frequency and damping at rest, alpha_crit,
/// alpha_sat, the transient's amplitude and their ratio. (Its cost column is the study's wall
/// time, which results.h5 holds only in parts.)
fn check_pseudo(all: &[Table], file: &hdf5::File) -> usize {
    let t = table_with(all, "mode", "alpha_crit (m)");
    for row in &t.rows {
        let name = &row[0];
        let g = format!("post/pseudo_trajectory/{name}");
        let (re, im) = (
            attr(file, &g, "nominal_re_s"),
            attr(file, &g, "nominal_im_s"),
        );
        let frequency = im / (2.0 * std::f64::consts::PI);
        check(&format!("{name} frequency"), &row[1], frequency);
        check(
            &format!("{name} zeta"),
            &row[2],
            -re / (re * re + im * im).sqrt(),
        );
        let sat = attr(file, &g, "alpha_sat_m");
        let ratio = attr(file, &g, "alpha_sat_over_transient");
        check(
            &format!("{name} alpha_crit"),
            &row[3],
            attr(file, &g, "alpha_crit_m"),
        );
        check(&format!("{name} alpha_sat"), &row[4], sat);
        check(&format!("{name} in the transient"), &row[5], sat / ratio);
        check(&format!("{name} alpha_sat / transient"), &row[6], ratio);
    }
    assert!(!t.rows.is_empty(), "a studied mode");
    6 * t.rows.len()
}

/// The stage timings: each stage against /timings, and the total against their sum.
fn check_timings(all: &[Table], file: &hdf5::File) -> usize {
    let t = table_with(all, "stage", "time (s)");
    let mut sum = 0.0;
    for row in &t.rows {
        if row[0] == "all stages" {
            check("all stages", &row[1], sum);
            continue;
        }
        let seconds = attr(file, "timings", &row[0].replace(' ', "_"));
        check(&format!("stage {}", row[0]), &row[1], seconds);
        sum += seconds;
    }
    t.rows.len()
}

/// Checks the report's tables and verdict against results.h5; returns the number of values
/// compared.
pub fn check_report_numbers(results: &Path) -> usize {
    let html = std::fs::read_to_string(results.join("report.html")).unwrap();
    let file = hdf5::File::open(results.join("results.h5")).unwrap();
    let all = tables(&html);
    let mut compared = check_real_modes(&all, &file)
        + check_dynamic_stability(&all, &file)
        + check_pseudo(&all, &file)
        + check_timings(&all, &file);
    // The complex-mode tables, one paragraph "<route> route..." before each route's tables.
    for part in html.split("<p>").skip(1) {
        let Some(route) = ["projected", "full"]
            .into_iter()
            .find(|r| part.starts_with(&format!("{r} route")))
        else {
            continue;
        };
        let group = format!("modes/complex/{route}");
        let frequency = table(&file, &format!("{group}/frequency"));
        let zeta = table(&file, &format!("{group}/damping_ratio"));
        let re_s = table(&file, &format!("{group}/eigenvalue_real"));
        let section = part.split("</details>").next().unwrap();
        for cells in mode_rows(section) {
            let k: usize = cells[0][1..].parse().unwrap();
            let i = k - 1;
            for (what, printed, value) in [
                ("frequency", &cells[1], frequency[i]),
                ("damping ratio", &cells[2], zeta[i]),
                ("Re(s)", &cells[3], re_s[i]),
            ] {
                assert!(
                    agrees(printed, value),
                    "report.html {route} {}: {what} {printed}, results.h5 {value}",
                    cells[0]
                );
                compared += 1;
            }
        }
    }
    // The verdict: "squeals: yes, 2.91 kHz, mode C35 (...), ..., 124.5 dB(A) sound power from
    // the saturated vibration".
    let verdict = html
        .split("squeals: ")
        .nth(1)
        .and_then(|v| v.split('<').next())
        .expect("a verdict in report.html");
    let words: Vec<&str> = verdict.split_whitespace().collect();
    let khz = words[1];
    let mode = words[4].trim_end_matches(',');
    let k: usize = mode[1..].parse().expect("mode C<k>");
    let frequency = table(&file, "modes/complex/projected/frequency");
    assert!(
        agrees(khz, frequency[k - 1] / 1e3),
        "verdict {khz} kHz, results.h5 {mode} {} Hz",
        frequency[k - 1]
    );
    // The verdict's mode is the most unstable one (largest growth rate of the unstable).
    let re_s = table(&file, "modes/complex/projected/eigenvalue_real");
    let unstable = table(&file, "modes/complex/projected/unstable");
    let most = (0..re_s.len())
        .filter(|&i| unstable[i] > 0.5)
        .max_by(|&a, &b| re_s[a].total_cmp(&re_s[b]))
        .unwrap();
    assert_eq!(k - 1, most, "verdict {mode}, most unstable C{}", most + 1);
    let level = words
        .iter()
        .position(|w| *w == "dB(A)")
        .map(|i| words[i - 1])
        .expect("a level in the verdict");
    let transient = file.group("post/loudness/transient").unwrap();
    let a_level: f64 = transient.attr("level_a_db").unwrap().read_scalar().unwrap();
    assert!(
        agrees(level, a_level),
        "verdict {level} dB(A), results.h5 {a_level}"
    );
    compared + 3
}

#[test]
fn printed_values_agree_to_their_last_digit() {
    assert!(agrees("2910.55", 2910.553));
    assert!(!agrees("2910.55", 2910.56));
    assert!(agrees("-1.860e-2", -0.018604));
    assert!(!agrees("-1.860e-2", -0.01862));
    assert!(!agrees("1.0", f64::NAN));
}
