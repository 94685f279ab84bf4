//! The result files of a solved case: `solution.xdmf` and `solution.h5` (every body's fields),
//! `summary.json`, and in contact runs `force_displacement.csv` and `.png`; `matrices/` when the
//! case asks for them. Rank 0 of a distributed run writes them, with the rows of the cells it
//! does not hold sent by the other ranks (`super::gathered_rows`).

use std::path::Path;
use std::time::Instant;

use crate::case::Case;
use crate::contact::StepRecord;
use crate::fem::assembly::{assemble_stiffness, assemble_surface_mass, stiffness_pattern};
use crate::mesh::Mesh;
use crate::output::{
    BodyFields, CaseSummary, OutputError, force_displacement_csv, write_force_displacement_png,
    write_matrix_market, write_xdmf, write_xdmf_with,
};

use super::gathered_rows::{gather_cell_rows, gather_node_rows};
use super::partition::whole_mesh;
use super::solve::case_name;
use super::{CaseSolution, RunError};

/// Writes the result files of `solution` into `dir` and returns the summary it wrote (its
/// timings include the writing).
pub fn write_results(
    solution: &CaseSolution,
    case: &Case,
    mesh: &Mesh,
    dir: &Path,
) -> Result<CaseSummary, RunError> {
    let phase = Instant::now();
    if !solution.contacts.is_empty() {
        let curves: Vec<(&str, &[StepRecord])> = (solution.contacts.iter())
            .map(|c| (c.summary.name.as_str(), &c.summary.steps[..]))
            .collect();
        let csv = dir.join("force_displacement.csv");
        std::fs::write(&csv, force_displacement_csv(&curves))
            .map_err(|source| OutputError::Io { path: csv, source })?;
        // The plot only pictures the CSV: without it (e.g. no font) the run is still complete.
        // A warning, since a file the user expects is missing.
        let png = dir.join("force_displacement.png");
        let approach = (solution.contacts.iter())
            .map(|c| c.imposed_approach)
            .fold(0.0, f64::max);
        let title = match &solution.contacts[..] {
            [single] => single.plot_title.clone(),
            _ => format!("{}: {} contact pairs", case_name(case), curves.len()),
        };
        if let Err(e) = write_force_displacement_png(&png, &title, &curves, approach) {
            log::warn!("{} not written: {e}", png.display());
        }
    }
    let fields = body_fields(solution, mesh);
    if fields.iter().any(|b| b.mesh.part.is_some()) {
        // A distributed run: the ranks send their nodes' coordinates and displacements, then
        // the rows of their cells, as they are written.
        write_xdmf_with(
            dir,
            "solution",
            &fields,
            &mut |k, table, nodes| {
                gather_node_rows(&fields, k, table, nodes).map_err(|e| e.to_string())
            },
            &mut |k, cells| gather_cell_rows(&fields, k, cells).map_err(|e| e.to_string()),
        )?;
    } else {
        write_xdmf(dir, "solution", &fields)?;
    }
    if case.export_matrices {
        export_matrices(case, whole_mesh(mesh, &case.path)?.as_ref(), dir)?;
    }
    let mut timings = solution.timings.clone();
    timings.record("write output", phase);
    let summary = solution.summary_with(case, mesh, &timings);
    summary.write(&dir.join("summary.json"))?;
    Ok(summary)
}

/// What the output writes of each solved body: its mesh (on a rank of a distributed run, the
/// part it keeps), displacement, material and interface fields.
pub(super) fn body_fields<'a>(solution: &'a CaseSolution, mesh: &'a Mesh) -> Vec<BodyFields<'a>> {
    (solution.bodies.iter())
        .map(|s| BodyFields {
            mesh: mesh.body(&s.name).expect("solved bodies are mesh bodies"),
            displacement: &s.solution.displacement,
            material: &s.material,
            surfaces: s.surfaces.iter().map(|s| &s.fields).collect(),
        })
        .collect()
}

/// Writes `matrices/<body>_stiffness.mtx` (unconstrained `K`) and
/// `matrices/<body>__<group>_mass.mtx` for every boundary group the case uses (not for point
/// groups, which have no surface).
fn export_matrices(case: &Case, mesh: &Mesh, output_dir: &Path) -> Result<(), RunError> {
    let dir = output_dir.join("matrices");
    std::fs::create_dir_all(&dir).map_err(|source| OutputError::Io {
        path: dir.clone(),
        source,
    })?;
    for spec in &case.bodies {
        let body = case.body_mesh(mesh, spec)?;
        let problem = case.elastic_problem(body, spec)?;
        let k = assemble_stiffness(body, &problem.material, &stiffness_pattern(body));
        write_matrix_market(&dir.join(format!("{}_stiffness.mtx", body.name)), &k)?;
        let mut groups: Vec<&String> = (problem.dirichlet.iter().map(|d| &d.group))
            .chain(problem.loads.iter().map(|l| &l.group))
            .collect();
        groups.sort();
        groups.dedup();
        for name in groups {
            if let Some(group) = body.boundary_group(name) {
                let m = assemble_surface_mass(body, group);
                write_matrix_market(&dir.join(format!("{}__{}_mass.mtx", body.name, name)), &m)?;
            }
        }
    }
    Ok(())
}
