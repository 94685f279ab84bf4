//! The mesh of a distributed run divided among the ranks, before anything is assembled: each
//! body's nodes partitioned once (METIS on the node graph of its whole mesh), and each rank
//! keeping only the cells it assembles ([`crate::mesh::RankPart`]). What reads a cell after
//! this is the assembly of a rank's own columns and of the prescribed ones, the only cells it
//! keeps; rank 0 writes the output from the mesh file read again ([`whole_mesh`]).

use std::path::Path;

use crate::case::{Case, CaseError};
use crate::elastic::{SolveError, far_apart_nodes};
use crate::fem::assembly::stiffness_graph;
use crate::linalg::node_owners;
use crate::mesh::{Mesh, MeshError, read_msh};

use super::RunError;

/// Partitions the nodes of every body of `case` among the ranks and keeps, on this rank, the
/// cells that hold one of its own nodes or a node whose columns every rank assembles: a node
/// of a group with a prescribed displacement or a force (the case's groups), or one a
/// floating body may be pinned at (`crate::elastic::ElasticProblem::floating`). Bodies the
/// case does not name are left whole (nothing assembles them). Collective.
pub(super) fn keep_rank_cells(mesh: &mut Mesh, case: &Case) -> Result<(), RunError> {
    let ranks = crate::parallel::ranks();
    for spec in &case.bodies {
        let Some(body) = mesh.bodies.iter_mut().find(|b| b.name == spec.name) else {
            continue; // named in the error of the case's own checks, which come next
        };
        let owner =
            node_owners(&stiffness_graph(body), ranks).map_err(|source| RunError::Solve {
                path: case.path.clone(),
                source: SolveError::Linalg {
                    body: body.name.clone(),
                    source,
                },
            })?;
        let mut keep: Vec<bool> = (owner.iter())
            .map(|&rank| rank as usize == ranks.rank)
            .collect();
        let held = (spec.dirichlet.iter().map(|d| &d.group))
            .chain(spec.forces.iter().map(|f| &f.group))
            .filter_map(|group| body.group_nodes(group))
            .flatten();
        for node in held.chain(far_apart_nodes(&body.coords, body.dim)) {
            keep[node] = true;
        }
        body.keep_cells(owner, |node| keep[node]);
        log::debug!(
            "body '{}': rank {} keeps {} of its {} cells",
            body.name,
            ranks.rank,
            body.num_cells(),
            body.total_cells()
        );
    }
    Ok(())
}

/// `mesh`, or where this rank kept only part of its cells, the whole mesh read again from its
/// file, for the output; refused if the file no longer holds the nodes and cells the run
/// solved on.
pub(super) fn whole_mesh(mesh: Mesh, case_path: &Path) -> Result<Mesh, RunError> {
    if mesh.bodies.iter().all(|b| b.part.is_none()) {
        return Ok(mesh);
    }
    let mesh_error = |source| CaseError::Mesh {
        path: case_path.to_owned(),
        source,
    };
    // The solve's memory, freed, goes back to the system first: glibc keeps freed blocks
    // between live ones resident, and the file's bytes and the whole mesh would come on top
    // of them (measured at 1M DOFs on 4 ranks: rank 0's peak 941 MB without, against 815 for
    // a run that kept every cell).
    #[cfg(target_env = "gnu")]
    // SAFETY: `malloc_trim` only returns free memory of the allocator to the system.
    unsafe {
        libc::malloc_trim(0);
    }
    let whole = read_msh(&mesh.path).map_err(mesh_error)?;
    for body in &mesh.bodies {
        let same = whole.body(&body.name).is_some_and(|read| {
            read.node_tags == body.node_tags
                && read.coords == body.coords
                && read.num_cells() == body.total_cells()
        });
        if !same {
            return Err(mesh_error(MeshError::Changed {
                path: mesh.path.clone(),
                body: body.name.clone(),
            })
            .into());
        }
    }
    Ok(whole)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name)
    }

    #[test]
    fn the_mesh_read_again_is_the_whole_one_and_refused_once_its_file_changed() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("mesh.msh");
        std::fs::copy(fixture("block_2d.msh"), &file).unwrap();
        let mut mesh = read_msh(&file).unwrap();
        let cells = mesh.bodies[0].num_cells();
        let owner = vec![0; mesh.bodies[0].num_nodes()];
        mesh.bodies[0].keep_cells(owner, |node| node == 0);
        assert!(mesh.bodies[0].num_cells() < cells);

        let whole = whole_mesh(mesh.clone(), Path::new("case.toml")).unwrap();
        assert_eq!(whole.bodies[0].num_cells(), cells);
        assert!(whole.bodies[0].part.is_none());

        std::fs::copy(fixture("flat_blocks_narrow_2d.msh"), &file).unwrap();
        let error = whole_mesh(mesh, Path::new("case.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("changed while the run was solving"),
            "{error}"
        );
    }
}
