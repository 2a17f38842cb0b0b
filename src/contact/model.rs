//! The contact model: the points of every interface paired once, distributed over the ranks,
//! with their observation matrices C_NOR, C_TAN, C_TAN2, C_CONV and laws; the contact state
//! and force at a displacement and velocity. Its fields are read through methods: the points,
//! their rows and the matrices agree with one another only as built here.

use std::rc::Rc;

use super::kernel::{self, Channel, Observed, PointRows};
use super::pairing::{self, ContactPoint};
use super::{ContactError, ContactSettings, ContactState, ResolvedInterface};
use crate::fem::dofmap::DofMap;
use crate::la::{LaError, ObservationMatrix, Petsc, Vector};
use crate::mesh::Mesh;

/// Contact points distributed over the ranks with their observation matrices.
pub struct ContactModel<'p> {
    pub(super) interfaces: Vec<ResolvedInterface>,
    /// Every point on every rank (pairing is cheap and replicated), by point id.
    pub(super) points: Vec<ContactPoint>,
    /// Master points that missed the slave surface, and candidates, per interface.
    pub(super) misses: Vec<usize>,
    pub(super) candidates: Vec<usize>,
    /// Point ids in global row order.
    pub(super) row_ids: Vec<usize>,
    /// Global rows of this rank: [first_row, first_row + local.len()).
    pub(super) first_row: usize,
    /// This rank's points (ids) and their dense rows.
    pub(super) local: Vec<usize>,
    /// How many points each rank owns (an even split of the rows).
    pub(super) points_per_rank: Vec<usize>,
    pub(super) rows: Vec<PointRows>,
    pub(super) c_nor: Rc<ObservationMatrix<'p>>,
    pub(super) c_tan: Rc<ObservationMatrix<'p>>,
    pub(super) c_tan2: Rc<ObservationMatrix<'p>>,
    pub(super) c_conv: Rc<ObservationMatrix<'p>>,
    /// The four channels stacked, four rows per point (normal, tangent, second tangent,
    /// convection): one product observes them all, one transposed product applies the
    /// force. Each product pays its scatter of the other ranks' entries, and at 100k a
    /// contact evaluation of five channel products ran at 4x its traffic bound.
    pub(super) c_all: Rc<ObservationMatrix<'p>>,
    /// This rank's columns (DOFs) and, for every point, the global columns it couples
    /// (master nodes then slave nodes; -1 where a DOF is eliminated).
    pub(super) columns: std::ops::Range<usize>,
    pub(super) point_columns: Vec<Vec<i32>>,
    pub(super) disc_speed: f64,
    pub(super) pairing_seconds: f64,
    /// Vectors reused by `evaluate` and `force` (the transient calls them every iteration;
    /// creating PETSc vectors there cost a tenth of an iteration): one of `c_all`'s rows, one
    /// of the points (the tangential velocity).
    stacked: std::cell::RefCell<Vector<'p>>,
    velocity: std::cell::RefCell<Vector<'p>>,
}

/// Rows per point of the stacked observation matrix.
const CHANNELS: usize = 4;

