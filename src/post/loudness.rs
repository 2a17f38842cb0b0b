//! How loud (DESIGN.md §2c): the equivalent radiated power (ERP) of a vibrating surface, its
//! sound power level, the IEC 61672 A-weighting, 1/3-octave bands, and the sound pressure at a
//! microphone by the Rayleigh integral (each face taken as baffled). Arrays in, numbers out:
//! the surface is given as quadrature points with their normal, area weight and the nodes and
//! shape values that interpolate a nodal field there; sums are this rank's part (the caller
//! sums over ranks).

use std::collections::BTreeMap;
use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use crate::contact::surface::{dot, Face};
use crate::invalid::InvalidSetting;
use crate::mesh::Mesh;

/// Reference sound power (W) of a power level in dB.
pub const POWER_REFERENCE: f64 = 1e-12;
/// Reference sound pressure (Pa, rms) of a pressure level in dB.
pub const PRESSURE_REFERENCE: f64 = 20e-6;

/// A complex number (re, im).
pub type Complex = (f64, f64);

/// The fluid the surface radiates into.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Air {
    /// kg/m^3
    #[serde(default = "default_density")]
    pub density: f64,
    /// m/s
    #[serde(default = "default_sound_speed")]
    pub sound_speed: f64,
}

fn default_density() -> f64 {
    1.204
}

fn default_sound_speed() -> f64 {
    343.0
}

impl Default for Air {
    fn default() -> Self {
        Air {
            density: default_density(),
            sound_speed: default_sound_speed(),
        }
    }
}

impl Air {
    /// rho0 c0 (Pa s/m): the radiation impedance per area of a plane wave.
    pub fn impedance(&self) -> f64 {
        self.density * self.sound_speed
    }
}

/// The `[post.loudness]` table of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoudnessSettings {
    /// Components (mesh blocks) whose exterior faces radiate; default the disc and the pads'
    /// backplates, those of them the model has.
    #[serde(default)]
    pub components: Option<Vec<String>>,
    /// Air density (kg/m^3) and sound speed (m/s).
    #[serde(default = "default_density")]
    pub density: f64,
    #[serde(default = "default_sound_speed")]
    pub sound_speed: f64,
    /// Microphones by name, positions in m: the sound pressure there by the Rayleigh
    /// integral (every face taken as baffled). Optional: each costs one pass over the points
    /// per mode.
    #[serde(default)]
    pub microphones: BTreeMap<String, [f64; 3]>,
    /// Gauss points per direction on each face.
    #[serde(default = "default_quadrature")]
    pub quadrature: usize,
    /// Periods of the run's vibration at its end over which the transient's level and bands
    /// are taken.
    #[serde(default = "default_cycles")]
    pub cycles: usize,
}

fn default_quadrature() -> usize {
    2
}

fn default_cycles() -> usize {
    10
}

impl Default for LoudnessSettings {
    fn default() -> Self {
        toml::from_str("").expect("the defaults parse")
    }
}

impl LoudnessSettings {
    pub fn air(&self) -> Air {
        Air {
            density: self.density,
            sound_speed: self.sound_speed,
        }
    }

    pub fn validate(&self) -> Result<(), InvalidSetting> {
        let key = "post.loudness";
        for (name, v) in [("density", self.density), ("sound_speed", self.sound_speed)] {
            if !(v.is_finite() && v > 0.0) {
                let detail = format!(" = {v}: must be positive and finite");
                return Err(InvalidSetting::new(format!("{key}.{name}"), detail));
            }
        }
        if !(1..=4).contains(&self.quadrature) {
            let detail = format!(" = {}: 1 to 4 Gauss points per direction", self.quadrature);
            return Err(InvalidSetting::new(format!("{key}.quadrature"), detail));
        }
        if self.cycles == 0 {
            return Err(InvalidSetting::new(
                format!("{key}.cycles"),
                " = 0: at least 1",
            ));
        }
        for (name, p) in &self.microphones {
            if p.iter().any(|x| !x.is_finite()) {
                let detail = ": a position is three finite coordinates (m)";
                return Err(InvalidSetting::new(
                    format!("{key}.microphones.{name}"),
                    detail,
                ));
            }
        }
        if let Some(c) = &self.components {
            if c.is_empty() {
                let detail = " = []: name at least one component, or leave the key out";
                return Err(InvalidSetting::new(format!("{key}.components"), detail));
            }
        }
        Ok(())
    }
}

/// A quadrature point of a radiating surface.
#[derive(Debug, Clone)]
pub struct RadiatingPoint {
    pub position: [f64; 3],
    /// Unit outward normal.
    pub normal: [f64; 3],
    /// Quadrature weight times the area Jacobian (m^2).
    pub weight: f64,
    /// The face's nodes and their shape values at the point.
    pub nodes: Vec<usize>,
    pub shape: Vec<f64>,
}

impl RadiatingPoint {
    /// Distance (m) from the point to `at`.
    pub fn distance_to(&self, at: [f64; 3]) -> f64 {
        let r = [
            at[0] - self.position[0],
            at[1] - self.position[1],
            at[2] - self.position[2],
        ];
        dot(r, r).sqrt()
    }
}

