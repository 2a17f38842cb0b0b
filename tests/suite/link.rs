//! The time/frequency link (DESIGN.md §2b): modal sensors and dynamic stability along a
//! trajectory.
//!
//! - Modal energies of an exact free vibration: q(t) = q_s + sum_k a_k phi_k cos(w_k t + p_k)
//!   solves M q'' + K (q - q_s) = 0 exactly, so E_k = a_k^2 w_k^2 / 2 at every time (closed
//!   form) and sum_k E_k = v'Mv/2 + (q - q_s)'K(q - q_s)/2 (energy identity), up to the
//!   modes' own orthogonality error d (measured here), bounded by 4 m d E for m modes (plus
//!   16 eps); the identity also carries the round-off of dq'K dq, eps sqrt(n) ||K||_inf
//!   ||dq||^2 (its terms dwarf the energy: K's largest eigenvalues sit far above the modes').
//! - Dynamic stability at rest: a transient started at the static state stays there, so the
//!   linearization at every stored state is the nominal one: each tracked mode equals the
//!   nominal projected complex mode of the same name (the complex-modes stage) at every time,
//!   to the drift of the state (< 1e-8 relative, see brake_transient_at_rest) times the
//!   tangent's sensitivity: asserted 1e-7 relative on s; and the 2-rank run's tracked
//!   eigenvalues against the 1-rank run's (1e-9 of |s|).
//! - Dynamic stability along a prescribed cycle of the 2-DOF mode-coupling model (Hoffmann et
//!   al. 2002, `mode_coupling.rs`; its tangent through squeal's contact point kernel as in
//!   `pseudo_trajectory.rs`): q = (x_s + a cos t, b sin t), v = q' w, two periods at 64 phases,
//!   b = 6 so that the mass leaves the belt (N = e^-y < 1 % of N0 for y > 4.6) on part of the
//!   cycle and presses into it (N up to e^6) on another. The belt's speed V = 100 saturates the
//!   friction's tanh (|x'| <= a w = 0.7), so its speed derivative is 0 in double precision and
//!   the frozen system is s^2 + c s + K_t(t) with K_t = K_s + [[0, mu k_c], [0, k_c]],
//!   k_c = e^-y: s = -c/2 +- sqrt(c^2/4 - kappa), kappa = tr/2 +- sqrt(tr^2/4 - det) of K_t
//!   (closed form, K_t from the state alone). Asserted: at every phase the linearization's two
//!   eigenvalues (Im > 0) are the closed form's to 1e-10 relative (dgeev on a 4 x 4 companion, entries O(e^6):
//!   backward error O(100 eps) relative to them); the flutter mode unstable at rest is
//!   followed through all 128 phases without a loss, is stable wherever the contact is open
//!   (the separated point adds no stiffness: K_t -> K_s, whose modes are damped by c/2), so
//!   its unstable fraction lies strictly between 0 and 1, and its mean damping ratio is the
//!   mean over the phases of its (closed-form, as above) damping ratios, to round-off.

use super::TestResult;
use squeal::eigen::real_modes::RealModeRequest;
use squeal::la::{Petsc, Vector};
use squeal::measure::{nan_max, nan_min};
use squeal::mesh::structured::block;
use squeal::mesh::Clamp;
use squeal::mesh::ElementKind;
use squeal::post::modal_energy::{modal_energy, ModalEnergySettings, ModalSensors};

use super::common::{one_rank_values, say, solve_modes, steel, suite_dir};

pub fn tests() -> Vec<super::NamedTest> {
    vec![
        (
            "modal_energies_of_a_free_vibration_are_its_closed_form_and_sum_to_the_mechanical_energy",
            modal_energy_identity,
        ),
        (
            "dynamic_stability_at_rest_is_the_nominal_projected_complex_modes",
            dynamic_stability_at_rest,
        ),
        (
            "hoffmann_dynamic_stability_along_a_separating_cycle_is_the_frozen_closed_form",
            hoffmann_frozen_closed_form,
        ),
    ]
}

type Cx = (f64, f64);

fn csqrt((a, b): Cx) -> Cx {
    let r = (a * a + b * b).sqrt();
    let re = nan_max(0.5 * (r + a), 0.0).sqrt();
    let im = nan_max(0.5 * (r - a), 0.0).sqrt();
    (re, if b < 0.0 { -im } else { im })
}

