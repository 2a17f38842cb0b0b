//! Loudness (DESIGN.md §2c) against closed forms, without MPI.
//!
//! References:
//! - IEC 61672-1:2013, Table 3 (A-weighting): 100 Hz -19.1 dB, 1 kHz 0.0 dB, 4 kHz +1.0 dB,
//!   10 kHz -2.5 dB, to the table's 0.1 dB.
//! - A rigid plate translating along its normal with velocity amplitude v radiates (with
//!   radiation efficiency 1) the ERP rho0 c0 S v^2 / 2: exact for any mesh of the plate, since
//!   the faces' quadrature integrates their area and a constant exactly.
//! - Baffled circular piston of radius a, velocity amplitude v, on its axis (Kinsler, Frey,
//!   Coppens & Sanders, Fundamentals of Acoustics, 4th ed., eq. 7.4.4):
//!   |p(z)| = 2 rho0 c0 v |sin(k (sqrt(z^2 + a^2) - z) / 2)|.
//! - Its radiated power (same book, eq. 7.5.11): P = rho0 c0 pi a^2 v^2 / 2 (1 - J1(2ka)/(ka)),
//!   with J1 from Abramowitz & Stegun, Handbook of Mathematical Functions, Table 9.1:
//!   J1(1) = 0.4400505857, J1(4) = -0.0660433280, J1(20) = 0.0668331242.

use std::f64::consts::PI;

use squeal::mesh::material::Material;
use squeal::mesh::structured::block;
use squeal::mesh::ElementKind;
use squeal::post::loudness::{
    a_weighting, erp_harmonic, exterior_faces, normal_velocity, power_level, radiating_points,
    rayleigh_pressure, third_octave_bands, Air, RadiatingPoint,
};

#[test]
fn a_weighting_matches_the_iec_61672_table() {
    for (f, table) in [
        (100.0, -19.1),
        (1000.0, 0.0),
        (4000.0, 1.0),
        (10000.0, -2.5),
    ] {
        let a = a_weighting(f);
        assert!(
            (a - table).abs() <= 0.05,
            "A({f} Hz) = {a:.3} dB, table {table}"
        );
    }
    assert!(a_weighting(f64::NAN).is_nan());
}

#[test]
fn third_octave_bands_tile_20_hz_to_20_khz() {
    let bands = third_octave_bands();
    assert_eq!(bands.len(), 31);
    assert_eq!(bands[17].nominal, 1000.0);
    assert!((bands[17].centre - 1000.0).abs() < 1e-9);
    for w in bands.windows(2) {
        assert!((w[0].upper - w[1].lower).abs() < 1e-9 * w[1].lower);
        // Nominal labels round the exact centres to within 3 %.
        assert!((w[1].nominal / w[1].centre - 1.0).abs() < 0.03);
    }
}

/// The top faces (z = max) of a block mesh of `kind`, the in-plane nodes moved to distort
/// the elements (z untouched, so the plate stays flat), and their area.
fn plate(kind: ElementKind, distort: bool) -> (squeal::mesh::Mesh, Vec<(usize, u8)>, f64) {
    let (lx, ly, lz) = (0.3, 0.2, 0.01);
    let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0);
    let mut mesh = block([lx, ly, lz], [4, 3, 1], kind, steel);
    if distort {
        for x in &mut mesh.coords {
            // A smooth in-plane map that keeps the boundary (the plate's area stays lx * ly).
            let (u, v) = (x[0] / lx, x[1] / ly);
            x[0] += 0.02 * (PI * u).sin() * (PI * v).sin();
            x[1] += 0.015 * (2.0 * PI * u).sin() * (PI * v).sin();
        }
    }
    let all: Vec<usize> = (0..mesh.blocks.len()).collect();
    let top: Vec<(usize, u8)> = exterior_faces(&mesh, &all)
        .into_iter()
        .filter(|&(e, f)| {
            let nodes = mesh.face_nodes(e, f);
            nodes
                .iter()
                .all(|&n| (mesh.coords[n][2] - lz).abs() < 1e-12)
        })
        .collect();
    (mesh, top, lx * ly)
}

