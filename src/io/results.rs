//! The results file (`results.h5`), written in parallel (MPI-IO): every rank writes the rows of
//! the nodes it owns; small tables are written by rank 0. Every dataset carries its units.
//! Readable by h5py without this program.

use std::path::Path;

use hdf5::types::VarLenUnicode;
use mpi::raw::AsRaw;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use ndarray::{s, Array1, Array2};

use crate::eigen::real_modes::RealModes;
use crate::fem::dofmap::DofMap;
use crate::la::LaError;
use crate::mesh::Mesh;

#[derive(Debug, thiserror::Error)]
pub enum ResultsError {
    #[error("{path}: HDF5: {source}")]
    Hdf5 { path: String, source: hdf5::Error },
    #[error(transparent)]
    La(#[from] LaError),
}

/// The group at `path` (slash-separated, from the root), created with its parents if missing.
pub(crate) fn group_at(file: &hdf5::File, path: &str) -> Result<hdf5::Group, hdf5::Error> {
    let mut g = file.group("/")?;
    for part in path.split('/').filter(|p| !p.is_empty()) {
        g = match g.group(part) {
            Ok(x) => x,
            Err(_) => g.create_group(part)?,
        };
    }
    Ok(g)
}

/// Opens (or creates) an HDF5 file for parallel access by every rank of `comm`.
///
/// # Collective
pub(crate) fn open_parallel(
    comm: &SimpleCommunicator,
    path: &Path,
    create: bool,
) -> Result<hdf5::File, ResultsError> {
    let mut builder = hdf5::File::with_options();
    builder.with_fapl(|fapl| fapl.mpio(comm.as_raw(), None));
    if create {
        builder.create(path)
    } else {
        builder.open_rw(path)
    }
    .map_err(|source| ResultsError::Hdf5 {
        path: path.to_string_lossy().to_string(),
        source,
    })
}

pub struct ResultsFile {
    file: hdf5::File,
    path: String,
    rank: i32,
}

impl ResultsFile {
    /// Creates (truncates) the file on every rank of `comm`.
    ///
    /// # Collective
    pub fn create(comm: &SimpleCommunicator, path: &Path) -> Result<Self, ResultsError> {
        let file = open_parallel(comm, path, true)?;
        Ok(ResultsFile {
            file,
            path: path.to_string_lossy().to_string(),
            rank: comm.rank(),
        })
    }

    fn err(&self) -> impl Fn(hdf5::Error) -> ResultsError + '_ {
        move |source| ResultsError::Hdf5 {
            path: self.path.clone(),
            source,
        }
    }

    fn group(&self, path: &str) -> Result<hdf5::Group, ResultsError> {
        group_at(&self.file, path).map_err(self.err())
    }

    /// Pushes what was written to the file, so a crash in a later stage keeps it.
    ///
    /// # Collective
    pub fn flush(&self) -> Result<(), ResultsError> {
        self.file.flush().map_err(self.err())
    }

    /// An external link at `link` to the root of `target` (a file name relative to this
    /// file's folder): h5py follows it like a group.
    ///
    /// # Collective
    pub fn link_external(&self, link: &str, target: &str) -> Result<(), ResultsError> {
        let (dir, name) = link.rsplit_once('/').unwrap_or(("", link));
        self.group(dir)?
            .link_external(target, "/", name)
            .map_err(self.err())
    }

    /// A string attribute on a group (created collectively).
    ///
    /// # Collective
    pub fn set_text(&self, group: &str, name: &str, value: &str) -> Result<(), ResultsError> {
        let g = self.group(group)?;
        let v: VarLenUnicode = value.replace('\0', " ").parse().unwrap();
        let attr = g
            .new_attr::<VarLenUnicode>()
            .create(name)
            .map_err(self.err())?;
        attr.write_scalar(&v).map_err(self.err())
    }

    /// A numeric attribute on a group.
    ///
    /// # Collective
    pub fn set_number(&self, group: &str, name: &str, value: f64) -> Result<(), ResultsError> {
        let g = self.group(group)?;
        let attr = g.new_attr::<f64>().create(name).map_err(self.err())?;
        attr.write_scalar(&value).map_err(self.err())
    }

