//! Writers of the modes: /modes/complex/<route>/ (tables, shapes), the CSV and the stability
//! diagram of each route. (The real modes: `ResultsFile::write_real_modes`.)

use std::path::Path;

use super::WriteError;
use crate::eigen::complex_modes::{ComplexMode, ComplexModes};
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::stages::complex::route_name;

/// Writes one route's complex modes: /modes/complex/<route>/ tables and shapes (real and
/// imaginary parts), `complex_modes_<route>.csv` and the stability diagram
/// `stability_<route>.png`.
///
/// # Collective
pub fn write_complex(
    petsc: &Petsc,
    file: &ResultsFile,
    c: &ComplexModes,
    dofs: Option<&crate::fem::dofmap::DofMap>,
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
