//! The complex modes of a brake against an independent dense solve (DESIGN.md §6, rung 6): not
//! the code against itself, but LAPACK's QZ algorithm (dggev) on the companion form of the
//! static state's linearization that `[output] export_matrices` writes: the mass M, the damping
//! C and the tangent K0 + K_c + K_stick + K_f (`K_tangent`), read back from the Matrix Market
//! files. QZ finds every eigenvalue at once (no shift, no Krylov space, no projection), so it
//! also checks that the full route missed none in its band.
//!
//! The companion pencil of (s^2 M + s C + K) x = 0, scaled so that its blocks have norm ~1
//! (s = gamma mu, gamma = sqrt(||K|| / ||M||), everything divided by ||K||; Fan, Lin & Van
//! Dooren, SIMAX 26, 2004), is A z = mu B z with A = [[0, I], [-K~, -C~]], B = [[I, 0], [0, M~]].
//! QZ is backward stable on it: its eigenvalues are exact for a pencil within ~n eps of it.
//!
//! Asserted: (1) the full route and QZ find the same number of modes below f_max, and each full
//! mode lies within its own bound of a QZ eigenvalue: kappa (eta_full + eta_qz), where eta_full
//! is the backward error the full route reports and eta_qz = 2 n eps is QZ's; kappa, the
//! eigenvalue's condition number, is bounded by 1e4 as long as the mode is not part of a
//! coalesced pair (then the square root of the backward error counts, as in complex_modes.rs).
//! (2) the projected route, whose basis truncation makes it an approximation, finds every QZ mode
//! below f_max within 1e-2 in frequency and with the same stability (the bound
//! complex_modes.rs derives for this basis), and no mode QZ does not have.
//! On 1 rank QZ runs and its eigenvalues are stored; on 2 and 4 ranks the routes (run there)
//! are compared with them.

use squeal::io::matrix_market;
use squeal::la::qz::generalized_eigenvalues;
use squeal::la::Petsc;
use squeal::measure::{exceeds, nan_max, nan_min};

use super::common::{say, suite_dir};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "small_brake_complex_modes_against_qz_of_the_exported_linearization",
        small_brake_against_qz,
    )]
}

const F_MAX_HZ: f64 = 4000.0;

fn scene(out: &str) -> String {
    format!(
        "[model]\nsource = \"brake\"\ncomponents = [\"disc\", \"inner_pad\", \"outer_pad\"]\n\
         target_dofs = 2400\npressure_bar = 20.0\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.6, slip_speed = 1.0e-3 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n\
         [real_modes]\ncount = 60\n\
         [complex_modes]\nmethod = \"both\"\nf_max_hz = {F_MAX_HZ}\n\
         [output]\ndirectory = \"{out}\"\nexport_matrices = [\"mtx\"]\n"
    )
}

fn small_brake_against_qz(petsc: &Petsc) -> Result<(), String> {
    let name = format!("dense-reference-{}", petsc.size());
    let out = suite_dir().join(&name);
    let text = scene(&out.display().to_string());
    let scene = squeal::scene::Scene::parse(&text, &name).map_err(|e| e.to_string())?;
    let run = squeal::pipeline::run(petsc, &scene, &text, std::path::Path::new("."), &out, &[])
        .map_err(|e| e.to_string())?;
    let route = |r: &str| {
        run.complex
            .iter()
            .find(|c| c.route == r)
            .map(|c| c.modes.clone())
            .ok_or(format!("no {r} route in the run"))
    };
    let (full, projected) = (route("full")?, route("projected")?);
    // QZ on rank 0 of the 1-rank run; its eigenvalues (Im > 0, below f_max) are the reference.
    let reference = if petsc.size() == 1 {
        let started = std::time::Instant::now();
        let (n, values) = qz_of_export(&out)?;
        say(
            petsc,
            &format!(
                "QZ on the companion form of order {}: {} eigenvalues below {F_MAX_HZ} Hz in {:.1} s",
                2 * n,
                values.len(),
                started.elapsed().as_secs_f64()
            ),
        );
        let row: Vec<String> = values
            .iter()
            .flat_map(|&(re, im)| [format!("{re:e}"), format!("{im:e}")])
            .collect();
        std::fs::write(stored_file(), format!("{}\n{n}\n", row.join(" ")))
            .map_err(|e| e.to_string())?;
        (n, values)
    } else {
        read_stored()?
    };
    compare(petsc, reference, &full, &projected)
}

fn stored_file() -> std::path::PathBuf {
    suite_dir().join("qz-eigenvalues-1-rank.txt")
}

/// The stored QZ eigenvalues of the 1-rank run and the order n of the model.
fn read_stored() -> Result<(usize, Vec<(f64, f64)>), String> {
    let file = stored_file();
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("{}: {e}: run the suite on 1 rank first", file.display()))?;
    let mut lines = text.lines();
    let parse = |l: &str| -> Vec<f64> {
        l.split_whitespace()
            .map(|x| x.parse().unwrap_or(f64::NAN))
            .collect()
    };
    let values = parse(lines.next().unwrap_or(""));
    let n = parse(lines.next().unwrap_or(""))
        .first()
        .copied()
        .unwrap_or(f64::NAN);
    if values.len() % 2 != 0 || n.is_nan() {
        return Err(format!("{}: malformed", file.display()));
    }
    Ok((n as usize, values.chunks(2).map(|c| (c[0], c[1])).collect()))
}