#[test]
fn rigid_plate_erp_is_rho_c_s_v2_over_2_for_any_mesh() {
    let air = Air::default();
    let v = 1e-3;
    for kind in [ElementKind::Hex8, ElementKind::Hex20] {
        for distort in [false, true] {
            let (mesh, top, area) = plate(kind, distort);
            assert_eq!(top.len(), 12, "{kind:?}: the top of a 4 x 3 plate");
            let points = radiating_points(&mesh, &top, 3);
            let vn = normal_velocity(&points, |_| [0.0, 0.0, v]);
            let harmonic: Vec<(f64, f64)> = vn.iter().map(|&x| (x, 0.0)).collect();
            let weights: Vec<f64> = points.iter().map(|p| p.weight).collect();
            let erp = erp_harmonic(&air, &weights, &harmonic);
            let exact = air.density * air.sound_speed * area * v * v / 2.0;
            let error = (erp - exact).abs() / exact;
            eprintln!("rigid plate {kind:?}, distorted {distort}: ERP relative error {error:.1e}");
            assert!(
                error <= 1e-12,
                "{kind:?} distorted {distort}: ERP {erp:e} W vs {exact:e} W (relative {error:e})"
            );
        }
    }
    let (mesh, top, _) = plate(ElementKind::Hex8, false);
    let points = radiating_points(&mesh, &top, 2);
    let vn = normal_velocity(&points, |_| [0.0, 0.0, f64::NAN]);
    let nan: Vec<(f64, f64)> = vn.iter().map(|&x| (x, 0.0)).collect();
    let weights: Vec<f64> = points.iter().map(|p| p.weight).collect();
    assert!(power_level(erp_harmonic(&Air::default(), &weights, &nan)).is_nan());
}

/// A disc of radius `a` in the plane z = 0 (normal +z) as `rings` x `sectors` polar cells,
/// each with an n x n Gauss rule in (r, theta): the integrand's quadrature on the exact
/// geometry, so the error is the rule's.
fn piston(a: f64, rings: usize, sectors: usize, n: usize) -> Vec<RadiatingPoint> {
    let (x, w) = gauss(n);
    let mut out = Vec::new();
    for i in 0..rings {
        let (r0, r1) = (
            a * i as f64 / rings as f64,
            a * (i + 1) as f64 / rings as f64,
        );
        for j in 0..sectors {
            let (t0, t1) = (
                2.0 * PI * j as f64 / sectors as f64,
                2.0 * PI * (j + 1) as f64 / sectors as f64,
            );
            for (xr, wr) in x.iter().zip(&w) {
                for (xt, wt) in x.iter().zip(&w) {
                    let r = 0.5 * (r0 + r1) + 0.5 * (r1 - r0) * xr;
                    let t = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * xt;
                    out.push(RadiatingPoint {
                        position: [r * t.cos(), r * t.sin(), 0.0],
                        normal: [0.0, 0.0, 1.0],
                        weight: wr * wt * 0.25 * (r1 - r0) * (t1 - t0) * r,
                        nodes: Vec::new(),
                        shape: Vec::new(),
                    });
                }
            }
        }
    }
    out
}

/// Gauss-Legendre points and weights on [-1, 1] (n = 2 or 3).
fn gauss(n: usize) -> (Vec<f64>, Vec<f64>) {
    match n {
        2 => (
            vec![-(1.0f64 / 3.0).sqrt(), (1.0f64 / 3.0).sqrt()],
            vec![1.0, 1.0],
        ),
        _ => (
            vec![-(0.6f64).sqrt(), 0.0, (0.6f64).sqrt()],
            vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0],
        ),
    }
}

