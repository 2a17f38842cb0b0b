//! Stage 5b: a parameter sweep. Per value the static state is re-solved (warm-started from the
//! previous point; from the unloaded state when that fails, which is logged and counted), the
//! contact tangent re-projected on the fixed real modes of the nominal state, the dense complex
//! modes solved, and the modes tracked by MAC.

use std::time::Instant;

use super::statics::Preloaded;
use crate::eigen::complex_modes::{
    damping_ratio, frequency_hz, ComplexModeSettings, DampingSettings,
};
use crate::eigen::real_modes::RealModes;
use crate::eigen::stability::ProjectedStability;
use crate::eigen::sweep::{apply_to_laws, SweepParameter, SweepSettings};
use crate::eigen::tracking::{track, Tracks};
use crate::fem::dofmap::DofMap;
use crate::la::{LaError, Petsc, SparseMatrix};
use crate::statics::{StaticError, StaticSettings};

/// Why a sweep stopped.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(
        "key 'sweep': point {point} ({parameter} = {value}): the static state failed from the previous point ({warm}) and from the unloaded state: {cold}"
    )]
    Statics {
        point: usize,
        parameter: &'static str,
        value: f64,
        warm: Box<StaticError>,
        cold: Box<StaticError>,
    },
    #[error("key 'sweep': point {point} ({parameter} = {value}): {source}")]
    Laws {
        point: usize,
        parameter: &'static str,
        value: f64,
        source: crate::eigen::sweep::LawMismatch,
    },
    #[error("key 'sweep': point {point} ({parameter} = {value}): {source}")]
    Modes {
        point: usize,
        parameter: &'static str,
        value: f64,
        source: crate::la::DenseError,
    },
    #[error(transparent)]
    La(#[from] LaError),
    #[error(transparent)]
    Contact(#[from] crate::contact::ContactError),
}

/// What a sweep needs from the earlier stages.
pub struct SweepInputs<'a, 'p> {
    pub k0: &'a SparseMatrix<'p>,
    pub dofs: &'a DofMap,
    pub modes: &'a RealModes<'p>,
    pub pressure_bar: f64,
}

/// The result of a sweep: tracked projected complex modes per parameter value.
pub struct SweepOutput {
    pub parameter: SweepParameter,
    pub values: Vec<f64>,
    pub tracks: Tracks,
    pub unstable: Vec<usize>,
    pub statics_seconds: Vec<f64>,
    pub modal_seconds: Vec<f64>,
    pub newton_iterations: Vec<usize>,
    /// Points whose warm-started static solve failed and was redone from the unloaded state.
    pub cold_restarts: Vec<usize>,
    pub margin: f64,
}

/// Sweeps one parameter from the preloaded state. Each point evaluates its own copy of the
/// contact laws ([`crate::contact::ContactModel::with_laws`]): the preloaded state is left as
/// it was given.
///
/// # Collective
pub fn sweep<'p>(
    petsc: &'p Petsc,
    sweep: &SweepSettings,
    settings: &ComplexModeSettings,
    damping: &DampingSettings,
    statics: &StaticSettings,
    preload: &Preloaded<'p>,
    input: SweepInputs<'_, 'p>,
) -> Result<SweepOutput, SweepError> {
    let mut out = SweepOutput {
        parameter: sweep.parameter,
        values: sweep.values(),
        tracks: Default::default(),
        unstable: Vec::new(),
        statics_seconds: Vec::new(),
        modal_seconds: Vec::new(),
        newton_iterations: Vec::new(),
        cold_restarts: Vec::new(),
        margin: settings.instability_margin,
    };
    let mut bar = crate::progress::Progress::new("sweep", out.values.len(), petsc.rank());
    let result = sweep_points(
        petsc, sweep, settings, damping, statics, preload, &input, &mut out, &mut bar,
    );
    bar.finish();
    let points = result?;
    let mut tracks = track(&points);
    // Every mode is tracked (a mode may cross f_max within the sweep); the tracks reported
    // are those below f_max somewhere.
    if let Some(f_max) = settings.f_max_hz {
        tracks
            .tracks
            .retain(|t| t.iter().flatten().any(|(s, _)| frequency_hz(*s) <= f_max));
    }
    out.tracks = tracks;
    Ok(out)
}

/// The points of the sweep: per value, statics, projection, dense complex modes (sorted by
/// frequency), with timings and counts into `out`.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the sweep's settings and its running state
fn sweep_points<'p>(
    petsc: &'p Petsc,
    sweep: &SweepSettings,
    settings: &ComplexModeSettings,
    damping: &DampingSettings,
    statics: &StaticSettings,
    preload: &Preloaded<'p>,
    input: &SweepInputs<'_, 'p>,
    out: &mut SweepOutput,
    bar: &mut crate::progress::Progress,
) -> Result<Vec<Vec<crate::eigen::complex_modes::DenseEigenpair>>, SweepError> {
    let world = petsc.world();
    let nominal_laws = preload.contact.interfaces().to_vec();
    let nominal_speed = preload.contact.disc_speed();
    let mut f = preload.load.duplicate()?;
    let mut q = preload.state.displacement.try_clone()?;
    let mut points = Vec::with_capacity(out.values.len());
    let name = sweep.parameter.name();
    let stability = ProjectedStability::new(
        world,
        &preload.contact,
        input.modes,
        &preload.state.contact,
        *damping,
    )?;
    for (i, &v) in out.values.clone().iter().enumerate() {
        let mut laws = nominal_laws.clone();
        let mut speed = nominal_speed;
        f.copy_from(&preload.load)?;
        match sweep.parameter {
            SweepParameter::PressureBar => f.scale(v / input.pressure_bar)?,
            SweepParameter::DiscSpeed => speed = v,
            p => apply_to_laws(p, v, &mut laws).map_err(|source| SweepError::Laws {
                point: i + 1,
                parameter: name,
                value: v,
                source,
            })?,
        }
        let contact = &preload.contact.with_laws(laws, speed)?;
        let t = Instant::now();
        let solve =
            |start| crate::statics::solve(petsc, input.k0, contact, &f, statics, start, |_| {});
        let state = match solve(Some(&q)) {
            Ok(s) => s,
            Err(warm) => {
                if petsc.rank() == 0 {
                    println!(
                        "  sweep point {} ({name} = {v}): warm-started statics failed ({warm}); solving from the unloaded state",
                        i + 1
                    );
                }
                out.cold_restarts.push(i + 1);
                solve(None).map_err(|cold| SweepError::Statics {
                    point: i + 1,
                    parameter: name,
                    value: v,
                    warm: Box::new(warm),
                    cold: Box::new(cold),
                })?
            }
        };
        out.statics_seconds.push(t.elapsed().as_secs_f64());
        out.newton_iterations
            .push(state.log.iter().filter(|r| r.step_length > 0.0).count());
        let t = Instant::now();
        let pairs = stability
            .modes_at(world, contact, &state.contact)
            .map_err(|source| SweepError::Modes {
                point: i + 1,
                parameter: name,
                value: v,
                source,
            })?;
        out.modal_seconds.push(t.elapsed().as_secs_f64());
        out.unstable.push(
            pairs
                .iter()
                .filter(|(s, _)| {
                    damping_ratio(*s) < -settings.instability_margin
                        && settings.f_max_hz.is_none_or(|f| frequency_hz(*s) <= f)
                })
                .count(),
        );
        let mut sorted = pairs;
        sorted.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1));
        points.push(sorted);
        q = state.displacement;
        bar.update(i + 1, &format!("{name} = {v:.4}"));
    }
    Ok(points)
}
