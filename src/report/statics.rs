//! Writer of the static preload: /static (displacement, every contact point, per-interface
//! sums, the Newton log) and the contact pressure/stiffness maps (PNG).

use std::path::Path;

use super::WriteError;
use crate::contact::pairing::ContactPoint;
use crate::fem::dofmap::DofMap;
use crate::io::results::ResultsFile;
use crate::la::Petsc;
use crate::report::contact_map::MapContext;
use crate::stages::model::Model;
use crate::stages::statics::Preloaded;
use crate::statics::NewtonRecord;

/// Writes the static state under /static: displacement, every contact point (point-id order)
/// and per-interface sums, and the contact maps of the sliding interfaces.
///
/// # Collective
pub fn write_static<'p>(
    petsc: &'p Petsc,
    file: &ResultsFile,
    preload: &Preloaded<'p>,
    dofs: &DofMap,
    model: &Model,
    maps: MapContext,
    output: &Path,
) -> Result<(), WriteError> {
    let (contact, state) = (&preload.contact, &preload.state);
    let q = state.displacement.local()?;
    file.write_nodal("static/displacement", dofs, &q, "m")?;
    drop(q);
    let c = &state.contact;
    let column =
        |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..contact.local().len()).map(f).collect() };
    let columns: Vec<(&str, Vec<f64>, &str)> = vec![
        ("gap", column(&|k| c.observed[k].gap), "m"),
        ("pressure", column(&|k| c.response[k].pressure), "Pa"),
        (
            "contact_stiffness",
            column(&|k| c.response[k].stiffness),
            "Pa/m",
        ),
        ("traction", column(&|k| c.response[k].traction[0]), "Pa"),
        ("sliding_speed", column(&|k| c.observed[k].speed), "m/s"),
        (
            "status",
            column(&|k| c.response[k].status as u8 as f64),
            "0 open, 1 stick, 2 slip",
        ),
    ];
    for (name, local, units) in columns {
        let all = contact.gather(petsc, &local)?;
        file.write_table(&format!("static/contact/{name}"), &all, units)?;
        if name == "pressure" {
            let nodal = pressure_at_nodes(contact.points(), &all, model.mesh.node_count());
            file.write_table("static/contact_pressure_at_nodes", &nodal, units)?;
        }
        // Maps of the sliding interfaces (the pads) in the disc plane.
        if petsc.rank() == 0 && (name == "pressure" || name == "contact_stiffness") {
            for (i, itf) in contact.interfaces().iter().enumerate() {
                if !itf.friction.is_sliding() {
                    continue;
                }
                let path = output.join(format!("contact_{name}_{}.png", itf.name));
                let what = name.replace('_', " ");
                crate::report::contact_map::write_map(
                    &path,
                    maps,
                    &all,
                    i,
                    &format!("static state: {what} on {}", itf.name),
                    &format!("{what} ({units})"),
                )
                .map_err(|source| WriteError::Io { path, source })?;
            }
        }
    }
    let pts = &contact.points();
    for (d, axis) in ["x", "y", "z"].iter().enumerate() {
        let v: Vec<f64> = pts.iter().map(|p| p.position[d]).collect();
        file.write_table(&format!("static/contact/{axis}"), &v, "m")?;
    }
    let v: Vec<f64> = pts.iter().map(|p| p.interface as f64).collect();
    file.write_table(
        "static/contact/interface",
        &v,
        "index into /static/interfaces order",
    )?;
    let v: Vec<f64> = pts.iter().map(|p| p.weight).collect();
    file.write_table("static/contact/weight", &v, "m^2")?;
    let v: Vec<f64> = pts.iter().map(|p| p.radius).collect();
    file.write_table("static/contact/radius", &v, "m")?;
    for (i, (itf, s)) in contact
        .interfaces()
        .iter()
        .zip(&state.summaries)
        .enumerate()
    {
        let g = format!("static/interfaces/{}", itf.name);
        file.set_number(&g, "index", i as f64)?;
        file.set_number(
            &g,
            "points",
            (contact.candidates()[i] - contact.misses()[i]) as f64,
        )?;
        file.set_number(&g, "missed_points", contact.misses()[i] as f64)?;
        file.set_number(&g, "normal_force_n", s.normal_force)?;
        file.set_number(&g, "friction_force_n", s.friction_force)?;
        file.set_number(&g, "braking_torque_nm", s.torque)?;
        file.set_number(&g, "max_pressure_pa", s.max_pressure)?;
        file.set_number(&g, "min_gap_m", s.min_gap)?;
        file.set_number(&g, "open_points", s.open as f64)?;
        file.set_number(&g, "stick_points", s.stick as f64)?;
        file.set_number(&g, "slip_points", s.slip as f64)?;
        file.set_text(&g, "normal_law", &format!("{:?}", itf.normal))?;
        file.set_text(&g, "friction_law", &format!("{:?}", itf.friction))?;
    }
    let log = |f: &dyn Fn(&NewtonRecord) -> f64| -> Vec<f64> { state.log.iter().map(f).collect() };
    file.write_table(
        "static/newton/load_step",
        &log(&|r| r.load_step as f64),
        "1",
    )?;
    file.write_table(
        "static/newton/iteration",
        &log(&|r| r.iteration as f64),
        "1",
    )?;
    file.write_table("static/newton/residual", &log(&|r| r.residual), "N")?;
    file.write_table("static/newton/step_length", &log(&|r| r.step_length), "1")?;
    file.set_number("static", "factorizations", state.factorizations as f64)?;
    file.set_number("static", "solves", state.solves as f64)?;
    file.set_number(
        "static",
        "krylov_corrections",
        state.krylov_corrections as f64,
    )?;
    file.set_number(
        "static",
        "krylov_iterations",
        state.krylov_iterations as f64,
    )?;
    file.set_number("static", "seconds_factorizing", state.seconds_factorizing)?;
    file.set_number("static", "seconds_solving", state.seconds_solving)?;
    file.set_number("static", "factor_flops", state.factor_flops)?;
    file.set_number("static", "factor_entries", state.factor_entries)?;
    file.set_number("static", "piston_force_n", model.piston_force())?;
    let torque: f64 = state.summaries.iter().map(|s| s.torque).sum();
    file.set_number("static", "braking_torque_nm", torque)?;
    Ok(())
}

/// The contact pressure at the nodes of both faces of every interface (zero elsewhere), for
/// ParaView: at each node the average of the points' pressures weighted by w |N| (a point's
/// area times the node's shape function there). |N| keeps it an average where the corner
/// functions of a quadratic face are negative.
pub fn pressure_at_nodes(points: &[ContactPoint], pressure: &[f64], nodes: usize) -> Vec<f64> {
    let (mut sum, mut weight) = (vec![0.0; nodes], vec![0.0; nodes]);
    for (p, &value) in points.iter().zip(pressure) {
        let sides = [
            (&p.master_nodes, &p.master_shape),
            (&p.slave_nodes, &p.slave_shape),
        ];
        for (ids, shape) in sides {
            for (&node, &n) in ids.iter().zip(shape.iter()) {
                sum[node] += p.weight * n.abs() * value;
                weight[node] += p.weight * n.abs();
            }
        }
    }
    sum.iter()
        .zip(&weight)
        .map(|(&s, &w)| if w > 0.0 { s / w } else { 0.0 })
        .collect()
}
