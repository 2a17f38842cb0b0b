//! XDMF 3 descriptions of results.h5, for ParaView and other XDMF readers (meshio):
//!
//! - results.xdmf: the brake as one grid (every element in one mixed topology, with the cell
//!   field `component`), carrying the static displacement and contact pressure and the mode
//!   shapes as nodal fields;
//! - surfaces.xdmf: the named surfaces (contact faces, loaded faces), one grid each, with the
//!   static contact pressure;
//! - vibration.xdmf: the transient's frames as a time series on the brake.
//!
//! One grid per file, or a mesh and one temporal collection, is what readers other than
//! ParaView's take (meshio reads a file of one grid, or a time series).

use std::fmt::Write as _;
use std::path::Path;

use crate::mesh::ElementKind;
use crate::mesh::Mesh;

/// The element's type code in an XDMF mixed topology (XdmfTopologyType's ids).
pub fn mixed_code(kind: ElementKind) -> u64 {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex8I => 0x9,
        ElementKind::Hex20 | ElementKind::Hex20R => 0x30,
        ElementKind::Tet10 => 0x26,
        ElementKind::Tet4 => 0x6,
        ElementKind::Wedge6 => 0x8,
        ElementKind::Wedge15 => 0x28,
    }
}

/// The element's nodes in XDMF's (VTK's) order, as positions in its Abaqus order: the same
/// for hexahedra and tetrahedra; a wedge's base triangle runs the other way round in VTK
/// (its normal points away from the top), so corners 2 and 3, 5 and 6 and their mid-edge
/// nodes swap.
pub fn xdmf_order(kind: ElementKind) -> Option<&'static [usize]> {
    match kind {
        ElementKind::Wedge6 => Some(&[0, 2, 1, 3, 5, 4]),
        ElementKind::Wedge15 => Some(&[0, 2, 1, 3, 5, 4, 8, 7, 6, 11, 10, 9, 12, 14, 13]),
        _ => None,
    }
}

/// A nodal field stored in the HDF5 file (3 components, or 1), shown under `label`.
pub struct NodalField {
    pub label: String,
    pub dataset: String,
    pub components: usize,
}

impl NodalField {
    pub fn vector(label: &str, dataset: &str) -> Self {
        NodalField {
            label: label.into(),
            dataset: dataset.into(),
            components: 3,
        }
    }

    pub fn scalar(label: &str, dataset: &str) -> Self {
        NodalField {
            label: label.into(),
            dataset: dataset.into(),
            components: 1,
        }
    }
}

/// Text safe inside an XML attribute or element.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A reference to an HDF5 dataset of `dims` values of `number` type.
fn data_item(dims: &str, number: &str, h5: &str, dataset: &str) -> String {
    format!(
        "<DataItem Dimensions=\"{dims}\" NumberType=\"{number}\" Precision=\"8\" Format=\"HDF\">{}:{}</DataItem>",
        escape(h5),
        escape(dataset)
    )
}

fn attribute(x: &mut String, name: &str, center: &str, components: usize, item: &str) {
    let kind = if components == 3 { "Vector" } else { "Scalar" };
    let _ = writeln!(
        x,
        "<Attribute Name=\"{}\" AttributeType=\"{kind}\" Center=\"{center}\">\n{item}\n</Attribute>",
        escape(name)
    );
}

fn geometry(x: &mut String, h5: &str, mesh: &Mesh) {
    let n = mesh.node_count();
    let item = data_item(&format!("{n} 3"), "Float", h5, "/model/coordinates");
    let _ = writeln!(x, "<Geometry GeometryType=\"XYZ\">\n{item}\n</Geometry>");
}

/// The brake's topology (every element, mixed) and geometry.
fn brake_mesh(x: &mut String, h5: &str, mesh: &Mesh) {
    let elements = mesh.element_count();
    let length: usize = mesh
        .blocks
        .iter()
        .map(|b| b.len() * (b.kind.nodes() + 1))
        .sum();
    let item = data_item(&length.to_string(), "UInt", h5, "/model/topology");
    let _ = writeln!(
        x,
        "<Topology TopologyType=\"Mixed\" NumberOfElements=\"{elements}\">\n{item}\n</Topology>"
    );
    geometry(x, h5, mesh);
}