impl<'p> ContactModel<'p> {
    /// Pairs the interfaces and builds the observation matrices.
    ///
    /// # Collective
    pub fn new(
        petsc: &'p Petsc,
        mesh: &Mesh,
        dofs: &DofMap,
        interfaces: Vec<ResolvedInterface>,
        settings: &ContactSettings,
    ) -> Result<Self, ContactError> {
        let start = std::time::Instant::now();
        let axis = settings.axis();
        let pairing = pairing::pair(
            mesh,
            &interfaces,
            axis,
            settings.gauss_points,
            settings.search_distance,
        )?;
        for (i, itf) in interfaces.iter().enumerate() {
            let found = pairing.candidates[i] - pairing.misses[i];
            if found == 0 {
                return Err(ContactError::NoPoints {
                    interface: itf.name.clone(),
                    candidates: pairing.candidates[i],
                    master: itf.master.clone(),
                    slave: itf.slave.clone(),
                    distance: settings.search_distance,
                });
            }
        }
        let points = pairing.points;
        // Rows in the order of the mesh partition (a point goes with its first master node's
        // rank), then split evenly: the partition balances the whole model and leaves the
        // contact zone on one rank (the small brake's 352 points [20, 332] on 2 ranks), while
        // every per-point cost (laws, observation products, projections on the modes) wants
        // an even share. A point's DOFs on another rank travel in the observation products
        // and at assembly, as they already did at the partition's border.
        let node_owner: Vec<usize> = points
            .iter()
            .map(|p| dofs.owner_of_node(*p.master_nodes.iter().min().unwrap()))
            .collect();
        let mut row_ids: Vec<usize> = (0..points.len()).collect();
        row_ids.sort_by_key(|&i| (node_owner[i], i));
        let (ranks, rank) = (dofs.node_ranges.len() - 1, dofs.rank);
        let first_of = |r: usize| r * points.len() / ranks;
        let points_per_rank: Vec<usize> =
            (0..ranks).map(|r| first_of(r + 1) - first_of(r)).collect();
        let first_row = first_of(rank);
        let local: Vec<usize> = row_ids[first_row..first_of(rank + 1)].to_vec();
        let rows: Vec<PointRows> = local
            .iter()
            .map(|&i| point_rows(&points[i], dofs, &interfaces))
            .collect();
        let point_columns = points
            .iter()
            .map(|p| {
                let mut d = Vec::new();
                point_dofs(p, dofs, &mut d);
                d
            })
            .collect();
        let [c_nor, c_tan, c_tan2, c_conv, c_all] =
            observation_matrices(petsc, first_row, &rows, dofs.owned_dofs())?;
        let (stacked, velocity) = (c_all.new_point_vector()?, c_nor.new_point_vector()?);
        Ok(ContactModel {
            interfaces,
            misses: pairing.misses,
            candidates: pairing.candidates,
            points,
            row_ids,
            first_row,
            local,
            points_per_rank,
            rows,
            c_nor: Rc::new(c_nor),
            c_tan: Rc::new(c_tan),
            c_tan2: Rc::new(c_tan2),
            c_conv: Rc::new(c_conv),
            c_all: Rc::new(c_all),
            columns: dofs.owned_dofs(),
            point_columns,
            disc_speed: settings.disc_speed,
            pairing_seconds: start.elapsed().as_secs_f64(),
            stacked: stacked.into(),
            velocity: velocity.into(),
        })
    }

