//! The transient's Jacobians: J = M/(beta h^2) + gamma/(beta h) C + K0 + the contact tangent,
//! factorized by MUMPS over the ranks or, for a small reduced model, whole on every rank by
//! PETSc's LU (one solve streams the factor at one core's bandwidth, ~3x faster than MUMPS'
//! distributed solve at 2,000 unknowns: benches/transient-results.md). The first uses the
//! static state's tangent: by default the consistent one (friction coupling and friction
//! damping included, unsymmetric, LU: the growth's iterations need ~1 correction per step),
//! or with `first_jacobian = "mock"` its normal and stick stiffness alone (symmetric, Cholesky
//! with MUMPS), the mock contact stiffness of DESIGN.md; a refresh uses the tangent of the
//! current state, friction and friction damping included (unsymmetric, LU).

use std::time::Instant;

use super::settings::{FirstJacobian, JacobianFactor};
use crate::contact::kernel::Part;
use crate::contact::linearize::Base;
use crate::contact::linearize::TangentOperator;
use crate::contact::{ContactModel, ContactState};
use crate::la::{BlockAddPlan, DirectSolver, Factorization, LaError, Petsc, SparseMatrix, Vector};
use crate::time::newmark::{jacobian, Damping, Jacobian, NewmarkSettings, RetiredJacobian, State};

/// The contact tangent parts of the consistent Jacobian (with the friction damping through
/// gamma / (beta h)): the joints' stick traction also moves with the gap
/// (StickCoupling).
const CONSISTENT: [Part; 4] = [
    Part::Normal,
    Part::Stick,
    Part::Friction,
    Part::StickCoupling,
];

/// Builds and factorizes Jacobians, and keeps what a checkpoint needs to rebuild the current
/// one (the state it was built at).
pub(super) struct JacobianBuilder<'a, 'p> {
    petsc: &'p Petsc<'p>,
    contact: &'a ContactModel<'p>,
    /// K0 on the pattern joined with the contact couplings.
    k0: &'a SparseMatrix<'p>,
    m: &'a SparseMatrix<'p>,
    c: Damping<'a, 'p>,
    static_state: &'a ContactState,
    /// The static mock contact stiffness (normal and stick), with `first_jacobian = "mock"`;
    /// None: the first J is the static state's consistent tangent.
    mock: Option<SparseMatrix<'p>>,
    /// Where J is factorized ("auto" resolved).
    factor: JacobianFactor,
    /// A restart's saved Jacobian state, used by the first factorization.
    restart_at: Option<(Vector<'p>, Vector<'p>)>,
    /// The state the current Jacobian was built at (None: the static state, the first J).
    pub built_at: Option<(Vector<'p>, Vector<'p>)>,
    /// The contact state the current Jacobian's tangent was built from (None: the static
    /// mock's), and gamma / (beta h) of its friction damping (0: none).
    built_contact: Option<ContactState>,
    built_damping: f64,
    pub factor_entries: f64,
    /// Of them, on the rank that holds most (FactorizationReport::factor_entries_largest_rank).
    pub factor_entries_largest_rank: f64,
    /// Bytes per factor value and passes over the factor per solve (LU 1, LDL^T 2), of the
    /// last factorization.
    pub factor_streaming: (f64, f64),
    pub built: usize,
    /// All factorizations, and those within the stepping loop.
    pub seconds_factorizing: f64,
    pub seconds_in_loop: f64,
    /// Of `seconds_factorizing`: assembling J (contact tangent and sums), before MUMPS.
    pub seconds_assembling: f64,
    /// What the refreshed Jacobians of the current step size share.
    base: Option<RefreshBase<'p>>,
}

/// J's values without the contact tangent, M / (beta h^2) + gamma / (beta h) C + K0 on J's
/// pattern, for one step size; where the tangent's entries land in the last refreshed J, and
/// which matrix that is (a refresh renews it in place when it is handed back).
struct RefreshBase<'p> {
    step: f64,
    values: SparseMatrix<'p>,
    plan: Option<BlockAddPlan>,
    last: Option<usize>,
}

impl<'a, 'p> JacobianBuilder<'a, 'p> {
    /// # Collective
    #[allow(clippy::too_many_arguments)] // the operators J is made of
    pub fn new(
        petsc: &'p Petsc<'p>,
        contact: &'a ContactModel<'p>,
        k0: &'a SparseMatrix<'p>,
        k0_input: &'a SparseMatrix<'p>,
        m: &'a SparseMatrix<'p>,
        c: Damping<'a, 'p>,
        static_state: &'a ContactState,
        restart_at: Option<(Vector<'p>, Vector<'p>)>,
        factor: JacobianFactor,
        first: FirstJacobian,
    ) -> Result<Self, LaError> {
        let mock = match first {
            FirstJacobian::Mock => Some(contact.linearize(
                petsc,
                Base::PatternOf(k0_input),
                static_state,
                &[Part::Normal, Part::Stick],
            )?),
            FirstJacobian::Consistent => None,
        };
        Ok(JacobianBuilder {
            petsc,
            contact,
            k0,
            m,
            c,
            static_state,
            mock,
            factor,
            restart_at,
            built_at: None,
            built_contact: None,
            built_damping: 0.0,
            factor_entries: 0.0,
            factor_entries_largest_rank: 0.0,
            factor_streaming: (8.0, 1.0),
            built: 0,
            seconds_factorizing: 0.0,
            seconds_in_loop: 0.0,
            seconds_assembling: 0.0,
            base: None,
        })
    }

