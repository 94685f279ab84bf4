//! The mesh of a distributed run divided among the ranks, before anything is assembled: each
//! body's nodes partitioned once (METIS on the node graph of its whole mesh), and each rank
//! keeping only the cells it assembles ([`crate::mesh::RankPart`]). What reads a cell after
//! this is the assembly of a rank's own columns and of the prescribed ones, the only cells it
//! keeps; rank 0 writes the output from the mesh file read again ([`whole_mesh`]).

use std::path::Path;

use crate::case::{Case, CaseError};
use crate::elastic::{SolveError, prescribed_dofs};
use crate::fem::assembly::stiffness_graph;
use crate::linalg::node_owners;
use crate::mesh::{Mesh, MeshError, read_msh};

use super::RunError;

/// Partitions the nodes of every body of `case` among the ranks and keeps, on this rank, the
/// cells that hold one of its own nodes or a node with a prescribed dof in the body's problem
/// (`crate::elastic::prescribed_dofs`: its Dirichlet and force-controlled groups, a floating
/// body's pins), whose columns every rank assembles. Bodies the case does not name are left
/// whole (nothing assembles them). Collective.
pub(super) fn keep_rank_cells(mesh: &mut Mesh, case: &Case) -> Result<(), RunError> {
    // The problems below read the case's groups, which its checks vouch for first.
    case.check_bodies(mesh)?;
    let ranks = crate::parallel::ranks();
    for spec in &case.bodies {
        let index = (mesh.bodies.iter().position(|b| b.name == spec.name))
            .expect("the checks found every body of the case");
        let body = &mesh.bodies[index];
        let linalg_error = |source| RunError::Solve {
            path: case.path.clone(),
            source: SolveError::Linalg {
                body: body.name.clone(),
                source,
            },
        };
        let owner = node_owners(&stiffness_graph(body), ranks).map_err(linalg_error)?;
        let prescribed =
            prescribed_dofs(&case.elastic_problem(body, spec)?).map_err(|e| RunError::Solve {
                path: case.path.clone(),
                source: e.into(),
            })?;
        let dim = body.dim;
        let keep: Vec<bool> = (0..body.num_nodes())
            .map(|a| {
                owner[a] as usize == ranks.rank
                    || (0..dim).any(|c| prescribed.is_fixed(dim * a + c))
            })
            .collect();
        let body = &mut mesh.bodies[index];
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
