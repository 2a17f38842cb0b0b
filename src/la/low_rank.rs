//! A factor of J0 corrected by a low-rank change (Woodbury): P = J0 + U D U^T,
//! P^-1 = F^-1 - W (I + D U^T W)^-1 D U^T F^-1 with W = F^-1 U.
//!
//! Why: in a transient's saturated regime the consistent tangent drifts away from the factored
//! Jacobian by the few contact points that stick, slip, open or close within a step (nearly
//! all of the change sits on a few percent of the points), and GMRES preconditioned by F^-1
//! alone needed over ten iterations per Newton iteration however fresh the factor
//! (benches/decisions-results.md, "low-rank"). Those points' columns make the preconditioner nearly exact, at one solve per
//! new column, cached for the factor's life.

use super::lapack::RealLu;
use super::{DirectSolver, LaError, Operator, SparseMatrix, Vector};

/// One column u of a change's explicit part: (global row of a contact point, channel), the
/// column being that channel's observation row of the point, transposed.
pub type ColumnKey = (usize, u8);

/// The dominant part of a change as U D U^T: D (s x s, row-major) over the keys' columns; a
/// point's keys are consecutive, and D is block-diagonal by point where the change is a sum
/// of point terms (the update then costs O(s^2), else O(s^3)).
#[derive(Debug, Clone, PartialEq)]
pub struct Dominant {
    pub keys: Vec<ColumnKey>,
    pub d: Vec<f64>,
}

/// A Jacobian's change applied as an operator (what GMRES multiplies by), which may also hand
/// over its dominant part explicitly (what the preconditioner is updated with). The default:
/// no explicit part (F^-1 alone).
pub trait TangentChange<'p>: Operator<'p> {
    /// The change's part on the fewest points that hold `fraction` of its squared Frobenius
    /// norm, at most `max_points` of them; the same on every rank.
    ///
    /// # Collective
    fn dominant(&self, _max_points: usize, _fraction: f64) -> Result<Option<Dominant>, LaError> {
        Ok(None)
    }

    /// The rows of the points with the largest change (squared Frobenius norm of their
    /// block), at most `max_points`, largest first; the same on every rank. What a nonlinear
    /// elimination needs: the points, not the coupling block of [`Self::dominant`], whose
    /// size grows with the square of their channels.
    ///
    /// # Collective
    fn dominant_points(&self, max_points: usize) -> Result<Option<Vec<usize>>, LaError> {
        Ok(self.dominant(max_points, 1.0)?.map(|d| {
            let mut rows: Vec<usize> = d.keys.iter().map(|k| k.0).collect();
            rows.dedup();
            rows
        }))
    }

    /// The column of `key` into `out` (a vector of the operator's layout).
    ///
    /// # Collective
    fn column(&self, _key: ColumnKey, _out: &mut Vector<'p>) -> Result<(), LaError> {
        Err(LaError::Invalid(
            "this tangent change has no explicit columns".into(),
        ))
    }
}

impl<'p> TangentChange<'p> for SparseMatrix<'p> {}

/// Points at most in an update (the small brake needs ~16-25).
pub const MAX_POINTS: usize = 32;
pub const HELD_FRACTION: f64 = 0.9999;

/// Columns at most cached per factor (beyond that the cache starts over): as many as
/// COLUMN_CACHE_BYTES hold (u and w, 16 bytes per unknown each, the whole length counted on
/// every rank), between 256 and 2,048 (the U^T W table then holds 32 MB). Where the factor
/// is kept updated for thousands of steps, the dominant points move over the whole contact
/// zone (the small brake's 352 points hold 1,408 columns): a cache of 256 started over
/// every few dozen steps, and its column solves were ~40 % of all solves.
pub const COLUMN_CACHE_BYTES: f64 = 512e6;
pub fn max_cached_columns(unknowns: usize) -> usize {
    ((COLUMN_CACHE_BYTES / (16.0 * unknowns.max(1) as f64)) as usize).clamp(256, 2048)
}

/// F^-1 updated by the dominant part of a tangent change; belongs to one factor.
#[derive(Default)]
pub struct LowRankUpdate<'p> {
    /// Columns u with w = F^-1 u, their index by key, and u_i . w_j (NaN until an update
    /// needs it; independent of the iterate, so an update over known pairs costs no
    /// reduction).
    position: std::collections::HashMap<ColumnKey, usize>,
    us: Vec<Vector<'p>>,
    ws: Vec<Vector<'p>>,
    g: Vec<Vec<f64>>,
    /// The active columns (indices into the cache), D, and the LU of I + D U^T W (LAPACK's
    /// dgetrf: a real system of order <= 128 once per Newton iteration; the complex LU used
    /// here before took ~8 % of a saturated transient's time).
    active: Vec<usize>,
    d: Vec<f64>,
    lu: Option<RealLu>,
}

impl<'p> LowRankUpdate<'p> {
    /// Columns in use.
    pub fn rank(&self) -> usize {
        self.active.len()
    }

