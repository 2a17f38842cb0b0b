//! A factor of J0 corrected by a low-rank change (Woodbury): P = J0 + U D U^T,
//! P^-1 = F^-1 - W (I + D U^T W)^-1 D U^T F^-1 with W = F^-1 U.
//!
//! Why: in a transient's saturated regime the consistent tangent drifts away from the factored
//! Jacobian by the few contact points that stick, slip, open or close within a step (nearly
//! all of the change sits on a few percent of the points), and GMRES preconditioned by F^-1
//! alone needed over ten iterations per Newton iteration however fresh the factor
//! (benches/decisions-results.md, "low-rank"). Those points' columns make the preconditioner nearly exact, at one solve per
//! new column, cached for the factor's life.

use num_complex::Complex64;

use super::lapack_complex::ComplexLu;
use super::{DirectSolver, LaError, Operator, SparseMatrix, Vector};

/// One column u of a change's explicit part: (global row of a contact point, channel), the
/// column being that channel's observation row of the point, transposed.
pub type ColumnKey = (usize, u8);

/// The dominant part of a change as U D U^T: D (s x s, row-major) over the keys' columns.
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

/// Points at most in an update (the small brake needs ~16), and columns at most cached per
/// factor (256 solves cost about one factorization of the small brake's reduced J; beyond
/// that the cache starts over).
pub const MAX_POINTS: usize = 32;
pub const HELD_FRACTION: f64 = 0.9999;
pub const MAX_CACHED_COLUMNS: usize = 256;

/// F^-1 updated by the dominant part of a tangent change; belongs to one factor.
#[derive(Default)]
pub struct LowRankUpdate<'p> {
    /// Columns u with w = F^-1 u, by key, and u_i . w_j between every two of them (row-major
    /// over the cache, grown as columns come: independent of the iterate, so an update over
    /// cached columns costs no reduction).
    keys: Vec<ColumnKey>,
    us: Vec<Vector<'p>>,
    ws: Vec<Vector<'p>>,
    g: Vec<Vec<f64>>,
    /// The active columns (indices into the cache), D, and the LU of I + D U^T W (LAPACK's,
    /// through the complex LU the near-shift eigen-solve already uses: a real system of order
    /// <= 128 once per Newton iteration, the complex arithmetic costs nothing that shows).
    active: Vec<usize>,
    d: Vec<f64>,
    lu: Option<ComplexLu>,
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
            .filter(|k| !self.keys.contains(k))
            .count();
        if self.keys.len() + new > MAX_CACHED_COLUMNS {
            self.keys.clear();
            self.us.clear();
            self.ws.clear();
            self.g.clear();
        }
        let mut solves = 0;
        for key in &dominant.keys {
            if !self.keys.contains(key) {
                self.add_column(factor, change, *key, like)?;
                solves += 1;
            }
        }
        for key in &dominant.keys {
            self.active.push(
                self.keys
                    .iter()
                    .position(|k| k == key)
                    .expect("cached above"),
            );
        }
        let s = self.active.len();
        // I + D G with G = U^T W over the active columns (column-major for LAPACK).
        let mut m = vec![Complex64::new(0.0, 0.0); s * s];
        for r in 0..s {
            for c in 0..s {
                let dg: f64 = (0..s)
                    .map(|k| dominant.d[r * s + k] * self.g[self.active[k]][self.active[c]])
                    .sum();
                m[c * s + r] = Complex64::new(f64::from(u8::from(r == c)) + dg, 0.0);
            }
        }
        // Singular or not finite: F^-1 alone.
        self.lu = ComplexLu::new(s, m).ok();
        if self.lu.is_some() {
            self.d = dominant.d;
        } else {
            self.active.clear();
        }
        Ok(solves)
    }

    /// Caches the column of `key`, w = F^-1 u, and its products with the cached columns
    /// (two reductions).
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
        self.keys.push(key);
        self.us.push(u);
        self.ws.push(w);
        let n = self.keys.len();
        let (u, w) = (&self.us[n - 1], &self.ws[n - 1]);
        // Row n-1: u_new . w_j; column n-1: u_i . w_new (both include the diagonal).
        let row = u.mdot(&self.ws.iter().collect::<Vec<_>>())?;
        let column = w.mdot(&self.us.iter().collect::<Vec<_>>())?;
        for (i, g) in self.g.iter_mut().enumerate() {
            g.push(column[i]);
        }
        self.g.push(row);
        Ok(())
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
        let mut x: Vec<Complex64> = (0..s)
            .map(|r| Complex64::new((0..s).map(|k| self.d[r * s + k] * t[k]).sum(), 0.0))
            .collect();
        let lu = self.lu.as_ref().expect("active columns have their LU");
        lu.solve(&mut x)?;
        let ws: Vec<&Vector<'p>> = self.active.iter().map(|&i| &self.ws[i]).collect();
        let negated: Vec<f64> = x.iter().map(|x| -x.re).collect();
        y.maxpy(&negated, &ws)
    }
}
