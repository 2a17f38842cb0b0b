//! The brake's contact model as a [`PseudoSystem`]: along a pseudo trajectory the contact
//! points see the static state's observation plus Re(alpha e^{i theta} C psi) (gap, slips,
//! convection) and Re(i omega alpha e^{i theta} C_TAN psi) (sliding velocity), with C psi
//! = (C Phi) y from the real modes' observation the projection keeps: no vector of size n, no
//! factorization; each point costs the laws and the projected tangent O(points x modes^2).

use super::pseudo_trajectory::PseudoError;
use crate::measure::nan_max;
use std::cell::RefCell;

use mpi::topology::SimpleCommunicator;

use super::pseudo_trajectory::{Linearized, PseudoSystem};
use crate::contact::kernel::Status;
use crate::contact::{ContactModel, ContactState};
use crate::eigen::complex_modes::Complex;
use crate::eigen::stability::ProjectedStability;
use crate::parallel::{max_in_place, sum_in_place};

/// A shape's observation at this rank's points, and where it is largest.
struct Observation {
    psi: Vec<Complex>,
    channels: [Vec<Complex>; 4],
    /// The local index of the point where the relative displacement is largest over all
    /// ranks, if this rank owns it.
    sample: Option<usize>,
}

pub struct ContactPseudoSystem<'a, 'p> {
    pub comm: &'a SimpleCommunicator,
    pub contact: &'a ContactModel<'p>,
    pub nominal: &'a ContactState,
    pub stability: &'a ProjectedStability,
    /// Added to the projected stiffness (with its Rayleigh part to the damping): a change of
    /// K0 on the basis, e.g. a noise-matrix point's lining stiffness. Empty: none.
    extra_stiffness: Vec<f64>,
    cache: RefCell<Option<Observation>>,
}

impl<'a, 'p> ContactPseudoSystem<'a, 'p> {
    pub fn new(
        comm: &'a SimpleCommunicator,
        contact: &'a ContactModel<'p>,
        nominal: &'a ContactState,
        stability: &'a ProjectedStability,
    ) -> Self {
        ContactPseudoSystem {
            comm,
            contact,
            nominal,
            stability,
            extra_stiffness: Vec::new(),
            cache: RefCell::new(None),
        }
    }

    /// The same system with `extra` (m x m, column-major) added to the projected elastic
    /// stiffness, as [`ProjectedStability::modes_with_stiffness`] adds it.
    pub fn with_extra_stiffness(mut self, extra: Vec<f64>) -> Self {
        self.extra_stiffness = extra;
        self
    }

    /// |(gap, slip 1, slip 2)| at each local point of the observed shape.
    fn relative(channels: &[Vec<Complex>; 4]) -> Vec<f64> {
        let abs2 = |c: Complex| c.0 * c.0 + c.1 * c.1;
        (0..channels[0].len())
            .map(|j| (abs2(channels[0][j]) + abs2(channels[1][j]) + abs2(channels[2][j])).sqrt())
            .collect()
    }

    /// The point where the relative displacement of the observed shape is largest over all
    /// ranks: that displacement, and the point's local index on the rank that owns it. Values
    /// within 1e-9 of the largest tie, and a tie goes to the lowest point id, so that all
    /// ranks, and any number of them, agree.
    ///
    /// # Collective
    fn largest_point(&self, channels: &[Vec<Complex>; 4]) -> (f64, Option<usize>) {
        let relative = Self::relative(channels);
        let mut largest = [relative.iter().copied().fold(0.0f64, nan_max)];
        max_in_place(self.comm, &mut largest);
        let tied = |r: f64| r >= (1.0 - 1e-9) * largest[0];
        let mine = (0..relative.len())
            .filter(|&k| tied(relative[k]))
            .min_by_key(|&k| self.contact.local()[k]);
        let mut lowest = [mine.map_or(f64::NEG_INFINITY, |k| -(self.contact.local()[k] as f64))];
        max_in_place(self.comm, &mut lowest);
        let owned = mine.filter(|&k| -(self.contact.local()[k] as f64) == lowest[0]);
        (largest[0], owned)
    }

