//! Complex-mode benchmark, speed against error (run under mpirun by scripts/bench): on the
//! preloaded brake (one preload, one set of real modes; the smaller bases are its leading
//! subsets), the time of the real modes, of the projected and of the full complex modes, and a
//! table of projected-vs-full frequency and damping error against the number of real modes in
//! the basis, with the time of each; then the cost of one sweep point (re-projection of a new
//! tangent state + dense complex modes, static re-solve apart).
//!
//!   mpirun -n 2 target/release/deps/complex_modes-* --dofs 30000 --bases 50,100,250,400

use std::path::Path;
use std::time::Instant;

use clap::Parser;
use squeal::contact::kernel::Part;
use squeal::contact::ContactModel;
use squeal::eigen::complex_modes::{full, projected, ComplexMode, ComplexModeSettings, Operators};
use squeal::eigen::real_modes::{real_modes, RealModeRequest};
use squeal::eigen::stability::ModalProjection;
use squeal::fem::petsc::assemble_system_as;
use squeal::la::{MatrixFormat, Petsc};
use squeal::pipeline::build_model;
use squeal::scene::Scene;
use squeal::statics::{pressure_load, solve as solve_statics};

#[derive(Parser)]
struct Args {
    /// Target size of the brake (DOF).
    #[arg(long, default_value_t = 600_000)]
    dofs: usize,
    /// Real modes in the projection basis, comma separated; the largest also serves the full
    /// comparison run.
    #[arg(long, value_delimiter = ',', default_value = "50,100,250,400")]
    bases: Vec<usize>,
    /// Modes compared: those of the full route below this frequency (Hz).
    #[arg(long, default_value_t = 2500.0)]
    f_max: f64,
    /// Repetitions of the timed sweep point (basis: 250 modes or the largest below it).
    #[arg(long, default_value_t = 20)]
    sweep_points: usize,
    /// Solve the full route (SLEPc PEP) for the error table; `--full false` times the
    /// projected route alone (the PEP's LU of the unsymmetric quadratic operator does not fit
    /// next to the stored modes at 600k on a 24 GiB machine).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    full: bool,
    /// cargo bench passes --bench; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn scene(dofs: usize) -> String {
    format!(
        "[model]\nsource = \"brake\"\ntarget_dofs = {dofs}\npressure_bar = 20.0\n\
         [contact]\ndisc_speed = 6.2832\n\
         [contact.sliding]\nnormal = {{ law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }}\n\
         friction = {{ law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }}\n\
         [statics]\n[damping]\nrayleigh_beta = 1.0e-7\n"
    )
}

/// Largest and median frequency error (relative) and largest damping-ratio error (absolute)
/// of the projected modes against every full mode, by nearest eigenvalue.
fn errors(full: &[ComplexMode], projected: &[ComplexMode]) -> (f64, f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    let mut all = Vec::new();
    for m in full {
        let Some(p) = projected.iter().min_by(|a, b| {
            let d = |x: &ComplexMode| {
                (x.eigenvalue.0 - m.eigenvalue.0).hypot(x.eigenvalue.1 - m.eigenvalue.1)
            };
            d(a).total_cmp(&d(b))
        }) else {
            return (f64::NAN, f64::NAN, f64::NAN);
        };
        all.push((p.frequency_hz - m.frequency_hz).abs() / m.frequency_hz);
        let frequency_error = (p.frequency_hz - m.frequency_hz).abs() / m.frequency_hz;
        worst.0 = squeal::measure::nan_max(worst.0, frequency_error);
        let damping_error = (p.damping_ratio - m.damping_ratio).abs();
        worst.1 = squeal::measure::nan_max(worst.1, damping_error);
    }
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(f64::NAN);
    (worst.0, median, worst.1)
}

