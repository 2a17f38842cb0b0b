//! One part of a nonlinear elimination (eliminate.rs): the unknowns b of a set of contact
//! points, coupled through L_bb and the points' rows and held apart from the rest, solved by
//! Newton with the exact local tangent: R_b(q + delta) = R_b(q) + L_bb delta - (f_b(q +
//! delta, v + c1 delta) - f_b(q, v)) = 0.

use super::local_jacobian::{BlockScratch, LocalPattern};
use crate::contact::kernel::{PointResponse, PointRows};
use crate::contact::ContactModel;
use crate::la::lapack::RealLu;
use crate::la::local_lu::{Csr, LocalLu};
use crate::la::{LaError, Petsc};

/// Local Newton iterations at most per elimination.
const MAX_LOCAL_ITERATIONS: usize = 25;

/// A local Jacobian's LU: sparse, or dense and pivoted where the sparse one met a zero pivot.
pub(super) enum LocalFactor<'p> {
    Sparse(LocalLu<'p>),
    Dense(RealLu),
}

impl LocalFactor<'_> {
    pub(super) fn solve(&self, b: &mut [f64]) -> Result<(), LaError> {
        match self {
            LocalFactor::Sparse(lu) => lu.solve(b),
            LocalFactor::Dense(lu) => Ok(lu.solve(b)?),
        }
    }
}

/// A part's unknowns b (ascending), the points that couple any of them, and for every such
/// point the position in b of each of its rows' DOFs (None: held).
pub(super) struct PartUnknowns {
    pub b: Vec<usize>,
    pub points: Vec<usize>,
    pub at: Vec<Vec<Option<usize>>>,
}

impl PartUnknowns {
    pub(super) fn new(rows: &[PointRows], b: Vec<usize>, points: Vec<usize>) -> Self {
        let position = |dof: i32| -> Option<usize> {
            (dof >= 0)
                .then(|| b.binary_search(&(dof as usize)).ok())
                .flatten()
        };
        let at = points
            .iter()
            .map(|&id| rows[id].dofs.iter().map(|&d| position(d)).collect())
            .collect();
        PartUnknowns { b, points, at }
    }
}

/// One part of an elimination's subproblem (parts.rs), solved on the rank it fell to.
pub(super) struct Local<'s, 'p> {
    petsc: &'p Petsc<'p>,
    contact: &'s ContactModel<'p>,
    rows: &'s [PointRows],
    zone_dofs: &'s [Vec<i32>],
    b: &'s [usize],
    points: &'s [usize],
    at: &'s [Vec<Option<usize>>],
    /// The iterate's displacement and velocity on the zone.
    q: &'s [f64],
    v: &'s [f64],
    c1: f64,
}

impl<'s, 'p> Local<'s, 'p> {
    #[allow(clippy::too_many_arguments)] // the subproblem's parts, each named once here
    pub(super) fn new(
        petsc: &'p Petsc<'p>,
        contact: &'s ContactModel<'p>,
        rows: &'s [PointRows],
        zone_dofs: &'s [Vec<i32>],
        part: &'s PartUnknowns,
        q: &'s [f64],
        v: &'s [f64],
        c1: f64,
    ) -> Self {
        Local {
            petsc,
            contact,
            rows,
            zone_dofs,
            b: &part.b,
            points: &part.points,
            at: &part.at,
            q,
            v,
            c1,
        }
    }

    /// The points' force on b at q + delta, and every coupling point's response there.
    fn force(&self, delta: &[f64]) -> (Vec<f64>, Vec<PointResponse>) {
        let mut f = vec![0.0; self.b.len()];
        let mut responses = Vec::with_capacity(self.points.len());
        let (mut u, mut w, mut force) = (Vec::new(), Vec::new(), Vec::new());
        for (&id, at) in self.points.iter().zip(self.at) {
            let dofs = &self.zone_dofs[id];
            let value = |x: &[f64], scale: f64, out: &mut Vec<f64>| {
                out.clear();
                out.extend(dofs.iter().zip(at).map(|(&z, p)| {
                    let base = if z >= 0 { x[z as usize] } else { 0.0 };
                    base + p.map_or(0.0, |p| scale * delta[p])
                }));
            };
            value(self.q, 1.0, &mut u);
            value(self.v, self.c1, &mut w);
            force.resize(at.len(), 0.0);
            let response = self
                .contact
                .evaluate_point(id, &self.rows[id], &u, &w, &mut force);
            for (i, p) in at.iter().enumerate() {
                if let Some(p) = p {
                    f[*p] += force[i];
                }
            }
            responses.push(response);
        }
        (f, responses)
    }

    /// L_bb + T_bb, T_bb the points' consistent tangent (-df_b/d delta) at `responses`, as
    /// values of `pattern`.
    fn jacobian_values(
        &self,
        linear: &Csr,
        pattern: &LocalPattern,
        responses: &[PointResponse],
    ) -> Vec<f64> {
        let mut values = pattern.linear_values(linear);
        let (mut terms, mut scratch) = (Vec::new(), BlockScratch::default());
        for (p, (&id, response)) in self.points.iter().zip(responses).enumerate() {
            self.contact
                .point_tangent_terms(id, response, self.c1, &mut terms);
            pattern.add_point(p, &self.rows[id], &terms, &mut values, &mut scratch);
        }
        values
    }