    fn dataset<T: hdf5::H5Type>(
        &self,
        path: &str,
        shape: &[usize],
        units: &str,
    ) -> Result<hdf5::Dataset, ResultsError> {
        let (dir, name) = path.rsplit_once('/').unwrap_or(("", path));
        let g = self.group(dir)?;
        let ds = g
            .new_dataset::<T>()
            .shape(shape)
            .create(name)
            .map_err(self.err())?;
        let v: VarLenUnicode = units.parse().unwrap();
        ds.new_attr::<VarLenUnicode>()
            .create("units")
            .map_err(self.err())?
            .write_scalar(&v)
            .map_err(self.err())?;
        Ok(ds)
    }

    /// A 1D table written by rank 0 (every rank passes the same values).
    ///
    /// # Collective
    pub fn write_table(&self, path: &str, values: &[f64], units: &str) -> Result<(), ResultsError> {
        let ds = self.dataset::<f64>(path, &[values.len()], units)?;
        if self.rank == 0 && !values.is_empty() {
            ds.write(&Array1::from(values.to_vec()))
                .map_err(self.err())?;
        }
        Ok(())
    }

    /// Node coordinates and the connectivity of every element block.
    ///
    /// # Collective
    pub fn write_mesh(&self, mesh: &Mesh) -> Result<(), ResultsError> {
        let n = mesh.node_count();
        let coords = self.dataset::<f64>("model/coordinates", &[n, 3], "m")?;
        if self.rank == 0 {
            let a = Array2::from_shape_vec((n, 3), mesh.coords.iter().flatten().copied().collect())
                .unwrap();
            coords.write(&a).map_err(self.err())?;
        }
        for block in &mesh.blocks {
            let nn = block.kind.nodes();
            let path = format!("model/blocks/{}/connectivity", block.name);
            let ds = self.dataset::<u64>(&path, &[block.len(), nn], "1")?;
            if self.rank == 0 && !block.is_empty() {
                let a = Array2::from_shape_vec(
                    (block.len(), nn),
                    block.connectivity.iter().map(|&v| v as u64).collect(),
                )
                .unwrap();
                ds.write(&a).map_err(self.err())?;
            }
            self.set_text(
                &format!("model/blocks/{}", block.name),
                "element_type",
                block.kind.name(),
            )?;
            self.set_text(
                &format!("model/blocks/{}", block.name),
                "material",
                &mesh.materials[block.material].name,
            )?;
        }
        // Every element in one XDMF "Mixed" topology (type code, then its nodes), in global
        // element order: readers that take one grid per file (meshio) see the whole brake.
        let topology: Vec<u64> = mesh
            .blocks
            .iter()
            .flat_map(|block| {
                let code = crate::io::xdmf::mixed_code(block.kind);
                let nn = block.kind.nodes();
                let order = crate::io::xdmf::xdmf_order(block.kind);
                block.connectivity.chunks(nn).flat_map(move |e| {
                    let nodes: Vec<u64> = match order {
                        Some(o) => o.iter().map(|&i| e[i] as u64).collect(),
                        None => e.iter().map(|&v| v as u64).collect(),
                    };
                    std::iter::once(code).chain(nodes)
                })
            })
            .collect();
        let ds = self.dataset::<u64>("model/topology", &[topology.len()], "1")?;
        if self.rank == 0 && !topology.is_empty() {
            ds.write(&Array1::from(topology)).map_err(self.err())?;
        }
        // Component id (block index) of every element, in global element order.
        let ids: Vec<u64> = mesh
            .blocks
            .iter()
            .enumerate()
            .flat_map(|(b, block)| std::iter::repeat_n(b as u64, block.len()))
            .collect();
        let ds = self.dataset::<u64>("model/component_id", &[ids.len()], "1")?;
        if self.rank == 0 && !ids.is_empty() {
            ds.write(&Array1::from(ids)).map_err(self.err())?;
        }
        self.set_text(
            "model",
            "components",
            &mesh
                .blocks
                .iter()
                .map(|b| b.name.as_str())
                .collect::<Vec<_>>()
                .join(","),
        )?;
        for (name, faces) in &mesh.surfaces {
            let group = format!("model/surfaces/{name}");
            let ds = self.dataset::<u64>(&format!("{group}/faces"), &[faces.len(), 2], "1")?;
            if self.rank == 0 && !faces.is_empty() {
                let a = Array2::from_shape_vec(
                    (faces.len(), 2),
                    faces
                        .iter()
                        .flat_map(|&(e, f)| [e as u64, f as u64])
                        .collect(),
                )
                .unwrap();
                ds.write(&a).map_err(self.err())?;
            }
            // Corner connectivity for ParaView (quadrilaterals or triangles).
            if let Some(corners) = surface_corners(mesh, faces) {
                let width = corners.len() / faces.len().max(1);
                let ds = self.dataset::<u64>(
                    &format!("{group}/connectivity"),
                    &[faces.len(), width],
                    "1",
                )?;
                if self.rank == 0 && !faces.is_empty() {
                    let a = Array2::from_shape_vec((faces.len(), width), corners).unwrap();
                    ds.write(&a).map_err(self.err())?;
                }
            }
        }
        Ok(())
    }

