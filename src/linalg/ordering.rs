//! Fill-reducing orderings for the sparse Cholesky factorization.
//!
//! Nested dissection comes from METIS (`METIS_NodeND`), applied to the node graph and expanded
//! to the `block` unknowns of each node, which keeps each node's unknowns together and makes
//! the graph `block^2` times smaller than the dof graph. faer's own AMD is the alternative.
//! On 3D elasticity nested dissection measured about 2x faster than AMD with a third less
//! memory (`validation/BENCHMARK.md` has this machine's figures).

use std::ptr;
use std::sync::{Mutex, PoisonError};

use super::LinalgError;
use crate::fem::NodeGraph;

/// METIS draws from the C library's `rand()`, one generator for the whole process, reseeded by
/// each call: two calls at once (the two bodies of a contact problem are factored in parallel)
/// would interleave their draws and get permutations, hence factors and solutions, that depend
/// on timing. One call at a time.
static METIS: Mutex<()> = Mutex::new(());

/// Nested-dissection permutation `(forward, inverse)` of the unknowns of the pattern whose node
/// graph is `graph`: `forward[new] = old`, `inverse[old] = new`.
pub fn nested_dissection(graph: &NodeGraph) -> Result<(Vec<usize>, Vec<usize>), LinalgError> {
    let n = graph.num_nodes();
    let block = graph.block();
    let mut xadj: Vec<metis_sys::idx_t> = Vec::with_capacity(n + 1);
    let mut adjncy: Vec<metis_sys::idx_t> = Vec::new();
    xadj.push(0);
    for a in 0..n {
        for &b in graph.neighbours(a) {
            if b != a {
                adjncy.push(to_idx(b)?);
            }
        }
        xadj.push(to_idx(adjncy.len())?);
    }
    let mut node_forward = vec![0 as metis_sys::idx_t; n];
    let mut node_inverse = vec![0 as metis_sys::idx_t; n];
    if n > 0 {
        let mut nvtxs = to_idx(n)?;
        let _one_at_a_time = METIS.lock().unwrap_or_else(PoisonError::into_inner);
        // SAFETY: the arrays have the lengths METIS_NodeND requires (n + 1, xadj[n], n, n);
        // null vertex weights and options select METIS's defaults.
        let status = unsafe {
            metis_sys::METIS_NodeND(
                &mut nvtxs,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                ptr::null_mut(),
                ptr::null_mut(),
                node_forward.as_mut_ptr(),
                node_inverse.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK as std::os::raw::c_int {
            return Err(LinalgError::Ordering(format!(
                "METIS_NodeND returned status {status}"
            )));
        }
    }
    let mut forward = Vec::with_capacity(block * n);
    for &old in &node_forward {
        forward.extend((0..block).map(|c| block * old as usize + c));
    }
    let mut inverse = vec![0usize; block * n];
    for (new, &old) in forward.iter().enumerate() {
        inverse[old] = new;
    }
    Ok((forward, inverse))
}

/// The part (0 to `parts - 1`) of each node of the graph whose node `a` has the neighbours
/// `neighbours[a]` (symmetric, without `a`): METIS's k-way partition, parts of nearly equal
/// size (METIS's default imbalance, 3%) with few edges cut. The same graph always gets the same
/// parts.
///
/// Where `interface` marks some nodes (`interface[a]`, or none where it is empty), each part
/// also gets a nearly equal share of them: METIS's multi-constraint partition, every node
/// weighing `(1, 1)` if marked and `(1, 0)` if not. The contact loop's operators hold rows for
/// the nodes of the contact surfaces (the coupling blocks, the interpolation's rows and
/// columns), a few percent of a body's nodes gathered in one region that a partition by size
/// alone leaves to one or two parts: measured at 1M DOFs on 4 ranks, those rows made one rank's
/// heap 798 MB against 691 to 736 for the others.
pub fn partition(
    neighbours: &[Vec<usize>],
    parts: usize,
    interface: &[bool],
) -> Result<Vec<usize>, LinalgError> {
    let n = neighbours.len();
    if parts <= 1 || n == 0 {
        return Ok(vec![0; n]);
    }
    let mut xadj: Vec<metis_sys::idx_t> = Vec::with_capacity(n + 1);
    let mut adjncy: Vec<metis_sys::idx_t> = Vec::new();
    xadj.push(0);
    for adjacent in neighbours {
        for &b in adjacent {
            adjncy.push(to_idx(b)?);
        }
        xadj.push(to_idx(adjncy.len())?);
    }
    // A constraint whose weights are all zero would leave METIS nothing to balance (it divides
    // by each constraint's total): one constraint where no node is marked.
    let marked = interface.iter().any(|&m| m);
    if marked && interface.len() != n {
        return Err(LinalgError::Sizes(format!(
            "{} interface marks for a graph of {n} nodes",
            interface.len()
        )));
    }
    let mut weights: Vec<metis_sys::idx_t> = if marked {
        interface
            .iter()
            .flat_map(|&m| [1, m as metis_sys::idx_t])
            .collect()
    } else {
        Vec::new()
    };
    let weights_ptr = if marked {
        weights.as_mut_ptr()
    } else {
        ptr::null_mut()
    };
    // Imbalances: the sizes' METIS's default (3%), the marked nodes' 10%: their rows matter
    // only roughly, and room on them lets METIS hold the sizes (with 3% on both, a body of
    // 58,695 unknowns split 3.5% over an even half).
    let mut imbalance: [metis_sys::real_t; 2] = [1.03, 1.10];
    let imbalance_ptr = if marked {
        imbalance.as_mut_ptr()
    } else {
        ptr::null_mut()
    };
    let mut part = vec![0 as metis_sys::idx_t; n];
    let (mut nvtxs, mut ncon, mut nparts, mut cut) =
        (to_idx(n)?, if marked { 2 } else { 1 }, to_idx(parts)?, 0);
    let _one_at_a_time = METIS.lock().unwrap_or_else(PoisonError::into_inner);
    // SAFETY: the arrays have the lengths METIS_PartGraphKway reads (n + 1, xadj[n], ncon n or
    // null, ncon or null, n); null target fractions and options, and a null imbalance with one
    // constraint, select METIS's defaults.
    let status = unsafe {
        metis_sys::METIS_PartGraphKway(
            &mut nvtxs,
            &mut ncon,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            weights_ptr,
            ptr::null_mut(),
            ptr::null_mut(),
            &mut nparts,
            ptr::null_mut(),
            imbalance_ptr,
            ptr::null_mut(),
            &mut cut,
            part.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK as std::os::raw::c_int {
        return Err(LinalgError::Partition(format!(
            "METIS_PartGraphKway into {parts} parts returned status {status}"
        )));
    }
    Ok(part.into_iter().map(|p| p as usize).collect())
}

fn to_idx(k: usize) -> Result<metis_sys::idx_t, LinalgError> {
    metis_sys::idx_t::try_from(k).map_err(|_| {
        LinalgError::Ordering(format!("graph too large for METIS's 32-bit indices ({k})"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::SparsityPattern;

    #[test]
    fn orderings_computed_at_the_same_time_equal_one_computed_alone() {
        // A 40 x 40 grid of quadrilaterals (as 4-node elements): enough for METIS to draw
        // random numbers many times.
        let m = 40;
        let quads: Vec<usize> = (0..m * m)
            .flat_map(|q| {
                let (i, j) = (q % m, q / m);
                let node = |di, dj| (j + dj) * (m + 1) + i + di;
                [node(0, 0), node(1, 0), node(1, 1), node(0, 1)]
            })
            .collect();
        let pattern = SparsityPattern::new((m + 1) * (m + 1), &quads, 4, 2);
        let alone = nested_dissection(pattern.graph()).unwrap();
        let together: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4)
                .map(|_| s.spawn(|| nested_dissection(pattern.graph()).unwrap()))
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for ordering in together {
            assert!(ordering == alone);
        }
    }

    #[test]
    fn a_partition_shares_the_marked_nodes_as_it_shares_the_nodes() {
        // A 60 x 60 grid of nodes (each joined to its four neighbours) with its top five rows
        // marked, as a body's contact surface and the layers under it: four parts by size
        // alone leave those rows to two of them.
        let m = 60;
        let neighbours: Vec<Vec<usize>> = (0..m * m)
            .map(|a| {
                let (i, j) = (a % m, a / m);
                let mut n = Vec::new();
                if i > 0 {
                    n.push(a - 1)
                }
                if i + 1 < m {
                    n.push(a + 1)
                }
                if j > 0 {
                    n.push(a - m)
                }
                if j + 1 < m {
                    n.push(a + m)
                }
                n
            })
            .collect();
        let marked: Vec<bool> = (0..m * m).map(|a| a / m >= m - 5).collect();
        let largest_share = |part: &[usize], of: &dyn Fn(usize) -> bool| {
            let mut count = [0usize; 4];
            (0..m * m)
                .filter(|&a| of(a))
                .for_each(|a| count[part[a]] += 1);
            let total: usize = count.iter().sum();
            *count.iter().max().unwrap() as f64 / (total as f64 / 4.0)
        };
        let by_size = partition(&neighbours, 4, &[]).unwrap();
        assert!(largest_share(&by_size, &|a| marked[a]) > 1.5);
        let both = partition(&neighbours, 4, &marked).unwrap();
        assert!(largest_share(&both, &|a| marked[a]) < 1.1);
        assert!(largest_share(&both, &|_| true) < 1.05);
        assert_eq!(partition(&neighbours, 4, &marked).unwrap(), both);
    }
}
