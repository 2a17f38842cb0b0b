//! Stability of a contact state on a fixed real-mode basis: linearize the contact at the
//! state, project the tangent on the nominal real modes through the observation rows
//! (O(points x modes^2), no factorization of size n), and solve the dense complex modes. The
//! recipe behind the projected route, the parameter sweeps and stability along a trajectory.

use crate::la::DenseError;
use mpi::topology::SimpleCommunicator;

use super::complex_modes::{solve_dense, DampingSettings, DenseEigenpair, PointTerms};
use super::real_modes::RealModes;
use crate::contact::kernel::Part;
use crate::contact::{ContactModel, ContactState};
use crate::la::{lapack, LaError};

/// The real-mode basis of the projected route, with the contact observation of every mode.
pub struct ModalProjection {
    /// Modes in the basis.
    pub size: usize,
    pub omega2: Vec<f64>,
    /// P_a = C_a Phi for the four channels: local points x modes, column-major.
    channels: [Vec<f64>; 4],
    points: usize,
    /// Phi^T (contact part of K_s) Phi, summed over ranks: removed again from diag(omega^2)
    /// when the contact state changes.
    reference: Vec<f64>,
}

impl ModalProjection {
    /// `omega2`: eigenvalues of the basis modes (M-orthonormal eigenvectors of K_s);
    /// `channels`: their observation (see [`crate::contact::ContactModel::observe_shapes`]);
    /// `reference`: the point terms of the symmetric contact part inside K_s.
    ///
    /// # Collective
    pub fn new(
        comm: &SimpleCommunicator,
        omega2: Vec<f64>,
        channels: [Vec<f64>; 4],
        points: usize,
        reference: &PointTerms,
    ) -> Self {
        let size = omega2.len();
        for c in &channels {
            assert_eq!(c.len(), points * size, "observed shapes: points x modes");
        }
        let mut p = ModalProjection {
            size,
            omega2,
            channels,
            points,
            reference: Vec::new(),
        };
        p.reference = p.project(comm, reference);
        p
    }

    /// The observation of the shape with modal coordinates y at this rank's points: per
    /// channel (normal, tangent, second tangent, convection) one complex value per point.
    pub fn observe(&self, y: &[(f64, f64)]) -> [Vec<(f64, f64)>; 4] {
        let n = self.points;
        self.channels.each_ref().map(|p| {
            (0..n)
                .map(|j| {
                    y.iter().enumerate().fold((0.0, 0.0), |acc, (k, &(r, i))| {
                        let c = p[k * n + j];
                        (acc.0 + c * r, acc.1 + c * i)
                    })
                })
                .collect()
        })
    }

    /// Sum over points of the terms, projected: m x m column-major, summed over ranks.
    ///
    /// # Collective
    pub fn project(&self, comm: &SimpleCommunicator, terms: &PointTerms) -> Vec<f64> {
        let (n, m) = (self.points, self.size);
        assert_eq!(terms.len(), n, "one term list per local point");
        let mut out = vec![0.0; m * m];
        // Weights per channel pair: out += P_a^T diag(g_ab) P_b.
        let mut weights = vec![vec![0.0f64; n]; 16];
        let mut present = [false; 16];
        for (j, list) in terms.iter().enumerate() {
            for &(g, a, b) in list {
                let pair = a as usize * 4 + b as usize;
                weights[pair][j] += g;
                present[pair] = true;
            }
        }
        // One GEMM per row channel a: out += P_a^T S_a with S_a = sum_b diag(g_ab) P_b (the
        // up to 11 channel pairs of sliding friction cost 4 products, not 11). A row channel
        // with its diagonal pair alone (the normal stiffness, the friction damping) is a
        // symmetric product: half the flops by dsyrk.
        let mut scaled = vec![0.0; n * m];
        for a in 0..4 {
            let pairs: Vec<usize> = (0..4).map(|b| a * 4 + b).filter(|&p| present[p]).collect();
            if pairs.is_empty() {
                continue;
            }
            // (A non-finite weight takes the GEMM, which carries it into the result.)
            if pairs == [a * 5] && weights[a * 5].iter().all(|g| g.is_finite()) {
                add_symmetric(n, m, &weights[a * 5], &self.channels[a], &mut out);
                continue;
            }
            scaled.fill(0.0);
            for &pair in &pairs {
                let (g, p_b) = (&weights[pair], &self.channels[pair % 4]);
                for (column, source) in scaled.chunks_mut(n.max(1)).zip(p_b.chunks(n.max(1))) {
                    for ((c, &gj), &pj) in column.iter_mut().zip(g).zip(source) {
                        *c += gj * pj;
                    }
                }
            }
            let product = lapack::gemm_tn(n, m, m, &self.channels[a], &scaled);
            for (o, p) in out.iter_mut().zip(&product) {
                *o += p;
            }
        }
        crate::parallel::sum_in_place(comm, &mut out);
        out
    }

