//! Stage 7: the nonlinear transient, on the reduced model when there is one, else on the full
//! model: its start (a real mode, a random modal combination or an impulse), sensors, modal
//! damping, and the run itself (`crate::time::transient`).

use super::model::Model;
use super::operators::Operators;
use super::reduce::Reduced;
use super::statics::Preloaded;
use super::RunError;
use crate::eigen::complex_modes::DampingSettings;
use crate::eigen::real_modes::RealModes;
use crate::la::{Petsc, SparseMatrix, Vector};
use crate::measure::nan_max;
use crate::mesh::Mesh;
use crate::post::modal_energy::ModalSensors;
use crate::time::newmark::{Damping, ModalDamping, TimeError};
use crate::time::transient::{
    Kick, Sensors, Start, Transient, TransientFiles, TransientInputs, TransientSettings,
    SATURATION_CHECK_EVERY,
};

/// Why the transient could not start.
#[derive(Debug, thiserror::Error)]
pub enum TransientSetupError {
    #[error("key 'transient': the start needs at least one real mode")]
    NoRealModes,
    #[error("key 'transient.mode' = {mode}: only {computed} real modes were computed")]
    NoSuchMode { mode: usize, computed: usize },
    #[error("key 'transient.impulse': an impulse start needs [transient.impulse] and a mesh")]
    ImpulseNeedsMesh,
    #[error(
        "key 'transient.impulse': node {node} nearest to the point is clamped; move the point"
    )]
    ImpulseClamped { node: usize },
    #[error("key 'transient.sensors': sensors need a mesh with nodes")]
    SensorsNeedMesh,
    #[error(
        "key 'damping.modal_band_hz' = [{low}, {high}]: the band reaches {high} Hz but the {modes} real modes stop at {highest:.1} Hz; raise 'real_modes.count' (or lower the band)"
    )]
    BandAboveModes {
        low: f64,
        high: f64,
        modes: usize,
        highest: f64,
    },
    #[error(
        "key 'damping.modal_band_hz' = [{low}, {high}]: no real mode in the band (modes from {lowest:.1} to {highest:.1} Hz)"
    )]
    NoModeInBand {
        low: f64,
        high: f64,
        lowest: f64,
        highest: f64,
    },
    #[error("key 'transient': a transient needs a mesh model (not user matrices)")]
    NoMesh,
    #[error(transparent)]
    La(#[from] crate::la::LaError),
}

/// The time response: the signals (streamed to transient.h5 as it ran) and, when a step
/// failed, the failure (reported after the signals are written).
pub struct Trajectory {
    pub signals: Transient,
    pub failure: Option<TimeError>,
    /// Where the sensors and the impulse landed (the nearest nodes), for the summary.
    pub notes: Vec<String>,
}

