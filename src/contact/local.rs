//! Contact points evaluated one by one from values at their DOFs, on every rank: what a small
//! subproblem over a few points needs (the transient's nonlinear elimination of the points
//! whose tangent changed most), where the distributed observation products would cost a
//! collective per evaluation. The same kernel as [`ContactModel::evaluate`].

use super::kernel::{self, Channel, Observed, Part, PointResponse, PointRows};
use super::ContactModel;
use crate::la::{LaError, Petsc};

impl<'p> ContactModel<'p> {
    /// Every point's observation rows on every rank, by point id (its DOFs in this model's
    /// numbering, -1 where eliminated). Gathered once: ~80 values per point.
    ///
    /// # Collective
    pub fn all_point_rows(&self, petsc: &'p Petsc) -> Result<Vec<PointRows>, LaError> {
        let lengths: Vec<f64> = self.rows.iter().map(|r| r.dofs.len() as f64).collect();
        let lengths = self.gather(petsc, &lengths)?;
        let width = lengths.iter().fold(0.0_f64, |a, &b| a.max(b)) as usize;
        let mut all: Vec<PointRows> = lengths
            .iter()
            .map(|&n| PointRows {
                dofs: vec![-1; n as usize],
                nor: vec![0.0; n as usize],
                tan: vec![0.0; n as usize],
                tan2: vec![0.0; n as usize],
                conv: vec![0.0; n as usize],
            })
            .collect();
        for slot in 0..width {
            let at = |x: &Vec<f64>| x.get(slot).copied().unwrap_or(0.0);
            let channels: [Vec<f64>; 5] = [
                self.rows
                    .iter()
                    .map(|r| r.dofs.get(slot).map_or(-1.0, |&d| f64::from(d)))
                    .collect(),
                self.rows.iter().map(|r| at(&r.nor)).collect(),
                self.rows.iter().map(|r| at(&r.tan)).collect(),
                self.rows.iter().map(|r| at(&r.tan2)).collect(),
                self.rows.iter().map(|r| at(&r.conv)).collect(),
            ];
            for (c, local) in channels.iter().enumerate() {
                let values = self.gather(petsc, local)?;
                for (rows, value) in all.iter_mut().zip(values) {
                    if slot >= rows.dofs.len() {
                        continue;
                    }
                    match c {
                        0 => rows.dofs[slot] = value as i32,
                        1 => rows.nor[slot] = value,
                        2 => rows.tan[slot] = value,
                        3 => rows.tan2[slot] = value,
                        _ => rows.conv[slot] = value,
                    }
                }
            }
        }
        Ok(all)
    }

    /// Point `id`'s response at displacement `u` and velocity `v` given at its rows' DOFs,
    /// and its force on them written to `force` (|dofs| long), as [`ContactModel::evaluate`]
    /// computes them (friction scale 1).
    pub fn evaluate_point(
        &self,
        id: usize,
        rows: &PointRows,
        u: &[f64],
        v: &[f64],
        force: &mut [f64],
    ) -> PointResponse {
        let p = &self.points[id];
        let itf = &self.interfaces[p.interface];
        let omega = self.point_omega(id);
        let o: Observed = kernel::observe(rows, p.initial_gap, self.rigid_speed(id), omega, u, v);
        let response = kernel::respond(&itf.normal, &itf.friction, 1.0, o);
        kernel::force(rows, p.weight, &response, force);
        response
    }

    /// Point `id`'s consistent tangent -d(force)/du at `response` as rank-one terms
    /// `coef c_a c_b^T` over its observation rows, the velocity's part through
    /// `velocity_factor` (dv/du of the time integration): the stiffness parts, and the
    /// friction damping times that factor. Replaces `out`'s contents.
    pub fn point_tangent_terms(
        &self,
        id: usize,
        response: &PointResponse,
        velocity_factor: f64,
        out: &mut Vec<(f64, Channel, Channel)>,
    ) {
        let weight = self.points[id].weight;
        let omega = self.point_omega(id);
        out.clear();
        for part in [
            Part::Normal,
            Part::Stick,
            Part::Friction,
            Part::StickCoupling,
        ] {
            kernel::push_tangent_terms(weight, omega, response, part, 1.0, out);
        }
        kernel::push_tangent_terms(weight, omega, response, Part::Damping, velocity_factor, out);
    }

    /// The disc speed on sliding interfaces (the convection term's factor), else 0.
    fn point_omega(&self, id: usize) -> f64 {
        if self.interfaces[self.points[id].interface]
            .friction
            .is_sliding()
        {
            self.disc_speed
        } else {
            0.0
        }
    }
}
