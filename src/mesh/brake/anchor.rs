//! The anchor bracket: bolted to the knuckle on the inboard side, two arms reach over the
//! disc's rim; their abutment faces hold the backplate ears of both pads against the drag, and
//! a U-shaped slot in each arm (a rail under and over each ear, as the abutment clips of real
//! calipers have) holds the ears radially. Without the rails only the friction of the end
//! faces holds the pad's in-plane rotation, and the static preload reaches a limit point near
//! mu = 0.29. Revolved about the disc axis.
//!
//! ```text
//!   theta ->  arm |        pads         | arm
//!             ====|====            =====|====  <- upper rail
//!   abutment  ->  |[ear]           [ear]|  <-  abutment     (both pad layers, z = +-back)
//!             ====|====            =====|====  <- lower rail
//!   mount bar  ===|=====================|===   (inboard, below the pads' inner radius)
//! ```

use super::grid::{revolved_volume, Axis, CellFace, Frame, Grid, GridMesh};
use super::{BrakeGeometry, Selector};
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

/// Angular width of each arm.
const ARM_DEG: f64 = 6.0;
/// Thickness of the mount bar (along z) and its radial height.
const MOUNT_THICKNESS: f64 = 0.0105;
const MOUNT_HEIGHT: f64 = 0.018;
/// Clearance of the arm bridge over the disc rim, and its radial thickness.
const RIM_CLEARANCE: f64 = 0.002;
const BRIDGE: f64 = 0.010;
/// Axial clearance of the arms to the disc faces.
const FACE_CLEARANCE: f64 = 0.002;

const R_MOUNT: usize = 0;
const R_LOWER_RAIL: usize = 1;
const R_ABUTMENT: usize = 2;
const R_UPPER_RAIL: usize = 3;
const R_BRIDGE: usize = 4;
/// Theta segments: arm, ear, centre (between the ears), ear, arm.
const T_CENTRE: usize = 2;
const Z_MOUNT: usize = 0;

fn is_ear(ti: usize) -> bool {
    ti == T_CENTRE - 1 || ti == T_CENTRE + 1
}

fn is_arm(ti: usize) -> bool {
    ti == 0 || ti == T_CENTRE + 2
}

fn is_pad_layer(zi: usize) -> bool {
    zi == 1 || zi == 5
}

pub fn breaks(g: &BrakeGeometry) -> ([f64; 6], [f64; 6], [f64; 7]) {
    let half = g.pad_arc_deg.to_radians() / 2.0;
    let ear = half + g.ear_deg.to_radians();
    let arm = ear + ARM_DEG.to_radians();
    // The mount bar stays radially inside the caliper housing.
    let (caliper_r, _, _) = super::caliper::breaks(g);
    let mount_top = caliper_r[0] - 0.002;
    let r = [
        mount_top - MOUNT_HEIGHT,
        mount_top,
        g.pad_inner_radius - g.backplate_margin,
        g.pad_outer_radius + g.backplate_margin,
        g.disc_outer_radius + RIM_CLEARANCE,
        g.disc_outer_radius + RIM_CLEARANCE + BRIDGE,
    ];
    let face = g.disc_thickness / 2.0;
    let bond = face + g.lining_thickness;
    let back = bond + g.backplate_thickness;
    let z = [
        -back - MOUNT_THICKNESS,
        -back,
        -bond,
        -face - FACE_CLEARANCE,
        face + FACE_CLEARANCE,
        bond,
        back,
    ];
    (r, [-arm, -ear, -half, half, ear, arm], z)
}

fn selector() -> Selector {
    Box::new(|c: [usize; 3]| -> Option<usize> {
        let [ri, ti, zi] = c;
        let on = if is_arm(ti) {
            match zi {
                Z_MOUNT => true,
                1 | 5 => ri >= R_LOWER_RAIL,
                _ => ri == R_BRIDGE,
            }
        } else if is_ear(ti) && is_pad_layer(zi) {
            ri == R_LOWER_RAIL || ri == R_UPPER_RAIL
        } else {
            zi == Z_MOUNT && ri == R_MOUNT
        };
        on.then_some(0)
    })
}

pub fn grid(g: &BrakeGeometry, h: f64) -> (Grid, Selector) {
    let (r, theta, z) = breaks(g);
    let r_mid = 0.5 * (r[0] + r[5]);
    let grid = Grid {
        axes: [
            Axis::sized(&r, h, 1.0),
            Axis::sized(&theta, h, r_mid),
            Axis::sized(&z, h, 1.0),
        ],
        frame: Frame::Cylindrical { center: [0.0, 0.0] },
    };
    (grid, selector())
}

/// Surfaces `anchor_abutments` (end faces and rail faces on the backplate ears) and
/// `anchor_mount` (bolt faces on the knuckle, under the arms); node set `anchor_bolts` (clamped).
pub fn mesh(g: &BrakeGeometry, material: &Material, h: f64, kind: ElementKind) -> GridMesh {
    let (grid, select) = grid(g, h);
    let mut m = grid.mesh(kind, &[("anchor", material.clone())], &select);
    m.add_surface("anchor_abutments", |c, f| {
        let [ri, ti, zi] = c;
        let end_face = is_arm(ti) && ri == R_ABUTMENT && f.axis == 1 && (ti == 0) == f.positive;
        let rail_face = is_ear(ti)
            && f.axis == 0
            && ((ri == R_LOWER_RAIL && f.positive) || (ri == R_UPPER_RAIL && !f.positive));
        is_pad_layer(zi) && (end_face || rail_face)
    });
    m.add_surface("anchor_mount", |c, f| {
        c[2] == Z_MOUNT
            && is_arm(c[1])
            && c[0] <= 1
            && f == CellFace {
                axis: 2,
                positive: false,
            }
    });
    m.add_node_set_of_surface("anchor_bolts", "anchor_mount");
    m
}

pub fn volume(g: &BrakeGeometry) -> f64 {
    let (r, theta, z) = breaks(g);
    revolved_volume(&r, &theta, &z, &*selector())
}