/// The faces of the elements of `blocks` that no other element of those blocks shares: the
/// outside of those components (element, face 1-based), in element order.
pub fn exterior_faces(mesh: &Mesh, blocks: &[usize]) -> Vec<(usize, u8)> {
    let mut faces = mesh.face_keys(|b| blocks.contains(&b));
    faces.sort();
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j == i + 1 {
            out.push(faces[i].1);
        }
        i = j;
    }
    out.sort_unstable();
    out
}

/// The quadrature points of `faces` (`order` Gauss points per direction; 3 integrates the
/// area of quadratic faces and the square of a bilinear velocity exactly).
pub fn radiating_points(mesh: &Mesh, faces: &[(usize, u8)], order: usize) -> Vec<RadiatingPoint> {
    let mut out = Vec::new();
    for &(element, face) in faces {
        let f = Face::new(mesh, element, face);
        for (xi, w) in f.shape.rule(order) {
            let p = f.at(xi);
            let (normal, jacobian) = p.normal();
            out.push(RadiatingPoint {
                position: p.x,
                normal,
                weight: w * jacobian,
                nodes: f.nodes.clone(),
                shape: p.n.clone(),
            });
        }
    }
    out
}

/// The normal velocity at each point from a nodal velocity field.
pub fn normal_velocity(
    points: &[RadiatingPoint],
    velocity: impl Fn(usize) -> [f64; 3],
) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            let mut v = [0.0; 3];
            for (&node, &n) in p.nodes.iter().zip(&p.shape) {
                let u = velocity(node);
                for d in 0..3 {
                    v[d] += n * u[d];
                }
            }
            dot(v, p.normal)
        })
        .collect()
}

/// ERP of a harmonic vibration with complex normal-velocity amplitudes `vn` at points of
/// area weights `weights`: rho0 c0 sum A |v|^2 / 2 (W; this rank's part).
pub fn erp_harmonic(air: &Air, weights: &[f64], vn: &[Complex]) -> f64 {
    let sum: f64 = weights
        .iter()
        .zip(vn)
        .map(|(w, v)| w * (v.0 * v.0 + v.1 * v.1))
        .sum();
    0.5 * air.impedance() * sum
}

/// Instantaneous ERP of real normal velocities: rho0 c0 sum A v^2 (W; this rank's part).
pub fn erp_instant(air: &Air, weights: &[f64], vn: &[f64]) -> f64 {
    air.impedance() * weights.iter().zip(vn).map(|(w, v)| w * v * v).sum::<f64>()
}

/// Sound power level (dB re 1 pW); -inf for no power, NaN for NaN.
pub fn power_level(watts: f64) -> f64 {
    10.0 * (watts / POWER_REFERENCE).log10()
}

/// Sound pressure level (dB re 20 uPa) of a harmonic pressure of amplitude |p| (Pa).
pub fn pressure_level(amplitude: f64) -> f64 {
    20.0 * (amplitude / 2f64.sqrt() / PRESSURE_REFERENCE).log10()
}

/// The A-weighting of IEC 61672-1 (dB) at frequency `f` (Hz): 0 at 1 kHz.
pub fn a_weighting(f: f64) -> f64 {
    let f2 = f * f;
    let (a, b, c, d) = (20.598997f64, 107.65265f64, 737.86223f64, 12194.217f64);
    let r = d * d * f2 * f2 / ((f2 + a * a) * ((f2 + b * b) * (f2 + c * c)).sqrt() * (f2 + d * d));
    20.0 * r.log10() + 2.0
}

/// Sound pressure (complex amplitude, Pa) at `at` of the harmonic normal velocities `vn`
/// (m/s) at angular frequency `omega`, each face radiating as if baffled (Rayleigh):
/// p = (i omega rho0 / 2 pi) sum A v exp(-i k R) / R, k = omega / c0 (this rank's part).
pub fn rayleigh_pressure(
    air: &Air,
    points: &[RadiatingPoint],
    vn: &[Complex],
    omega: f64,
    at: [f64; 3],
) -> Complex {
    let k = omega / air.sound_speed;
    let (mut re, mut im) = (0.0, 0.0);
    for (p, v) in points.iter().zip(vn) {
        let distance = p.distance_to(at);
        let (c, s) = ((k * distance).cos(), -(k * distance).sin());
        // v exp(-ikR) / R, times the weight.
        let g = p.weight / distance;
        re += g * (v.0 * c - v.1 * s);
        im += g * (v.0 * s + v.1 * c);
    }
    // Times i omega rho0 / (2 pi): i (re + i im) = -im + i re.
    let f = omega * air.density / (2.0 * PI);
    (-f * im, f * re)
}

/// A 1/3-octave band (base-10 system of IEC 61260): its nominal label and exact edges (Hz).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    pub nominal: f64,
    pub lower: f64,
    pub centre: f64,
    pub upper: f64,
}

