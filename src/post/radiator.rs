//! The radiating surfaces of the loudness analysis (DESIGN.md §2c): the exterior faces of
//! the components a scene names, observed by a distributed normal-velocity matrix N (rows:
//! face quadrature points, split evenly over the ranks), their equivalent radiated power and
//! the Rayleigh pressure at microphones; and a complex mode's levels at a contact amplitude.

use super::loudness::{
    a_weighting, erp_harmonic, exterior_faces, power_level, pressure_level, radiating_points,
    rayleigh_pressure, LoudnessSettings, RadiatingPoint,
};
use crate::eigen::complex_modes::{expand, Complex};
use crate::fem::dofmap::DofMap;
use crate::invalid::InvalidSetting;
use crate::la::{LaError, ObservationMatrix, Petsc, Vector};
use crate::mesh::Mesh;

/// Why the radiating surfaces could not be built.
#[derive(Debug, thiserror::Error)]
pub enum RadiatorError {
    #[error(transparent)]
    Invalid(#[from] InvalidSetting),
    #[error(transparent)]
    La(#[from] LaError),
}

/// Contact amplitude of the per-amplitude levels (m): 1 um.
pub const UNIT_AMPLITUDE: f64 = 1e-6;

/// The radiating surfaces with this rank's share of their quadrature points.
pub struct Radiator<'p> {
    pub components: Vec<String>,
    /// Faces and quadrature points over all ranks, and the radiating area (m^2).
    pub faces: usize,
    pub points: usize,
    pub area: f64,
    /// This rank's points (rows of N).
    pub(crate) local: Vec<RadiatingPoint>,
    pub(crate) weights: Vec<f64>,
    normal: ObservationMatrix<'p>,
}

/// The radiating surfaces of `settings` on the mesh.
///
/// # Collective
pub fn radiator<'p>(
    petsc: &'p Petsc,
    mesh: &Mesh,
    dofs: &DofMap,
    settings: &LoudnessSettings,
) -> Result<Radiator<'p>, RadiatorError> {
    let names: Vec<String> = match &settings.components {
        Some(names) => names.clone(),
        None => ["disc", "inner_backplate", "outer_backplate"]
            .iter()
            .filter(|n| mesh.blocks.iter().any(|b| b.name == **n))
            .map(|n| n.to_string())
            .collect(),
    };
    let mut blocks = Vec::new();
    for name in &names {
        let found: Vec<usize> = (0..mesh.blocks.len())
            .filter(|&b| mesh.blocks[b].name == *name)
            .collect();
        if found.is_empty() {
            let have: Vec<&str> = mesh.blocks.iter().map(|b| b.name.as_str()).collect();
            let detail = format!(
                ": '{name}' is not a component of the model (it has: {})",
                have.join(", ")
            );
            return Err(InvalidSetting::new("post.loudness.components", detail).into());
        }
        blocks.extend(found);
    }
    if blocks.is_empty() {
        let detail = ": no radiating component (the model has no disc or backplate); name them";
        return Err(InvalidSetting::new("post.loudness.components", detail).into());
    }
    let faces = exterior_faces(mesh, &blocks);
    let all = radiating_points(mesh, &faces, settings.quadrature);
    let area = all.iter().map(|p| p.weight).sum();
    let (ranks, rank) = (petsc.size() as usize, petsc.rank() as usize);
    let first_of = |r: usize| r * all.len() / ranks;
    let (first, last) = (first_of(rank), first_of(rank + 1));
    let local: Vec<RadiatingPoint> = all[first..last].to_vec();
    let rows: Vec<Vec<(i32, f64)>> = local
        .iter()
        .map(|p| {
            let mut row = Vec::with_capacity(3 * p.nodes.len());
            for (&node, &n) in p.nodes.iter().zip(&p.shape) {
                for c in 0..3 {
                    row.push((dofs.node_dofs[node][c], n * p.normal[c]));
                }
            }
            row
        })
        .collect();
    let normal = ObservationMatrix::from_rows(petsc, first, &rows, dofs.owned_dofs())?;
    Ok(Radiator {
        components: names,
        faces: faces.len(),
        points: all.len(),
        area,
        weights: local.iter().map(|p| p.weight).collect(),
        local,
        normal,
    })
}

impl<'p> Radiator<'p> {
    /// The mean radiated power (W) of the harmonic vibration q(t) = x cos(omega t) of a real
    /// displacement shape `x` (full model).
    ///
    /// # Collective
    pub fn harmonic_power(
        &self,
        petsc: &Petsc,
        settings: &LoudnessSettings,
        x: &Vector<'p>,
        omega: f64,
    ) -> Result<f64, LaError> {
        let vn = self.harmonic_velocity(x, omega)?;
        Ok(self.power(petsc, settings, &vn))
    }