    /// The observation of `psi` (cached: one mode's sweep asks for the same psi each time).
    ///
    /// # Collective
    fn observe(&self, psi: &[Complex]) {
        let mut cache = self.cache.borrow_mut();
        if cache.as_ref().is_some_and(|o| o.psi == psi) {
            return;
        }
        let channels = self.stability.projection.observe(psi);
        let (_, sample) = self.largest_point(&channels);
        *cache = Some(Observation {
            psi: psi.to_vec(),
            channels,
            sample,
        });
    }
}

impl PseudoSystem for ContactPseudoSystem<'_, '_> {
    fn contact_normalization(&self, y: &[Complex]) -> Result<Complex, PseudoError> {
        let channels = self.stability.projection.observe(y);
        let (largest, owned) = self.largest_point(&channels);
        // The phase of the largest of gap and slips at that point, from its owner.
        let mut phase = [0.0, 0.0];
        if let Some(k) = owned {
            let abs = |c: Complex| c.0.hypot(c.1);
            let at = (0..3).map(|j| channels[j][k]).fold((0.0, 0.0), |a, c| {
                if abs(c) > abs(a) {
                    c
                } else {
                    a
                }
            });
            let r = abs(at);
            if r > 0.0 {
                phase = [at.0 / r, at.1 / r];
            }
        }
        sum_in_place(self.comm, &mut phase);
        Ok((largest * phase[0], largest * phase[1]))
    }

    fn linearize(
        &self,
        psi: &[Complex],
        omega: f64,
        alpha: f64,
        theta: f64,
    ) -> Result<Linearized, PseudoError> {
        self.observe(psi);
        let cache = self.cache.borrow();
        let o = cache.as_ref().expect("observed above");
        let (c, s) = (theta.cos(), theta.sin());
        // Re(alpha z e^{i theta}) and Re(i omega alpha z e^{i theta}).
        let re = |z: Complex| alpha * (z.0 * c - z.1 * s);
        let ch = &o.channels;
        let state = self.contact.moved(self.nominal, |k| {
            let d = [re(ch[0][k]), re(ch[1][k]), re(ch[2][k]), re(ch[3][k])];
            let v = -omega * alpha * (ch[1][k].0 * s + ch[1][k].1 * c);
            (d, v)
        });
        let (mut kp, mut cp) = self.stability.operators_at(self.comm, self.contact, &state);
        if !self.extra_stiffness.is_empty() {
            let beta = self.stability.damping.rayleigh_beta;
            for ((k, c), e) in kp.iter_mut().zip(cp.iter_mut()).zip(&self.extra_stiffness) {
                *k += e;
                *c += beta * e;
            }
        }
        // Statuses over the sliding interfaces (the pads), and the sample point's.
        let mut counts = [0.0; 4];
        for (k, r) in state.response.iter().enumerate() {
            let id = self.contact.local()[k];
            if self.contact.interfaces()[self.contact.points()[id].interface]
                .friction
                .is_sliding()
            {
                counts[r.status as usize] += 1.0;
            }
        }
        let mut sample = [o
            .sample
            .map_or(0.0, |k| 1.0 + state.response[k].status as u8 as f64)];
        sum_in_place(self.comm, &mut counts[..3]);
        max_in_place(self.comm, &mut sample);
        let total = counts[..3].iter().sum::<f64>().max(1.0);
        Ok(Linearized {
            kp,
            cp,
            fractions: [counts[0] / total, counts[1] / total, counts[2] / total],
            sample: (sample[0] as u8).saturating_sub(1),
        })
    }

    fn gap_scale(&self) -> f64 {
        // Sum of p * (p / k_c) and of p over the sliding interfaces' points in contact.
        let mut sums = [0.0; 2];
        for (k, r) in self.nominal.response.iter().enumerate() {
            let id = self.contact.local()[k];
            let sliding = self.contact.interfaces()[self.contact.points()[id].interface]
                .friction
                .is_sliding();
            if sliding && r.status != Status::Open && r.pressure > 0.0 && r.stiffness > 0.0 {
                sums[0] += r.pressure * r.pressure / r.stiffness;
                sums[1] += r.pressure;
            }
        }
        sum_in_place(self.comm, &mut sums);
        sums[0] / sums[1]
    }
}
