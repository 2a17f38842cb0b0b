//! Writers of the modes: /modes/complex/<route>/ (tables, shapes), the CSV and the stability
//! diagram of each route. (The real modes: `ResultsFile::write_real_modes`.)

use std::path::Path;

use super::WriteError;
use crate::eigen::complex_modes::{ComplexMode, ComplexModes};
use crate::fem::dofmap::DofMap;
use crate::io::preview;
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::mesh::Mesh;
use crate::stages::complex::route_name;

/// Writes one route's complex modes: /modes/complex/<route>/ tables and shapes (real and
/// imaginary parts), `complex_modes_<route>.csv`, the stability diagram
/// `stability_<route>.png` and, on a mesh, a picture of each unstable mode's shape.
///
/// # Collective
pub fn write_complex(
    petsc: &Petsc,
    file: &ResultsFile,
    c: &ComplexModes,
    dofs: Option<&crate::fem::dofmap::DofMap>,
    mesh: Option<&Mesh>,
    output: &Path,
) -> Result<(), WriteError> {
    let route = route_name(c.route);
    let group = format!("modes/complex/{route}");
    let col = |f: &dyn Fn(&ComplexMode) -> f64| -> Vec<f64> { c.modes.iter().map(f).collect() };
    file.write_table(
        &format!("{group}/eigenvalue_real"),
        &col(&|m| m.eigenvalue.0),
        "1/s",
    )?;
    file.write_table(
        &format!("{group}/eigenvalue_imag"),
        &col(&|m| m.eigenvalue.1),
        "rad/s",
    )?;
    file.write_table(
        &format!("{group}/frequency"),
        &col(&|m| m.frequency_hz),
        "Hz",
    )?;
    file.write_table(
        &format!("{group}/damping_ratio"),
        &col(&|m| m.damping_ratio),
        "1",
    )?;
    file.write_table(
        &format!("{group}/backward_error"),
        &col(&|m| m.backward_error),
        "1",
    )?;
    file.write_table(
        &format!("{group}/unstable"),
        &col(&|m| f64::from(u8::from(m.unstable))),
        "1 = unstable",
    )?;
    file.write_table(
        &format!("{group}/dominant_real_mode"),
        &col(&|m| m.dominant_real_mode.map_or(0.0, |k| (k + 1) as f64)),
        "real mode number (1-based; 0 = unknown)",
    )?;
    file.set_number(&group, "basis_size", c.basis as f64)?;
    file.set_number(&group, "seconds", c.seconds)?;
    for (i, (xr, xi)) in c.shapes.iter().enumerate() {
        for (part, v) in [("re", xr), ("im", xi)] {
            let name = format!("{group}/shapes/mode_{:04}_{part}", i + 1);
            match dofs {
                Some(dofs) => file.write_nodal(&name, dofs, &v.local()?, "m")?,
                None => file.write_dof_vector(&name, v, "1")?,
            }
        }
    }
    if let (Some(dofs), Some(mesh)) = (dofs, mesh) {
        write_unstable_shapes(petsc, c, dofs, mesh, output)?;
    }
    if petsc.rank() == 0 {
        let path = output.join(format!("complex_modes_{route}.csv"));
        let mut text = String::from(
            "name,frequency_hz,damping_ratio,re_s,im_s,backward_error,unstable,dominant_real_mode\n",
        );
        for m in &c.modes {
            text.push_str(&format!(
                "{},{:.10e},{:.10e},{:.10e},{:.10e},{:.3e},{},{}\n",
                m.name,
                m.frequency_hz,
                m.damping_ratio,
                m.eigenvalue.0,
                m.eigenvalue.1,
                m.backward_error,
                u8::from(m.unstable),
                m.dominant_real_mode
                    .map_or(String::new(), |k| format!("R{}", k + 1))
            ));
        }
        std::fs::write(&path, text).map_err(|source| WriteError::Io {
            path: path.clone(),
            source,
        })?;
        let path = output.join(format!("stability_{route}.png"));
        crate::report::stability::write_diagram(
            &path,
            &c.modes,
            &format!("complex modes ({route})"),
        )
        .map_err(|source| WriteError::Io { path, source })?;
    }
    Ok(())
}

/// `mode_shape_<route>_<name>.png` of every unstable mode with a shape: the brake deformed by
/// the shape at the phase where it moves most, coloured by the displacement's size.
///
/// # Collective
fn write_unstable_shapes(
    petsc: &Petsc,
    c: &ComplexModes,
    dofs: &DofMap,
    mesh: &Mesh,
    output: &Path,
) -> Result<(), WriteError> {
    let route = route_name(c.route);
    for (mode, (xr, xi)) in c.modes.iter().zip(&c.shapes) {
        if !mode.unstable {
            continue;
        }
        let (re, im) = (xr.gather_all()?, xi.gather_all()?);
        if petsc.rank() != 0 {
            continue;
        }
        let u = at_largest_phase(dofs, &re, &im);
        let (width, height) = (900, 675);
        let rgb = preview::render_deformed(mesh, &u, width, height);
        let path = output.join(format!("mode_shape_{route}_{}.png", mode.name));
        preview::save(&path, &rgb, width, height)
            .map_err(|source| WriteError::Io { path, source })?;
    }
    Ok(())
}

/// The nodal displacement Re(psi e^{i phi}) = re cos(phi) - im sin(phi) at the phase phi where
/// its norm is largest: |.|^2 = (A+B)/2 + (A-B)/2 cos(2 phi) - C sin(2 phi) with A = re.re,
/// B = im.im, C = re.im, largest at 2 phi = atan2(-2C, A-B).
pub fn at_largest_phase(dofs: &DofMap, re: &[f64], im: &[f64]) -> Vec<[f64; 3]> {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let (a, b, c) = (dot(re, re), dot(im, im), dot(re, im));
    let phi = 0.5 * (-2.0 * c).atan2(a - b);
    let (cos, sin) = (phi.cos(), phi.sin());
    dofs.node_dofs
        .iter()
        .map(|d| {
            d.map(|k| {
                if k < 0 {
                    0.0
                } else {
                    re[k as usize] * cos - im[k as usize] * sin
                }
            })
        })
        .collect()
}

#[cfg(test)]
#[deny(clippy::disallowed_methods)] // f64 max/min banned in tests: NaN-blind (clippy.toml) (clippy.toml)
mod tests {
    use super::*;

    #[test]
    fn the_shape_is_taken_where_it_moves_most() {
        // Two nodes, one DOF fixed: psi = (1, 2i) at the free DOFs moves most at phi = -pi/2,
        // where Re(psi e^{i phi}) = (0, 2).
        let dofs = DofMap::new(&[[false, true, true], [false, true, true]], 1, 0);
        let u = at_largest_phase(&dofs, &[1.0, 0.0], &[0.0, 2.0]);
        assert!(
            u[0][0].abs() < 1e-12 && (u[1][0].abs() - 2.0).abs() < 1e-12,
            "{u:?}"
        );
        assert_eq!((u[0][1], u[1][2]), (0.0, 0.0));
    }
}
