//! The stages called one by one, as a program built on squeal would (DESIGN.md §3): no scene
//! run, no file written. The preloaded 6k brake of the suite (mu 0.4, 20 bar, disc turning).

use super::TestResult;
use squeal::measure::{nan_max, nan_min};
use std::path::Path;

use squeal::contact::law::FrictionLaw;
use squeal::eigen::complex_modes::{damping_ratio, ComplexModeSettings, Route};
use squeal::eigen::real_modes::RealModeRequest;
use squeal::eigen::stability::ProjectedStability;
use squeal::eigen::sweep::{SweepParameter, SweepSettings};
use squeal::la::Petsc;
use squeal::reduce::ReductionSettings;
use squeal::scene::Scene;
use squeal::stages::{self, RunError, Timings};

pub fn tests() -> Vec<super::NamedTest> {
    vec![
        (
            "stages_reduction_of_the_preloaded_brake_keeps_its_real_modes",
            reduction_stage,
        ),
        (
            "stages_stability_at_the_static_state_is_the_nominal_projected_modes",
            stability_at_static_state,
        ),
        (
            "stages_statics_without_contact_interfaces_names_the_key",
            statics_without_interfaces,
        ),
    ]
}

const BRAKE: &str = "[model]\nsource = \"brake\"\ntarget_dofs = 6000\npressure_bar = 20.0\n\
     [contact]\ndisc_speed = 6.2832\n\
     [contact.sliding]\nnormal = { law = \"exponential\", p0 = 1.0e6, lambda = 2.0e5 }\n\
     friction = { law = \"coulomb\", mu = 0.4, slip_speed = 1.0e-3 }\n[statics]\n";

/// The small brake through the first stages: scene, model, operators and preload.
struct SmallBrake<'p> {
    scene: Scene,
    model: squeal::stages::model::Model,
    ops: squeal::stages::operators::Operators<'p>,
    preload: squeal::stages::statics::Preloaded<'p>,
}

fn small_brake<'p>(petsc: &'p Petsc) -> TestResult<SmallBrake<'p>> {
    let scene = Scene::parse(BRAKE, "stages test")?;
    let mut timings = Timings::default();
    let (model, _, ops) =
        stages::operators::from_scene(petsc, &scene, Path::new("."), &mut timings)?;
    let model = model.ok_or("a brake model")?;
    let statics = scene.statics.as_ref().ok_or("[statics]")?;
    let contact = scene.contact.clone().unwrap_or_default();
    let preload = stages::statics::preload(petsc, &model, &ops, &contact, statics, &mut timings)?;
    Ok(SmallBrake {
        scene,
        model,
        ops,
        preload,
    })
}

/// Rayleigh-Ritz on a subspace that holds the modes exactly (DESIGN.md §2, reduction): the
/// reduced tangent's real modes equal the full ones to the eigensolver's tolerance (modes
/// solved to 1e-10; asserted 1e-9 relative), the static state lies in span(T) through the
/// static shape (1e-10), and the stage keeps every contact point.
fn reduction_stage(petsc: &Petsc) -> TestResult {
    let SmallBrake {
        model,
        ops,
        preload,
        ..
    } = small_brake(petsc)?;
    let request = RealModeRequest {
        count: 30,
        tolerance: 1e-10,
        ..Default::default()
    };
    let modes = stages::modes::real_modes(petsc, &ops, Some(&preload), &request)?;
    let settings: ReductionSettings = toml::from_str("")?;
    let reduced = stages::reduce::reduce(petsc, &settings, &model, &ops, &preload, &modes, &[])?;
    let mode_error = reduced.mode_error();
    if reduced.mode_check.len() != 30 || mode_error.is_nan() || mode_error > 1e-9 {
        return Err(format!(
            "reduced vs full real modes: {} compared, largest relative gap {mode_error:e}",
            reduced.mode_check.len()
        )
        .into());
    }
    if reduced.static_error.is_nan() || reduced.static_error > 1e-10 {
        return Err(format!("static state in span(T) to {:e}", reduced.static_error).into());
    }
    if reduced.contact.points().len() != preload.contact.points().len() {
        return Err("the reduced contact model lost points".into());
    }
    Ok(())
}