    /// The same points on a renumbered set of unknowns (a reduced model that keeps every
    /// contact DOF as it is): `map[old column]` is the new global column, and `columns` this
    /// rank's new range. A point coupling a DOF the map drops (negative) is an error naming
    /// the interface: such a point would lose its force.
    ///
    /// # Collective
    pub fn restricted(
        &self,
        petsc: &'p Petsc,
        map: &[i32],
        columns: std::ops::Range<usize>,
    ) -> Result<ContactModel<'p>, ContactError> {
        let remap = |cols: &[i32], id: usize| -> Result<Vec<i32>, ContactError> {
            cols.iter()
                .map(|&c| {
                    if c < 0 {
                        return Ok(-1);
                    }
                    match map[c as usize] {
                        m if m >= 0 => Ok(m),
                        _ => Err(ContactError::NotKept {
                            interface: self.interfaces[self.points[id].interface].name.clone(),
                            dof: c,
                        }),
                    }
                })
                .collect()
        };
        let point_columns = self
            .point_columns
            .iter()
            .enumerate()
            .map(|(id, cols)| remap(cols, id))
            .collect::<Result<Vec<_>, _>>()?;
        let rows = self
            .rows
            .iter()
            .zip(&self.local)
            .map(|(r, &id)| {
                Ok(PointRows {
                    dofs: remap(&r.dofs, id)?,
                    ..r.clone()
                })
            })
            .collect::<Result<Vec<_>, ContactError>>()?;
        let [c_nor, c_tan, c_tan2, c_conv, c_all] =
            observation_matrices(petsc, self.first_row, &rows, columns.clone())?;
        let (stacked, velocity) = (c_all.new_point_vector()?, c_nor.new_point_vector()?);
        Ok(ContactModel {
            interfaces: self.interfaces.clone(),
            points: self.points.clone(),
            misses: self.misses.clone(),
            candidates: self.candidates.clone(),
            row_ids: self.row_ids.clone(),
            first_row: self.first_row,
            local: self.local.clone(),
            points_per_rank: self.points_per_rank.clone(),
            rows,
            c_nor: Rc::new(c_nor),
            c_tan: Rc::new(c_tan),
            c_tan2: Rc::new(c_tan2),
            c_conv: Rc::new(c_conv),
            c_all: Rc::new(c_all),
            columns,
            point_columns,
            disc_speed: self.disc_speed,
            pairing_seconds: self.pairing_seconds,
            stacked: stacked.into(),
            velocity: velocity.into(),
        })
    }

    /// Omega r at a point (zero on interfaces that do not slide).
    pub(super) fn rigid_speed(&self, id: usize) -> f64 {
        let p = &self.points[id];
        if self.interfaces[p.interface].friction.is_sliding() {
            self.disc_speed * p.radius
        } else {
            0.0
        }
    }

    /// Observes displacement q (and velocity v, zero if None) and applies the laws.
    ///
    /// # Collective
    pub fn evaluate(
        &self,
        q: &Vector,
        v: Option<&Vector>,
        friction_scale: f64,
    ) -> Result<ContactState, LaError> {
        let mut w = self.velocity.borrow_mut();
        let mut stacked = self.stacked.borrow_mut();
        self.c_all.mult(q, &mut stacked)?;
        match v {
            Some(v) => self.c_tan.mult(v, &mut w)?,
            None => w.set_all(0.0)?,
        }
        let (o, w) = (stacked.local()?, w.local()?);
        let mut observed = Vec::with_capacity(self.local.len());
        let mut response = Vec::with_capacity(self.local.len());
        for (k, &id) in self.local.iter().enumerate() {
            let p = &self.points[id];
            let itf = &self.interfaces[p.interface];
            let sliding = itf.friction.is_sliding();
            let [g, s1, s2, conv] = [0, 1, 2, 3].map(|c| o[CHANNELS * k + c]);
            let o = Observed {
                gap: g + p.initial_gap,
                slip: [s1, s2],
                speed: w[k]
                    + self.rigid_speed(id)
                    + if sliding { self.disc_speed * conv } else { 0.0 },
            };
            response.push(kernel::respond(
                &itf.normal,
                &itf.friction,
                friction_scale,
                o,
            ));
            observed.push(o);
        }
        Ok(ContactState {
            observed,
            response,
            friction_scale,
        })
    }

    /// The contact state at `base` moved by an observed increment per local point k:
    /// `increment(k)` = ([gap, slip 1, slip 2, convection], tangential velocity), the
    /// observation rows applied to a displacement and a velocity (the sliding speed gains the
    /// velocity plus the disc speed times the convection on sliding interfaces, as in
    /// [`Self::evaluate`]). No vector of size n: what the pseudo trajectories need at
    /// thousands of states of one mode.
    pub fn moved(
        &self,
        base: &ContactState,
        increment: impl Fn(usize) -> ([f64; 4], f64),
    ) -> ContactState {
        let mut observed = Vec::with_capacity(self.local.len());
        let mut response = Vec::with_capacity(self.local.len());
        for (k, &id) in self.local.iter().enumerate() {
            let itf = &self.interfaces[self.points[id].interface];
            let ([g, s1, s2, conv], w) = increment(k);
            let b = &base.observed[k];
            let convected = if itf.friction.is_sliding() {
                self.disc_speed * conv
            } else {
                0.0
            };
            let o = Observed {
                gap: b.gap + g,
                slip: [b.slip[0] + s1, b.slip[1] + s2],
                speed: b.speed + w + convected,
            };
            response.push(kernel::respond(
                &itf.normal,
                &itf.friction,
                base.friction_scale,
                o,
            ));
            observed.push(o);
        }
        ContactState {
            observed,
            response,
            friction_scale: base.friction_scale,
        }
    }

    /// The contact force f_N + f_T = C_NOR^T (w p) - C_TAN^T (w t1) - C_TAN2^T (w t2).
    ///
    /// # Collective
    pub fn force(&self, state: &ContactState, out: &mut Vector) -> Result<(), LaError> {
        let mut stacked = self.stacked.borrow_mut();
        {
            let mut a = stacked.local_mut()?;
            for (k, &id) in self.local.iter().enumerate() {
                let w = self.points[id].weight;
                let r = &state.response[k];
                let values = [w * r.pressure, -w * r.traction[0], -w * r.traction[1], 0.0];
                a[CHANNELS * k..CHANNELS * (k + 1)].copy_from_slice(&values);
            }
        }
        self.c_all.mult_transpose(&stacked, out)
    }

    /// Stored entries of the observation rows of each channel (normal, tangent, second
    /// tangent, convection), summed over the ranks: the bytes a contact evaluation streams.
    ///
    /// # Collective
    pub fn observation_entries(&self) -> Result<[f64; 4], LaError> {
        Ok([
            self.c_nor.stored_entries()?,
            self.c_tan.stored_entries()?,
            self.c_tan2.stored_entries()?,
            self.c_conv.stored_entries()?,
        ])
    }

    pub(crate) fn observation(&self, c: Channel) -> &ObservationMatrix<'p> {
        match c {
            Channel::Nor => self.c_nor.as_ref(),
            Channel::Tan => self.c_tan.as_ref(),
            Channel::Tan2 => self.c_tan2.as_ref(),
            Channel::Conv => self.c_conv.as_ref(),
        }
    }

    /// The observation rows applied to each shape: for every channel (normal, tangent, second
    /// tangent, convection) a local-points x shapes column-major block.
    ///
    /// # Collective
    pub fn observe_shapes(&self, shapes: &[Vector]) -> Result<[Vec<f64>; 4], LaError> {
        let n = self.local.len();
        let mut out: [Vec<f64>; 4] = Default::default();
        let mut y = self.c_nor.new_point_vector()?;
        for (c, matrix) in [&*self.c_nor, &*self.c_tan, &*self.c_tan2, &*self.c_conv]
            .into_iter()
            .enumerate()
        {
            out[c].reserve(n * shapes.len());
            for x in shapes {
                matrix.mult(x, &mut y)?;
                out[c].extend_from_slice(&y.local()?);
            }
        }
        Ok(out)
    }

    /// A per-point value of this rank's points, gathered on every rank in point-id order.
    ///
    /// # Collective
    pub fn gather(&self, petsc: &'p Petsc, local: &[f64]) -> Result<Vec<f64>, LaError> {
        let v = Vector::from_local(petsc, local)?;
        let rows = v.gather_all()?;
        let mut out = vec![0.0; rows.len()];
        for (row, value) in rows.into_iter().enumerate() {
            out[self.row_ids[row]] = value;
        }
        Ok(out)
    }
}

