//! Nonlinear elimination of the contact points whose tangent changed most (Lanzkron, Rose &
//! Wilkes, SIAM J. Sci. Comput. 17 (1996) 1139; Cai & Li, SIAM J. Sci. Comput. 33 (2011)
//! 746): at an iterate, the unknowns b those points couple are moved so that the residual's
//! rows b vanish with the other unknowns held, solving the small nonlinear system
//! R_b(q + delta) = 0 by Newton with its exact tangent, redundantly on every rank. The
//! fixed factor's correction then acts on a residual whose stiff, switching local laws (the
//! friction band's mu p / slip_speed through gamma / (beta h), the exponential contact of a
//! point that opens or closes) are already satisfied: the kinks at which the fixed J's
//! iterations stall in the saturated regime (benches/transient-results.md). What the
//! elimination leaves is smooth but can be slow along a few global directions (the
//! consistent tangent far softer than J there): Anderson acceleration of the fixed factor's
//! corrections (`transient.anderson`) removes those; alone, the elimination stalled there.
//!
//! R_b(q + delta) = R_b(q) + L_bb delta - (f_b(q + delta, v + c1 delta) - f_b(q, v)), with
//! L = M / (beta h^2) + c1 C + K (the linear part of R, c1 = gamma / (beta h)) and f the
//! contact force of the points that couple some unknown of b (the modal damping force, a few
//! modes' low-rank term, is left to the global iteration).
//!
//! The local Jacobian is sparse (the kept FE DOFs of the contact zone, coupled as its mesh and
//! the points couple them, 4-6 unknowns per point): factored by a sparse LU
//! ([`crate::la::local_lu`]), whose cost grows far slower with the points than a dense LU's
//! cube (at 256 points of the 600k brake, 1,088 unknowns, a dense LU is 0.86 GFLOP: 80 ms
//! per elimination, 56 with the sparse one); a dense pivoted LU only where the sparse one
//! meets a zero pivot.

use super::local_jacobian::{BlockScratch, LocalPattern};
use crate::contact::kernel::{PointResponse, PointRows};
use crate::contact::ContactModel;
use crate::la::lapack::RealLu;
use crate::la::local_lu::{Csr, LocalLu, RowMarker};
use crate::la::{
    ColumnBlock, LaError, MatrixFormat, Petsc, Selection, SparseMatrix, TangentChange, Vector,
};
use crate::time::newmark::{Damping, Elimination, NewmarkSettings, State};

/// Local Newton iterations at most per elimination.
const MAX_LOCAL_ITERATIONS: usize = 25;

/// What the eliminations of a run did.
#[derive(Debug, Clone, Copy, Default)]
pub struct EliminationCounts {
    pub eliminations: usize,
    pub points: usize,
    pub unknowns: usize,
    pub local_iterations: usize,
    /// LU factorizations of the local Jacobian (a factor is kept while it contracts the
    /// local residual tenfold per iteration, across the eliminations of a step when their
    /// unknowns are the same).
    pub local_factorizations: usize,
    /// Of those, the dense pivoted LUs made where the sparse LU met a zero pivot, and the
    /// sparse ones renewed by the numerical phase alone (the pattern of an earlier local
    /// Jacobian on the same unknowns, its ordering and symbolic factorization kept).
    pub dense_factorizations: usize,
    pub numeric_refactorizations: usize,
    /// The sparse factors' stored entries, summed over the local factorizations.
    pub factor_entries: f64,
    pub unconverged: usize,
    pub seconds: f64,
    /// Of `seconds`: ranking the points by their tangent change, taking L_bb out of the
    /// operators and building the local Jacobian's pattern (when the unknowns changed), the
    /// local Newton, and in it the local Jacobians' assembly and LU.
    pub seconds_ranking: f64,
    /// Of `seconds`: the consistent tangent's change at the iterate (from the contact state
    /// of the residual's evaluation there), which the ranking reads.
    pub seconds_tangent: f64,
    pub seconds_blocks: f64,
    pub seconds_local_newton: f64,
    pub seconds_factorizing: f64,
    /// Of `seconds`: the linear force's change of each move, from the operators' columns on
    /// the moved unknowns.
    pub seconds_linear_change: f64,
    /// The largest of the steps' `StepReport::elimination_mismatch` (<= 0.1 where the local
    /// residual is the global residual's rows and every local Newton converged).
    pub worst_mismatch: f64,
}