/// The roots s (Im > 0) of det(s^2 I + s c I + K) = 0 for a 2 x 2 K (column-major).
fn frozen_roots(k: &[f64], c: f64) -> Vec<Cx> {
    let (tr, det) = (k[0] + k[3], k[0] * k[3] - k[1] * k[2]);
    let d = csqrt((tr * tr / 4.0 - det, 0.0));
    let mut roots = Vec::new();
    for kappa in [(tr / 2.0 + d.0, d.1), (tr / 2.0 - d.0, -d.1)] {
        let r = csqrt((c * c / 4.0 - kappa.0, -kappa.1));
        for s in [(-c / 2.0 + r.0, r.1), (-c / 2.0 - r.0, -r.1)] {
            if s.1 > 0.0 {
                roots.push(s);
            }
        }
    }
    roots.sort_by(|a, b| a.1.total_cmp(&b.1));
    roots
}

fn hoffmann_frozen_closed_form(petsc: &Petsc) -> TestResult {
    use super::mode_coupling::{static_x, C, K_S, MU};
    use super::pseudo_trajectory::Hoffmann;
    use squeal::eigen::complex_modes::{damping_ratio, projected_coordinates};
    use squeal::post::dynamic_stability::tracked_modes;
    let (a, b, w, phases) = (0.5, 6.0, 1.4, 64);
    let mut states = vec![([static_x(), 0.0], [0.0, 0.0])];
    for k in 0..2 * phases {
        let t = 2.0 * std::f64::consts::PI * k as f64 / phases as f64;
        let q = [static_x() + a * t.cos(), b * t.sin()];
        states.push((q, [-a * w * t.sin(), b * w * t.cos()]));
    }
    let (mut points, mut closed, mut open) = (Vec::new(), Vec::new(), Vec::new());
    for (q, v) in &states {
        let lin = Hoffmann.tangent(*q, *v);
        if lin.cp[0] != C || lin.cp[1] != 0.0 || lin.cp[2] != 0.0 || lin.cp[3] != C {
            return Err(format!("the damping is not c I: {:?}", lin.cp).into());
        }
        let pairs = projected_coordinates(2, &lin.kp, &lin.cp)?;
        // The frozen tangent from the state alone: k_c = lambda N0 e^(-lambda y) = e^-y.
        let kc = (-q[1]).exp();
        let frozen = [K_S[0][0], K_S[1][0], K_S[0][1] + MU * kc, K_S[1][1] + kc];
        let exact = frozen_roots(&frozen, C);
        let found: Vec<Cx> = pairs.iter().map(|p| p.0).filter(|s| s.1 > 0.0).collect();
        let scale = exact.iter().map(|s| s.0.hypot(s.1)).fold(0.0, nan_max);
        // As sets: a flutter pair shares its imaginary part.
        let nearest = |x: &Cx, to: &[Cx]| {
            to.iter()
                .map(|e| (x.0 - e.0).hypot(x.1 - e.1) / scale)
                .fold(f64::INFINITY, nan_min)
        };
        let error = found
            .iter()
            .map(|f| nearest(f, &exact))
            .chain(exact.iter().map(|e| nearest(e, &found)))
            .fold(0.0, nan_max);
        if found.len() != 2 || exact.len() != 2 || error.is_nan() || error > 1e-10 {
            return Err(format!(
                "at q = {q:?}: linearization {found:?} vs closed form {exact:?} ({error:.1e})"
            )
            .into());
        }
        points.push(pairs);
        closed.push(exact);
        open.push(lin.fractions[0] == 1.0);
    }
    let gap: Vec<f64> = states[1..].iter().map(|(q, _)| q[1]).collect();
    let (tracks, _, lost) = tracked_modes(&points, &gap, 1e-9);
    let flutter = tracks
        .iter()
        .find(|t| damping_ratio(t.eigenvalue[0]) < -1e-9)
        .ok_or("no mode unstable at rest")?;
    let along = &flutter.eigenvalue[1..];
    if lost > 0 || along.iter().any(|s| !s.0.is_finite()) {
        return Err(format!("{lost} tracks lost").into());
    }
    let open_phases = open[1..].iter().filter(|&&o| o).count();
    let unstable_when_open = along
        .iter()
        .zip(&open[1..])
        .filter(|(s, &o)| o && damping_ratio(**s) <= 0.0)
        .count();
    let mean: f64 = along.iter().map(|&s| damping_ratio(s)).sum::<f64>() / along.len() as f64;
    say(
        petsc,
        &format!(
            "2-DOF along a separating cycle: open at {open_phases} of {} phases; {} unstable {:.0} % of them, mean damping ratio {:.3e}",
            along.len(),
            flutter.name,
            100.0 * flutter.unstable_fraction,
            flutter.mean_damping_ratio
        ),
    );
    if open_phases == 0 || unstable_when_open > 0 {
        return Err(format!(
            "open at {open_phases} phases, unstable at {unstable_when_open} of them"
        )
        .into());
    }
    let fraction = flutter.unstable_fraction;
    if fraction.is_nan() || fraction <= 0.0 || fraction >= 1.0 {
        return Err(format!("unstable fraction {fraction}").into());
    }
    let difference = (flutter.mean_damping_ratio - mean).abs();
    if difference.is_nan() || difference > 1e-12 {
        return Err(format!("mean damping {} vs {mean}", flutter.mean_damping_ratio).into());
    }
    Ok(())
}