#[test]
fn rayleigh_integral_reproduces_the_baffled_piston_on_its_axis() {
    let air = Air::default();
    let (a, v) = (0.05, 1e-3);
    for ka in [0.5, 2.0, 10.0] {
        let k = ka / a;
        let omega = k * air.sound_speed;
        let z = 2.0 * a;
        let exact = 2.0
            * air.density
            * air.sound_speed
            * v
            * (k * ((z * z + a * a).sqrt() - z) / 2.0).sin().abs();
        let error = |rings: usize| {
            let points = piston(a, rings, 4 * rings, 2);
            let vn = vec![(v, 0.0); points.len()];
            let p = rayleigh_pressure(&air, &points, &vn, omega, [0.0, 0.0, z]);
            (p.0.hypot(p.1) - exact).abs() / exact
        };
        let (coarse, fine) = (error(4), error(8));
        // A 2-point Gauss rule integrates to order 4 in the cell size: halving it divides the
        // error by ~16 once resolved; ka = 10 (3 wavelengths over the radius) is resolved
        // from 8 rings on.
        let rate = (coarse / fine).log2();
        eprintln!("piston ka = {ka}: |p| on the axis at z = 2a, error {coarse:.2e} (4 rings), {fine:.2e} (8 rings), rate {rate:.2}");
        assert!(fine < 1e-4, "ka = {ka}: |p| error {fine:e} with 8 rings");
        assert!(
            rate > 3.5 || fine < 1e-12,
            "ka = {ka}: convergence rate {rate:.2} (errors {coarse:e}, {fine:e})"
        );
    }
}

#[test]
fn piston_power_follows_its_radiation_resistance() {
    let air = Air::default();
    let (a, v) = (0.05, 1e-3);
    // J1(2 ka) from Abramowitz & Stegun, Table 9.1.
    for (ka, j1) in [
        (0.5, 0.4400505857),
        (2.0, -0.0660433280),
        (10.0, 0.0668331242),
    ] {
        let k: f64 = ka / a;
        let omega = k * air.sound_speed;
        let sigma = 1.0 - j1 / ka;
        let exact = air.density * air.sound_speed * PI * a * a * v * v / 2.0 * sigma;
        let points = piston(a, 16, 64, 3);
        let vn = vec![(v, 0.0); points.len()];
        // The power through a far hemisphere (r = 50 a, kr >= 12.5), |p|^2 / (2 rho0 c0)
        // integrated by Gauss in cos(theta) and the trapezoid rule in phi.
        let r = 50.0 * a;
        let (x, w) = gauss_many(48);
        let phis = 64;
        let mut power = 0.0;
        for (xc, wc) in x.iter().zip(&w) {
            let cos_t = 0.5 * (1.0 + xc);
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for m in 0..phis {
                let phi = 2.0 * PI * m as f64 / phis as f64;
                let at = [r * sin_t * phi.cos(), r * sin_t * phi.sin(), r * cos_t];
                let p = rayleigh_pressure(&air, &points, &vn, omega, at);
                let intensity = (p.0 * p.0 + p.1 * p.1) / (2.0 * air.density * air.sound_speed);
                power += intensity * r * r * 0.5 * wc * 2.0 * PI / phis as f64;
            }
        }
        let error = (power - exact).abs() / exact;
        eprintln!("piston ka = {ka}: power {power:.6e} W vs {exact:.6e} W (sigma {sigma:.4}), relative {error:.1e}");
        // Tolerance: the near-field part of |p|^2 / (2 rho0 c0) at finite kr, O((a / r)^2)
        // ~ 4e-4, and the hemisphere rule's error (negligible at 48 x 64 for ka <= 10).
        assert!(
            error < 2e-3,
            "ka = {ka}: P {power:e} W vs {exact:e} W (sigma {sigma:.4}), relative {error:e}"
        );
    }
}

/// Gauss-Legendre points and weights on [-1, 1] by Newton on P_n.
fn gauss_many(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        loop {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                x[i] = z;
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
    (x, w)
}