    /// The change of the consistent contact tangent from the current Jacobian's to an
    /// iterate's, as one operator through the observation rows (what Newton-Krylov adds to J).
    ///
    /// # Collective
    pub fn linearize(
        &self,
        ns: &NewmarkSettings,
        at: &State<'p>,
    ) -> Result<TangentOperator<'a, 'p>, LaError> {
        let cs = self.contact.evaluate(&at.q, Some(&at.v), 1.0)?;
        self.linearize_at(ns, &cs)
    }

    /// [`Self::linearize`] from the iterate's contact state `cs`, already evaluated.
    ///
    /// # Collective
    pub fn linearize_at(
        &self,
        ns: &NewmarkSettings,
        cs: &ContactState,
    ) -> Result<TangentOperator<'a, 'p>, LaError> {
        let contact = self.contact;
        let c1 = ns.gamma / (ns.beta * ns.step);
        let damping: &[Part] = &[Part::Damping];
        let mock: &[Part] = &[Part::Normal, Part::Stick];
        let mut terms = vec![(cs, &CONSISTENT[..], 1.0), (cs, damping, c1)];
        match &self.built_contact {
            Some(built) => {
                terms.push((built, &CONSISTENT[..], -1.0));
                terms.push((built, damping, -self.built_damping));
            }
            None => terms.push((self.static_state, mock, -1.0)),
        }
        contact.tangent_operator_of(self.petsc, &terms)
    }

