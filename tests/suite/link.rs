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

use squeal::eigen::real_modes::RealModeRequest;
use squeal::fem::shape::ElementKind;
use squeal::la::{Petsc, Vector};
use squeal::mesh::structured::block;
use squeal::mesh::Clamp;
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
    ]
}

fn modal_energy_identity(petsc: &Petsc) -> Result<(), String> {
    let e = |x: squeal::la::LaError| x.to_string();
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
    let mut y = modes.shapes[0].duplicate().map_err(e)?;
    for (j, phi) in modes.shapes.iter().enumerate() {
        let mut w = phi.duplicate().map_err(e)?;
        m.mult(phi, &mut w).map_err(e)?;
        k.mult(phi, &mut y).map_err(e)?;
        for (i, psi) in modes.shapes.iter().enumerate() {
            let eye = f64::from(u8::from(i == j));
            d = d.max((psi.dot(&w).map_err(e)? - eye).abs());
            let kij = psi.dot(&y).map_err(e)? - eye * omega[j].powi(2);
            d = d.max(kij.abs() / omega[n - 1].powi(2));
        }
        mass_shapes.push(w);
    }
    // An arbitrary static offset and vibration: amplitudes a_k, phases p_k.
    let mut q_static = modes.shapes[0].duplicate().map_err(e)?;
    {
        let range = q_static.ownership();
        let mut l = q_static.local_mut().map_err(e)?;
        for (i, x) in l.iter_mut().enumerate() {
            *x = 1e-4 * ((range.start + i) as f64 * 0.37).sin();
        }
    }
    let a: Vec<f64> = (0..n).map(|k| 1e-5 / (1.0 + k as f64)).collect();
    let p: Vec<f64> = (0..n).map(|k| 0.7 * k as f64).collect();
    let times: Vec<f64> = (0..25).map(|i| 7.3e-4 * i as f64).collect();
    let shapes: Vec<&Vector> = modes.shapes.iter().collect();
    let mut q = q_static.duplicate().map_err(e)?;
    let mut v = q_static.duplicate().map_err(e)?;
    let sensors = ModalSensors {
        mass_shapes: &mass_shapes,
        omega2: &modes.eigenvalues,
        mass: m,
        q_static: &q_static,
    };
    // The states at `times`, as the transient samples them.
    let state_at = |t: f64, q: &mut Vector, v: &mut Vector| -> Result<(), String> {
        let c: Vec<f64> = (0..n).map(|k| a[k] * (omega[k] * t + p[k]).cos()).collect();
        let cd: Vec<f64> = (0..n)
            .map(|k| -a[k] * omega[k] * (omega[k] * t + p[k]).sin())
            .collect();
        q.copy_from(&q_static).map_err(e)?;
        q.maxpy(&c, &shapes).map_err(e)?;
        v.set_all(0.0).map_err(e)?;
        v.maxpy(&cd, &shapes).map_err(e)
    };
    let mut samples = Vec::new();
    for &t in &times {
        state_at(t, &mut q, &mut v)?;
        samples.push(sensors.sample(&q, &v).map_err(e)?);
    }
    let settings = ModalEnergySettings::default();
    let out = modal_energy(&times, &samples, &modes.eigenvalues, &settings, 1e-3);
    // The reference at every time: closed-form E_k, and the energy from the matrices.
    let (mut worst_mode, mut worst_total, mut worst_kinetic) = (0.0f64, 0.0f64, 0.0f64);
    let mut dq = q_static.duplicate().map_err(e)?;
    let mut kdq = q_static.duplicate().map_err(e)?;
    let mut mv = q_static.duplicate().map_err(e)?;
    let exact_total: f64 = (0..n).map(|k| 0.5 * (a[k] * omega[k]).powi(2)).sum();
    // Round-off of dq'K dq: its terms are of size ||K|| ||dq||^2, far above the energy (K's
    // largest eigenvalues sit far above the modes'), summed over the unknowns.
    let k_norm = k.norm_infinity().map_err(e)?;
    let mut roundoff = 0.0f64;
    for (i, &t) in times.iter().enumerate() {
        for (k, ek) in out.energy.iter().enumerate() {
            let exact = 0.5 * (a[k] * omega[k]).powi(2);
            worst_mode = worst_mode.max((ek[i] - exact).abs() / exact_total);
        }
        state_at(t, &mut q, &mut v)?;
        dq.copy_from(&q).map_err(e)?;
        dq.axpy(-1.0, &q_static).map_err(e)?;
        k.mult(&dq, &mut kdq).map_err(e)?;
        m.mult(&v, &mut mv).map_err(e)?;
        let energy = 0.5 * v.dot(&mv).map_err(e)? + 0.5 * dq.dot(&kdq).map_err(e)?;
        let terms = k_norm * dq.norm2().map_err(e)?.powi(2);
        let unknowns = q.global_len() as f64;
        roundoff = roundoff.max(f64::EPSILON * unknowns.sqrt() * terms / energy);
        worst_total = worst_total.max((out.total(i) - energy).abs() / energy);
        worst_kinetic =
            worst_kinetic.max((out.kinetic_in_basis[i] - out.kinetic[i]).abs() / exact_total);
        if !(out.total(i).is_finite() && (t - out.times[i]).abs() < 1e-15) {
            return Err(format!(
                "state {i}: total {} at {}",
                out.total(i),
                out.times[i]
            ));
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
    let modal = worst_mode.max(worst_kinetic);
    if modal.is_nan() || worst_total.is_nan() || modal > modal_bound || worst_total > bound {
        return Err(format!(
            "modal energies off by {worst_mode:e} (closed form), {worst_kinetic:e} (kinetic), bound {modal_bound:e}; {worst_total:e} (identity), bound {bound:e}"
        ));
    }
    // The ranking: the largest a_k w_k first.
    let exact_first = (0..n)
        .max_by(|&i, &j| (a[i] * omega[i]).total_cmp(&(a[j] * omega[j])))
        .unwrap_or(0);
    if out.ranked[0].mode != exact_first || out.ranked.len() != n.min(settings.top) {
        return Err(format!(
            "ranked {:?}, expected mode {} first",
            out.ranked, exact_first
        ));
    }
    Ok(())
}

fn dynamic_stability_at_rest(petsc: &Petsc) -> Result<(), String> {
    let text = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
        [contact]\ndisc_speed = 6.2832\n\
        [contact.sliding]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
        friction = { law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-2 }\n\
        [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n[real_modes]\ncount = 40\n\
        [complex_modes]\nmethod = \"projected\"\n[reduction]\n\
        [transient]\nstep = 2.0e-6\nsteps = 40\nmode = 2\namplitude = 0.0\n\
        state_interval = 2.0e-5\n\
        [post.modal_energy]\n[post.dynamic_stability]\ntimes = [0.0, 4.0e-5, 8.0e-5]\n";
    let scene = squeal::scene::Scene::parse(text, "link-rest").map_err(|e| e.to_string())?;
    let out = suite_dir().join("link-rest");
    let run = squeal::pipeline::run(petsc, &scene, text, std::path::Path::new("."), &out, &[])
        .map_err(|e| e.to_string())?;
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
            worst = worst.max((x.0 - r.0).hypot(x.1 - r.1) / r.0.hypot(r.1));
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
        ));
    }
    if worst.is_nan() || worst > 1e-7 || unstable.is_empty() {
        return Err(format!(
            "tracked modes move by {worst:e} at rest ({} unstable)",
            unstable.len()
        ));
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
) -> Result<(), String> {
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
        .fold(0.0f64, |m, d| if d.is_nan() { d } else { m.max(d) });
    say(
        petsc,
        &format!(
            "tracked eigenvalues, {} ranks vs 1: {diff:.1e}",
            petsc.size()
        ),
    );
    if diff.is_nan() || diff > 1e-9 {
        return Err(format!(
            "tracked eigenvalues differ from 1 rank by {diff:e}"
        ));
    }
    Ok(())
}
