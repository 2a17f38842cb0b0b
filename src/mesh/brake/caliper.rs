//! The floating caliper housing: the bore around the piston on the inboard side, a bridge
//! over the disc's rim, and two fingers on the outer backplate. Revolved about the disc axis
//! (its faces are cylinders and planes of the disc's frame), guided by two pin bosses whose end
//! faces slide along z on the anchor's pins.
//!
//! ```text
//!                 bridge
//!       _________________________________
//!      |  _____________________________  |   z ->
//!      | |                             | |__
//!      | |   bore    | piston | pad |d| pad |  fingers
//!      |_|___________|________|_____|_|_____|
//!   housing back
//! ```

use super::grid::{revolved_volume, Axis, CellFace, Frame, Grid, GridMesh};
use super::{piston, BrakeGeometry, Selector};
use crate::mesh::material::Material;
use crate::mesh::ElementKind;

/// Radial clearance between piston and bore.
pub const BORE_CLEARANCE: f64 = 0.002;
/// Gap between the housing front and the inner backplate.
const FRONT_GAP: f64 = 0.003;
/// Fluid gap between the piston bottom and the bore bottom.
const FLUID_GAP: f64 = 0.001;
/// Angular extent of each pin boss beyond the backplate ears.
const PIN_BOSS_DEG: f64 = 2.5;

// Coarse segments: r (housing wall, bore/finger root, finger, rim gap, bridge), theta (boss,
// finger, bore side, centre, bore side, finger, boss), z (housing back, bore, span, fingers).
const R_BRIDGE: usize = 4;
const Z_BACK: usize = 0;
const Z_BORE: usize = 1;
const Z_SPAN: usize = 2;
const Z_FINGERS: usize = 3;

/// Coarse breaks (r, theta, z) of the caliper.
pub fn breaks(g: &BrakeGeometry) -> ([f64; 6], [f64; 8], [f64; 5]) {
    let [cx, _] = piston::center(g);
    let rp = g.piston_diameter / 2.0 + BORE_CLEARANCE;
    let bore_r0 = cx - rp;
    let bore_r1 = cx + rp;
    let bridge_r0 = g.disc_outer_radius + g.caliper_clearance;
    let r = [
        bore_r0 - g.caliper_wall,
        bore_r0,
        g.pad_inner_radius + g.caliper_wall,
        bore_r1,
        bridge_r0,
        bridge_r0 + g.caliper_wall,
    ];
    let half = g.pad_arc_deg.to_radians() / 2.0;
    let ear = half + g.ear_deg.to_radians();
    let span = 0.9 * half;
    let bore_t = (rp / cx).asin();
    let finger_gap = 0.4 * bore_t;
    let pin = ear + PIN_BOSS_DEG.to_radians();
    let theta = [
        -pin,
        -span,
        -bore_t,
        -finger_gap,
        finger_gap,
        bore_t,
        span,
        pin,
    ];
    let back = g.disc_thickness / 2.0 + g.lining_thickness + g.backplate_thickness;
    let (piston_bottom, _) = piston::z_range(g);
    let bore_bottom = piston_bottom - FLUID_GAP;
    let z = [
        bore_bottom - g.caliper_wall,
        bore_bottom,
        -back - FRONT_GAP,
        back,
        back + g.caliper_wall,
    ];
    (r, theta, z)
}

fn selector() -> Selector {
    Box::new(|c: [usize; 3]| -> Option<usize> {
        let [ri, ti, zi] = c;
        let boss = ti == 0 || ti == 6;
        let bore = (1..=2).contains(&ri) && (2..=4).contains(&ti);
        let finger = (2..=4).contains(&ri) && matches!(ti, 1 | 2 | 4 | 5);
        let on = match zi {
            Z_BACK => !boss || ri >= 3,
            Z_BORE => !boss && !bore,
            Z_SPAN => !boss && ri == R_BRIDGE,
            _ => finger,
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

/// Surfaces `caliper_fingers` (on the outer backplate), `caliper_bore` (bore bottom: the
/// hydraulic reaction), `caliper_pin_faces` (end faces of the pin bosses); node set
/// `caliper_pins` (the sliding constraint holds x and y there, z is free).
pub fn mesh(g: &BrakeGeometry, material: &Material, h: f64, kind: ElementKind) -> GridMesh {
    let (grid, select) = grid(g, h);
    let mut m = grid.mesh(kind, &[("caliper", material.clone())], &select);
    m.add_surface("caliper_fingers", |c, f| {
        c[2] == Z_FINGERS
            && c[0] == 2
            && f == CellFace {
                axis: 2,
                positive: false,
            }
    });
    m.add_surface("caliper_bore", |c, f| {
        c[2] == Z_BACK
            && (1..=2).contains(&c[0])
            && (2..=4).contains(&c[1])
            && f == CellFace {
                axis: 2,
                positive: true,
            }
    });
    m.add_surface("caliper_pin_faces", |c, f| {
        (c[1] == 0 || c[1] == 6) && f.axis == 1
    });
    m.add_node_set_of_surface("caliper_pins", "caliper_pin_faces");
    m
}

/// Exact volume: the sum of the revolved coarse cells.
pub fn volume(g: &BrakeGeometry) -> f64 {
    let (r, theta, z) = breaks(g);
    revolved_volume(&r, &theta, &z, &*selector())
}