/// Runs the transient from the preloaded state; `files`: where transient.h5 and the
/// checkpoint go, and whether to resume from it.
///
/// # Collective
#[allow(clippy::too_many_arguments)] // the stages it joins
pub fn transient<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    damping: &DampingSettings,
    model: Option<&Model>,
    ops: &Operators<'p>,
    preload: &Preloaded<'p>,
    modes: &RealModes<'p>,
    reduced: Option<&Reduced<'p>>,
    files: &TransientFiles,
) -> Result<Trajectory, RunError> {
    let dofs = ops.dofs.as_ref().ok_or(TransientSetupError::NoMesh)?;
    let reduction = reduced.map(|r| &r.model.reduction);
    let mut notes = Vec::new();
    let sensors = match model {
        Some(model) if !settings.sensors.is_empty() => Some(sensor_rows(
            petsc,
            settings,
            &model.mesh,
            dofs,
            reduction,
            &mut notes,
        )?),
        _ => None,
    };
    let mesh = model.map(|m| &m.mesh);
    let mut kick_full = kick(settings, modes, mesh, dofs, &mut notes)?;
    if crate::fault::poisoned("transient") {
        if let Some(x) = kick_full.local_mut()?.first_mut() {
            *x = f64::NAN;
        }
    }
    // The full model, or the reduced one in its own unknowns.
    let kick_reduced = match (reduction, settings.start) {
        (Some(r), Start::Impulse) => Some(r.project_force(petsc, &kick_full)?),
        (Some(r), _) => Some(r.restrict(petsc, &kick_full)?),
        (None, _) => None,
    };
    let (k0, m, contact, f_ext, q_static, static_state): (&SparseMatrix<'p>, _, _, _, _, _) =
        match reduced {
            Some(r) => (
                &r.model.stiffness,
                &r.model.mass,
                &r.contact,
                &r.f_ext,
                &r.q_static,
                &r.static_state,
            ),
            None => (
                &ops.k0,
                &ops.m,
                &preload.contact,
                &preload.load,
                &preload.state.displacement,
                &preload.state.contact,
            ),
        };
    let kick_shape = kick_reduced.as_ref().unwrap_or(&kick_full);
    // Rayleigh damping on the integrated operators (never assembled).
    let c = if damping.rayleigh_alpha != 0.0 || damping.rayleigh_beta != 0.0 {
        Damping::Rayleigh {
            alpha: damping.rayleigh_alpha,
            beta: damping.rayleigh_beta,
        }
    } else {
        Damping::None
    };
    let modal = if damping.has_modal() {
        let modal = modal_damping(petsc, damping, modes, m, reduction)?;
        if petsc.rank() == 0 {
            let [low, high] = damping.modal_band_hz.unwrap_or_default();
            println!(
                "modal damping: ratio {} on the {} real modes in [{low}, {high}] Hz",
                damping.modal_ratio,
                modal.modes()
            );
        }
        Some(modal)
    } else {
        None
    };
    // The real modes' coordinates go with every stored state (modal sensors, DESIGN.md §2b).
    let mass_shapes = if settings.state_interval > 0.0 {
        modes
            .shapes
            .iter()
            .map(|phi| mass_shape(petsc, phi, m, reduction))
            .collect::<Result<Vec<Vector>, _>>()?
    } else {
        Vec::new()
    };
    let modal_sensors = if mass_shapes.is_empty() {
        None
    } else {
        Some(ModalSensors::new(
            petsc,
            &mass_shapes,
            &modes.eigenvalues,
            m,
            q_static,
        )?)
    };
    drop(mass_shapes);
    let (signals, failure) = crate::time::transient::run(
        petsc,
        settings,
        TransientInputs {
            k0,
            m,
            c,
            contact,
            f_ext,
            q_static,
            static_state,
            kick: match settings.start {
                Start::Impulse => Kick::Impulse(kick_shape),
                _ => Kick::Displacement(kick_shape),
            },
            sensors: sensors.as_ref(),
            modal_damping: modal.as_ref(),
            reduction,
            modal_sensors: modal_sensors
                .as_ref()
                .map(|m| m as &dyn crate::time::transient::StateSampler),
        },
        files,
        &mut SaturationStop {
            cycles: settings.stop_after_saturation,
            world: petsc.world(),
        },
    )?;
    Ok(Trajectory {
        signals,
        failure,
        notes,
    })
}

/// The node nearest to a point and its distance.
fn nearest_node(mesh: &Mesh, p: &[f64; 3]) -> Option<(usize, f64)> {
    mesh.coords
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let d = (0..3).map(|k| (c[k] - p[k]).powi(2)).sum::<f64>().sqrt();
            (i, d)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The transient's kick in full-model unknowns: a real mode shape, a seeded random
/// combination of all of them, or an impulse vector (N s) at a node.
///
/// # Collective
pub fn kick<'p>(
    settings: &TransientSettings,
    modes: &RealModes<'p>,
    mesh: Option<&Mesh>,
    dofs: &crate::fem::dofmap::DofMap,
    notes: &mut Vec<String>,
) -> Result<Vector<'p>, TransientSetupError> {
    let first = modes
        .shapes
        .first()
        .ok_or(TransientSetupError::NoRealModes)?;
    // A mode's sign is the eigensolver's choice (it may differ with the number of ranks):
    // each kick shape is signed so that its product with a fixed field of the node positions
    // is positive, so the same scene starts the same way on any number of ranks.
    let mut sign_field = first.duplicate()?;
    if let Some(mesh) = mesh {
        let start = sign_field.ownership().start;
        let mut local = sign_field.local_mut()?;
        for node in dofs.owned_nodes() {
            let x = mesh.coords[node];
            for (k, &d) in dofs.node_dofs[node].iter().enumerate() {
                if d >= 0 {
                    local[d as usize - start] =
                        (37.0 * x[0] + 53.0 * x[1] + 71.0 * x[2] + 1.1 * k as f64 + 0.3).sin();
                }
            }
        }
    } else {
        sign_field.set_all(1.0)?;
    }
    let signed = |shape: &Vector<'p>| -> Result<f64, TransientSetupError> {
        Ok(if shape.dot(&sign_field)? < 0.0 {
            -1.0
        } else {
            1.0
        })
    };
    match settings.start {
        Start::Mode => {
            let shape =
                modes
                    .shapes
                    .get(settings.mode - 1)
                    .ok_or(TransientSetupError::NoSuchMode {
                        mode: settings.mode,
                        computed: modes.shapes.len(),
                    })?;
            let mut kick = shape.try_clone()?;
            kick.scale(signed(shape)?)?;
            Ok(kick)
        }
        Start::Random => {
            let mut field = first.duplicate()?;
            field.set_all(0.0)?;
            let coefficients =
                crate::time::transient::random_coefficients(settings.seed, modes.shapes.len());
            for (c, shape) in coefficients.iter().zip(&modes.shapes) {
                field.axpy(c * signed(shape)?, shape)?;
            }
            Ok(field)
        }
        Start::Impulse => {
            let (Some(impulse), Some(mesh)) = (&settings.impulse, mesh) else {
                return Err(TransientSetupError::ImpulseNeedsMesh);
            };
            let (node, distance) =
                nearest_node(mesh, &impulse.point).ok_or(TransientSetupError::ImpulseNeedsMesh)?;
            let c = mesh.coords[node];
            notes.push(format!(
                "impulse ({:.3e}, {:.3e}, {:.3e}) N s at node {node} ({:.4}, {:.4}, {:.4}) m, {distance:.2e} m from the position asked",
                impulse.value[0], impulse.value[1], impulse.value[2], c[0], c[1], c[2]
            ));
            let mut force = first.duplicate()?;
            force.set_all(0.0)?;
            if dofs.owner_of_node(node) == dofs.rank {
                let (rows, values): (Vec<i32>, Vec<f64>) = dofs.node_dofs[node]
                    .iter()
                    .zip(impulse.value)
                    .filter(|(d, _)| **d >= 0)
                    .map(|(&d, v)| (d, v))
                    .unzip();
                if rows.is_empty() {
                    return Err(TransientSetupError::ImpulseClamped { node });
                }
                force.add_values(&rows, &values)?;
            }
            force.assemble()?;
            Ok(force)
        }
    }
}