    /// The sound pressure amplitude (Pa) at `at` of the harmonic vibration q(t) = x cos(omega t)
    /// (Rayleigh integral).
    ///
    /// # Collective
    pub fn harmonic_pressure(
        &self,
        petsc: &Petsc,
        settings: &LoudnessSettings,
        x: &Vector<'p>,
        omega: f64,
        at: [f64; 3],
    ) -> Result<f64, LaError> {
        let vn = self.harmonic_velocity(x, omega)?;
        Ok(self.pressure(petsc, settings, &vn, omega, at))
    }

    /// The normal velocity amplitudes omega N x at this rank's points (real: in phase).
    ///
    /// # Collective
    fn harmonic_velocity(&self, x: &Vector<'p>, omega: f64) -> Result<Vec<(f64, f64)>, LaError> {
        let vn = self.normal_velocity(x)?;
        Ok(vn.iter().map(|v| (omega * v, 0.0)).collect())
    }

    /// The mean power (W) of complex normal-velocity amplitudes at this rank's points, summed
    /// over the ranks.
    ///
    /// # Collective
    fn power(&self, petsc: &Petsc, settings: &LoudnessSettings, vn: &[(f64, f64)]) -> f64 {
        let mut erp = [erp_harmonic(&settings.air(), &self.weights, vn)];
        crate::parallel::sum_in_place(petsc.world(), &mut erp);
        erp[0]
    }

    /// The pressure amplitude (Pa) at `at` of complex normal-velocity amplitudes at angular
    /// frequency omega (Rayleigh integral over every rank's points).
    ///
    /// # Collective
    fn pressure(
        &self,
        petsc: &Petsc,
        settings: &LoudnessSettings,
        vn: &[(f64, f64)],
        omega: f64,
        at: [f64; 3],
    ) -> f64 {
        let p = rayleigh_pressure(&settings.air(), &self.local, vn, omega, at);
        let mut sum = [p.0, p.1];
        crate::parallel::sum_in_place(petsc.world(), &mut sum);
        sum[0].hypot(sum[1])
    }

    /// N v: the normal velocity at this rank's points.
    ///
    /// # Collective
    pub fn normal_velocity(&self, v: &Vector<'p>) -> Result<Vec<f64>, LaError> {
        let mut y = self.normal.new_point_vector()?;
        self.normal.mult(v, &mut y)?;
        let out = y.local()?.to_vec();
        Ok(out)
    }
}

/// A mode's levels: its radiated power (W) per 1 um of contact amplitude and at its predicted
/// saturation amplitude, and the pressure levels at the microphones.
#[derive(Debug, Clone)]
pub struct ModeLoudness {
    pub name: String,
    pub frequency_hz: f64,
    /// Re(s) of the mode at the static state (1/s).
    pub growth: f64,
    pub alpha_sat: Option<f64>,
    pub power_per_unit: f64,
    pub power_at_sat: Option<f64>,
    /// Per microphone: name, pressure level (dB re 20 uPa) per unit amplitude and at alpha_sat.
    pub microphones: Vec<(String, f64, Option<f64>)>,
}

impl ModeLoudness {
    /// L_W(A) at alpha_sat, else per unit amplitude (dB).
    pub fn level_a(&self) -> f64 {
        power_level(self.power_at_sat.unwrap_or(self.power_per_unit))
            + a_weighting(self.frequency_hz)
    }
}

/// A mode's levels: `shape` is its name, nominal eigenvalue and psi's coordinates (contact
/// amplitude 1).
///
/// # Collective
pub fn mode_loudness<'p>(
    petsc: &'p Petsc,
    radiator: &Radiator<'p>,
    settings: &LoudnessSettings,
    shapes: &[Vector<'p>],
    (name, eigenvalue, psi): (&str, Complex, &[Complex]),
    alpha_sat: Option<f64>,
) -> Result<ModeLoudness, LaError> {
    // psi has contact amplitude 1 (m per m): at amplitude alpha the velocity is
    // i omega alpha psi; its normal component at the points, per unit alpha.
    let (xr, xi) = expand(shapes, psi)?;
    let (nr, ni) = (
        radiator.normal_velocity(&xr)?,
        radiator.normal_velocity(&xi)?,
    );
    let omega = eigenvalue.1;
    let per_alpha: Vec<(f64, f64)> = nr
        .iter()
        .zip(&ni)
        .map(|(r, i)| (-omega * i, omega * r))
        .collect();
    let erp = radiator.power(petsc, settings, &per_alpha);
    let mut microphones = Vec::new();
    for (mic, at) in &settings.microphones {
        let amplitude = radiator.pressure(petsc, settings, &per_alpha, omega, *at);
        microphones.push((
            mic.clone(),
            pressure_level(amplitude * UNIT_AMPLITUDE),
            alpha_sat.map(|a| pressure_level(amplitude * a)),
        ));
    }
    Ok(ModeLoudness {
        name: name.to_string(),
        frequency_hz: omega / (2.0 * std::f64::consts::PI),
        growth: eigenvalue.0,
        alpha_sat,
        power_per_unit: erp * UNIT_AMPLITUDE * UNIT_AMPLITUDE,
        power_at_sat: alpha_sat.map(|a| erp * a * a),
        microphones,
    })
}
