//! report.html's numbers against results.h5: the verdict's frequency, mode and level, and
//! every row of the complex-mode tables, each to the precision it is printed with.

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

/// Checks the report's complex-mode rows and verdict against results.h5; returns the number
/// of values compared.
pub fn check_report_numbers(results: &Path) -> usize {
    let html = std::fs::read_to_string(results.join("report.html")).unwrap();
    let file = hdf5::File::open(results.join("results.h5")).unwrap();
    let mut compared = 0;
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
