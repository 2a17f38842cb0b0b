//! Nonlinear elimination of the contact points whose tangent changed most (Lanzkron, Rose &
//! Wilkes, SIAM J. Sci. Comput. 17 (1996) 1139; Cai & Li, SIAM J. Sci. Comput. 33 (2011)
//! 746): at an iterate, the unknowns b those points couple are moved so that the residual's
//! rows b vanish with the other unknowns held, solving the small nonlinear system
//! R_b(q + delta) = 0 by Newton with its exact tangent. b falls into independent parts
//! (`parts.rs`), each solved on one rank (`local_newton.rs`), their moves summed over the
//! ranks (every rank solving all of b makes an elimination at 600k take 1.6x as long on
//! 2 ranks, benches/transient-results.md). A part that recurs keeps
//! its rank and its factor. The
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

use super::local_jacobian::LocalPattern;
use super::local_newton::{Local, LocalFactor, PartUnknowns};
use super::parts::{block, share_out, split};
use crate::contact::kernel::PointRows;
use crate::contact::ContactModel;
use crate::la::local_lu::{Csr, RowMarker};
use crate::la::{
    ColumnBlock, LaError, MatrixFormat, Petsc, Selection, SparseMatrix, TangentChange, Vector,
};
use crate::measure::nan_max;
use crate::parallel::sum_in_place;
use crate::time::newmark::{Damping, Elimination, NewmarkSettings, State};

/// What the eliminations of a run did.
#[derive(Debug, Clone, Copy, Default)]
pub struct EliminationCounts {
    pub eliminations: usize,
    pub points: usize,
    pub unknowns: usize,
    /// The independent parts the eliminations' unknowns fell into (`parts.rs`), and the
    /// unknowns of each elimination's largest part, summed over the eliminations.
    pub parts: usize,
    pub largest_parts: usize,
    /// Of the parts, those whose local Newton started from a factor kept from an earlier
    /// elimination on the same unknowns (the same b, or a part of another b on the same
    /// unknowns as one of the last elimination's).
    pub parts_on_kept_factors: usize,
    /// Local Newton iterations, of each elimination the most any of its parts took.
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
    /// Of each elimination the local Newton's time on the rank that took longest, summed:
    /// what the parts cost on the critical path (`seconds_combining` is this rank's wait).
    pub seconds_local_newton_slowest: f64,
    /// Of `seconds`: the linear force's change of each move, from the operators' columns on
    /// the moved unknowns.
    pub seconds_linear_change: f64,
    /// Of `seconds`: the reduction that gives every rank all the parts' moves (with this
    /// rank's wait for the others: the parts' imbalance).
    pub seconds_combining: f64,
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
    /// b's parts (positions in b), the rank of each, and this rank's parts with their blocks
    /// and factors.
    parts: Vec<Vec<usize>>,
    owner: Vec<usize>,
    own: Vec<OwnPart<'p>>,
}

/// A part of b this rank solves: its unknowns, the points that couple them, L_bb on them,
/// the local Jacobian's pattern and its last local factor.
struct OwnPart<'p> {
    part: usize,
    unknowns: PartUnknowns,
    linear: Csr,
    pattern: LocalPattern,
    factor: Option<LocalFactor<'p>>,
}