/// The sensor rows of the transient: the node nearest to each sensor position, its x, y, z
/// over the integrated unknowns (the full model's DOFs, or a row of T for the reduced one).
///
/// # Collective
pub fn sensor_rows<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    mesh: &Mesh,
    dofs: &crate::fem::dofmap::DofMap,
    reduction: Option<&crate::reduce::Reduction>,
    notes: &mut Vec<String>,
) -> Result<Sensors<'p>, TransientSetupError> {
    let mut names = Vec::new();
    let mut rows = Vec::new();
    let mut first_row = 0;
    let mut owners = Vec::new();
    for (name, p) in &settings.sensors {
        let (node, distance) = nearest_node(mesh, p).ok_or(TransientSetupError::SensorsNeedMesh)?;
        let c = mesh.coords[node];
        notes.push(format!(
            "sensor '{name}': node {node} at ({:.4}, {:.4}, {:.4}) m, {distance:.2e} m from the position asked",
            c[0], c[1], c[2]
        ));
        let owner = dofs.owner_of_node(node);
        owners.push(owner);
        if owner < dofs.rank {
            first_row += 3;
        } else if owner == dofs.rank {
            for &d in &dofs.node_dofs[node] {
                rows.push(match (d, reduction) {
                    (d, _) if d < 0 => Vec::new(),
                    (d, Some(r)) => r.recovery_row(d as usize),
                    (d, None) => vec![(d, 1.0)],
                });
            }
        }
        names.push(name.clone());
    }
    let columns = match reduction {
        Some(r) => r.columns.clone(),
        None => dofs.owned_dofs(),
    };
    let rows = crate::la::ObservationMatrix::from_rows(petsc, first_row, &rows, columns)?;
    // Rows go rank by rank: block k of the gathered values is sensor order[k].
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by_key(|&i| owners[i]);
    Ok(Sensors { names, rows, order })
}