/// Reads M, C and K_tangent from the export, forms the scaled companion pencil and returns the
/// model's order and the eigenvalues s with 0 < Im(s) <= 2 pi f_max, ascending in Im.
fn qz_of_export(out: &std::path::Path) -> Result<(usize, Vec<(f64, f64)>), String> {
    let read = |name: &str| {
        let t = matrix_market::read(&out.join(format!("{name}.mtx"))).map_err(|e| e.to_string())?;
        let n = t.rows;
        let mut dense = vec![0.0; n * n];
        for (i, j, v) in t.expanded() {
            dense[i as usize + n * j as usize] += v;
        }
        Ok::<_, String>((n, dense))
    };
    let (n, m) = read("M")?;
    let (nc, c) = read("C")?;
    let (nk, k) = read("K_tangent")?;
    if nc != n || nk != n {
        return Err(format!("orders differ: M {n}, C {nc}, K_tangent {nk}"));
    }
    let norm = |a: &[f64]| {
        (0..n)
            .map(|i| (0..n).map(|j| a[i + n * j].abs()).sum::<f64>())
            .fold(0.0, nan_max)
    };
    let (nk_, nm_) = (norm(&k), norm(&m));
    let gamma = (nk_ / nm_).sqrt();
    let two = 2 * n;
    let (mut a, mut b) = (vec![0.0; two * two], vec![0.0; two * two]);
    for i in 0..n {
        a[i + two * (n + i)] = 1.0; // A[0, 1] = I
        b[i + two * i] = 1.0; // B[0, 0] = I
        for j in 0..n {
            a[(n + i) + two * j] = -k[i + n * j] / nk_;
            a[(n + i) + two * (n + j)] = -c[i + n * j] * gamma / nk_;
            b[(n + i) + two * (n + j)] = m[i + n * j] * gamma * gamma / nk_;
        }
    }
    let omega_max = 2.0 * std::f64::consts::PI * F_MAX_HZ;
    let mut values: Vec<(f64, f64)> = generalized_eigenvalues(two, a, b)?
        .into_iter()
        .map(|(re, im)| (re * gamma, im * gamma))
        .filter(|&(_, im)| im > 0.0 && im <= omega_max)
        .collect();
    values.sort_by(|x, y| x.1.total_cmp(&y.1));
    Ok((n, values))
}

fn compare(
    petsc: &Petsc,
    (n, qz): (usize, Vec<(f64, f64)>),
    full: &[squeal::eigen::complex_modes::ComplexMode],
    projected: &[squeal::eigen::complex_modes::ComplexMode],
) -> Result<(), String> {
    let nearest = |s: (f64, f64)| {
        qz.iter()
            .map(|q| (q.0 - s.0).hypot(q.1 - s.1) / q.0.hypot(q.1))
            .fold(f64::INFINITY, nan_min)
    };
    let in_band = |m: &&squeal::eigen::complex_modes::ComplexMode| m.frequency_hz <= F_MAX_HZ;
    let full: Vec<_> = full.iter().filter(in_band).collect();
    let projected: Vec<_> = projected.iter().filter(in_band).collect();
    if full.len() != qz.len() {
        return Err(format!(
            "{} full-route modes below {F_MAX_HZ} Hz, QZ finds {}",
            full.len(),
            qz.len()
        ));
    }
    let eta_qz = 2.0 * (2 * n) as f64 * f64::EPSILON;
    let (mut worst_full, mut worst_ratio) = (0.0f64, 0.0f64);
    for m in &full {
        let d = nearest(m.eigenvalue);
        let paired = full.iter().any(|o| {
            o.name != m.name
                && (o.frequency_hz - m.frequency_hz).abs() <= 1e-3 * m.frequency_hz
                && o.damping_ratio * m.damping_ratio < 0.0
        });
        let eta = m.backward_error + eta_qz;
        let bound = if paired { 1e2 * eta.sqrt() } else { 1e4 * eta };
        worst_full = nan_max(worst_full, d);
        worst_ratio = nan_max(worst_ratio, d / bound);
        if exceeds(d, bound) {
            return Err(format!(
                "full route {} at {:.3} Hz: {d:.2e} from the nearest QZ eigenvalue (bound {bound:.1e})",
                m.name, m.frequency_hz
            ));
        }
    }
    let mut worst_projected = 0.0f64;
    for q in &qz {
        let f = q.1 / (2.0 * std::f64::consts::PI);
        let partner = projected
            .iter()
            .min_by(|a, b| {
                (a.frequency_hz - f)
                    .abs()
                    .total_cmp(&(b.frequency_hz - f).abs())
            })
            .ok_or("no projected modes")?;
        let d = (partner.frequency_hz - f).abs() / f;
        worst_projected = nan_max(worst_projected, d);
        if exceeds(d, 1e-2) || (partner.unstable != (q.0 > 0.0)) {
            return Err(format!(
                "QZ mode at {f:.3} Hz (Re {:.3e}): projected partner {} at {:.3} Hz, {d:.2e} off, unstable {}",
                q.0, partner.name, partner.frequency_hz, partner.unstable
            ));
        }
    }
    if projected.len() != qz.len() {
        return Err(format!(
            "{} projected modes below {F_MAX_HZ} Hz, QZ finds {}",
            projected.len(),
            qz.len()
        ));
    }
    say(
        petsc,
        &format!(
            "{} modes below {F_MAX_HZ} Hz ({} unstable): full route within {worst_full:.1e} of QZ ({worst_ratio:.1e} of its bound), projected within {worst_projected:.1e} in frequency",
            qz.len(),
            qz.iter().filter(|q| q.0 > 0.0).count()
        ),
    );
    Ok(())
}
