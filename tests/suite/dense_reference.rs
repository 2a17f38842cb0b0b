//! The complex modes of a brake against an independent dense solve (DESIGN.md §6, rung 6): not
//! the code against itself, but LAPACK (Cholesky of M, then dgeev on the scaled companion form;
//! `la::dense_quadratic`) on the static state's linearization that `[output] export_matrices`
//! writes: the mass M, the damping C and the tangent K0 + K_c + K_stick + K_f (`K_tangent`),
//! read back from the Matrix Market files. The dense solve finds every eigenvalue at once (no
//! shift, no Krylov space, no projection), so it also checks that the full route missed none
//! in its band. It is backward stable on the scaled companion matrix: its eigenvalues are exact
//! for a matrix within ~n eps of it.
//!
//! Asserted: (1) the full route and the dense solve find the same number of modes below f_max,
//! and each full mode lies within kappa (eta_full + eta_dense) of a dense eigenvalue, where
//! eta_full is the backward error the full route reports, eta_dense = 2 (2n) eps the dense
//! solve's, and kappa the eigenvalue's condition number. kappa is not computed here (it needs
//! left eigenvectors): 1e4 is assumed for a mode away from coalescence, where the friction's
//! non-normality is mild; for a member of a coalesced pair (frequencies within 1e-3, damping of
//! opposite sign) the eigenvalue moves with the square root of a perturbation, so
//! 1e2 sqrt(eta). (2) The projected route, whose basis truncation makes it an approximation,
//! has for every dense mode below f_max a partner (nearest in the complex plane) within 1e-2 of
//! |s| and of the same stability (the frequency bound complex_modes.rs uses for a basis of
//! this size), and no mode more.
//! On 1 rank the dense solve runs and its eigenvalues are stored; on 2 and 4 ranks the routes
//! (run there) are compared with them.
//!
//! Measured (disc and pads, 2,032 free DOF, mu 0.6, 31 modes below 10 kHz, one unstable pair
//! member at 4,846 Hz): dense solve 26 s on one core; full route within 3.4e-11 of it (2e-3 of
//! its bound), projected route within 5.3e-4.

use super::TestResult;
use squeal::io::matrix_market;
use squeal::la::dense_quadratic::quadratic_eigenvalues;
use squeal::la::Petsc;
use squeal::measure::{exceeds, nan_max, nan_min};

use super::common::{say, suite_dir};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "small_brake_complex_modes_against_a_dense_solve_of_the_exported_linearization",
        small_brake_against_dense,
    )]
}

const F_MAX_HZ: f64 = 10000.0;

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

fn small_brake_against_dense(petsc: &Petsc) -> TestResult {
    let name = format!("dense-reference-{}", petsc.size());
    let out = suite_dir().join(&name);
    let text = scene(&out.display().to_string());
    let scene = squeal::scene::Scene::parse(&text, &name)?;
    let run = squeal::pipeline::run(petsc, &scene, &text, std::path::Path::new("."), &out, &[])?;
    let route = |r: &str| {
        run.complex
            .iter()
            .find(|c| c.route == r)
            .map(|c| c.modes.clone())
            .ok_or(format!("no {r} route in the run"))
    };
    let (full, projected) = (route("full")?, route("projected")?);
    // The dense solve on rank 0 of the 1-rank run; its eigenvalues (Im > 0, below f_max) are the reference.
    let reference = if petsc.size() == 1 {
        let started = std::time::Instant::now();
        let (n, values) = dense_of_export(&out)?;
        say(
            petsc,
            &format!(
                "dense solve of the companion form of order {}: {} eigenvalues below {F_MAX_HZ} Hz in {:.1} s",
                2 * n,
                values.len(),
                started.elapsed().as_secs_f64()
            ),
        );
        let row: Vec<String> = values
            .iter()
            .flat_map(|&(re, im)| [format!("{re:e}"), format!("{im:e}")])
            .collect();
        std::fs::write(stored_file(), format!("{}\n{n}\n", row.join(" ")))?;
        (n, values)
    } else {
        read_stored()?
    };
    compare(petsc, reference, &full, &projected)
}

fn stored_file() -> std::path::PathBuf {
    suite_dir().join("dense-eigenvalues-1-rank.txt")
}

/// The stored dense eigenvalues of the 1-rank run and the order n of the model.
fn read_stored() -> TestResult<(usize, Vec<(f64, f64)>)> {
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
    if !values.len().is_multiple_of(2) || n.is_nan() {
        return Err(format!("{}: malformed", file.display()).into());
    }
    Ok((n as usize, values.chunks(2).map(|c| (c[0], c[1])).collect()))
}