fn modal_energy_identity(petsc: &Petsc) -> TestResult {
    let mesh = block([1.0, 0.1, 0.05], [20, 2, 2], ElementKind::Hex8I, steel());
    let request = RealModeRequest {
        count: 6,
        ..Default::default()
    };
    let (system, modes) = solve_modes(petsc, &mesh, &[Clamp::all("u0")], &request)?;
    let (k, m) = (&system.stiffness, &system.mass);
    let n = modes.shapes.len();
    let omega: Vec<f64> = modes.eigenvalues.iter().map(|l| l.sqrt()).collect();
    // The modes' orthogonality error: max |Phi'M Phi - I|, |Phi'K Phi - W^2| / w_max^2.
    let mut mass_shapes = Vec::new();
    let mut d = 0.0f64;
    let mut y = modes.shapes[0].duplicate()?;
    for (j, phi) in modes.shapes.iter().enumerate() {
        let mut w = phi.duplicate()?;
        m.mult(phi, &mut w)?;
        k.mult(phi, &mut y)?;
        for (i, psi) in modes.shapes.iter().enumerate() {
            let eye = f64::from(u8::from(i == j));
            d = nan_max(d, (psi.dot(&w)? - eye).abs());
            let kij = psi.dot(&y)? - eye * omega[j].powi(2);
            d = nan_max(d, kij.abs() / omega[n - 1].powi(2));
        }
        mass_shapes.push(w);
    }
    // An arbitrary static offset and vibration: amplitudes a_k, phases p_k.
    let mut q_static = modes.shapes[0].duplicate()?;
    {
        let range = q_static.ownership();
        let mut l = q_static.local_mut()?;
        for (i, x) in l.iter_mut().enumerate() {
            *x = 1e-4 * ((range.start + i) as f64 * 0.37).sin();
        }
    }
    let a: Vec<f64> = (0..n).map(|k| 1e-5 / (1.0 + k as f64)).collect();
    let p: Vec<f64> = (0..n).map(|k| 0.7 * k as f64).collect();
    let times: Vec<f64> = (0..25).map(|i| 7.3e-4 * i as f64).collect();
    let shapes: Vec<&Vector> = modes.shapes.iter().collect();
    let mut q = q_static.duplicate()?;
    let mut v = q_static.duplicate()?;
    let sensors = ModalSensors::new(petsc, &mass_shapes, &modes.eigenvalues, m, &q_static)?;
    // The states at `times`, as the transient samples them.
    let state_at = |t: f64, q: &mut Vector, v: &mut Vector| -> TestResult {
        let c: Vec<f64> = (0..n).map(|k| a[k] * (omega[k] * t + p[k]).cos()).collect();
        let cd: Vec<f64> = (0..n)
            .map(|k| -a[k] * omega[k] * (omega[k] * t + p[k]).sin())
            .collect();
        q.copy_from(&q_static)?;
        q.maxpy(&c, &shapes)?;
        v.set_all(0.0)?;
        Ok(v.maxpy(&cd, &shapes)?)
    };
    // Sampled in one block, as the transient's recorder samples its buffered states.
    let (mut qs, mut vs) = (Vec::new(), Vec::new());
    for &t in &times {
        state_at(t, &mut q, &mut v)?;
        qs.extend_from_slice(&q.local()?);
        vs.extend_from_slice(&v.local()?);
    }
    let samples = sensors.sample_block(&qs, &vs, times.len())?;
    let settings = ModalEnergySettings::default();
    let out = modal_energy(&times, &samples, &modes.eigenvalues, &settings, 1e-3);
    // The reference at every time: closed-form E_k, and the energy from the matrices.
    let (mut worst_mode, mut worst_total, mut worst_kinetic) = (0.0f64, 0.0f64, 0.0f64);
    let mut dq = q_static.duplicate()?;
    let mut kdq = q_static.duplicate()?;
    let mut mv = q_static.duplicate()?;
    let exact_total: f64 = (0..n).map(|k| 0.5 * (a[k] * omega[k]).powi(2)).sum();
    // Round-off of dq'K dq: its terms are of size ||K|| ||dq||^2, far above the energy (K's
    // largest eigenvalues sit far above the modes'), summed over the unknowns.
    let k_norm = k.norm_infinity()?;
    let mut roundoff = 0.0f64;
    for (i, &t) in times.iter().enumerate() {
        for (k, ek) in out.energy.iter().enumerate() {
            let exact = 0.5 * (a[k] * omega[k]).powi(2);
            worst_mode = nan_max(worst_mode, (ek[i] - exact).abs() / exact_total);
        }
        state_at(t, &mut q, &mut v)?;
        dq.copy_from(&q)?;
        dq.axpy(-1.0, &q_static)?;
        k.mult(&dq, &mut kdq)?;
        m.mult(&v, &mut mv)?;
        let energy = 0.5 * v.dot(&mv)? + 0.5 * dq.dot(&kdq)?;
        let terms = k_norm * dq.norm2()?.powi(2);
        let unknowns = q.global_len() as f64;
        roundoff = nan_max(roundoff, f64::EPSILON * unknowns.sqrt() * terms / energy);
        worst_total = nan_max(worst_total, (out.total(i) - energy).abs() / energy);
        let kinetic_error = (out.kinetic_in_basis[i] - out.kinetic[i]).abs() / exact_total;
        worst_kinetic = nan_max(worst_kinetic, kinetic_error);
        if !(out.total(i).is_finite() && (t - out.times[i]).abs() < 1e-15) {
            return Err(format!("state {i}: total {} at {}", out.total(i), out.times[i]).into());
        }
    }
    let modal_bound = 4.0 * n as f64 * d + 16.0 * f64::EPSILON;
    let bound = modal_bound + roundoff;
    say(
        petsc,
        &format!(
            "{n} modes, orthogonality error {d:.1e}: modal energies vs closed form {worst_mode:.1e}, sum vs v'Mv/2 + dq'K dq/2 {worst_total:.1e}, kinetic in basis vs v'Mv/2 {worst_kinetic:.1e} (bounds {modal_bound:.1e}, identity {bound:.1e}); top mode R{} with {:.1} %",
            out.ranked[0].mode + 1,
            100.0 * out.ranked[0].share
        ),
    );
    let modal = nan_max(worst_mode, worst_kinetic);
    if modal.is_nan() || worst_total.is_nan() || modal > modal_bound || worst_total > bound {
        return Err(format!(
            "modal energies off by {worst_mode:e} (closed form), {worst_kinetic:e} (kinetic), bound {modal_bound:e}; {worst_total:e} (identity), bound {bound:e}"
        ).into());
    }
    // The ranking: the largest a_k w_k first.
    let exact_first = (0..n)
        .max_by(|&i, &j| (a[i] * omega[i]).total_cmp(&(a[j] * omega[j])))
        .unwrap_or(0);
    if out.ranked[0].mode != exact_first || out.ranked.len() != n.min(settings.top) {
        return Err(format!(
            "ranked {:?}, expected mode {} first",
            out.ranked, exact_first
        )
        .into());
    }
    Ok(())
}