/// The cell field naming each element's component (block index).
fn component_field(x: &mut String, h5: &str, mesh: &Mesh) {
    let names: Vec<String> = (mesh.blocks.iter().enumerate())
        .map(|(i, b)| format!("{i} {}", b.name))
        .collect();
    let label = if names.len() <= 12 {
        format!("component ({})", names.join(", "))
    } else {
        "component (index into the /model attribute 'components')".to_string()
    };
    let item = data_item(
        &mesh.element_count().to_string(),
        "UInt",
        h5,
        "/model/component_id",
    );
    attribute(x, &label, "Cell", 1, &item);
}

fn nodal(x: &mut String, h5: &str, n: usize, f: &NodalField) {
    let dims = match f.components {
        1 => n.to_string(),
        c => format!("{n} {c}"),
    };
    let item = data_item(&dims, "Float", h5, &f.dataset);
    attribute(x, &f.label, "Node", f.components, &item);
}

const HEADER: &str = "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n";
const FOOTER: &str = "</Domain>\n</Xdmf>\n";

/// results.xdmf: the brake with `fields` (call on one rank; `h5` relative to the file).
pub fn write_brake(
    path: &Path,
    h5: &str,
    mesh: &Mesh,
    fields: &[NodalField],
) -> std::io::Result<()> {
    let mut x = String::from(HEADER);
    x += "<Grid Name=\"brake\" GridType=\"Uniform\">\n";
    brake_mesh(&mut x, h5, mesh);
    component_field(&mut x, h5, mesh);
    for f in fields {
        nodal(&mut x, h5, mesh.node_count(), f);
    }
    x += "</Grid>\n";
    x += FOOTER;
    std::fs::write(path, x)
}

/// surfaces.xdmf: each named surface of uniform face shape as a grid, with the static
/// contact pressure at the nodes when `pressure`.
pub fn write_surfaces(path: &Path, h5: &str, mesh: &Mesh, pressure: bool) -> std::io::Result<()> {
    let mut x = String::from(HEADER);
    x += "<Grid Name=\"surfaces\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
    for (name, faces) in &mesh.surfaces {
        let Some(corners) = crate::io::results::surface_corners(mesh, faces) else {
            continue;
        };
        let nf = faces.len();
        let width = corners.len() / nf.max(1);
        let topology = if width == 4 {
            "Quadrilateral"
        } else {
            "Triangle"
        };
        let dataset = format!("/model/surfaces/{name}/connectivity");
        let item = data_item(&format!("{nf} {width}"), "UInt", h5, &dataset);
        let _ = writeln!(
            x,
            "<Grid Name=\"{}\" GridType=\"Uniform\">\n<Topology TopologyType=\"{topology}\" NumberOfElements=\"{nf}\">\n{item}\n</Topology>",
            escape(name)
        );
        geometry(&mut x, h5, mesh);
        if pressure {
            let f = NodalField::scalar(
                "static contact pressure (Pa)",
                "/static/contact_pressure_at_nodes",
            );
            nodal(&mut x, h5, mesh.node_count(), &f);
        }
        x += "</Grid>\n";
    }
    x += "</Grid>\n";
    x += FOOTER;
    std::fs::write(path, x)
}

/// vibration.xdmf: the brake, then the frames as a temporal collection (each frame repeats
/// the brake's topology and geometry references, which every reader follows).
/// The dataset of the transient's frame `k` (from 0) in results.h5.
pub fn frame_dataset(k: usize) -> String {
    format!("/vibration/frame_{:04}", k + 1)
}

pub fn write_frames(path: &Path, h5: &str, mesh: &Mesh, times: &[f64]) -> std::io::Result<()> {
    let mut x = String::from(HEADER);
    x += "<Grid Name=\"brake\" GridType=\"Uniform\">\n";
    brake_mesh(&mut x, h5, mesh);
    component_field(&mut x, h5, mesh);
    x += "</Grid>\n";
    x += "<Grid Name=\"vibration\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (k, t) in times.iter().enumerate() {
        let _ = writeln!(
            x,
            "<Grid Name=\"frame {}\" GridType=\"Uniform\">\n<Time Value=\"{t:.9e}\"/>",
            k + 1
        );
        brake_mesh(&mut x, h5, mesh);
        let f = NodalField::vector("vibration (m)", &frame_dataset(k));
        nodal(&mut x, h5, mesh.node_count(), &f);
        x += "</Grid>\n";
    }
    x += "</Grid>\n";
    x += FOOTER;
    std::fs::write(path, x)
}
