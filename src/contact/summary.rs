//! Per-interface sums of a contact state (forces, braking torque, extreme pressure and gap,
//! how many points are open, sticking, slipping), reduced over the ranks.

use super::kernel::Status;
use super::{ContactModel, ContactState};
use crate::la::Petsc;

/// Summed results per interface.
#[derive(Debug, Clone, Default)]
pub struct InterfaceSummary {
    pub normal_force: f64,
    pub friction_force: f64,
    /// Braking torque about the axis (N m): sum of r w t over the points.
    pub torque: f64,
    /// Sum of mu_k w p r over the sliding points (the Coulomb estimate of the torque).
    pub coulomb_torque: f64,
    pub max_pressure: f64,
    pub min_gap: f64,
    pub open: usize,
    pub stick: usize,
    pub slip: usize,
}

impl ContactModel<'_> {
    /// Per-interface sums over all ranks.
    ///
    /// # Collective
    pub fn summarize(&self, petsc: &Petsc, state: &ContactState) -> Vec<InterfaceSummary> {
        let mut out = vec![
            InterfaceSummary {
                min_gap: f64::INFINITY,
                ..Default::default()
            };
            self.interfaces.len()
        ];
        for (k, &id) in self.local.iter().enumerate() {
            let p = &self.points[id];
            let itf = &self.interfaces[p.interface];
            let (o, r) = (&state.observed[k], &state.response[k]);
            let s = &mut out[p.interface];
            s.normal_force += p.weight * r.pressure;
            s.friction_force += p.weight * r.traction[0];
            if itf.friction.is_sliding() {
                s.torque += p.weight * r.traction[0] * p.radius;
                s.coulomb_torque +=
                    state.friction_scale * itf.friction.mu() * p.weight * r.pressure * p.radius;
            }
            s.max_pressure = s.max_pressure.max(r.pressure);
            s.min_gap = s.min_gap.min(o.gap);
            match r.status {
                Status::Open => s.open += 1,
                Status::Stick => s.stick += 1,
                Status::Slip => s.slip += 1,
            }
        }
        // Two reductions for all interfaces (sums, and maxima with min_gap negated): this runs
        // at every time step.
        let world = petsc.world();
        let mut sums: Vec<f64> = out
            .iter()
            .flat_map(|s| {
                [
                    s.normal_force,
                    s.friction_force,
                    s.torque,
                    s.coulomb_torque,
                    s.open as f64,
                    s.stick as f64,
                    s.slip as f64,
                ]
            })
            .collect();
        let mut maxima: Vec<f64> = out
            .iter()
            .flat_map(|s| [s.max_pressure, -s.min_gap])
            .collect();
        crate::parallel::sum_in_place(world, &mut sums);
        crate::parallel::max_in_place(world, &mut maxima);
        for (i, s) in out.iter_mut().enumerate() {
            let v = &sums[7 * i..7 * i + 7];
            s.normal_force = v[0];
            s.friction_force = v[1];
            s.torque = v[2];
            s.coulomb_torque = v[3];
            s.open = v[4] as usize;
            s.stick = v[5] as usize;
            s.slip = v[6] as usize;
            s.max_pressure = maxima[2 * i];
            s.min_gap = -maxima[2 * i + 1];
        }
        out
    }
}