fn dynamic_stability_at_rest(petsc: &Petsc) -> TestResult {
    let text = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
        [contact]\ndisc_speed = 6.2832\n\
        [contact.sliding]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
        friction = { law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-2 }\n\
        [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = 40\n\
        [complex_modes]\nmethod = \"projected\"\n[reduction]\n\
        [transient]\nstep = 2.0e-6\nsteps = 40\nmode = 2\namplitude = 0.0\n\
        state_interval = 2.0e-5\n\
        [post.modal_energy]\n[post.dynamic_stability]\ntimes = [0.0, 4.0e-5, 8.0e-5]\n";
    let scene = squeal::scene::Scene::parse(text, "link-rest")?;
    let out = suite_dir().join("link-rest");
    let run = squeal::pipeline::run(petsc, &scene, text, std::path::Path::new("."), &out, &[])?;
    let ds = run
        .link
        .dynamic_stability
        .as_ref()
        .ok_or("no dynamic stability")?;
    let nominal = run.complex.first().ok_or("no complex modes")?;
    let unstable: Vec<_> = nominal.modes.iter().filter(|m| m.unstable).collect();
    let s = &ds.stability;
    let mut worst = 0.0f64;
    for t in &s.tracks {
        let reference = nominal
            .modes
            .iter()
            .find(|m| m.name == t.name)
            .ok_or(format!("track {} is no nominal mode", t.name))?;
        let r = reference.eigenvalue;
        for &x in &t.eigenvalue {
            worst = nan_max(worst, (x.0 - r.0).hypot(x.1 - r.1) / r.0.hypot(r.1));
        }
    }
    say(
        petsc,
        &format!(
            "{} states, {} tracks reported ({} nominal unstable: {}), {} followed, {} lost; largest relative change of s {worst:.1e}",
            s.times.len(),
            s.tracks.len(),
            unstable.len(),
            unstable.iter().map(|m| m.name.as_str()).collect::<Vec<_>>().join(" "),
            s.followed,
            s.lost
        ),
    );
    let names: Vec<&str> = s.tracks.iter().map(|t| t.name.as_str()).collect();
    let expected: Vec<&str> = unstable.iter().map(|m| m.name.as_str()).collect();
    if names != expected || s.times.len() != 3 || s.lost != 0 {
        return Err(format!(
            "tracks {names:?} vs unstable {expected:?}; {} times, {} lost",
            s.times.len(),
            s.lost
        )
        .into());
    }
    if worst.is_nan() || worst > 1e-7 || unstable.is_empty() {
        return Err(format!(
            "tracked modes move by {worst:e} at rest ({} unstable)",
            unstable.len()
        )
        .into());
    }
    same_on_one_and_two_ranks(petsc, s)
}

/// The 1-rank run writes its tracked eigenvalues, the 2-rank run compares: the projection
/// sums over the ranks' points and the contact is gathered, so a layout error would show.
/// Bound 1e-9 of |s|: the real modes and the static state agree across rank counts to
/// ~1e-12 of themselves (their last bits differ: parallel MUMPS).
fn same_on_one_and_two_ranks(
    petsc: &Petsc,
    s: &squeal::post::dynamic_stability::DynamicStability,
) -> TestResult {
    let values: Vec<f64> = s
        .tracks
        .iter()
        .flat_map(|t| t.eigenvalue.iter().flat_map(|&(a, b)| [a, b]))
        .collect();
    let Some(one) = one_rank_values(petsc, "link-rest", &values)? else {
        return Ok(());
    };
    let pairs = |v: &[f64]| -> Vec<(f64, f64)> { v.chunks(2).map(|c| (c[0], c[1])).collect() };
    let (one, values) = (pairs(&one), pairs(&values));
    let diff = one
        .iter()
        .zip(&values)
        .map(|(a, b)| (a.0 - b.0).hypot(a.1 - b.1) / a.0.hypot(a.1))
        .fold(0.0f64, nan_max);
    say(
        petsc,
        &format!(
            "tracked eigenvalues, {} ranks vs 1: {diff:.1e}",
            petsc.size()
        ),
    );
    if diff.is_nan() || diff > 1e-9 {
        return Err(format!("tracked eigenvalues differ from 1 rank by {diff:e}").into());
    }
    Ok(())
}
