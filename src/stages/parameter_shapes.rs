//! Stage 6a (before the reduction, for a noise matrix on the superelement): the static shapes
//! of the operating parameters the matrix varies. The reduction's basis holds the real modes
//! and the nominal static shape; a point at another pressure, friction, contact law or lining
//! stiffness deforms the reduced part (backplates, caliper, the lining's far layer) in shapes
//! the modes barely hold (the 6k brake with 30 modes: 2.7 % off in displacement at 30 bar,
//! 12-15 % with the lining at half its stiffness). The first-order change of the static state
//! per parameter, dq/dtheta = J^-1 df/dtheta with J the full tangent at the nominal state, adds
//! those shapes: one factorization of J and one solve per parameter, once.

use super::operators::Operators;
use super::statics::Preloaded;
use super::RunError;
use crate::contact::kernel::Part;
use crate::contact::linearize::Base;
use crate::eigen::sweep::{apply_to_laws, SweepParameter};
use crate::la::{DirectSolver, Factorization, Petsc, SparseMatrix, Vector};
use crate::matrix::{Axis, MatrixSettings};

/// The relative step of a contact-law parameter for its force derivative (a secant: exact for
/// the friction coefficient, on which the forces depend linearly; a direction for the others).
const LAW_STEP: f64 = 0.1;

/// dq/dtheta for each axis of `matrix` that changes the static state (pressure, friction,
/// contact law, disc speed, lining stiffness; temperature through its table's columns), in
/// axis order; axes that change nothing at this state give no shape.
///
/// # Collective
pub fn parameter_shapes<'p>(
    petsc: &'p Petsc,
    matrix: &MatrixSettings,
    ops: &Operators<'p>,
    preload: &Preloaded<'p>,
    lining: Option<&SparseMatrix<'p>>,
) -> Result<Vec<Vector<'p>>, RunError> {
    let (contact, state) = (&preload.contact, &preload.state);
    let q0 = &state.displacement;
    let mut rhs: Vec<Vector<'p>> = Vec::new();
    let mut f0 = q0.duplicate()?;
    contact.force(&state.contact, &mut f0)?;
    // The contact force at the nominal state with one law parameter changed, minus f0.
    let law_change = |parameter: Option<SweepParameter>, speed_factor: f64| {
        let mut laws = contact.interfaces().to_vec();
        if let Some(p) = parameter {
            let sliding = laws.iter().find(|i| i.friction.is_sliding());
            let nominal = match (p, sliding) {
                (SweepParameter::Mu, Some(i)) => i.friction.mu(),
                (SweepParameter::P0 | SweepParameter::Lambda, Some(i)) => match i.normal {
                    crate::contact::law::NormalLaw::Exponential { p0, lambda, .. } => {
                        if p == SweepParameter::P0 {
                            p0
                        } else {
                            lambda
                        }
                    }
                    _ => return Ok(None),
                },
                _ => return Ok(None),
            };
            let value = if nominal > 0.0 {
                nominal * (1.0 + LAW_STEP)
            } else {
                LAW_STEP
            };
            apply_to_laws(p, value, &mut laws)
                .map_err(|e| RunError::scene("matrix.axes", e.to_string()))?;
        }
        let changed = contact.with_laws(laws, contact.disc_speed() * speed_factor)?;
        let s = changed.evaluate(q0, None, state.contact.friction_scale)?;
        let mut f = q0.duplicate()?;
        changed.force(&s, &mut f)?;
        f.axpy(-1.0, &f0)?;
        Ok::<_, RunError>(Some(f))
    };
    for axis in matrix.axis_list() {
        let change = match axis {
            Axis::PressureBar => {
                let mut f = preload.load.duplicate()?;
                f.copy_from(&preload.load)?;
                Some(f)
            }
            Axis::DiscSpeed => law_change(None, 1.0 + LAW_STEP)?,
            Axis::Mu => law_change(Some(SweepParameter::Mu), 1.0)?,
            Axis::P0 => law_change(Some(SweepParameter::P0), 1.0)?,
            Axis::Lambda => law_change(Some(SweepParameter::Lambda), 1.0)?,
            Axis::Temperature => match &matrix.temperature {
                Some(t) if !t.mu.is_empty() => law_change(Some(SweepParameter::Mu), 1.0)?,
                _ => None,
            },
            Axis::LiningModulus => None,
        };
        rhs.extend(change);
    }
    if let Some(k_l) = lining {
        // d/ds (K0 + (s - 1) K_l) q = K_l q: the load a softer lining gives way to.
        let mut f = q0.duplicate()?;
        k_l.mult(q0, &mut f)?;
        f.scale(-1.0)?;
        rhs.push(f);
    }
    // Right-hand sides that vanish (a speed far above the friction's regularization) add
    // nothing; a zero column would only be dropped by the reduction.
    let mut nonzero = Vec::with_capacity(rhs.len());
    for f in rhs {
        if f.norm2()? > 0.0 {
            nonzero.push(f);
        }
    }
    if nonzero.is_empty() {
        return Ok(Vec::new());
    }
    let parts = [
        Part::Normal,
        Part::Stick,
        Part::Friction,
        Part::StickCoupling,
    ];
    let jacobian = contact.linearize(petsc, Base::Plus(&ops.k0), &state.contact, &parts)?;
    let solver = DirectSolver::factorize(petsc, &jacobian, Factorization::Lu, "static_")?;
    nonzero
        .iter()
        .map(|f| {
            let mut x = f.duplicate()?;
            solver.solve(f, &mut x)?;
            Ok(x)
        })
        .collect()
}