/// Reads M, C and K_tangent from the export, forms the scaled companion pencil and returns the
/// model's order and the eigenvalues s with 0 < Im(s) <= 2 pi f_max, ascending in Im.
fn dense_of_export(out: &std::path::Path) -> TestResult<(usize, Vec<(f64, f64)>)> {
    let read = |name: &str| -> TestResult<_> {
        let t = matrix_market::read(&out.join(format!("{name}.mtx")))?;
        let n = t.rows;
        let mut dense = vec![0.0; n * n];
        for (i, j, v) in t.expanded() {
            dense[i as usize + n * j as usize] += v;
        }
        Ok((n, dense))
    };
    let (n, m) = read("M")?;
    let (nc, c) = read("C")?;
    let (nk, k) = read("K_tangent")?;
    if nc != n || nk != n {
        return Err(format!("orders differ: M {n}, C {nc}, K_tangent {nk}").into());
    }
    let omega_max = 2.0 * std::f64::consts::PI * F_MAX_HZ;
    let mut values: Vec<(f64, f64)> = quadratic_eigenvalues(n, &k, &c, &m)?
        .into_iter()
        .filter(|&(_, im)| im > 0.0 && im <= omega_max)
        .collect();
    values.sort_by(|x, y| x.1.total_cmp(&y.1));
    Ok((n, values))
}

fn compare(
    petsc: &Petsc,
    (n, dense): (usize, Vec<(f64, f64)>),
    full: &[squeal::eigen::complex_modes::ComplexMode],
    projected: &[squeal::eigen::complex_modes::ComplexMode],
) -> TestResult {
    let nearest = |s: (f64, f64)| {
        dense
            .iter()
            .map(|q| (q.0 - s.0).hypot(q.1 - s.1) / q.0.hypot(q.1))
            .fold(f64::INFINITY, nan_min)
    };
    let in_band = |m: &&squeal::eigen::complex_modes::ComplexMode| m.frequency_hz <= F_MAX_HZ;
    let full: Vec<_> = full.iter().filter(in_band).collect();
    let projected: Vec<_> = projected.iter().filter(in_band).collect();
    if full.len() != dense.len() {
        return Err(format!(
            "{} full-route modes below {F_MAX_HZ} Hz, the dense solve finds {}",
            full.len(),
            dense.len()
        )
        .into());
    }
    let eta_dense = 2.0 * (2 * n) as f64 * f64::EPSILON;
    let (mut worst_full, mut worst_ratio) = (0.0f64, 0.0f64);
    for m in &full {
        let d = nearest(m.eigenvalue);
        let paired = full.iter().any(|o| {
            o.name != m.name
                && (o.frequency_hz - m.frequency_hz).abs() <= 1e-3 * m.frequency_hz
                && o.damping_ratio * m.damping_ratio < 0.0
        });
        let eta = m.backward_error + eta_dense;
        let bound = if paired { 1e2 * eta.sqrt() } else { 1e4 * eta };
        worst_full = nan_max(worst_full, d);
        worst_ratio = nan_max(worst_ratio, d / bound);
        if exceeds(d, bound) {
            return Err(format!(
                "full route {} at {:.3} Hz: {d:.2e} from the nearest dense eigenvalue (bound {bound:.1e})",
                m.name, m.frequency_hz
            ).into());
        }
    }
    // The projected route against the dense one, partner by partner: nearest in the complex
    // plane (a flutter pair has two members at nearly the same frequency).
    let mut worst_projected = 0.0f64;
    for q in &dense {
        let f = q.1 / (2.0 * std::f64::consts::PI);
        let distance = |m: &&&squeal::eigen::complex_modes::ComplexMode| {
            (m.eigenvalue.0 - q.0).hypot(m.eigenvalue.1 - q.1) / q.0.hypot(q.1)
        };
        let partner = projected
            .iter()
            .min_by(|a, b| distance(a).total_cmp(&distance(b)))
            .ok_or("no projected modes")?;
        let d = distance(&partner);
        worst_projected = nan_max(worst_projected, d);
        if exceeds(d, 1e-2) || (partner.unstable != (q.0 > 0.0)) {
            return Err(format!(
                "dense mode at {f:.3} Hz (Re {:.3e}): projected partner {} at {:.3} Hz (Re {:.3e}), {d:.2e} off, unstable {}",
                q.0, partner.name, partner.frequency_hz, partner.eigenvalue.0, partner.unstable
            ).into());
        }
    }
    if projected.len() != dense.len() {
        return Err(format!(
            "{} projected modes below {F_MAX_HZ} Hz, the dense solve finds {}",
            projected.len(),
            dense.len()
        )
        .into());
    }
    say(
        petsc,
        &format!(
            "{} modes below {F_MAX_HZ} Hz ({} unstable): full route within {worst_full:.1e} of the dense solve ({worst_ratio:.1e} of its bound), projected within {worst_projected:.1e} (relative distance in s)",
            dense.len(),
            dense.iter().filter(|q| q.0 > 0.0).count()
        ),
    );
    Ok(())
}
