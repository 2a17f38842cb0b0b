//! The radiated power of a transient against the closed form of a mode vibrating alone.
//!
//! Reference: a real mode of the linearized model, started from rest at a displacement x,
//! vibrates as q(t) = q_static + x cos(omega t); its normal velocity at the surface is
//! -omega (N x) sin(omega t), so the instantaneous ERP rho0 c0 sum A v_n^2 has the time mean
//! rho0 c0 sum A (omega N x)^2 / 2, the ERP of the harmonic amplitude omega x (DESIGN.md
//! §2c). The transient (reduced model, recovered to the full one at every stored state) must
//! give that mean over whole periods, and at a microphone the pressure level of that
//! harmonic vibration (Rayleigh integral of the window's spectrum against the harmonic one).

use super::TestResult;
use std::path::Path;

use squeal::io::series::{Hdf5Storage, SeriesFile};
use squeal::la::Petsc;
use squeal::post::limit_cycle::LimitCycle;
use squeal::post::loudness::LoudnessSettings;
use squeal::post::states::StoredStates;
use squeal::scene::Scene;
use squeal::stages::{self, loudness, Timings};
use squeal::time::transient::{TransientFiles, TransientSettings};

use super::common::{say, suite_dir};

pub fn tests() -> Vec<super::NamedTest> {
    vec![(
        "transient_erp_of_one_real_mode_equals_its_modal_erp",
        single_mode_erp,
    )]
}

