//! XDMF 3 description of results.h5 so ParaView opens the mesh and the mode shapes.

use std::fmt::Write as _;
use std::path::Path;

use crate::fem::shape::ElementKind;
use crate::mesh::Mesh;

fn topology_type(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex8I => "Hexahedron",
        ElementKind::Hex20 => "Hexahedron_20",
        ElementKind::Tet10 => "Tetrahedron_10",
        ElementKind::Tet4 => "Tetrahedron",
    }
}

/// A nodal vector field stored in the HDF5 file, shown in ParaView under `label`.
pub struct NodalField {
    pub label: String,
    pub dataset: String,
}

/// Writes the XDMF file (call on one rank) referring to `h5_name` (relative to the XDMF file).
pub fn write(
    path: &Path,
    h5_name: &str,
    mesh: &Mesh,
    fields: &[NodalField],
) -> std::io::Result<()> {
    let n = mesh.node_count();
    let mut x = String::new();
    x += "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n";
    x += "<Grid Name=\"model\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
    for block in &mesh.blocks {
        let ne = block.len();
        let nn = block.kind.nodes();
        let _ = writeln!(x, "<Grid Name=\"{}\" GridType=\"Uniform\">", block.name);
        let _ = writeln!(
            x,
            "<Topology TopologyType=\"{}\" NumberOfElements=\"{ne}\">\n<DataItem Dimensions=\"{ne} {nn}\" NumberType=\"UInt\" Precision=\"8\" Format=\"HDF\">{h5_name}:/model/blocks/{}/connectivity</DataItem>\n</Topology>",
            topology_type(block.kind),
            block.name
        );
        let _ = writeln!(
            x,
            "<Geometry GeometryType=\"XYZ\">\n<DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5_name}:/model/coordinates</DataItem>\n</Geometry>"
        );
        for f in fields {
            let _ = writeln!(
                x,
                "<Attribute Name=\"{}\" AttributeType=\"Vector\" Center=\"Node\">\n<DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5_name}:{}</DataItem>\n</Attribute>",
                f.label, f.dataset
            );
        }
        x += "</Grid>\n";
    }
    x += "</Grid>\n";
    // Surfaces (contact interfaces, loaded faces) as their own grids.
    let surfaces: Vec<(&String, usize, usize)> = mesh
        .surfaces
        .iter()
        .filter_map(|(name, faces)| {
            crate::io::results::surface_corners(mesh, faces)
                .map(|c| (name, faces.len(), c.len() / faces.len().max(1)))
        })
        .collect();
    if !surfaces.is_empty() {
        x += "<Grid Name=\"surfaces\" GridType=\"Collection\" CollectionType=\"Spatial\">\n";
        for (name, nf, width) in surfaces {
            let topology = if width == 4 {
                "Quadrilateral"
            } else {
                "Triangle"
            };
            let _ = writeln!(
                x,
                "<Grid Name=\"{name}\" GridType=\"Uniform\">\n<Topology TopologyType=\"{topology}\" NumberOfElements=\"{nf}\">\n<DataItem Dimensions=\"{nf} {width}\" NumberType=\"UInt\" Precision=\"8\" Format=\"HDF\">{h5_name}:/model/surfaces/{name}/connectivity</DataItem>\n</Topology>\n<Geometry GeometryType=\"XYZ\">\n<DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5_name}:/model/coordinates</DataItem>\n</Geometry>\n</Grid>"
            );
        }
        x += "</Grid>\n";
    }
    x += "</Domain>\n</Xdmf>\n";
    std::fs::write(path, x)
}