    /// Where J is factorized, for the summary.
    pub fn solver_name(&self) -> &'static str {
        match self.factor {
            JacobianFactor::PerRank => "LU on every rank",
            JacobianFactor::Single => "MUMPS over all ranks in single precision",
            _ => "MUMPS over all ranks",
        }
    }

    /// Factorizes J at `at` (the current state's tangent) or, with None, with the static
    /// state's (`first_jacobian`); a restart's saved state takes precedence once. The contact
    /// tangent beyond K0 comes back as an operator applied through the observation rows (the
    /// iteration's correction of the carried linear force). `retired`, the Jacobian this one replaces:
    /// when it is the last refreshed J of this step size, its matrix takes the new values in
    /// place and its factor is renewed by the numerical phase alone.
    ///
    /// # Collective
    pub fn factorize(
        &mut self,
        ns: &NewmarkSettings,
        at: Option<&State<'p>>,
        retired: Option<RetiredJacobian<'p>>,
    ) -> Result<Jacobian<'a, 'p>, LaError> {
        let t = Instant::now();
        let saved = self.restart_at.take();
        let at: Option<(&Vector<'p>, &Vector<'p>)> = match (&saved, at) {
            (Some((q, v)), _) => Some((q, v)),
            (None, Some(s)) => Some((&s.q, &s.v)),
            (None, None) => None,
        };
        let (cs, built_at) = match at {
            Some((q, v)) => (
                self.contact.evaluate(q, Some(v), 1.0)?,
                Some((q.try_clone()?, v.try_clone()?)),
            ),
            None if self.mock.is_some() => {
                drop(retired);
                return self.factorize_mock(ns, t);
            }
            // The static state's consistent tangent; `built_at` None marks it as the first
            // J, which a checkpoint's restart rebuilds the same way.
            None => (self.static_state.clone(), None),
        };
        let contact = self.contact;
        // The friction damping C_f (w dt/dw c_t c_t^T, large where points nearly stick)
        // enters through gamma / (beta h); the joints' stick traction also moves with the gap
        // (StickCoupling).
        let c1 = ns.gamma / (ns.beta * ns.step);
        let terms: [(&[Part], f64); 2] = [(&CONSISTENT, 1.0), (&[Part::Damping], c1)];
        let (mut j, old_factor) = self.refresh_matrix(ns, retired)?;
        self.add_tangent(&cs, &terms, &mut j)?;
        self.built_at = built_at;
        self.built_damping = c1;
        let extra = contact.tangent_operator(self.petsc, &cs, &terms)?;
        self.built_contact = Some(cs);
        self.seconds_assembling += t.elapsed().as_secs_f64();
        let factor = match old_factor {
            Some(factor) => {
                factor.renewed_or(&j, || self.factorize_matrix(&j, Factorization::Lu))?
            }
            None => self.factorize_matrix(&j, Factorization::Lu)?,
        };
        Ok(self.finish(factor, Factorization::Lu, t, extra, j))
    }

    /// J with the static mock contact stiffness (symmetric: Cholesky).
    ///
    /// # Collective
    fn factorize_mock(
        &mut self,
        ns: &NewmarkSettings,
        t: Instant,
    ) -> Result<Jacobian<'a, 'p>, LaError> {
        self.built_contact = None;
        self.built_damping = 0.0;
        self.built_at = None;
        let extra = self.contact.tangent_operator(
            self.petsc,
            self.static_state,
            &[(&[Part::Normal, Part::Stick], 1.0)],
        )?;
        let j = jacobian(ns, self.m, self.c, self.k0, self.mock.as_ref())?;
        j.set_symmetric(true)?;
        self.seconds_assembling += t.elapsed().as_secs_f64();
        let factor = self.factorize_matrix(&j, Factorization::Cholesky)?;
        Ok(self.finish(factor, Factorization::Cholesky, t, extra, j))
    }

    /// A refreshed J's matrix holding M / (beta h^2) + gamma / (beta h) C + K0 (the contact
    /// tangent still to add): `retired`'s matrix, with its factor, when it is the last one
    /// refreshed for this step size, else a new copy of those values (`retired` freed
    /// first: peak memory).
    ///
    /// # Collective
    fn refresh_matrix(
        &mut self,
        ns: &NewmarkSettings,
        retired: Option<RetiredJacobian<'p>>,
    ) -> Result<(SparseMatrix<'p>, Option<DirectSolver<'p>>), LaError> {
        if self.base.as_ref().map(|b| b.step) != Some(ns.step) {
            self.base = None;
            self.base = Some(RefreshBase {
                step: ns.step,
                values: jacobian(ns, self.m, self.c, self.k0, None)?,
                plan: None,
                last: None,
            });
        }
        let base = self.base.as_mut().expect("set above");
        let renewable = retired.filter(|r| Some(r.matrix.identity()) == base.last);
        // The same decision on every rank (a renewal and a new build are collective).
        let (matrix, factor) = match renewable {
            Some(RetiredJacobian { mut matrix, factor }) => {
                let keeps = factor.factors(&matrix)?;
                matrix.copy_values_from(&base.values)?;
                (matrix, keeps.then_some(factor))
            }
            None => {
                let matrix = base.values.try_clone()?;
                base.plan = None;
                (matrix, None)
            }
        };
        base.last = Some(matrix.identity());
        Ok((matrix, factor))
    }

    /// Adds the contact tangent `terms` at `state` to a refreshed J, through the plan of where
    /// its entries land (planned once per matrix).
    ///
    /// # Collective
    fn add_tangent(
        &mut self,
        state: &ContactState,
        terms: &[(&[Part], f64)],
        j: &mut SparseMatrix<'p>,
    ) -> Result<(), LaError> {
        let contact = self.contact;
        let base = self.base.as_mut().expect("a refresh sets its base first");
        let fits = match &base.plan {
            Some(plan) => contact.tangent_plan_fits(plan, j)?,
            None => false,
        };
        if !fits {
            base.plan = None;
            base.plan = contact.tangent_plan(j)?;
        }
        match &mut base.plan {
            Some(plan) => contact.add_tangent_terms_planned(state, terms, j, plan),
            None => {
                contact.add_tangent_terms(state, terms, j)?;
                j.assemble()
            }
        }
    }

    /// A new factor of `j` where this builder factorizes.
    ///
    /// # Collective
    fn factorize_matrix(
        &self,
        j: &SparseMatrix<'p>,
        kind: Factorization,
    ) -> Result<DirectSolver<'p>, LaError> {
        match self.factor {
            JacobianFactor::PerRank => DirectSolver::factorize_per_rank(self.petsc, j, "time_"),
            JacobianFactor::Single => DirectSolver::factorize_single(self.petsc, j, kind, "time_"),
            _ => DirectSolver::factorize(self.petsc, j, kind, "time_"),
        }
    }

    /// Records a factorization's size, streaming and time, and makes the Jacobian.
    fn finish(
        &mut self,
        factor: DirectSolver<'p>,
        kind: Factorization,
        t: Instant,
        extra: TangentOperator<'a, 'p>,
        j: SparseMatrix<'p>,
    ) -> Jacobian<'a, 'p> {
        self.factor_entries = factor.report().factor_entries;
        self.factor_entries_largest_rank = factor.report().factor_entries_largest_rank;
        let value_bytes = if self.factor == JacobianFactor::Single {
            4.0
        } else {
            8.0
        };
        // PETSc's per-rank LU factors whatever J is: one pass over L and U.
        let passes = match (kind, self.factor) {
            (Factorization::Cholesky, JacobianFactor::Distributed | JacobianFactor::Single) => 2.0,
            _ => 1.0,
        };
        self.factor_streaming = (value_bytes, passes);
        self.built += 1;
        self.seconds_factorizing += t.elapsed().as_secs_f64();
        self.seconds_in_loop += t.elapsed().as_secs_f64();
        Jacobian {
            factor,
            extra: Some(Box::new(extra)),
            matrix: Some(j),
        }
    }
}