/// The small brake without friction anywhere, the disc at rest, preloaded, 40 real modes,
/// reduced; the transient starts at 1 nm along one mode between 2 and 3 kHz and runs 20 of
/// its periods without damping. Friction is out because a real mode is then not a mode of
/// the transient's tangent: the pads' regularized Coulomb law damps their tangential motion
/// viscously (measured: 0.44 of the closed form), and the joints' stick traction couples
/// with the gap (unsymmetric, left out of the real modes; measured 5.9 % off, the ERP's peak
/// 2.45 times its mean where one mode alone gives 2).
///
/// Without friction the pads are held tangentially and radially by their abutments and rails
/// alone, open contacts of nearly no stiffness: the preload's tangent is nearly singular, and
/// on 2 ranks, where MUMPS' dynamically scheduled factorization rounds differently from run to
/// run, the modified Newton's reused factors steered the iterates along that direction
/// differently every time: 17 of 100 runs of this preload cut load steps, one 18 times, and
/// one suite run failed at load step 9 (24 cuts are allowed). A full Newton (a new factor at
/// every iteration) cut in 3 of 100, once each: this test uses it (the preload is its start,
/// not its subject; the transient starts from it as an equilibrium whatever its route).
///
/// Bound: the window holds whole periods of the mode only up to the stored states' spacing,
/// and the mean of cos^2 over T_w differs from 1/2 by at most 1 / (2 omega T_w) relative;
/// Newmark's period elongation changes omega by (omega h)^2 / 12, the power by twice that;
/// the contact laws at 1 nm of a 5 um gap scale are linear to 2e-4. Sum asserted (measured
/// value printed).
fn single_mode_erp(petsc: &Petsc) -> TestResult {
    let text = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
                [contact]\ndisc_speed = 0.0\n\
                [contact.sliding]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
                friction = { law = \"coulomb\", mu = 0.0, slip_speed = 1.0e-3 }\n\
                [contact.sticking]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
                friction = { law = \"none\" }\n\
                [statics]\nreuse_contraction = 0.0\n[real_modes]\ncount = 40\n[reduction]\n";
    let scene = Scene::parse(text, "loudness test")?;
    let mut timings = Timings::default();
    let (model, _, ops) =
        stages::operators::from_scene(petsc, &scene, Path::new("."), &mut timings)?;
    let model = model.ok_or("a brake model")?;
    let statics = scene.statics.as_ref().ok_or("[statics]")?;
    let contact = scene.contact.clone().unwrap_or_default();
    let preload = stages::statics::preload(petsc, &model, &ops, &contact, statics, &mut timings)?;
    let request = scene.real_modes.clone().ok_or("[real_modes]")?;
    let modes = stages::modes::real_modes(petsc, &ops, Some(&preload), &request)?;
    let reduction = scene.reduction.clone().ok_or("[reduction]")?;
    let reduced = stages::reduce::reduce(petsc, &reduction, &model, &ops, &preload, &modes, &[])?;
    let (index, f) = modes
        .frequencies_hz
        .iter()
        .enumerate()
        .find(|(_, f)| (2000.0..3000.0).contains(*f))
        .ok_or("no real mode between 2 and 3 kHz")?;
    let h = 2e-6;
    let periods = 20.0;
    let steps = (periods / f / h).ceil() as usize + 10;
    let transient: TransientSettings = toml::from_str(&format!(
        "step = {h:e}\nsteps = {steps}\nstart = \"mode\"\nmode = {}\namplitude = 1.0e-9\n\
         state_interval = 1.0e-5\ncheckpoint_every = 0\n",
        index + 1
    ))?;
    let dir = suite_dir().join(format!("loudness-mode-{}", petsc.size()));
    std::fs::create_dir_all(&dir)?;
    squeal::parallel::barrier(petsc.world());
    let storage = Hdf5Storage {
        comm: petsc.world(),
    };
    let files = TransientFiles::in_directory(&storage, &dir, false);
    let trajectory = stages::transient::transient(
        petsc,
        &transient,
        &Default::default(),
        Some(&model),
        &ops,
        &preload,
        &modes,
        Some(&reduced),
        &files,
    )?;
    if let Some(failure) = trajectory.failure {
        return Err(failure.to_string().into());
    }
    let file = SeriesFile::open(petsc.world(), &files.stream)?;
    let states = StoredStates::new(Box::new(file), "transient.h5".into(), 2)?;
    let front = [0.0, 0.0, 0.5];
    let settings = LoudnessSettings {
        cycles: periods as usize,
        microphones: [("front".to_string(), front)].into_iter().collect(),
        ..Default::default()
    };
    let mesh = &model.mesh;
    let dofs = ops.dofs.as_ref().ok_or("a DOF map")?;
    let radiator = loudness::radiator(petsc, mesh, dofs, &settings)?;
    let nominal = stages::link::Nominal {
        preload: &preload,
        modes: &modes,
        reduced: Some(&reduced),
    };
    // The closed form: the start state's displacement from the static state, x.
    let at = nominal.contact_at(petsc);
    let mut x0 = at.state_template.duplicate()?;
    let mut v0 = at.state_template.duplicate()?;
    states.read(0, &mut x0, &mut v0)?;
    // From the superelement's static state, about which the transient vibrates (it starts
    // from it as an equilibrium), not the full model's: the two differ by the reduction's
    // static error, which on this frictionless brake (pads held tangentially by open
    // abutment contacts only) varies with round-off from run to run, and counting it as
    // vibration moved this closed form by up to 0.35 dB between runs on 2 ranks.
    let mut dx0 = x0.try_clone()?;
    dx0.axpy(-1.0, &reduced.q_static)?;
    let mut x = preload.state.displacement.duplicate()?;
    reduced.model.reduction.recover(petsc, &dx0, &mut x)?;
    let omega = 2.0 * std::f64::consts::PI * f;
    let expected = radiator.harmonic_power(petsc, &settings, &x, omega)?;
    let cycle = LimitCycle {
        period: Some(1.0 / f),
        dominant_frequency: *f,
        ..Default::default()
    };
    let run = loudness::StoredRun {
        states: &states,
        cycle: &cycle,
    };
    let report = loudness::loudness(petsc, &radiator, &settings, nominal, &[], None, Some(run))?;
    let t = report.transient.as_ref().ok_or("no transient level")?;
    let error = (t.mean_power - expected).abs() / expected;
    let peak = squeal::measure::largest(t.power.iter().copied()) / expected;
    let window = t.window.1 - t.window.0;
    let bound = 1.0 / (2.0 * omega * window) + (omega * h).powi(2) / 6.0 + 2e-4;
    say(
        petsc,
        &format!(
            "real mode {} ({f:.1} Hz) alone, {} stored states over {window:.3e} s: transient mean ERP {:.6e} W vs {expected:.6e} W closed form, relative {error:.1e} (bound {bound:.1e}); peak / mean {peak:.4} (2 for one mode)",
            index + 1,
            t.states,
            t.mean_power
        ),
    );
    if squeal::measure::exceeds(error, bound) {
        return Err(format!(
            "transient ERP {:e} W vs the mode's {expected:e} W: relative {error:e} > {bound:e}",
            t.mean_power
        )
        .into());
    }
    // The microphone: the time-domain Rayleigh integral (retarded accelerations by central
    // differences and linear interpolation of the stored states, every 1e-5 s) against the
    // mode's harmonic pressure. Derived part of the bound, on the mean square: the window
    // after the largest delay, 1 / (2 omega T); the differences and the interpolation,
    // 2 (1/6 + 1/8) (omega dt)^2; together 0.06 dB here. A microphone sees one point of the
    // field, where the small admixture of other modes (the ERP's peak / mean departs from 2
    // by 0.3 %) can add more: 0.25 dB allowed in all (a frequency-domain version that
    // evaluated each bin at its own frequency was off by 0.38 dB and fails this).
    let amplitude = radiator.harmonic_pressure(petsc, &settings, &x, omega, front)?;
    let expected_db = squeal::post::loudness::pressure_level(amplitude);
    let measured_db = t.microphones.first().map_or(f64::NAN, |m| m.1);
    let db_bound = 0.25;
    let db_error = (measured_db - expected_db).abs();
    say(
        petsc,
        &format!(
            "front microphone: transient {measured_db:.4} dB vs the mode's {expected_db:.4} dB, difference {db_error:.1e} dB (bound {db_bound:.1e})"
        ),
    );
    if squeal::measure::exceeds(db_error, db_bound) {
        return Err(format!("microphone: transient {measured_db} dB vs {expected_db} dB").into());
    }
    Ok(())
}