    /// Projected stiffness and damping of a contact state: K_p = diag(omega^2) - reference +
    /// Phi^T (stiffness terms) Phi; C_p = alpha I + beta K0_p + Phi^T (damping terms) Phi, with
    /// K0_p = diag(omega^2) - reference.
    ///
    /// # Collective
    pub fn operators(
        &self,
        comm: &SimpleCommunicator,
        stiffness: &PointTerms,
        damping_terms: &PointTerms,
        damping: &DampingSettings,
    ) -> (Vec<f64>, Vec<f64>) {
        let m = self.size;
        let mut k0 = self.reference.iter().map(|x| -x).collect::<Vec<f64>>();
        for i in 0..m {
            k0[i * m + i] += self.omega2[i];
        }
        let contact = self.project(comm, stiffness);
        let kp: Vec<f64> = k0.iter().zip(&contact).map(|(a, b)| a + b).collect();
        let mut cp = self.project(comm, damping_terms);
        for (c, k) in cp.iter_mut().zip(&k0) {
            *c += damping.rayleigh_beta * k;
        }
        for i in 0..m {
            cp[i * m + i] += damping.rayleigh_alpha;
        }
        (kp, cp)
    }
}

/// out += P^T diag(g) P for P (points x modes, column-major): sum over the points of either
/// sign of (sqrt|g| P)^T (sqrt|g| P), each by dsyrk over those points' rows only.
fn add_symmetric(n: usize, m: usize, g: &[f64], p: &[f64], out: &mut [f64]) {
    for sign in [1.0, -1.0] {
        let rows: Vec<(usize, f64)> = (0..n)
            .filter(|&j| g[j] * sign > 0.0)
            .map(|j| (j, (g[j] * sign).sqrt()))
            .collect();
        if rows.is_empty() {
            continue;
        }
        let k = rows.len();
        let mut z = vec![0.0; k * m];
        for (column, source) in z.chunks_mut(k).zip(p.chunks(n)) {
            for (zi, &(j, root)) in column.iter_mut().zip(&rows) {
                *zi = root * source[j];
            }
        }
        lapack::add_gram(k, m, sign, &z, out);
    }
}

/// The contact parts of the projected stiffness (symmetric contact, sticking, sliding
/// friction, and the sticking joints' gap coupling: their traction changes with the gap, an
/// unsymmetric, non-conservative term) and of the damping (friction damping).
const STIFFNESS: [Part; 4] = [
    Part::Normal,
    Part::Stick,
    Part::Friction,
    Part::StickCoupling,
];
const DAMPING: [Part; 1] = [Part::Damping];

/// Stability of contact states on the nominal real modes. The observation of the modes is
/// computed once; the laws of the contact model may change between states (a sweep).
pub struct ProjectedStability {
    pub projection: ModalProjection,
    pub damping: DampingSettings,
}

impl ProjectedStability {
    /// The basis: the real modes of the symmetric tangent at `nominal` (its contact part,
    /// normal and stick, is what a new state's tangent replaces).
    ///
    /// # Collective
    pub fn new(
        comm: &SimpleCommunicator,
        contact: &ContactModel,
        modes: &RealModes,
        nominal: &ContactState,
        damping: DampingSettings,
    ) -> Result<Self, LaError> {
        let projection = ModalProjection::new(
            comm,
            modes.eigenvalues.clone(),
            contact.observe_shapes(&modes.shapes)?,
            contact.local().len(),
            &contact.tangent_terms(nominal, &[Part::Normal, Part::Stick]),
        );
        Ok(ProjectedStability {
            projection,
            damping,
        })
    }