/// The nominal labels of the bands from 20 Hz to 20 kHz.
const NOMINAL: [f64; 31] = [
    20.0, 25.0, 31.5, 40.0, 50.0, 63.0, 80.0, 100.0, 125.0, 160.0, 200.0, 250.0, 315.0, 400.0,
    500.0, 630.0, 800.0, 1000.0, 1250.0, 1600.0, 2000.0, 2500.0, 3150.0, 4000.0, 5000.0, 6300.0,
    8000.0, 10000.0, 12500.0, 16000.0, 20000.0,
];

/// The 1/3-octave bands of 20 Hz to 20 kHz: centres 1000 x 10^(x/10), edges at 10^(+-1/20).
pub fn third_octave_bands() -> Vec<Band> {
    let edge = 10f64.powf(1.0 / 20.0);
    (-17i32..=13)
        .map(|x| {
            let centre = 1000.0 * 10f64.powf(x as f64 / 10.0);
            Band {
                nominal: NOMINAL[(x + 17) as usize],
                lower: centre / edge,
                centre,
                upper: centre * edge,
            }
        })
        .collect()
}

/// The mean radiated power of each 1/3-octave band from the normal velocities at points
/// (`series[j]`: point j's samples, every `dt` seconds): rho0 c0 sum A_j times the band's share
/// of the mean square of v_j (one-sided periodogram, Parseval). This rank's part.
pub fn band_powers(air: &Air, weights: &[f64], series: &[Vec<f64>], dt: f64) -> Vec<(Band, f64)> {
    let bands = third_octave_bands();
    let mut power = vec![0.0; bands.len()];
    for (w, v) in weights.iter().zip(series) {
        let n = v.len();
        if n < 2 {
            continue;
        }
        let spectrum = super::spectrum::power_spectrum(v);
        let df = 1.0 / (n as f64 * dt);
        for (k, s) in spectrum.iter().enumerate().skip(1) {
            // Mean square of the one-sided bin k: 2 |X_k|^2 / n^2 (the Nyquist bin once).
            let twice = if 2 * k == n { 1.0 } else { 2.0 };
            let mean_square = twice * s / (n as f64 * n as f64);
            let f = k as f64 * df;
            if let Some(b) = bands.iter().position(|b| f >= b.lower && f < b.upper) {
                power[b] += air.impedance() * w * mean_square;
            }
        }
    }
    bands.into_iter().zip(power).collect()
}

/// The sound pressure at `at` over time from normal velocities sampled every `dt` (one series
/// per point), by the Rayleigh integral in the time domain, each face baffled:
/// p(t) = sum rho0 A / (2 pi R) dv_n/dt (t - R / c0). Accelerations by central differences,
/// retarded values by linear interpolation; the samples from index `first` on (every rank
/// passes the same `first`, at least the largest delay over all points in samples plus 2).
/// This rank's part.
pub fn pressure_series(
    air: &Air,
    points: &[RadiatingPoint],
    series: &[Vec<f64>],
    dt: f64,
    at: [f64; 3],
    first: usize,
) -> Vec<f64> {
    let n = series.first().map_or(0, Vec::len);
    let mut p = vec![0.0; n.saturating_sub(first + 1)];
    for (point, v) in points.iter().zip(series) {
        let distance = point.distance_to(at);
        let gain = air.density * point.weight / (2.0 * PI * distance);
        let delay = distance / air.sound_speed / dt;
        let acceleration = |i: usize| (v[i + 1] - v[i - 1]) / (2.0 * dt);
        for (m, out) in p.iter_mut().enumerate() {
            let t = (first + m) as f64 - delay;
            let i = t.floor() as usize;
            let frac = t - i as f64;
            if i >= 1 && i + 2 < n {
                *out += gain * ((1.0 - frac) * acceleration(i) + frac * acceleration(i + 1));
            }
        }
    }
    p
}

/// The level (dB re 20 uPa) of pressure samples every `dt`, and A-weighted (the one-sided
/// spectrum of the samples weighted per bin; Parseval keeps the plain mean square).
pub fn series_levels(p: &[f64], dt: f64) -> (f64, f64) {
    let n = p.len();
    let level = |ms: f64| 10.0 * (ms / (PRESSURE_REFERENCE * PRESSURE_REFERENCE)).log10();
    if n < 2 {
        return (f64::NAN, f64::NAN);
    }
    let mean = p.iter().sum::<f64>() / n as f64;
    let centred: Vec<f64> = p.iter().map(|x| x - mean).collect();
    let plain = centred.iter().map(|x| x * x).sum::<f64>() / n as f64;
    let spectrum = super::spectrum::power_spectrum(&centred);
    let mut weighted = 0.0;
    for (k, s) in spectrum.iter().enumerate().skip(1) {
        let twice = if 2 * k == n { 1.0 } else { 2.0 };
        let f = k as f64 / (n as f64 * dt);
        weighted += twice * s / (n as f64 * n as f64) * 10f64.powf(a_weighting(f) / 10.0);
    }
    (level(plain), level(weighted))
}
