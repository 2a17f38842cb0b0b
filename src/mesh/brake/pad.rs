//! A brake pad: friction lining on a steel backplate, one conforming mesh (they share the
//! nodes of their bond face). Both are annular sectors centred on theta = 0; the backplate is
//! wider by a radial margin and by its ears, whose end faces lean on the anchor's abutments.
//!
//! ```text
//!   theta ->   ear |          lining           | ear
//!             _____|___________________________|_____   backplate (steel)
//!                  |___________________________|        lining (friction material)
//!   ===================================================  disc friction face
//! ```

use super::grid::{Axis, CellFace, Frame, Grid, GridMesh};
use super::{cells, BrakeGeometry, Selector, Side};
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

const R_LINING: usize = 1;
const T_LINING: usize = 1;

/// Coarse z segments (lining, backplate) of a side, ordered along z.
fn z_layout(g: &BrakeGeometry, side: Side) -> ([f64; 3], usize, usize) {
    let face = g.disc_thickness / 2.0;
    let bond = face + g.lining_thickness;
    let back = bond + g.backplate_thickness;
    match side {
        Side::Outer => ([face, bond, back], 0, 1),
        Side::Inner => ([-back, -bond, -face], 1, 0),
    }
}

pub fn grid(g: &BrakeGeometry, side: Side, h: f64) -> (Grid, Selector) {
    let half = g.pad_arc_deg.to_radians() / 2.0;
    let ear = half + g.ear_deg.to_radians();
    let r = [
        g.pad_inner_radius - g.backplate_margin,
        g.pad_inner_radius,
        g.pad_outer_radius,
        g.pad_outer_radius + g.backplate_margin,
    ];
    let mean = 0.5 * (g.pad_inner_radius + g.pad_outer_radius);
    let theta = [-ear, -half, half, ear];
    let (z, z_lining, z_backplate) = z_layout(g, side);
    let mut z_cells = [0; 2];
    // Finer through the lining, where the contact pressure varies.
    z_cells[z_lining] = cells(g.lining_thickness, h / 2.0, 2);
    z_cells[z_backplate] = cells(g.backplate_thickness, h, 1);
    let grid = Grid {
        axes: [
            Axis::sized(&r, h, 1.0),
            Axis::sized(&theta, h, mean),
            Axis::new(&z, &z_cells),
        ],
        frame: Frame::Cylindrical { center: [0.0, 0.0] },
    };
    let select = move |c: [usize; 3]| -> Option<usize> {
        let [ri, ti, zi] = c;
        if zi == z_backplate {
            Some(1)
        } else if ri == R_LINING && ti == T_LINING {
            Some(0)
        } else {
            None
        }
    };
    (grid, Box::new(select))
}

/// Blocks `<side>_lining`, `<side>_backplate`; surfaces `<side>_lining_friction` (facing the
/// disc), `<side>_backplate_back` (facing piston or fingers), `<side>_backplate_ears` (the
/// end and radial faces of the ears, on the anchor's abutments and rails); node sets of the last two.
pub fn mesh(
    g: &BrakeGeometry,
    side: Side,
    lining: &Material,
    backplate: &Material,
    h: f64,
    kind: ElementKind,
) -> GridMesh {
    let (grid, select) = grid(g, side, h);
    let s = side.name();
    let mut m = grid.mesh(
        kind,
        &[
            (&format!("{s}_lining"), lining.clone()),
            (&format!("{s}_backplate"), backplate.clone()),
        ],
        &select,
    );
    let (_, z_lining, z_backplate) = z_layout(g, side);
    // Towards the disc: -z for the outer pad, +z for the inner one.
    let towards_disc = CellFace {
        axis: 2,
        positive: side == Side::Inner,
    };
    let away = CellFace {
        axis: 2,
        positive: side == Side::Outer,
    };
    m.add_surface(&format!("{s}_lining_friction"), |c, f| {
        c[2] == z_lining && f == towards_disc
    });
    m.add_surface(&format!("{s}_backplate_back"), |c, f| {
        c[2] == z_backplate && f == away
    });
    // End faces and the radial faces of the ears (on the anchor's rails).
    m.add_surface(&format!("{s}_backplate_ears"), |c, f| {
        c[2] == z_backplate && (f.axis == 1 || (c[1] != T_LINING && f.axis == 0))
    });
    m.add_node_set_of_surface(
        &format!("{s}_backplate_back"),
        &format!("{s}_backplate_back"),
    );
    m.add_node_set_of_surface(
        &format!("{s}_backplate_ears"),
        &format!("{s}_backplate_ears"),
    );
    m
}

/// Exact volumes (lining, backplate) of one pad.
pub fn volumes(g: &BrakeGeometry) -> (f64, f64) {
    let sector = |r0: f64, r1: f64, angle: f64, dz: f64| 0.5 * angle * (r1 * r1 - r0 * r0) * dz;
    let arc = g.pad_arc_deg.to_radians();
    let lining = sector(
        g.pad_inner_radius,
        g.pad_outer_radius,
        arc,
        g.lining_thickness,
    );
    let backplate = sector(
        g.pad_inner_radius - g.backplate_margin,
        g.pad_outer_radius + g.backplate_margin,
        arc + 2.0 * g.ear_deg.to_radians(),
        g.backplate_thickness,
    );
    (lining, backplate)
}
