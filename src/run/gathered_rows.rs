//! The rows of a distributed run's output that rank 0 does not hold, gathered onto it a chunk
//! at a time.
//!
//! After the partition no rank holds a whole body's cells (`super::partition`), every node's
//! coordinates (`crate::mesh::NodeCoords`) or every node's displacement
//! (`crate::elastic::ElasticSolution::displacement`: those of the nodes it keeps), so rank 0,
//! which writes `solution.h5`, receives the rows of the geometry and the displacement (each
//! node's coordinates and displacement) and of the cell datasets (each cell's nodes, strain,
//! stress and von Mises stress) from the ranks that hold them, in the chunks it writes them in
//! (`crate::output::row_chunks`). A node is sent by its owner, which keeps its coordinates and
//! displacement. A cell is sent by one rank, the lowest that owns one of its nodes: that rank
//! holds it (a rank keeps every cell around its own nodes, and the displacement of their
//! nodes), and no other sends it; it computes the cell's strain and stress. So rank 0 holds at
//! most one chunk of rows beyond its own part of the mesh and of the displacement, and nobody
//! reads the mesh file again.

use std::ops::Range;

use crate::output::{BodyFields, CellRows, NodeTable, row_chunks};
use crate::parallel::{self, ParallelError};

/// The rows of body `k`'s cells `cells` (indices in the whole body), on rank 0; an empty
/// [`CellRows`] on the other ranks. Collective: every rank calls it with the same `k` and
/// `cells`, in the same order, and sends the rows of the cells it writes.
pub(super) fn gather_cell_rows(
    bodies: &[BodyFields],
    k: usize,
    cells: Range<usize>,
) -> Result<CellRows, ParallelError> {
    let body = &bodies[k];
    let width = body.mesh.nodes_per_cell();
    let (local, indices): (Vec<usize>, Vec<usize>) = sent_cells(body, cells.clone()).unzip();
    let sent = CellRows::of(body, local.into_iter());
    // A cell as values: its index in the whole body, its nodes, strain, stress, von Mises.
    let values_per_cell = 1 + width + 9 + 9 + 1;
    let mut values = Vec::with_capacity(values_per_cell * sent.len());
    for (s, &index) in indices.iter().enumerate() {
        values.push(index as f64);
        values.extend(
            sent.topology[width * s..width * (s + 1)]
                .iter()
                .map(|&a| a as f64),
        );
        values.extend_from_slice(&sent.strain[9 * s..9 * (s + 1)]);
        values.extend_from_slice(&sent.stress[9 * s..9 * (s + 1)]);
        values.push(sent.von_mises[s]);
    }
    let Some(all) = on_root(&values)? else {
        return Ok(CellRows::default());
    };
    // Rank 0: each cell's rows in its place in the chunk.
    let n = cells.len();
    let mut rows = CellRows {
        topology: vec![0; width * n],
        strain: vec![0.0; 9 * n],
        stress: vec![0.0; 9 * n],
        von_mises: vec![f64::NAN; n],
    };
    let mut placed = vec![false; n];
    for cell in all.chunks_exact(values_per_cell) {
        let index = cell[0] as usize;
        let at = index.wrapping_sub(cells.start);
        if at >= n || placed[at] {
            return Err(ParallelError::Message(format!(
                "the output's cell {index} of body '{}' was sent twice or is not in {cells:?}",
                body.mesh.name
            )));
        }
        placed[at] = true;
        let (nodes, fields) = cell[1..].split_at(width);
        (rows.topology[width * at..width * (at + 1)]
            .iter_mut()
            .zip(nodes))
        .for_each(|(a, &node)| *a = node as u32);
        rows.strain[9 * at..9 * (at + 1)].copy_from_slice(&fields[..9]);
        rows.stress[9 * at..9 * (at + 1)].copy_from_slice(&fields[9..18]);
        rows.von_mises[at] = fields[18];
    }
    if let Some(at) = placed.iter().position(|&p| !p) {
        return Err(ParallelError::Message(format!(
            "no rank sent the output's cell {} of body '{}'",
            cells.start + at,
            body.mesh.name
        )));
    }
    Ok(rows)
}