/// The operators and the points' rows an elimination needs, gathered once.
pub(super) struct Eliminator<'a, 'p> {
    petsc: &'p Petsc<'p>,
    contact: &'a ContactModel<'p>,
    rows: Vec<PointRows>,
    /// For every point, each of its rows' DOFs' position in the zone (-1: eliminated).
    zone_dofs: Vec<Vec<i32>>,
    /// For every unknown, the points whose rows couple it.
    points_of: Vec<Vec<u32>>,
    /// Markers over the unknowns and over the points (their distinct members, sorted).
    unknown_marker: RowMarker,
    point_marker: RowMarker,
    /// K, M and C (a damping matrix) on the unknowns of every contact point, whole on every
    /// rank: L_bb of any b is taken out of them, no communication (b changes at nearly every
    /// elimination; taking its blocks out of the distributed operators cost 5.2 ms each at
    /// 600k, 10 % of the eliminations).
    zone: Zone,
    /// K, M and C's columns on the zone, this rank's rows: the linear force's change of a
    /// move of b from b's columns alone (a product with the whole J streamed the operator
    /// for the ~3 % of it a move of 256 points touches, 2026-11-30).
    columns: ZoneColumns,
    /// The zone's entries of q, v and R gathered by one scatter built at the first
    /// elimination (a scatter of the whole vector built per gather cost 7 % of them).
    gather: Option<Selection<'p>>,
    rayleigh: (f64, f64),
    max_points: usize,
    /// The last elimination's unknowns, L_bb for them (and the c1 it was built with), the
    /// local Jacobian's pattern and its last local factor, reused while the unknowns stay
    /// the same.
    kept: Option<Kept<'p>>,
    pub counts: EliminationCounts,
}

/// The unknowns coupled by the contact points and the operators' blocks on them.
struct Zone {
    unknowns: Vec<usize>,
    /// Position in `unknowns` of every unknown (-1: not coupled by any point).
    position: Vec<i32>,
    k: Csr,
    m: Csr,
    c: Option<Csr>,
}

/// The operators' columns on the zone's unknowns, this rank's rows.
struct ZoneColumns {
    k: ColumnBlock,
    m: ColumnBlock,
    c: Option<ColumnBlock>,
}

/// What an elimination leaves for the next one on the same unknowns.
struct Kept<'p> {
    b: Vec<usize>,
    c1: f64,
    linear: Csr,
    pattern: LocalPattern,
    factor: Option<LocalFactor<'p>>,
}

/// A local Jacobian's LU: sparse, or dense and pivoted where the sparse one met a zero pivot.
enum LocalFactor<'p> {
    Sparse(LocalLu<'p>),
    Dense(RealLu),
}

impl LocalFactor<'_> {
    fn solve(&self, b: &mut [f64]) -> Result<(), LaError> {
        match self {
            LocalFactor::Sparse(lu) => lu.solve(b),
            LocalFactor::Dense(lu) => Ok(lu.solve(b)?),
        }
    }
}