/// What the model holds, read-only.
impl<'p> ContactModel<'p> {
    /// The interfaces with their laws, in the scene's order.
    pub fn interfaces(&self) -> &[ResolvedInterface] {
        &self.interfaces
    }
    /// Every point on every rank (pairing is cheap and replicated), by point id.
    pub fn points(&self) -> &[ContactPoint] {
        &self.points
    }
    /// Per interface: the master points that missed the slave surface, and the candidates.
    pub fn misses(&self) -> &[usize] {
        &self.misses
    }
    pub fn candidates(&self) -> &[usize] {
        &self.candidates
    }
    /// Point ids in global row order.
    pub fn row_ids(&self) -> &[usize] {
        &self.row_ids
    }
    /// This rank's first global row: its rows are [first_row, first_row + local().len()).
    pub fn first_row(&self) -> usize {
        self.first_row
    }
    /// This rank's points (ids), in row order.
    pub fn local(&self) -> &[usize] {
        &self.local
    }
    /// How many points each rank owns (an even split of the rows).
    pub fn points_per_rank(&self) -> &[usize] {
        &self.points_per_rank
    }
    /// This rank's points' dense observation rows.
    pub fn rows(&self) -> &[PointRows] {
        &self.rows
    }
    pub fn c_nor(&self) -> &ObservationMatrix<'p> {
        &self.c_nor
    }
    pub fn c_tan(&self) -> &ObservationMatrix<'p> {
        &self.c_tan
    }
    pub fn c_tan2(&self) -> &ObservationMatrix<'p> {
        &self.c_tan2
    }
    pub fn c_conv(&self) -> &ObservationMatrix<'p> {
        &self.c_conv
    }
    /// This rank's columns (DOFs).
    pub fn columns(&self) -> std::ops::Range<usize> {
        self.columns.clone()
    }
    /// For every point, the global columns it couples (master nodes then slave nodes; -1
    /// where a DOF is eliminated).
    pub fn point_columns(&self) -> &[Vec<i32>] {
        &self.point_columns
    }
    /// Disc speed Omega (rad/s).
    pub fn disc_speed(&self) -> f64 {
        self.disc_speed
    }
    pub fn pairing_seconds(&self) -> f64 {
        self.pairing_seconds
    }

    /// The same points and observation matrices (shared, not copied) with other laws and
    /// disc speed: what a sweep evaluates, leaving this model as it is. The laws may change
    /// their parameters, not whether an interface slides (that decides the convection rows).
    pub fn with_laws(
        &self,
        interfaces: Vec<ResolvedInterface>,
        disc_speed: f64,
    ) -> Result<ContactModel<'p>, ContactError> {
        for (new, old) in interfaces.iter().zip(&self.interfaces) {
            if new.friction.is_sliding() != old.friction.is_sliding() {
                return Err(ContactError::SlidingChanged {
                    interface: old.name.clone(),
                });
            }
        }
        if interfaces.len() != self.interfaces.len() {
            return Err(ContactError::SlidingChanged {
                interface: format!(
                    "{} interfaces for {}",
                    interfaces.len(),
                    self.interfaces.len()
                ),
            });
        }
        let stacked = self.c_all.new_point_vector()?;
        let velocity = self.c_nor.new_point_vector()?;
        Ok(ContactModel {
            interfaces,
            points: self.points.clone(),
            misses: self.misses.clone(),
            candidates: self.candidates.clone(),
            row_ids: self.row_ids.clone(),
            first_row: self.first_row,
            local: self.local.clone(),
            points_per_rank: self.points_per_rank.clone(),
            rows: self.rows.clone(),
            c_nor: Rc::clone(&self.c_nor),
            c_tan: Rc::clone(&self.c_tan),
            c_tan2: Rc::clone(&self.c_tan2),
            c_conv: Rc::clone(&self.c_conv),
            c_all: Rc::clone(&self.c_all),
            columns: self.columns.clone(),
            point_columns: self.point_columns.clone(),
            disc_speed,
            pairing_seconds: self.pairing_seconds,
            stacked: stacked.into(),
            velocity: velocity.into(),
        })
    }
}

