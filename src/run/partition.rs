//! The mesh of a distributed run divided among the ranks, before anything is assembled: rank 0
//! reads the whole mesh, partitions each body's nodes once (METIS on the node graph of its
//! whole mesh, each part given to the rank that keeps the ranks' totals even) and sends every
//! rank what it keeps ([`crate::mesh::RankPart`]): the groups and boundary of every body, the
//! extent of its nodes, the cells it assembles and the coordinates and owners of the nodes it
//! reads (those of its cells and of the body's boundary and groups). No other rank ever holds
//! a whole body's cells or nodes, or the file's bytes. What reads a cell after this is the
//! assembly of a rank's own columns and of the prescribed ones, the only cells it keeps, and
//! the output, whose cell rows each rank sends rank 0 for the cells it writes (`super::write`).
//! Only the export of the assembled matrices reads the mesh file again ([`whole_mesh`]).

use std::borrow::Cow;
use std::path::Path;

use crate::case::{Case, CaseError};
use crate::elastic::{SolveError, prescribed_dofs};
use crate::fem::assembly::stiffness_graph;
use crate::linalg::{node_owners, spread_parts};
use crate::mesh::{
    BodyMesh, CellsByRank, GmshTags, Mesh, MeshError, NODE_WORDS, NodesByRank, read_msh,
};
use crate::parallel::{self, ParallelError};

use super::RunError;

/// This rank's part of the mesh of a distributed run; `whole` is the mesh on rank 0 and `None`
/// on the others. Rank 0 checks the case against the mesh, partitions the nodes of every body
/// of the case among the ranks, and gives each rank the cells that hold one of its own nodes
/// or a node with a prescribed dof in the body's problem (`crate::elastic::prescribed_dofs`:
/// its Dirichlet and force-controlled groups, a floating body's pins), whose columns every rank
/// assembles. Bodies the case does not name go whole (nothing assembles them). Collective: an
/// error of rank 0 ends the run on every rank (`crate::parallel::abort`).
pub(super) fn scatter_mesh(whole: Option<Mesh>, case: &Case) -> Result<Mesh, RunError> {
    let message = |e: postcard::Error| RunError::Parallel(ParallelError::Message(e.to_string()));
    // 1. On rank 0: the partition, each body's cells divided, and the mesh without them.
    let (skeleton, divided) = match whole {
        Some(mut mesh) => {
            let divided = divide_cells(&mut mesh, case)?;
            (postcard::to_allocvec(&mesh).map_err(message)?, divided)
        }
        None => (Vec::new(), Vec::new()),
    };
    // 2. The mesh without the cells on every rank, then each rank's cells, body by body.
    // The bytes are freed only once the cells are here, so that the cells and indices are
    // allocated beside them rather than in the room they leave: with glibc's default (a
    // threshold that rises to the largest mapped block freed) the indices received after the
    // free raised rank 1's peak at 1M DOFs on 2 ranks to 1,394 to 1,407 MB in three runs of
    // four, against 1,335 to 1,339 in this order. Since `crate::parallel::start` fixes the
    // threshold, the order matters only for blocks under 4 MiB; that fix was measured with it
    // (1,336 to 1,343 MB).
    let bytes = parallel::share_from_root(skeleton).map_err(RunError::Parallel)?;
    let mut mesh: Mesh = postcard::from_bytes(&bytes).map_err(message)?;
    let mut divided = divided.into_iter();
    for spec in &case.bodies {
        let body = (mesh.bodies.iter_mut().find(|b| b.name == spec.name))
            .expect("rank 0's checks found every body of the case");
        // Rank 0 keeps the body's element tags, for the output; the others receive none.
        let (
            CellsByRank {
                cells,
                indices,
                counts,
            },
            NodesByRank {
                nodes,
                words,
                counts: node_counts,
            },
            tags,
        ) = match divided.next() {
            Some((cells, nodes, tags)) => (cells, nodes, Some(tags)),
            None => (CellsByRank::default(), NodesByRank::default(), None),
        };
        let width = body.nodes_per_cell();
        let scatter = |values, counts: &[usize], width| {
            parallel::scatter_cells(values, counts, width).map_err(RunError::Parallel)
        };
        let (cells, indices) = (
            scatter(cells, &counts, width)?,
            scatter(indices, &counts, 1)?,
        );
        body.receive_cells(cells, indices);
        let nodes = scatter(nodes, &node_counts, 1)?;
        body.receive_nodes(nodes, &scatter(words, &node_counts, NODE_WORDS)?);
        if let Some(part) = body.part.as_mut() {
            part.whole_cell_tags = tags;
        }
        log::debug!(
            "body '{}': rank {} keeps {} of its {} cells and the coordinates of {} of its {} nodes",
            body.name,
            parallel::ranks().rank,
            body.num_cells(),
            body.total_cells(),
            body.coords.kept().len(),
            body.num_nodes()
        );
    }
    drop(bytes);
    // Rank 0's whole mesh, the file's bytes and the divided cells are freed by now (measured
    // at 1M DOFs on 4 ranks: rank 0's peak 837 MB without, 774 with; the others' 719 to 785).
    return_freed_memory();
    Ok(mesh)
}