fn main() {
    let args = Args::parse();
    let universe = mpi::initialize().expect("MPI");
    squeal::la::install_panic_hook();
    let petsc = Petsc::initialize(&universe, &[]).expect("PETSc");
    let rank0 = petsc.rank() == 0;
    let world = petsc.world();
    let mut bases = args.bases.clone();
    bases.sort_unstable();
    let largest = *bases.last().expect("at least one basis size");

    // One model, one preload, one set of real modes (the largest basis); the smaller bases
    // are its leading subsets.
    let text = scene(args.dofs);
    let scene = Scene::parse(&text, "bench").expect("bench scene");
    let t = Instant::now();
    let model = build_model(&scene.model, Path::new("."))
        .expect("brake model")
        .expect("a mesh model");
    let system = assemble_system_as(&petsc, &model.mesh, &model.clamps, Some(MatrixFormat::Aij))
        .expect("assembly");
    let contact_settings = scene.contact.clone().unwrap_or_default();
    let interfaces = contact_settings
        .resolve(&model.interfaces)
        .expect("interfaces");
    let contact = ContactModel::new(
        &petsc,
        &model.mesh,
        &system.dofs,
        interfaces,
        &contact_settings,
    )
    .expect("pairing");
    let f_ext = pressure_load(
        &petsc,
        &model.mesh,
        &system.dofs,
        &model.loads,
        model.pressure,
    )
    .expect("load");
    let setup = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let statics = scene.statics.clone().unwrap_or_default();
    let state = solve_statics(
        &petsc,
        &system.stiffness,
        &contact,
        &f_ext,
        &statics,
        None,
        |_| {},
    )
    .expect("static preload");
    let preload = t.elapsed().as_secs_f64();
    let terms = |parts: &[Part]| contact.tangent_terms(&state.contact, parts);
    let mut ks = contact
        .joined_matrix(&petsc, &system.stiffness)
        .expect("tangent");
    contact
        .add_tangent(&state.contact, &[Part::Normal, Part::Stick], &mut ks)
        .expect("tangent");
    ks.assemble().expect("tangent");
    ks.set_symmetric(true).expect("tangent");
    let request = RealModeRequest {
        count: largest,
        ..Default::default()
    };
    let t = Instant::now();
    let modes = real_modes(&petsc, &ks, &system.mass, false, &request, "").expect("real modes");
    let real_seconds = t.elapsed().as_secs_f64();
    drop(ks);
    // The full operators.
    let damping = scene.damping.unwrap_or_default();
    let mut kf = contact.joined_matrix(&petsc, &system.stiffness).expect("K");
    contact
        .add_tangent(
            &state.contact,
            &[Part::Normal, Part::Stick, Part::Friction],
            &mut kf,
        )
        .expect("K");
    kf.assemble().expect("K");
    let mut cf = contact.joined_matrix(&petsc, &system.stiffness).expect("C");
    cf.scale(damping.rayleigh_beta).expect("C");
    contact
        .add_tangent(&state.contact, &[Part::Damping], &mut cf)
        .expect("C");
    cf.assemble().expect("C");
    let ops = Operators::new(&kf, &cf, &system.mass).expect("operators");
    let settings = ComplexModeSettings {
        f_max_hz: Some(args.f_max),
        count: Some(40),
        ..Default::default()
    };
    let full_modes = if args.full {
        Some(full(&petsc, &ops, &settings, 40).expect("full complex modes"))
    } else {
        None
    };
    let full_list = full_modes
        .as_ref()
        .map(|f| f.modes.clone())
        .unwrap_or_default();
    if rank0 {
        println!(
            "brake: {} DOF on {} ranks; model + pairing {setup:.1} s; static preload {preload:.1} s; \
             {largest} real modes {real_seconds:.1} s; {}",
            system.stiffness.global_rows(),
            petsc.size(),
            match &full_modes {
                Some(f) => format!(
                    "full complex modes (SLEPc PEP, {} modes below {} Hz, {} unstable) {:.1} s",
                    full_list.len(),
                    args.f_max,
                    full_list.iter().filter(|m| m.unstable).count(),
                    f.seconds
                ),
                None => "full route not run (--full false): no error columns".into(),
            }
        );
        println!(
            "{:>10} {:>13} {:>14} {:>13} {:>15} {:>32}",
            "real modes",
            "top mode (Hz)",
            "projection (s)",
            "dense CEA (s)",
            "residuals (s)",
            "error f max / f median / zeta max"
        );
    }
    let mut sweep_point = None;
    for &m in &bases {
        let m = m.min(modes.shapes.len());
        let shapes = &modes.shapes[..m];
        let t = Instant::now();
        let projection = ModalProjection::new(
            world,
            modes.eigenvalues[..m].to_vec(),
            contact.observe_shapes(shapes).expect("observe"),
            contact.local().len(),
            &terms(&[Part::Normal, Part::Stick]),
        );
        let (kp, cp) = projection.operators(
            world,
            &terms(&[Part::Normal, Part::Stick, Part::Friction]),
            &terms(&[Part::Damping]),
            &damping,
        );
        let projection_seconds = t.elapsed().as_secs_f64();
        let with_residuals = projected(shapes, &kp, &cp, Some(&ops), &settings).expect("projected");
        let (df, median, dz) = if args.full {
            errors(&full_list, &with_residuals.modes)
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };
        if rank0 {
            println!(
                "{m:>10} {:>13.1} {:>14.4} {:>13.4} {:>15.3} {:>12.2e} / {:.2e} / {:.2e}",
                modes.frequencies_hz[m - 1],
                projection_seconds,
                with_residuals.solve_seconds,
                with_residuals.seconds - with_residuals.solve_seconds,
                df,
                median,
                dz
            );
        }
        if m <= 250 {
            // One sweep point: a new tangent state re-projected (observation of the basis
            // kept) + the dense complex modes, no residuals.
            let t = Instant::now();
            for _ in 0..args.sweep_points {
                let (kp, cp) = projection.operators(
                    world,
                    &terms(&[Part::Normal, Part::Stick, Part::Friction]),
                    &terms(&[Part::Damping]),
                    &damping,
                );
                projected(shapes, &kp, &cp, None, &settings).expect("projected");
            }
            sweep_point = Some((
                m,
                t.elapsed().as_secs_f64() / args.sweep_points.max(1) as f64,
            ));
        }
    }
    if let (true, Some((m, seconds))) = (rank0, sweep_point) {
        println!(
            "sweep point (basis {m}): {seconds:.4} s re-projection + dense complex modes (target \
             < 1 s: {}); 100 points: {:.1} s plus the static re-solves",
            if seconds < 1.0 { "met" } else { "missed" },
            100.0 * seconds
        );
    }
}