impl<'a, 'p> Eliminator<'a, 'p> {
    /// # Collective
    pub fn new(
        petsc: &'p Petsc,
        contact: &'a ContactModel<'p>,
        k: &'a SparseMatrix<'p>,
        m: &'a SparseMatrix<'p>,
        c: Damping<'a, 'p>,
        max_points: usize,
    ) -> Result<Self, LaError> {
        let rows = contact.all_point_rows(petsc)?;
        let mut points_of = vec![Vec::new(); k.global_rows()];
        for (id, r) in rows.iter().enumerate() {
            for &d in r.dofs.iter().filter(|&&d| d >= 0) {
                points_of[d as usize].push(id as u32);
            }
        }
        for p in &mut points_of {
            p.sort_unstable();
            p.dedup();
        }
        let unknowns: Vec<usize> = (0..points_of.len())
            .filter(|&d| !points_of[d].is_empty())
            .collect();
        let mut position = vec![-1i32; points_of.len()];
        for (z, &d) in unknowns.iter().enumerate() {
            position[d] = z as i32;
        }
        let zone_dofs = rows
            .iter()
            .map(|r| {
                r.dofs
                    .iter()
                    .map(|&d| if d >= 0 { position[d as usize] } else { -1 })
                    .collect()
            })
            .collect();
        let block = |a: &SparseMatrix<'p>| -> Result<Csr, LaError> {
            match a.format() {
                MatrixFormat::Aij => a.block(&unknowns),
                _ => a.convert(MatrixFormat::Aij)?.block(&unknowns),
            }
        };
        let (c_block, c_columns, rayleigh) = match c {
            Damping::None => (None, None, (0.0, 0.0)),
            Damping::Rayleigh { alpha, beta } => (None, None, (alpha, beta)),
            Damping::Matrix(c) => (
                Some(block(c)?),
                Some(ColumnBlock::new(c, &unknowns)?),
                (0.0, 0.0),
            ),
        };
        let columns = ZoneColumns {
            k: ColumnBlock::new(k, &unknowns)?,
            m: ColumnBlock::new(m, &unknowns)?,
            c: c_columns,
        };
        let (k, m, c) = (block(k)?, block(m)?, c_block);
        Ok(Eliminator {
            petsc,
            contact,
            point_marker: RowMarker::new(rows.len()),
            rows,
            zone_dofs,
            unknown_marker: RowMarker::new(points_of.len()),
            points_of,
            columns,
            zone: Zone {
                unknowns,
                position,
                k,
                m,
                c,
            },
            gather: None,
            rayleigh,
            max_points,
            kept: None,
            counts: EliminationCounts::default(),
        })
    }

    /// The increment delta (zero off b) that zeroes the residual's rows b at the iterate
    /// `at` with residual `r`, b being the unknowns of the points where `tangent` (the
    /// consistent tangent's change from the factored J's) is largest; None: no such point.
    ///
    /// # Collective
    pub fn solve(
        &mut self,
        ns: &NewmarkSettings,
        at: &State<'p>,
        r: &Vector<'p>,
        tangent: &dyn TangentChange<'p>,
        target: f64,
    ) -> Result<Option<Elimination<'p>>, LaError> {
        let clock = std::time::Instant::now();
        // The `max_points` largest changes, however small the rest: a point left out with a
        // tangent far from J's stalls the global iteration (measured: keeping 99.99 % of the
        // change's norm instead, ~30 points on the small brake, refreshed J 6x as often).
        let dominant = tangent.dominant_points(self.max_points)?;
        self.counts.seconds_ranking += clock.elapsed().as_secs_f64();
        let Some(dominant) = dominant else {
            return Ok(None);
        };
        let row_ids = self.contact.row_ids();
        let mut chosen: Vec<usize> = dominant.iter().map(|&row| row_ids[row]).collect();
        chosen.dedup();
        // The distinct unknowns and points by markers (sorting the repeated ones, ~6 per
        // unknown, took 5 % of the eliminations).
        let mut b = Vec::new();
        let dofs = chosen
            .iter()
            .flat_map(|&id| self.rows[id].dofs.iter())
            .filter(|&&d| d >= 0)
            .map(|&d| d as usize);
        self.unknown_marker.push_row(dofs, &mut b);
        self.unknown_marker.clear(&b);
        if b.is_empty() {
            return Ok(None);
        }
        let mut touching = Vec::new();
        let points = b
            .iter()
            .flat_map(|&d| self.points_of[d].iter().map(|&p| p as usize));
        self.point_marker.push_row(points, &mut touching);
        self.point_marker.clear(&touching);
        if self.gather.is_none() {
            self.gather = Some(Selection::new(r, &self.zone.unknowns)?);
        }
        let gather = self.gather.as_ref().expect("built above");
        let (q, v, residual) = (
            gather.gather(&at.q)?,
            gather.gather(&at.v)?,
            gather.gather(r)?,
        );
        let c1 = ns.gamma / (ns.beta * ns.step);
        let problem = Local::new(
            self.petsc,
            self.contact,
            &self.rows,
            &self.zone_dofs,
            &b,
            &touching,
            &q,
            &v,
            c1,
        );
        // (Every rank holds the same b: the same branch everywhere, collective or not.)
        let blocks = std::time::Instant::now();
        let kept = match self.kept.take() {
            Some(k) if k.b == b && k.c1 == c1 => k,
            _ => {
                let linear = self.linear_block(ns, &b);
                let pattern = LocalPattern::new(b.len(), &problem.at, &linear);
                Kept {
                    b: b.clone(),
                    c1,
                    linear,
                    pattern,
                    factor: None,
                }
            }
        };
        self.counts.seconds_blocks += blocks.elapsed().as_secs_f64();
        let rb: Vec<f64> = b
            .iter()
            .map(|&i| residual[self.zone.position[i] as usize])
            .collect();
        let newton = std::time::Instant::now();
        let Kept {
            linear,
            pattern,
            factor,
            ..
        } = kept;
        let solved = problem.newton(&linear, &pattern, &rb, 0.1 * target, factor)?;
        let c = &mut self.counts;
        c.seconds_local_newton += newton.elapsed().as_secs_f64();
        c.seconds_factorizing += solved.factor_seconds;
        c.eliminations += 1;
        c.points += chosen.len();
        c.unknowns += b.len();
        c.local_iterations += solved.iterations;
        c.local_factorizations += solved.factorizations;
        c.dense_factorizations += solved.dense_factorizations;
        c.numeric_refactorizations += solved.numeric_refactorizations;
        c.factor_entries += solved.factor_entries;
        c.unconverged += usize::from(!solved.converged);
        let mut delta = r.duplicate()?;
        delta.set_all(0.0)?;
        let own = delta.ownership();
        {
            let mut local = delta.local_mut()?;
            for (&i, &d) in b.iter().zip(&solved.delta) {
                if own.contains(&i) {
                    local[i - own.start] = d;
                }
            }
        }
        let change = std::time::Instant::now();
        let linear_change = self.linear_change(ns, &b, &solved.delta, r)?;
        self.counts.seconds_linear_change += change.elapsed().as_secs_f64();
        self.kept = Some(Kept {
            b,
            c1,
            linear,
            pattern,
            factor: solved.factor,
        });
        self.counts.seconds += clock.elapsed().as_secs_f64();
        Ok(Some(Elimination {
            delta,
            linear_change,
        }))
    }

    /// The factors of K, M and C in L = M / (beta h^2) + c1 C + K with the Rayleigh
    /// damping's C = alpha M + beta K folded into the first two.
    fn linear_coefficients(&self, ns: &NewmarkSettings) -> (f64, f64, f64) {
        let c1 = ns.gamma / (ns.beta * ns.step);
        let (alpha, beta) = self.rayleigh;
        let mass = 1.0 / (ns.beta * ns.step * ns.step) + c1 * alpha;
        (1.0 + c1 * beta, mass, c1)
    }

    /// L delta (delta given on b), a vector laid out as `like`, from the operators' columns
    /// on b: this rank's rows, no communication (every rank holds delta).
    ///
    /// # Collective
    fn linear_change(
        &self,
        ns: &NewmarkSettings,
        b: &[usize],
        delta: &[f64],
        like: &Vector<'p>,
    ) -> Result<Vector<'p>, LaError> {
        let (stiffness, mass, c1) = self.linear_coefficients(ns);
        let mut out = like.duplicate()?;
        out.set_all(0.0)?;
        {
            let mut y = out.local_mut()?;
            let moved = || {
                b.iter()
                    .zip(delta)
                    .map(|(&i, &d)| (self.zone.position[i] as usize, d))
            };
            let columns = &self.columns;
            columns.k.mult_add(stiffness, moved(), &mut y);
            columns.m.mult_add(mass, moved(), &mut y);
            if let Some(c) = &columns.c {
                c.mult_add(c1, moved(), &mut y);
            }
        }
        Ok(out)
    }

    /// L_bb = M_bb / (beta h^2) + c1 C_bb + K_bb, sparse, from the zone's blocks.
    fn linear_block(&self, ns: &NewmarkSettings, b: &[usize]) -> Csr {
        let (stiffness, mass, c1) = self.linear_coefficients(ns);
        let zone = &self.zone;
        // Position in b of every zone unknown (-1: held).
        let mut in_b = vec![-1i32; zone.k.n];
        let rows: Vec<usize> = b.iter().map(|&d| zone.position[d] as usize).collect();
        for (i, &z) in rows.iter().enumerate() {
            in_b[z] = i as i32;
        }
        let mut entries = Vec::new();
        let mut add = |a: &Csr, scale: f64| {
            for (i, &z) in rows.iter().enumerate() {
                for k in a.row_start[z]..a.row_start[z + 1] {
                    let j = in_b[a.columns[k]];
                    if j >= 0 {
                        entries.push((i, j as usize, scale * a.values[k]));
                    }
                }
            }
        };
        add(&zone.k, stiffness);
        add(&zone.m, mass);
        if let Some(c) = &zone.c {
            add(c, c1);
        }
        Csr::from_triplets(b.len(), entries)
    }
}