/// The linearize-project-solve recipe (eigen::stability) at the static state is the projected
/// route of the complex-mode stage: the same eigenvalues to round-off (asserted 1e-12 relative
/// in s), and the same unstable modes. A friction sweep stage run afterwards leaves the static
/// state it was given bit for bit unchanged (it works on its own copy of the laws).
fn stability_at_static_state(petsc: &Petsc) -> TestResult {
    let SmallBrake {
        scene,
        model,
        ops,
        preload,
    } = small_brake(petsc)?;
    let mut timings = Timings::default();
    let statics = scene.statics.as_ref().ok_or("[statics]")?;
    let request = RealModeRequest {
        count: 30,
        ..Default::default()
    };
    let modes = stages::modes::real_modes(petsc, &ops, Some(&preload), &request)?;
    let settings = ComplexModeSettings {
        method: Route::Projected,
        ..Default::default()
    };
    let damping = Default::default();
    let nominal = stages::complex::complex_modes(
        petsc,
        &settings,
        &damping,
        &ops,
        Some(&preload),
        Some(&modes),
        &mut timings,
    )?;
    let nominal = &nominal.first().ok_or("no projected route")?.modes;
    let world = petsc.world();
    let stability = ProjectedStability::new(
        world,
        &preload.contact,
        &modes,
        &preload.state.contact,
        damping,
    )?;
    let pairs = stability.modes_at(world, &preload.contact, &preload.state.contact)?;
    let mut worst = 0.0f64;
    for m in nominal {
        let s = m.eigenvalue;
        let gap = pairs
            .iter()
            .map(|(p, _)| (p.0 - s.0).hypot(p.1 - s.1) / s.0.hypot(s.1))
            .fold(f64::INFINITY, nan_min);
        worst = nan_max(worst, gap);
    }
    if nominal.is_empty() || worst.is_nan() || worst > 1e-12 {
        return Err(format!(
            "stability at the static state vs the projected route: {} modes, largest gap {worst:e}",
            nominal.len()
        )
        .into());
    }
    let unstable = |ratios: &mut dyn Iterator<Item = f64>| ratios.filter(|z| *z < -1e-6).count();
    let from_pairs = unstable(
        &mut pairs
            .iter()
            .filter(|(s, _)| s.1 > 0.0)
            .map(|(s, _)| damping_ratio(*s)),
    );
    let from_stage = unstable(&mut nominal.iter().map(|m| m.damping_ratio));
    if from_pairs < from_stage {
        return Err(format!("unstable modes: stage {from_stage}, recipe {from_pairs}").into());
    }
    let sweep = SweepSettings {
        parameter: SweepParameter::Mu,
        range: squeal::range::AxisRange::listed(vec![0.3, 0.35]),
    };
    let input = stages::sweep::SweepInputs {
        k0: &ops.k0,
        dofs: ops.dofs.as_ref().ok_or("a DOF map")?,
        modes: &modes,
        pressure_bar: model.pressure / 1e5,
    };
    // The static state the sweep is given, bit for bit: displacement, load, contact state,
    // laws and disc speed.
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    let snapshot = |p: &stages::statics::Preloaded| -> TestResult<_> {
        let c = &p.state.contact;
        let observed: Vec<f64> = c
            .observed
            .iter()
            .flat_map(|o| [o.gap, o.slip[0], o.slip[1], o.speed])
            .collect();
        let response: Vec<f64> = c
            .response
            .iter()
            .flat_map(|r| [r.pressure, r.stiffness, r.traction[0], r.traction[1]])
            .collect();
        Ok((
            bits(&p.state.displacement.local()?),
            bits(&p.load.local()?),
            bits(&observed),
            bits(&response),
            format!("{:?}", p.contact.interfaces()),
            p.contact.disc_speed().to_bits(),
        ))
    };
    let before = snapshot(&preload)?;
    stages::sweep::sweep(petsc, &sweep, &settings, &damping, statics, &preload, input)?;
    if snapshot(&preload)? != before {
        return Err("the sweep changed the static state it was given".into());
    }
    for itf in preload.contact.interfaces() {
        if let FrictionLaw::Coulomb { mu, .. } = itf.friction {
            if mu != 0.4 {
                return Err(format!("after the sweep '{}' has mu {mu}, not 0.4", itf.name).into());
            }
        }
    }
    Ok(())
}

/// A structured block has no contact interfaces: the statics stage refuses it with an error
/// that names the scene key, on every rank.
fn statics_without_interfaces(petsc: &Petsc) -> TestResult {
    let text = "[model]\nsource = \"block\"\nelement = \"hex8\"\nsize = [0.1, 0.02, 0.01]\n\
                cells = [4, 2, 2]\nclamp = [\"u0\"]\n\
                material = { name = \"steel\", density = 7850.0, elasticity = { model = \"isotropic\", e = 2.1e11, nu = 0.3 } }\n\
                [statics]\n";
    let scene = Scene::parse(text, "block")?;
    let mut timings = Timings::default();
    let (model, _, ops) =
        stages::operators::from_scene(petsc, &scene, Path::new("."), &mut timings)?;
    let model = model.ok_or("a block model")?;
    let statics = scene.statics.as_ref().ok_or("[statics]")?;
    match stages::statics::preload(
        petsc,
        &model,
        &ops,
        &Default::default(),
        statics,
        &mut timings,
    ) {
        Err(RunError::Scene {
            key: "statics",
            message,
        }) if message.contains("interfaces") => Ok(()),
        Err(other) => Err(format!("wrong error: {other}").into()),
        Ok(_) => Err("a model without interfaces was preloaded".into()),
    }
}
