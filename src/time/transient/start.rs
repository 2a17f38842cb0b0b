//! The transient's start (the kicked static state, the load that makes the static state an
//! equilibrium) and its forces: the external load, contact and friction, modal damping.

use super::settings::TransientSettings;
use super::{Kick, TransientInputs};
use crate::contact::ContactState;
use crate::la::{DirectSolver, Factorization, LaError, Petsc, SparseMatrix, Vector};
use crate::time::newmark::{initial_acceleration, State, TimeError};

/// The start: the static state + amplitude x the kick's shape (scaled to its largest entry),
/// or at rest there with the velocity of an impulse; the acceleration from the equation of
/// motion.
///
/// # Collective
pub(super) fn start_state<'p>(
    petsc: &'p Petsc,
    settings: &TransientSettings,
    input: &TransientInputs<'_, 'p>,
    k0: &SparseMatrix<'p>,
) -> Result<State<'p>, TimeError> {
    let mass = DirectSolver::factorize(petsc, input.m, Factorization::Lu, "time_mass_")?;
    let mut q = input.q_static.try_clone()?;
    let mut v = q.duplicate()?;
    v.set_all(0.0)?;
    match input.kick {
        Kick::Displacement(shape) => {
            let largest = shape.norm_inf()?;
            if !largest.is_finite() {
                let what = "the start's kick (the real mode or the random shape)";
                return Err(TimeError::NotFinite {
                    step: 0,
                    time: 0.0,
                    what,
                });
            }
            if largest > 0.0 {
                q.axpy(settings.amplitude / largest, shape)?;
            }
        }
        Kick::Impulse(impulse) => mass.solve(impulse, &mut v)?,
    }
    let a = q.duplicate()?;
    let mut state = State {
        time: 0.0,
        step: 0,
        q,
        v,
        a,
        linear: None,
    };
    let mut contact = ContactForces::new(input)?;
    let mut forces =
        |_t: f64, q: &Vector<'p>, v: &Vector<'p>, f: &mut Vector<'p>| contact.evaluate(q, v, f);
    initial_acceleration(input.m, input.c, k0, &mut state, &mut forces, &mass)?;
    Ok(state)
}

/// The load the transient balances, K0 q_s - f_c(q_s, v = 0), and its difference from f_ext,
/// the static residual's norm. The static state balances f_ext only to the static Newton's
/// tolerance; that residual, a constant force, would set the soft modes of the model vibrating
/// from the first step (a kick of 1 nm along one real mode sees it: 3 % of its radiated power
/// on the small frictionless brake). With this load the static state is an equilibrium of the
/// transient's own equations, whichever route the static solve took.
///
/// # Collective
pub(super) fn balanced_load<'p>(
    input: &TransientInputs<'_, 'p>,
    k0: &SparseMatrix<'p>,
) -> Result<(Vector<'p>, f64), LaError> {
    let at_rest = input.q_static.duplicate()?;
    let state = input
        .contact
        .evaluate(input.q_static, Some(&at_rest), 1.0)?;
    let mut fc = input.q_static.duplicate()?;
    input.contact.force(&state, &mut fc)?;
    let mut load = input.q_static.duplicate()?;
    k0.mult(input.q_static, &mut load)?;
    load.axpy(-1.0, &fc)?;
    let mut residual = load.try_clone()?;
    residual.axpy(-1.0, input.f_ext)?;
    Ok((load, residual.norm2()?))
}

/// A contact state and the displacement and velocity it was evaluated at.
struct Evaluated<'p> {
    state: ContactState,
    q: Vector<'p>,
    v: Vector<'p>,
}

/// The forces of the equation of motion beyond the linear operators, with the contact state
/// of the last evaluation and where it was taken (the step's record reuses it when the step
/// ended there, an elimination when it starts there), and the contact points whose status
/// (open / stick: inside the friction law's regularization band / slip) changed between
/// consecutive evaluations since the last accepted step (the evidence a stalled step's log
/// line gives).
pub(super) struct ContactForces<'r, 'p> {
    input: &'r TransientInputs<'r, 'p>,
    fc: Vector<'p>,
    last: Option<Evaluated<'p>>,
    pub status_changes: usize,
}

impl<'r, 'p> ContactForces<'r, 'p> {
    pub fn new(input: &'r TransientInputs<'r, 'p>) -> Result<Self, LaError> {
        Ok(ContactForces {
            input,
            fc: input.f_ext.duplicate()?,
            last: None,
            status_changes: 0,
        })
    }

    /// f = f_ext + f_contact(q, v) - modal damping force; keeps the contact state evaluated.
    ///
    /// # Collective
    pub fn evaluate(
        &mut self,
        q: &Vector<'p>,
        v: &Vector<'p>,
        f: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        let input = self.input;
        let state = input.contact.evaluate(q, Some(v), 1.0)?;
        input.contact.force(&state, &mut self.fc)?;
        match self.last.as_mut() {
            Some(previous) => {
                let changed = previous
                    .state
                    .response
                    .iter()
                    .zip(&state.response)
                    .filter(|(a, b)| a.status != b.status)
                    .count();
                self.status_changes += changed;
                previous.state = state;
                previous.q.copy_from(q)?;
                previous.v.copy_from(v)?;
            }
            None => {
                self.last = Some(Evaluated {
                    state,
                    q: q.try_clone()?,
                    v: v.try_clone()?,
                })
            }
        }
        f.copy_from(input.f_ext)?;
        f.axpy(1.0, &self.fc)?;
        match input.modal_damping {
            Some(modal) => modal.subtract_force(v, f),
            None => Ok(()),
        }
    }

    /// The last evaluation's contact state (None: none yet).
    pub fn last(&self) -> Option<&ContactState> {
        self.last.as_ref().map(|e| &e.state)
    }

    /// The last evaluation's contact state if it was taken at `at` (None: elsewhere).
    pub fn last_at(&self, at: &State<'p>) -> Result<Option<&ContactState>, LaError> {
        match &self.last {
            Some(e) if e.q.equals(&at.q)? && e.v.equals(&at.v)? => Ok(Some(&e.state)),
            _ => Ok(None),
        }
    }

    /// Sliding points of the last evaluation inside the friction regularization band, on
    /// this rank.
    pub fn in_friction_band(&self) -> usize {
        self.last().map_or(0, |s| {
            s.response.iter().filter(|r| r.in_friction_band()).count()
        })
    }
}