/// The counters an elimination adds up over the ranks, after its moves in one reduction.
const SUMMED: usize = 6;

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
        let Some(Chosen {
            points,
            unknowns: b,
            touching,
        }) = self.choose(tangent)?
        else {
            return Ok(None);
        };
        if self.gather.is_none() {
            self.gather = Some(Selection::new(r, &self.zone.unknowns)?);
        }
        let gather = self.gather.as_ref().expect("built above");
        let zone = ZoneValues {
            q: gather.gather(&at.q)?,
            v: gather.gather(&at.v)?,
            residual: gather.gather(r)?,
        };
        let c1 = ns.gamma / (ns.beta * ns.step);
        // (Every rank holds the same b: the same branch everywhere, collective or not.)
        let blocks = std::time::Instant::now();
        let mut kept = match self.kept.take() {
            Some(k) if k.b == b && k.c1 == c1 => k,
            Some(k) if k.c1 == c1 => self.split(ns, b, &touching, c1, Some(k)),
            _ => self.split(ns, b, &touching, c1, None),
        };
        self.counts.seconds_blocks += blocks.elapsed().as_secs_f64();
        let combined = self.solve_parts(&mut kept, &zone, c1, target)?;
        self.count(&combined, points, &kept);
        let solved_delta = &combined[..kept.b.len()];
        let delta = scattered(r, &kept.b, solved_delta)?;
        let change = std::time::Instant::now();
        let linear_change = self.linear_change(ns, &kept.b, solved_delta, r)?;
        self.counts.seconds_linear_change += change.elapsed().as_secs_f64();
        self.kept = Some(kept);
        self.counts.seconds += clock.elapsed().as_secs_f64();
        Ok(Some(Elimination {
            delta,
            linear_change,
        }))
    }

    /// The points to eliminate, the `max_points` largest changes, however small the rest
    /// (a point left out with a tangent far from J's stalls the global iteration; measured:
    /// keeping 99.99 % of the change's norm instead, ~30 points on the small brake, refreshed
    /// J 6x as often): how many, their distinct unknowns b and the points touching b. None:
    /// no point, or none with an unknown.
    ///
    /// # Collective
    fn choose(&mut self, tangent: &dyn TangentChange<'p>) -> Result<Option<Chosen>, LaError> {
        let clock = std::time::Instant::now();
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
        Ok(Some(Chosen {
            points: chosen.len(),
            unknowns: b,
            touching,
        }))
    }

    /// This rank's parts solved by their local Newton: their moves in place in b, then the
    /// counters, then each rank's deepest local Newton and its time; zero elsewhere, summed
    /// over the ranks so every rank holds all of delta (a sum with zeros is exact).
    ///
    /// # Collective
    fn solve_parts(
        &mut self,
        kept: &mut Kept<'p>,
        zone: &ZoneValues,
        c1: f64,
        target: f64,
    ) -> Result<Vec<f64>, LaError> {
        let n = kept.b.len();
        let ranks = self.petsc.size() as usize;
        let mut combined = vec![0.0; n + SUMMED + 2 * ranks];
        let newton = std::time::Instant::now();
        let mut deepest = 0usize;
        for own in &mut kept.own {
            let members = &kept.parts[own.part];
            let problem = Local::new(
                self.petsc,
                self.contact,
                &self.rows,
                &self.zone_dofs,
                &own.unknowns,
                &zone.q,
                &zone.v,
                c1,
            );
            let rb: Vec<f64> = own
                .unknowns
                .b
                .iter()
                .map(|&i| zone.residual[self.zone.position[i] as usize])
                .collect();
            // |R_b| <= 0.1 target over all parts when each part's share is held to its
            // share of the unknowns.
            let tolerance = 0.1 * target * (members.len() as f64 / n as f64).sqrt();
            let kept_factor = own.factor.take();
            combined[n + 5] += f64::from(u8::from(kept_factor.is_some()));
            let solved = problem.newton(&own.linear, &own.pattern, &rb, tolerance, kept_factor)?;
            for (&i, &d) in members.iter().zip(&solved.delta) {
                combined[i] = d;
            }
            let summed = &mut combined[n..n + SUMMED];
            summed[0] += solved.factorizations as f64;
            summed[1] += solved.dense_factorizations as f64;
            summed[2] += solved.numeric_refactorizations as f64;
            summed[3] += solved.factor_entries;
            summed[4] += f64::from(u8::from(!solved.converged));
            deepest = deepest.max(solved.iterations);
            self.counts.seconds_factorizing += solved.factor_seconds;
            own.factor = solved.factor;
        }
        let newton_seconds = newton.elapsed().as_secs_f64();
        self.counts.seconds_local_newton += newton_seconds;
        let rank = self.petsc.rank() as usize;
        combined[n + SUMMED + rank] = deepest as f64;
        combined[n + SUMMED + ranks + rank] = newton_seconds;
        let waiting = std::time::Instant::now();
        sum_in_place(self.petsc.world(), &mut combined);
        self.counts.seconds_combining += waiting.elapsed().as_secs_f64();
        Ok(combined)
    }

    /// Adds one elimination of `points` points to the counts, from its summed counters.
    fn count(&mut self, combined: &[f64], points: usize, kept: &Kept<'p>) {
        let (n, ranks) = (kept.b.len(), self.petsc.size() as usize);
        let summed = &combined[n..n + SUMMED];
        let c = &mut self.counts;
        c.eliminations += 1;
        c.points += points;
        c.unknowns += n;
        c.parts += kept.parts.len();
        c.parts_on_kept_factors += summed[5] as usize;
        c.largest_parts += kept.parts.iter().map(Vec::len).max().unwrap_or(0);
        let (deepest, newton_seconds) = combined[n + SUMMED..].split_at(ranks);
        c.local_iterations += deepest.iter().fold(0.0, |m, &x| nan_max(m, x)) as usize;
        c.seconds_local_newton_slowest += newton_seconds.iter().fold(0.0, |m, &x| nan_max(m, x));
        c.local_factorizations += summed[0] as usize;
        c.dense_factorizations += summed[1] as usize;
        c.numeric_refactorizations += summed[2] as usize;
        c.factor_entries += summed[3];
        c.unconverged += usize::from(summed[4] > 0.0);
    }

    /// b's parts, and this rank's with their L_bb and local Jacobian's pattern; a part on the
    /// same unknowns as one of the `earlier` elimination's (at the same c1) stays on its rank
    /// and is that one, its factor kept (a part away from where the contact changes keeps its
    /// unknowns from step to step while the rest of b moves; measured on the small brake,
    /// 93 % of the parts).
    fn split(
        &self,
        ns: &NewmarkSettings,
        b: Vec<usize>,
        touching: &[usize],
        c1: f64,
        earlier: Option<Kept<'p>>,
    ) -> Kept<'p> {
        let linear = self.linear_block(ns, &b);
        let point_unknowns: Vec<Vec<usize>> = touching
            .iter()
            .map(|&id| {
                let dofs = self.rows[id].dofs.iter().filter(|&&d| d >= 0);
                dofs.filter_map(|&d| b.binary_search(&(d as usize)).ok())
                    .collect()
            })
            .collect();
        let (parts, point_part) = split(&linear, &point_unknowns);
        let unknowns_of =
            |b: &[usize], part: &[usize]| -> Vec<usize> { part.iter().map(|&i| b[i]).collect() };
        let (mut earlier_own, earlier_parts) = match earlier {
            Some(k) => {
                let parts: Vec<(Vec<usize>, usize)> = (k.parts.iter().zip(&k.owner))
                    .map(|(p, &o)| (unknowns_of(&k.b, p), o))
                    .collect();
                (k.own, parts)
            }
            None => (Vec::new(), Vec::new()),
        };
        let fixed: Vec<Option<usize>> = parts
            .iter()
            .map(|p| {
                let unknowns = unknowns_of(&b, p);
                earlier_parts
                    .iter()
                    .find(|(e, _)| *e == unknowns)
                    .map(|&(_, o)| o)
            })
            .collect();
        let owner = share_out(&parts, self.petsc.size() as usize, &fixed);
        let rank = self.petsc.rank() as usize;
        let own = (0..parts.len())
            .filter(|&p| owner[p] == rank)
            .map(|part| {
                let part_b = unknowns_of(&b, &parts[part]);
                if let Some(same) = earlier_own.iter().position(|e| e.unknowns.b == part_b) {
                    let mut same = earlier_own.swap_remove(same);
                    same.part = part;
                    return same;
                }
                let points: Vec<usize> = touching
                    .iter()
                    .zip(&point_part)
                    .filter(|&(_, &p)| p == part)
                    .map(|(&id, _)| id)
                    .collect();
                let linear = block(&linear, &parts[part]);
                let unknowns = PartUnknowns::new(&self.rows, part_b, points);
                let pattern = LocalPattern::new(unknowns.b.len(), &unknowns.at, &linear);
                OwnPart {
                    part,
                    unknowns,
                    linear,
                    pattern,
                    factor: None,
                }
            })
            .collect();
        Kept {
            b,
            c1,
            parts,
            owner,
            own,
        }
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

/// The points an elimination moves: how many, their distinct unknowns b, and the points
/// touching b.
struct Chosen {
    points: usize,
    unknowns: Vec<usize>,
    touching: Vec<usize>,
}

/// The zone's entries of the iterate's q, v and residual.
struct ZoneValues {
    q: Vec<f64>,
    v: Vec<f64>,
    residual: Vec<f64>,
}

/// A vector like `like`, `values` at the unknowns `at` and zero elsewhere.
fn scattered<'p>(like: &Vector<'p>, at: &[usize], values: &[f64]) -> Result<Vector<'p>, LaError> {
    let mut v = like.duplicate()?;
    v.set_all(0.0)?;
    let own = v.ownership();
    {
        let mut local = v.local_mut()?;
        for (&i, &d) in at.iter().zip(values) {
            if own.contains(&i) {
                local[i - own.start] = d;
            }
        }
    }
    Ok(v)
}