/// One elimination's subproblem, the same on every rank.
struct Local<'s, 'p> {
    petsc: &'p Petsc<'p>,
    contact: &'s ContactModel<'p>,
    rows: &'s [PointRows],
    zone_dofs: &'s [Vec<i32>],
    /// The eliminated unknowns (ascending) and the points that couple any of them.
    b: &'s [usize],
    points: &'s [usize],
    /// For every point, the position in b of each of its rows' DOFs (None: held).
    at: Vec<Vec<Option<usize>>>,
    /// The iterate's displacement and velocity on the zone.
    q: &'s [f64],
    v: &'s [f64],
    c1: f64,
}

impl<'s, 'p> Local<'s, 'p> {
    #[allow(clippy::too_many_arguments)] // the subproblem's parts, each named once here
    fn new(
        petsc: &'p Petsc<'p>,
        contact: &'s ContactModel<'p>,
        rows: &'s [PointRows],
        zone_dofs: &'s [Vec<i32>],
        b: &'s [usize],
        points: &'s [usize],
        q: &'s [f64],
        v: &'s [f64],
        c1: f64,
    ) -> Self {
        let position = |dof: i32| -> Option<usize> {
            (dof >= 0)
                .then(|| b.binary_search(&(dof as usize)).ok())
                .flatten()
        };
        let at = points
            .iter()
            .map(|&id| rows[id].dofs.iter().map(|&d| position(d)).collect())
            .collect();
        Local {
            petsc,
            contact,
            rows,
            zone_dofs,
            b,
            points,
            at,
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
        for (&id, at) in self.points.iter().zip(&self.at) {
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
    fn newton(
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
struct LocalSolution<'p> {
    delta: Vec<f64>,
    iterations: usize,
    factorizations: usize,
    dense_factorizations: usize,
    numeric_refactorizations: usize,
    factor_entries: f64,
    factor_seconds: f64,
    converged: bool,
    /// The last factor used (for the next elimination on the same unknowns).
    factor: Option<LocalFactor<'p>>,
}