/// The rows of `table` (each node's coordinates or displacement) for body `k`'s nodes `nodes`
/// (indices in the whole body), on rank 0; an empty vector on the other ranks. Collective:
/// every rank calls it with the same `k`, `table` and `nodes`, in the same order, and sends
/// the rows of the nodes it owns among them.
pub(super) fn gather_node_rows(
    bodies: &[BodyFields],
    k: usize,
    table: NodeTable,
    nodes: Range<usize>,
) -> Result<Vec<[f64; 3]>, ParallelError> {
    let body = &bodies[k];
    let mesh = body.mesh;
    let missing = |a: usize| {
        ParallelError::Message(format!(
            "the output's node {a} of body '{}' is not kept by the rank that sends it",
            mesh.name
        ))
    };
    if mesh.part.is_none() {
        // A body every rank holds whole: rank 0 has every node's.
        return match parallel::is_root() {
            true => (nodes.map(|a| body.node_row(table, a).ok_or_else(|| missing(a)))).collect(),
            false => Ok(Vec::new()),
        };
    }
    // A node as values: its index, then its row.
    let mut values = Vec::new();
    for (a, _) in mesh.owned_within(parallel::ranks().rank, nodes.clone()) {
        values.push(a as f64);
        values.extend_from_slice(&body.node_row(table, a).ok_or_else(|| missing(a))?);
    }
    let Some(all) = on_root(&values)? else {
        return Ok(Vec::new());
    };
    let mut rows = vec![[f64::NAN; 3]; nodes.len()];
    let mut placed = vec![false; nodes.len()];
    for node in all.chunks_exact(4) {
        let a = node[0] as usize;
        let at = a.wrapping_sub(nodes.start);
        if at >= rows.len() || placed[at] {
            return Err(ParallelError::Message(format!(
                "the output's node {a} of body '{}' was sent twice or is not in {nodes:?}",
                mesh.name
            )));
        }
        placed[at] = true;
        rows[at].copy_from_slice(&node[1..]);
    }
    if let Some(at) = placed.iter().position(|&p| !p) {
        return Err(ParallelError::Message(format!(
            "no rank sent the {} of the output's node {} of body '{}'",
            table.name(),
            nodes.start + at,
            mesh.name
        )));
    }
    Ok(rows)
}

/// Every rank's `values`, one rank's after the other in rank order, on rank 0; `None` on the
/// other ranks (collective).
fn on_root(values: &[f64]) -> Result<Option<Vec<f64>>, ParallelError> {
    let counts: Vec<usize> = (parallel::gather(values.len() as f64)?.iter())
        .map(|&count| count as usize)
        .collect();
    let all = parallel::gather_to_root(values, &counts)?;
    Ok(parallel::is_root().then_some(all))
}

/// On a rank other than 0: sends the coordinates of every node this rank owns, then their
/// displacements, then the rows of every cell it writes, chunk by chunk, as rank 0 gathers
/// them while it writes (`gather_node_rows`, `gather_cell_rows`; the order of
/// `crate::output::write_xdmf_with`).
pub(super) fn send_output_rows(bodies: &[BodyFields]) -> Result<(), ParallelError> {
    let nodes: Vec<usize> = bodies.iter().map(|b| b.mesh.num_nodes()).collect();
    for table in [NodeTable::Geometry, NodeTable::Displacement] {
        for (k, range) in row_chunks(&nodes) {
            gather_node_rows(bodies, k, table, range)?;
        }
    }
    let cells: Vec<usize> = bodies.iter().map(|b| b.mesh.total_cells()).collect();
    for (k, range) in row_chunks(&cells) {
        gather_cell_rows(bodies, k, range)?;
    }
    Ok(())
}

/// This rank's cells among the whole body's `cells` that it sends, as (index in its mesh,
/// index in the whole body): those whose lowest owning rank is this one. A body held whole
/// (one process) sends them all.
fn sent_cells<'a>(
    body: &'a BodyFields,
    cells: Range<usize>,
) -> Box<dyn Iterator<Item = (usize, usize)> + 'a> {
    let Some(part) = &body.mesh.part else {
        return Box::new(cells.map(|c| (c, c)));
    };
    let rank = parallel::ranks().rank as u32;
    let width = body.mesh.nodes_per_cell();
    let first = part
        .cell_indices
        .partition_point(|&c| (c as usize) < cells.start);
    let end = part
        .cell_indices
        .partition_point(|&c| (c as usize) < cells.end);
    Box::new((first..end).filter_map(move |c| {
        let nodes = &body.mesh.cells[width * c..width * (c + 1)];
        let writer = nodes
            .iter()
            .filter_map(|&a| body.mesh.owner(a as usize))
            .min();
        (writer == Some(rank)).then_some((c, part.cell_indices[c] as usize))
    }))
}