    /// Projected stiffness and damping (column-major) of the tangent at `state`.
    ///
    /// # Collective
    pub fn operators_at(
        &self,
        comm: &SimpleCommunicator,
        contact: &ContactModel,
        state: &ContactState,
    ) -> (Vec<f64>, Vec<f64>) {
        self.projection.operators(
            comm,
            &contact.tangent_terms(state, &STIFFNESS),
            &contact.tangent_terms(state, &DAMPING),
            &self.damping,
        )
    }

    /// [`Self::modes_at`] with `extra` (m x m, column-major) added to the projected elastic
    /// stiffness, and its Rayleigh part to the damping: a change of K0 on the fixed basis
    /// (e.g. the lining's stiffness scaled, [`project_operator`]).
    ///
    /// # Collective
    pub fn modes_with_stiffness(
        &self,
        comm: &SimpleCommunicator,
        contact: &ContactModel,
        state: &ContactState,
        extra: &[f64],
    ) -> Result<Vec<DenseEigenpair>, DenseError> {
        let (kp, cp) = self.operators_with_stiffness(comm, contact, state, extra);
        solve_dense(self.projection.size, &kp, &cp)
    }

    /// [`Self::operators_at`] with `extra` (m x m, column-major; empty: none) added to the
    /// projected elastic stiffness, and its Rayleigh part to the damping.
    ///
    /// # Collective
    pub fn operators_with_stiffness(
        &self,
        comm: &SimpleCommunicator,
        contact: &ContactModel,
        state: &ContactState,
        extra: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let (mut kp, mut cp) = self.operators_at(comm, contact, state);
        if extra.is_empty() {
            return (kp, cp);
        }
        assert_eq!(extra.len(), kp.len(), "extra stiffness: m x m");
        let beta = self.damping.rayleigh_beta;
        for ((k, c), e) in kp.iter_mut().zip(cp.iter_mut()).zip(extra) {
            *k += e;
            *c += beta * e;
        }
        (kp, cp)
    }

    /// The complex modes at `state` (of `contact`, whose points and rows are the basis'):
    /// eigenvalues with their modal coordinates, unsorted.
    ///
    /// # Collective
    pub fn modes_at(
        &self,
        comm: &SimpleCommunicator,
        contact: &ContactModel,
        state: &ContactState,
    ) -> Result<Vec<DenseEigenpair>, DenseError> {
        let (kp, cp) = self.operators_at(comm, contact, state);
        solve_dense(self.projection.size, &kp, &cp)
    }
}

/// Phi^T A Phi (m x m, column-major, on every rank) of the basis `shapes` and an operator of
/// the full model.
///
/// # Collective
pub fn project_operator(
    comm: &SimpleCommunicator,
    shapes: &[crate::la::Vector],
    a: &crate::la::SparseMatrix,
) -> Result<Vec<f64>, LaError> {
    let m = shapes.len();
    let Some(first) = shapes.first() else {
        return Ok(Vec::new());
    };
    let mut product = first.duplicate()?;
    let n = first.local()?.len();
    let (mut phi, mut a_phi) = (Vec::with_capacity(n * m), Vec::with_capacity(n * m));
    for shape in shapes {
        a.mult(shape, &mut product)?;
        phi.extend_from_slice(&shape.local()?);
        a_phi.extend_from_slice(&product.local()?);
    }
    let mut out = lapack::gemm_tn(n, m, m, &phi, &a_phi);
    crate::parallel::sum_in_place(comm, &mut out);
    Ok(out)
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    /// The symmetric route against the sum over points written out: weights of both signs
    /// and zero, each point's rows taken once.
    #[test]
    fn symmetric_projection_matches_the_sum_over_points() {
        let (n, m) = (9, 4);
        let p: Vec<f64> = (0..n * m).map(|i| (i as f64 * 0.37).sin()).collect();
        let g: Vec<f64> = (0..n)
            .map(|j| [2.0, -0.5, 0.0][j % 3] * (1.0 + j as f64))
            .collect();
        let mut out = vec![1.0; m * m];
        add_symmetric(n, m, &g, &p, &mut out);
        for a in 0..m {
            for b in 0..m {
                let sum: f64 = (0..n).map(|j| g[j] * p[a * n + j] * p[b * n + j]).sum();
                let got = out[b * m + a] - 1.0;
                assert!((got - sum).abs() < 1e-12, "({a}, {b}): {got} vs {sum}");
            }
        }
    }
}
