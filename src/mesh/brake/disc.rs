//! The disc: a solid friction ring joined by a cylindrical hat wall to a flange bolted to the
//! hub, revolved about z. The hat is on the outboard (+z) side.
//!
//! ```text
//!   z ^        flange  ___________
//!     |  bolt circle  |___|___|__| |  hat wall
//!     |                          | |
//!     |                          |_|_________________________  +t/2  friction face (outer)
//!     |                          |    friction ring          |
//!     |                          |___________________________|  -t/2  friction face (inner)
//!     +----------------------------------------------------------> r
//!      bore radius                hat radius          outer radius
//! ```

use std::f64::consts::TAU;

use super::grid::{Axis, CellFace, Frame, Grading, Grid, GridMesh};
use super::{cells, BrakeGeometry, Selector};
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

/// Radial half-width of the clamped annulus around the bolt circle (the hub's face).
pub const BOLT_HALF_WIDTH: f64 = 0.006;

// Coarse segments.
const R_BOLT: usize = 1;
const R_WALL: usize = 3;
const R_RING: usize = 4;
const Z_RING: usize = 0;
const Z_WALL: usize = 1;
const Z_FLANGE: usize = 2;

pub fn grid(g: &BrakeGeometry, h: f64) -> (Grid, Selector) {
    let t = g.disc_thickness;
    let wall_in = g.hat_radius - g.hat_wall;
    let r = [
        g.center_bore_radius,
        g.bolt_circle_radius - BOLT_HALF_WIDTH,
        g.bolt_circle_radius + BOLT_HALF_WIDTH,
        wall_in,
        g.hat_radius,
        g.disc_outer_radius,
    ];
    let z = [
        -t / 2.0,
        t / 2.0,
        t / 2.0 + g.hat_height - g.hat_flange,
        t / 2.0 + g.hat_height,
    ];
    let r_cells: Vec<usize> = r.windows(2).map(|w| cells(w[1] - w[0], h, 1)).collect();
    // Through the ring: finer than elsewhere and graded towards both friction faces.
    let nz_ring = cells(t, h / 1.5, 2);
    let z_cells = [nz_ring, cells(z[2] - z[1], h, 1), cells(g.hat_flange, h, 1)];
    let ring_mean = 0.5 * (g.hat_radius + g.disc_outer_radius);
    let n_theta = cells(TAU * ring_mean, h, 36);
    let mut z_axis = Axis::new(&z, &z_cells);
    if nz_ring >= 4 {
        z_axis = z_axis.graded(Z_RING, Grading::Ends(2.0));
    }
    let grid = Grid {
        axes: [
            Axis::new(&r, &r_cells),
            Axis::new(&[0.0, TAU], &[n_theta]).periodic(),
            z_axis,
        ],
        frame: Frame::Cylindrical { center: [0.0, 0.0] },
    };
    let select = |c: [usize; 3]| -> Option<usize> {
        let [ri, _, zi] = c;
        let on = match zi {
            Z_RING => ri >= R_WALL,
            Z_WALL => ri == R_WALL,
            _ => ri <= R_WALL,
        };
        on.then_some(0)
    };
    (grid, Box::new(select))
}

/// Surfaces `disc_friction_inner`, `disc_friction_outer` (the two friction faces of the ring)
/// and `disc_hub_face` (the flange face on the hub, around the bolt circle), node set
/// `disc_bolts` (clamped).
pub fn mesh(g: &BrakeGeometry, material: &Material, h: f64, kind: ElementKind) -> GridMesh {
    let (grid, select) = grid(g, h);
    let mut m = grid.mesh(kind, &[("disc", material.clone())], &select);
    let down = CellFace {
        axis: 2,
        positive: false,
    };
    let up = CellFace {
        axis: 2,
        positive: true,
    };
    m.add_surface("disc_friction_inner", |c, f| c[2] == Z_RING && f == down);
    m.add_surface("disc_friction_outer", |c, f| {
        c[2] == Z_RING && c[0] == R_RING && f == up
    });
    m.add_surface("disc_hub_face", |c, f| {
        c[2] == Z_FLANGE && c[0] == R_BOLT && f == up
    });
    m.add_node_set_of_surface("disc_bolts", "disc_hub_face");
    m
}

/// Exact volume of the disc (revolved profile).
pub fn volume(g: &BrakeGeometry) -> f64 {
    let ring = |r0: f64, r1: f64, dz: f64| std::f64::consts::PI * (r1 * r1 - r0 * r0) * dz;
    let wall_in = g.hat_radius - g.hat_wall;
    ring(wall_in, g.disc_outer_radius, g.disc_thickness)
        + ring(wall_in, g.hat_radius, g.hat_height - g.hat_flange)
        + ring(g.center_bore_radius, g.hat_radius, g.hat_flange)
}