    /// Newton with backtracking on |R_b| from delta = 0, its LU kept while it contracts the
    /// residual tenfold per iteration (a chord: the local tangent changes at few points
    /// between iterates), starting from `factor` (the previous elimination's, on the same
    /// unknowns) when given.
    pub(super) fn newton(
        &self,
        linear: &Csr,
        pattern: &LocalPattern,
        rb: &[f64],
        tolerance: f64,
        mut factor: Option<LocalFactor<'p>>,
    ) -> Result<LocalSolution<'p>, LaError> {
        let n = self.b.len();
        let (f0, responses0) = self.force(&vec![0.0; n]);
        let residual = |delta: &[f64]| -> (Vec<f64>, f64, Vec<PointResponse>) {
            let (f, responses) = self.force(delta);
            let mut r = rb.to_vec();
            linear.mult_add(delta, &mut r);
            for i in 0..n {
                r[i] -= f[i] - f0[i];
            }
            let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            (r, norm, responses)
        };
        let mut out = LocalSolution {
            delta: vec![0.0; n],
            iterations: 0,
            factorizations: 0,
            dense_factorizations: 0,
            numeric_refactorizations: 0,
            factor_entries: 0.0,
            factor_seconds: 0.0,
            converged: false,
            factor: None,
        };
        // At delta = 0 the residual is R_b itself (the forces' change is zero).
        let (mut r, mut responses) = (rb.to_vec(), responses0);
        let mut norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut previous = f64::INFINITY;
        while out.iterations < MAX_LOCAL_ITERATIONS {
            if norm <= tolerance {
                out.converged = true;
                break;
            }
            let fresh = factor.is_none() || norm > 0.1 * previous;
            if fresh {
                let clock = std::time::Instant::now();
                let values = self.jacobian_values(linear, pattern, &responses);
                let (made, numeric_only) = self.factor(pattern, values, factor.take())?;
                out.factor_seconds += clock.elapsed().as_secs_f64();
                out.factorizations += 1;
                out.numeric_refactorizations += usize::from(numeric_only);
                match &made {
                    LocalFactor::Sparse(lu) => out.factor_entries += lu.factor_entries(),
                    LocalFactor::Dense(_) => out.dense_factorizations += 1,
                }
                factor = Some(made);
            }
            let lu = factor.as_ref().expect("factored above");
            let mut step: Vec<f64> = r.iter().map(|x| -x).collect();
            lu.solve(&mut step)?;
            out.iterations += 1;
            let mut alpha = 1.0;
            loop {
                let trial: Vec<f64> = (out.delta.iter().zip(&step))
                    .map(|(d, s)| d + alpha * s)
                    .collect();
                let (rt, nt, at_trial) = residual(&trial);
                if nt.is_finite() && (nt <= (1.0 - 1e-4 * alpha) * norm || alpha < 1.0 / 64.0) {
                    if nt < norm {
                        previous = norm;
                        (out.delta, r, norm, responses) = (trial, rt, nt, at_trial);
                    } else if fresh {
                        // No descent along the exact tangent's direction: give up here.
                        out.factor = factor;
                        return Ok(out);
                    } else {
                        // A kept factor's direction: refactor at this iterate and retry.
                        previous = 0.0;
                    }
                    break;
                }
                alpha *= 0.5;
            }
        }
        out.converged = norm <= tolerance;
        out.factor = factor;
        Ok(out)
    }

    /// LU of the local Jacobian with `values` in `pattern`: sparse, dense where that meets a
    /// zero pivot; `previous`, a sparse factor on these unknowns, is refactored in place
    /// (then true: the numerical phase alone).
    fn factor(
        &self,
        pattern: &LocalPattern,
        values: Vec<f64>,
        previous: Option<LocalFactor<'p>>,
    ) -> Result<(LocalFactor<'p>, bool), LaError> {
        if let Some(LocalFactor::Sparse(mut lu)) = previous {
            if lu.refactor(&values)? {
                return Ok((LocalFactor::Sparse(lu), true));
            }
        }
        let jacobian = Csr {
            values,
            ..pattern.jacobian.clone()
        };
        let made = match LocalLu::new(self.petsc, &jacobian)? {
            Some(lu) => LocalFactor::Sparse(lu),
            None => LocalFactor::Dense(RealLu::new(jacobian.n, jacobian.dense_columns())?),
        };
        Ok((made, false))
    }
}

/// A local Newton's outcome.
pub(super) struct LocalSolution<'p> {
    pub(super) delta: Vec<f64>,
    pub(super) iterations: usize,
    pub(super) factorizations: usize,
    pub(super) dense_factorizations: usize,
    pub(super) numeric_refactorizations: usize,
    pub(super) factor_entries: f64,
    pub(super) factor_seconds: f64,
    pub(super) converged: bool,
    /// The last factor used (for the next elimination on the same unknowns).
    pub(super) factor: Option<LocalFactor<'p>>,
}
