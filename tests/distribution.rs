//! Owned-row assembly without MPI: the ranks of a distributed run, played one after another in
//! one process. Each rank assembles only the columns of its own nodes and constrains them;
//! together the ranks must hold the constrained matrix a single process assembles, every
//! entry bit for bit, and its right-hand side to rounding.

mod common;

use common::read_fixture;
use internodes::fem::assembly::{assemble_stiffness, stiffness_graph, stiffness_pattern};
use internodes::fem::{Constraints, Material, NodeColumns};
use internodes::linalg::Distribution;
use internodes::mesh::BodyMesh;
use internodes::parallel::Ranks;

/// The base clamped and the top pushed down and sideways: prescribed values that are not all
/// zero, so that the free rows carry a pull of the prescribed ones.
fn constraints(body: &BodyMesh) -> Constraints {
    let dim = body.dim;
    let mut constraints = Constraints::new(body.num_dofs());
    for (group, values) in [
        ("block_base", [0.0; 3]),
        ("block_top", [0.003, -0.002, -0.01]),
    ] {
        for node in body.group_nodes(group).unwrap() {
            for (c, &value) in values.iter().enumerate().take(dim) {
                constraints.prescribe(dim * node + c, value).unwrap();
            }
        }
    }
    constraints
}

#[test]
fn the_ranks_rows_are_the_whole_constrained_matrix() {
    let material = Material::new(1000.0, 0.3).unwrap();
    for file in ["block_2d.msh", "block_3d.msh"] {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let dim = body.dim;
        let n = body.num_dofs();
        let constraints = constraints(body);
        // A load on every dof, so that f_c = f - K_FD g differs from f everywhere it can.
        let f: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.5)
            .collect();
        let k = assemble_stiffness(body, &material, &stiffness_pattern(body));
        let (k_c, f_c) = constraints.apply(k, &f);
        let whole = k_c.to_dense();
        let f_c_scale = f_c.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let graph = stiffness_graph(body);
        let coords = body.coords.flat(dim);

        for size in [1, 2, 3] {
            let distributions: Vec<Distribution> = (0..size)
                .map(|rank| Distribution::new(&graph, &coords, Ranks { rank, size }).unwrap())
                .collect();
            // PETSc's numbering: rank 0's nodes first (along a Z curve), each node's unknowns
            // together.
            let ours: Vec<usize> = (distributions.iter())
                .flat_map(|d| d.own_nodes().iter().map(|&node| node as usize))
                .flat_map(|node| (0..dim).map(move |c| dim * node + c))
                .collect();
            let mut seen = ours.clone();
            seen.sort_unstable();
            assert_eq!(
                seen,
                (0..n).collect::<Vec<_>>(),
                "{file} on {size}: a partition"
            );

            let mut first = 0;
            for (rank, distribution) in distributions.into_iter().enumerate() {
                assert_eq!(distribution.counts().len(), size);
                let mut columns =
                    NodeColumns::assemble(body, &material, &graph, distribution.nodes());
                // This rank's entries of f_c, at the unknowns of its columns.
                let values = constraints.apply_to_columns(&mut columns, |dof| f[dof]);
                let local_f_c: std::collections::HashMap<usize, f64> = (values.iter().enumerate())
                    .map(|(q, &value)| (columns.dof(q), value))
                    .collect();
                let rows = distribution.rows(&columns, &body.coords);
                assert_eq!(rows.num_dofs(), n);
                for (p, &i) in ours[first..first + rows.num_rows()].iter().enumerate() {
                    let at = |q: usize| rows.row_ptr[q] as usize;
                    let row = at(p)..at(p + 1);
                    assert!(rows.columns[row.clone()].windows(2).all(|w| w[0] < w[1]));
                    let mut held = vec![0.0; n];
                    for (&column, &value) in rows.columns[row.clone()].iter().zip(&rows.values[row])
                    {
                        held[ours[column as usize]] = value;
                    }
                    // Row i is column i of the whole matrix, as PETSc reads a whole matrix's
                    // compressed columns as rows (K is symmetric up to rounding).
                    for j in 0..n {
                        assert_eq!(
                            held[j].to_bits(),
                            whole[(j, i)].to_bits(),
                            "{file}, rank {rank} of {size}: K_c({j}, {i})"
                        );
                    }
                    assert_eq!(rows.coords[p], coords[i]);
                    // The pull of the prescribed dofs is read from row i instead of column i:
                    // the same numbers up to the rounding of the symmetric element matrices.
                    let difference = (local_f_c[&i] - f_c[i]).abs() / f_c_scale;
                    assert!(
                        difference <= 1e-14,
                        "{file}, rank {rank} of {size}: f_c({i}) {} against {} ({difference:.1e})",
                        local_f_c[&i],
                        f_c[i]
                    );
                }
                first += rows.num_rows();
            }
            assert_eq!(first, n);
        }
    }
}