    /// Takes `change`'s dominant part; returns the solves made for new columns. A singular
    /// or non-finite small system leaves F^-1 alone (never a wrong preconditioner).
    ///
    /// # Collective
    pub fn prepare(
        &mut self,
        factor: &DirectSolver<'p>,
        change: &dyn TangentChange<'p>,
        like: &Vector<'p>,
    ) -> Result<usize, LaError> {
        self.active.clear();
        let Some(dominant) = change.dominant(MAX_POINTS, HELD_FRACTION)? else {
            return Ok(0);
        };
        let new = dominant
            .keys
            .iter()
            .filter(|k| !self.position.contains_key(k))
            .count();
        if self.position.len() + new > max_cached_columns(like.global_len()) {
            self.position.clear();
            self.us.clear();
            self.ws.clear();
            self.g.clear();
        }
        let mut solves = 0;
        for key in &dominant.keys {
            if !self.position.contains_key(key) {
                self.add_column(factor, change, *key, like)?;
                solves += 1;
            }
        }
        for key in &dominant.keys {
            self.active.push(self.position[key]);
        }
        self.fill_products()?;
        let s = self.active.len();
        // I + D G with G = U^T W over the active columns (column-major for LAPACK). D is
        // block-diagonal by point (a point's channels are consecutive keys): row r of D G
        // sums over r's own block only, 4 s^2 products instead of s^3.
        let g: Vec<f64> = self
            .active
            .iter()
            .flat_map(|&k| self.active.iter().map(move |&c| (k, c)))
            .map(|(k, c)| self.g[k][c])
            .collect();
        let point = |i: usize| dominant.keys[i].0;
        // Blocks of consecutive keys of one point; all of D as one block if it has entries
        // between points (not what the contact tangent hands over, but the trait allows it).
        let blocks =
            (0..s).all(|r| (0..s).all(|k| point(k) == point(r) || dominant.d[r * s + k] == 0.0));
        let mut m = vec![0.0; s * s];
        let mut first = 0;
        while first < s {
            let last = if blocks {
                (first..s).find(|&i| point(i) != point(first)).unwrap_or(s)
            } else {
                s
            };
            for r in first..last {
                for c in 0..s {
                    let dg: f64 = (first..last)
                        .map(|k| dominant.d[r * s + k] * g[k * s + c])
                        .sum();
                    m[c * s + r] = f64::from(u8::from(r == c)) + dg;
                }
            }
            first = last;
        }
        // Singular or not finite: F^-1 alone.
        self.lu = RealLu::new(s, m).ok();
        if self.lu.is_some() {
            self.d = dominant.d;
        } else {
            self.active.clear();
        }
        Ok(solves)
    }

    /// Caches the column of `key` and w = F^-1 u.
    ///
    /// # Collective
    fn add_column(
        &mut self,
        factor: &DirectSolver<'p>,
        change: &dyn TangentChange<'p>,
        key: ColumnKey,
        like: &Vector<'p>,
    ) -> Result<(), LaError> {
        let mut u = like.duplicate()?;
        change.column(key, &mut u)?;
        let mut w = like.duplicate()?;
        factor.solve(&u, &mut w)?;
        self.position.insert(key, self.us.len());
        self.us.push(u);
        self.ws.push(w);
        // Its row and column of U^T W are filled when an update needs them.
        for g in self.g.iter_mut() {
            g.push(f64::NAN);
        }
        self.g.push(vec![f64::NAN; self.us.len()]);
        Ok(())
    }

    /// Fills the entries u_i . w_j of U^T W between the active columns not computed yet (one
    /// reduction per row with missing entries). Computing them all when a column comes cost
    /// two products with every cached column: 70 MB of traffic per new column with 2,048
    /// cached columns of the small brake, where an update needs the pairs of points that
    /// change together.
    ///
    /// # Collective
    fn fill_products(&mut self) -> Result<(), LaError> {
        for &i in &self.active {
            let missing: Vec<usize> = self
                .active
                .iter()
                .copied()
                .filter(|&j| self.g[i][j].is_nan())
                .collect();
            if missing.is_empty() {
                continue;
            }
            let ws: Vec<&Vector<'p>> = missing.iter().map(|&j| &self.ws[j]).collect();
            let products = self.us[i].mdot(&ws)?;
            for (j, p) in missing.into_iter().zip(products) {
                self.g[i][j] = p;
            }
        }
        Ok(())
    }

    /// y += U D U^T x over the active columns (the update's own part of P = F + U D U^T:
    /// what a correction solved with P changed beyond F).
    ///
    /// # Collective
    pub fn mult_add_update(&self, x: &Vector<'p>, y: &mut Vector<'p>) -> Result<(), LaError> {
        let s = self.active.len();
        if s == 0 {
            return Ok(());
        }
        let us: Vec<&Vector<'p>> = self.active.iter().map(|&i| &self.us[i]).collect();
        let t = x.mdot(&us)?;
        let dt: Vec<f64> = (0..s)
            .map(|r| (0..s).map(|k| self.d[r * s + k] * t[k]).sum())
            .collect();
        y.maxpy(&dt, &us)
    }

    /// y = P^-1 v: one solve with the factor, then the low-rank correction.
    ///
    /// # Collective
    pub fn apply(
        &self,
        factor: &DirectSolver<'p>,
        v: &Vector<'p>,
        y: &mut Vector<'p>,
    ) -> Result<(), LaError> {
        factor.solve(v, y)?;
        let s = self.active.len();
        if s == 0 {
            return Ok(());
        }
        let us: Vec<&Vector<'p>> = self.active.iter().map(|&i| &self.us[i]).collect();
        let t = y.mdot(&us)?;
        let mut x: Vec<f64> = (0..s)
            .map(|r| (0..s).map(|k| self.d[r * s + k] * t[k]).sum())
            .collect();
        let lu = self.lu.as_ref().expect("active columns have their LU");
        lu.solve(&mut x)?;
        let ws: Vec<&Vector<'p>> = self.active.iter().map(|&i| &self.ws[i]).collect();
        let negated: Vec<f64> = x.iter().map(|x| -x).collect();
        y.maxpy(&negated, &ws)
    }
}