    /// A nodal vector field (3 per node) from a distributed DOF vector: each rank writes its
    /// owned nodes.
    ///
    /// # Collective
    pub fn write_nodal(
        &self,
        path: &str,
        dofs: &DofMap,
        local: &[f64],
        units: &str,
    ) -> Result<(), ResultsError> {
        let n = dofs.node_dofs.len();
        let ds = self.dataset::<f64>(path, &[n, 3], units)?;
        let owned = dofs.owned_nodes();
        if !owned.is_empty() {
            let field = dofs.to_nodal(local);
            let a = Array2::from_shape_vec((owned.len(), 3), field.into_iter().flatten().collect())
                .unwrap();
            ds.write_slice(&a, s![owned.start..owned.end, ..])
                .map_err(self.err())?;
        }
        Ok(())
    }

    /// A distributed DOF vector (for models without a mesh): each rank writes its range.
    ///
    /// # Collective
    pub fn write_dof_vector(
        &self,
        path: &str,
        vector: &crate::la::Vector,
        units: &str,
    ) -> Result<(), ResultsError> {
        let ds = self.dataset::<f64>(path, &[vector.global_len()], units)?;
        let range = vector.ownership();
        if !range.is_empty() {
            let local = vector.local()?;
            ds.write_slice(&Array1::from(local.to_vec()), s![range.start..range.end])
                .map_err(self.err())?;
        }
        Ok(())
    }

    /// Frequencies, residuals, rigid flags and M-normalized shapes of real modes: nodal
    /// fields under `shapes/` with a DOF map, raw DOF vectors under `vectors/` without.
    ///
    /// # Collective
    pub fn write_real_modes(
        &self,
        modes: &RealModes,
        dofs: Option<&DofMap>,
    ) -> Result<(), ResultsError> {
        self.write_table("modes/real/frequency", &modes.frequencies_hz, "Hz")?;
        self.write_table("modes/real/eigenvalue", &modes.eigenvalues, "rad^2/s^2")?;
        self.write_table(
            "modes/real/residual_norm",
            &modes.residual_norms,
            "N (phi M-normalized)",
        )?;
        self.write_table("modes/real/backward_error", &modes.backward_errors, "1")?;
        let rigid: Vec<f64> = modes.rigid.iter().map(|&r| r as i32 as f64).collect();
        self.write_table("modes/real/rigid_body", &rigid, "1 = rigid-body mode")?;
        for (i, shape) in modes.shapes.iter().enumerate() {
            let units = "m / sqrt(kg) (M-normalized)";
            match dofs {
                Some(dofs) => {
                    let local = shape.local()?;
                    self.write_nodal(
                        &format!("modes/real/shapes/mode_{:04}", i + 1),
                        dofs,
                        &local,
                        units,
                    )?;
                }
                None => self.write_dof_vector(
                    &format!("modes/real/vectors/mode_{:04}", i + 1),
                    shape,
                    units,
                )?,
            }
        }
        Ok(())
    }
}

/// Corner nodes of every face of a surface, when all faces have the same corner count.
pub fn surface_corners(mesh: &Mesh, faces: &[(usize, u8)]) -> Option<Vec<u64>> {
    let mut out = Vec::new();
    let mut width = None;
    for &(e, f) in faces {
        let (b, _) = mesh.locate_element(e);
        let corners = if mesh.blocks[b].kind.faces() == 6 {
            4
        } else {
            3
        };
        if *width.get_or_insert(corners) != corners {
            return None;
        }
        out.extend(mesh.face_nodes(e, f)[..corners].iter().map(|&n| n as u64));
    }
    Some(out)
}
