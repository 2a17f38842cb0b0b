//! The piston: a steel cup whose open rim pushes on the inner backplate; its closed bottom
//! carries the hydraulic pressure. It sits centred on the pads' mean radius at theta = 0,
//! its axis parallel to z. The bottom has a small central vent hole (which also keeps the
//! revolved hexahedral mesh free of degenerate cells on the axis).

use std::f64::consts::{PI, TAU};

use super::grid::{Axis, CellFace, Frame, Grid, GridMesh};
use super::{cells, BrakeGeometry, Selector};
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

/// Radius of the vent hole in the piston bottom.
pub const VENT_RADIUS: f64 = 0.004;

const R_WALL: usize = 1;
const Z_BOTTOM: usize = 0;
const Z_WALL: usize = 1;

/// Centre (x, y) of the piston axis.
pub fn center(g: &BrakeGeometry) -> [f64; 2] {
    [0.5 * (g.pad_inner_radius + g.pad_outer_radius), 0.0]
}

/// z of the rim (on the inner backplate) and of the bottom face.
pub fn z_range(g: &BrakeGeometry) -> (f64, f64) {
    let rim = -(g.disc_thickness / 2.0 + g.lining_thickness + g.backplate_thickness);
    (rim - g.piston_length, rim)
}

pub fn grid(g: &BrakeGeometry, h: f64) -> (Grid, Selector) {
    let ro = g.piston_diameter / 2.0;
    let r = [VENT_RADIUS, ro - g.piston_wall, ro];
    let (z0, z1) = z_range(g);
    let z = [z0, z0 + g.piston_wall, z1];
    let grid = Grid {
        axes: [
            Axis::new(&r, &[cells(r[1] - r[0], h, 1), cells(g.piston_wall, h, 1)]),
            Axis::new(&[0.0, TAU], &[cells(TAU * ro, h, 16)]).periodic(),
            Axis::new(&z, &[cells(g.piston_wall, h, 1), cells(z[2] - z[1], h, 1)]),
        ],
        frame: Frame::Cylindrical { center: center(g) },
    };
    let select =
        |c: [usize; 3]| -> Option<usize> { (c[2] == Z_BOTTOM || c[0] == R_WALL).then_some(0) };
    (grid, Box::new(select))
}

/// Surfaces `piston_rim` (on the inner backplate) and `piston_bottom` (pressure).
pub fn mesh(g: &BrakeGeometry, material: &Material, h: f64, kind: ElementKind) -> GridMesh {
    let (grid, select) = grid(g, h);
    let mut m = grid.mesh(kind, &[("piston", material.clone())], &select);
    m.add_surface("piston_rim", |c, f| {
        c[2] == Z_WALL
            && f == CellFace {
                axis: 2,
                positive: true,
            }
    });
    m.add_surface("piston_bottom", |c, f| {
        c[2] == Z_BOTTOM
            && f == CellFace {
                axis: 2,
                positive: false,
            }
    });
    m
}

/// Hydraulic area of the bore: the pressure times this is the clamping force.
pub fn hydraulic_area(g: &BrakeGeometry) -> f64 {
    PI * (g.piston_diameter / 2.0).powi(2)
}

pub fn volume(g: &BrakeGeometry) -> f64 {
    let ro = g.piston_diameter / 2.0;
    let ri = ro - g.piston_wall;
    PI * (ro * ro - VENT_RADIUS * VENT_RADIUS) * g.piston_wall
        + PI * (ro * ro - ri * ri) * (g.piston_length - g.piston_wall)
}