/// The four observation matrices (normal, tangent, second tangent, convection) of this rank's
/// point rows, and the four stacked (CHANNELS rows per point, in that order).
///
/// # Collective
fn observation_matrices<'p>(
    petsc: &'p Petsc,
    first_row: usize,
    rows: &[PointRows],
    columns: std::ops::Range<usize>,
) -> Result<[ObservationMatrix<'p>; 5], LaError> {
    let sparse = |f: fn(&PointRows) -> &Vec<f64>| -> Vec<Vec<(i32, f64)>> {
        rows.iter()
            .map(|r| {
                r.dofs
                    .iter()
                    .zip(f(r))
                    .filter(|(d, v)| **d >= 0 && **v != 0.0)
                    .map(|(d, v)| (*d, *v))
                    .collect()
            })
            .collect()
    };
    let channels: [fn(&PointRows) -> &Vec<f64>; CHANNELS] =
        [|r| &r.nor, |r| &r.tan, |r| &r.tan2, |r| &r.conv];
    let each: Vec<Vec<Vec<(i32, f64)>>> = channels.iter().map(|&f| sparse(f)).collect();
    let stacked: Vec<Vec<(i32, f64)>> = (0..rows.len())
        .flat_map(|k| each.iter().map(move |c| c[k].clone()))
        .collect();
    Ok([
        ObservationMatrix::from_rows(petsc, first_row, &each[0], columns.clone())?,
        ObservationMatrix::from_rows(petsc, first_row, &each[1], columns.clone())?,
        ObservationMatrix::from_rows(petsc, first_row, &each[2], columns.clone())?,
        ObservationMatrix::from_rows(petsc, first_row, &each[3], columns.clone())?,
        ObservationMatrix::from_rows(petsc, CHANNELS * first_row, &stacked, columns)?,
    ])
}

/// The DOFs of a point: master nodes then slave nodes, 3 each.
fn point_dofs(p: &ContactPoint, dofs: &DofMap, out: &mut Vec<i32>) {
    for &n in p.master_nodes.iter().chain(&p.slave_nodes) {
        out.extend_from_slice(&dofs.node_dofs[n]);
    }
}

/// Dense rows of C_NOR, C_TAN, C_TAN2, C_CONV at a point. Normal rows observe master minus
/// slave (the gap opens when the pad moves along the slave's outward normal); tangential rows
/// slave minus master (the disc's motion under the pad).
pub fn point_rows(p: &ContactPoint, dofs: &DofMap, interfaces: &[ResolvedInterface]) -> PointRows {
    let mut d = Vec::new();
    point_dofs(p, dofs, &mut d);
    let n = d.len();
    let mut rows = PointRows {
        dofs: d,
        nor: vec![0.0; n],
        tan: vec![0.0; n],
        tan2: vec![0.0; n],
        conv: vec![0.0; n],
    };
    let sliding = interfaces[p.interface].friction.is_sliding();
    let nm = p.master_nodes.len();
    for (a, &na) in p.master_shape.iter().enumerate() {
        for c in 0..3 {
            rows.nor[3 * a + c] = na * p.normal[c];
            rows.tan[3 * a + c] = -na * p.tangent[c];
            rows.tan2[3 * a + c] = -na * p.tangent2[c];
        }
    }
    for (b, &nb) in p.slave_shape.iter().enumerate() {
        for c in 0..3 {
            let i = 3 * (nm + b) + c;
            rows.nor[i] = -nb * p.normal[c];
            rows.tan[i] = nb * p.tangent[c];
            rows.tan2[i] = nb * p.tangent2[c];
            if sliding {
                rows.conv[i] = p.slave_dtheta[b] * p.tangent[c];
            }
        }
    }
    rows
}