/// The modal damping of `[damping]` over the real modes in its band, in the integrated
/// unknowns: M phi_i of the full model, or M_r x_i with x_i the reduced coordinates of phi_i
/// (exact: the modes lie in the reduction's span).
///
/// # Collective
pub fn modal_damping<'p>(
    petsc: &'p Petsc,
    damping: &DampingSettings,
    modes: &RealModes<'p>,
    m: &SparseMatrix<'p>,
    reduction: Option<&crate::reduce::Reduction>,
) -> Result<ModalDamping<'p>, TransientSetupError> {
    let [low, high] = damping.modal_band_hz.unwrap_or([0.0, 0.0]);
    let highest = modes.frequencies_hz.iter().copied().fold(0.0, nan_max);
    if high > highest {
        return Err(TransientSetupError::BandAboveModes {
            low,
            high,
            modes: modes.frequencies_hz.len(),
            highest,
        });
    }
    let mut shapes = Vec::new();
    let mut coefficients = Vec::new();
    for (shape, &f) in modes.shapes.iter().zip(&modes.frequencies_hz) {
        let c = damping.modal_coefficient(2.0 * std::f64::consts::PI * f);
        if c <= 0.0 {
            continue;
        }
        shapes.push(mass_shape(petsc, shape, m, reduction)?);
        coefficients.push(c);
    }
    if shapes.is_empty() {
        return Err(TransientSetupError::NoModeInBand {
            low,
            high,
            lowest: modes.frequencies_hz.first().copied().unwrap_or(0.0),
            highest,
        });
    }
    Ok(ModalDamping::new(shapes, coefficients))
}

/// M x of a full-model mode shape in the integrated unknowns: M phi of the full model, or
/// M_r x with x the reduced coordinates of phi (exact: the modes lie in the reduction's span).
///
/// # Collective
pub fn mass_shape<'p>(
    petsc: &'p Petsc,
    shape: &Vector<'p>,
    m: &SparseMatrix<'p>,
    reduction: Option<&crate::reduce::Reduction>,
) -> Result<Vector<'p>, crate::la::LaError> {
    let x = match reduction {
        Some(r) => r.restrict(petsc, shape)?,
        None => shape.try_clone()?,
    };
    let mut out = x.duplicate()?;
    m.mult(&x, &mut out)?;
    Ok(out)
}

/// The transient's monitor: ends the run once the braking torque has saturated and run
/// `cycles` cycles since (`transient.stop_after_saturation`), checked every
/// [`SATURATION_CHECK_EVERY`] steps (the detector reads the whole record).
struct SaturationStop<'w> {
    cycles: Option<usize>,
    world: &'w mpi::topology::SimpleCommunicator,
}

impl crate::time::transient::Monitor for SaturationStop<'_> {
    /// Every rank decides alike (the record is the same on each), and the verdict is agreed
    /// on anyway.
    fn stop(&mut self, steps: usize, record: &Transient) -> bool {
        let Some(cycles) = self.cycles else {
            return false;
        };
        if !steps.is_multiple_of(SATURATION_CHECK_EVERY) {
            return false;
        }
        let torque = record.braking_torque();
        let saturated = crate::post::limit_cycle::saturated_for(
            &record.time,
            &torque,
            record.nominal_step,
            cycles,
        );
        crate::parallel::any_rank(self.world, saturated)
    }
}