/// Returns the allocator's free memory to the system. Glibc keeps freed blocks that lie
/// below live ones resident, so what a phase freed still counts in the process's peak when
/// the next phase allocates elsewhere.
fn return_freed_memory() {
    #[cfg(target_env = "gnu")]
    // SAFETY: `malloc_trim` only returns free memory of the allocator to the system.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Rank 0's division of the cells of every body of `case` among the ranks, in the case's
/// order of bodies, each with the body's element tags; each of those bodies of `mesh` is left
/// without its cells and tags ([`crate::mesh::BodyMesh::drop_cells`]).
fn divide_cells(
    mesh: &mut Mesh,
    case: &Case,
) -> Result<Vec<(CellsByRank, NodesByRank, GmshTags)>, RunError> {
    // The problems below read the case's groups, which its checks vouch for first.
    case.check_bodies(mesh)?;
    let ranks = parallel::ranks();
    let mut divided = Vec::with_capacity(case.bodies.len());
    // The nodes each rank owns of the bodies divided so far: each body's parts go where they
    // even out the ranks' totals (`crate::linalg::spread_parts`).
    let mut nodes_on_rank = vec![0; ranks.size];
    for spec in &case.bodies {
        let body = (mesh.bodies.iter_mut().find(|b| b.name == spec.name))
            .expect("the checks found every body of the case");
        if u32::try_from(body.num_cells()).is_err() {
            return Err(RunError::Case(CaseError::Mesh {
                path: case.path.clone(),
                source: MeshError::TooManyCells {
                    path: mesh.path.clone(),
                    body: body.name.clone(),
                    cells: body.num_cells(),
                },
            }));
        }
        let linalg_error = |source| RunError::Solve {
            path: case.path.clone(),
            source: SolveError::Linalg {
                body: body.name.clone(),
                source,
            },
        };
        let mut owner = node_owners(&stiffness_graph(body), ranks, &contact_nodes(body, case))
            .map_err(linalg_error)?;
        let rank_of_part = spread_parts(&mut owner, &mut nodes_on_rank);
        log::debug!(
            "body '{}': its {} parts on ranks {rank_of_part:?}, the ranks' nodes so far \
             {nodes_on_rank:?}",
            body.name,
            ranks.size
        );
        let prescribed =
            prescribed_dofs(&case.elastic_problem(body, spec)?).map_err(|e| RunError::Solve {
                path: case.path.clone(),
                source: e.into(),
            })?;
        let dim = body.dim;
        let everywhere = |a: usize| (0..dim).any(|c| prescribed.is_fixed(dim * a + c));
        let cells = body.cells_by_rank(&owner, ranks.size, everywhere);
        let tags = body.drop_cells(owner);
        let nodes = body.divide_nodes(&cells);
        divided.push((cells, nodes, tags));
    }
    Ok(divided)
}

/// The nodes of `body` on a contact surface of `case` (any pair's, either side), marked: the
/// nodes whose rows the contact loop's operators hold, which the partition shares among the
/// ranks besides the body's nodes (`crate::linalg::node_owners`).
fn contact_nodes(body: &BodyMesh, case: &Case) -> Vec<bool> {
    let mut marked = vec![false; body.num_nodes()];
    for pair in &case.contacts {
        for (name, surface) in pair.bodies.iter().zip(&pair.surfaces) {
            if *name == body.name {
                for node in body.group_nodes(surface).unwrap_or_default() {
                    marked[node] = true;
                }
            }
        }
    }
    marked
}

/// `mesh`, or where this rank kept only part of its cells, the whole mesh read again from its
/// file, for the export of the assembled matrices (`[output] export_matrices`: the whole
/// body's matrix, in one process); refused if the file no longer holds the nodes and cells
/// the run solved on.
pub(super) fn whole_mesh<'a>(mesh: &'a Mesh, case_path: &Path) -> Result<Cow<'a, Mesh>, RunError> {
    if mesh.bodies.iter().all(|b| b.part.is_none()) {
        return Ok(Cow::Borrowed(mesh));
    }
    let mesh_error = |source| CaseError::Mesh {
        path: case_path.to_owned(),
        source,
    };
    // The solve's memory, freed, goes back to the system first: the file's bytes and the
    // whole mesh would come on top of it (measured at 1M DOFs on 4 ranks: rank 0's peak 941
    // MB without, against 815 for a run that kept every cell).
    return_freed_memory();
    let whole = read_msh(&mesh.path).map_err(mesh_error)?;
    for body in &mesh.bodies {
        let same = whole.body(&body.name).is_some_and(|read| {
            read.node_tags == body.node_tags
                && read.num_nodes() == body.num_nodes()
                && (body.coords.kept()).all(|(a, x)| read.coords.get(a) == Some(x))
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
    Ok(Cow::Owned(whole))
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
        let kept = mesh.bodies[0].cells_by_rank(&owner, 2, |_| false);
        mesh.bodies[0].drop_cells(owner);
        mesh.bodies[0].receive_cells(kept.cells[..3].to_vec(), kept.indices[..1].to_vec());
        assert!(mesh.bodies[0].num_cells() < cells);

        let whole = whole_mesh(&mesh, Path::new("case.toml")).unwrap();
        assert_eq!(whole.bodies[0].num_cells(), cells);
        assert!(whole.bodies[0].part.is_none());

        std::fs::copy(fixture("flat_blocks_narrow_2d.msh"), &file).unwrap();
        let error = whole_mesh(&mesh, Path::new("case.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("changed while the run was solving"),
            "{error}"
        );
    }
}
