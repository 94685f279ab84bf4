//! The linear system of one active-set iteration (`docs/method.md`, section 2.5), assembled in
//! one place.
//!
//! ```text
//! [ K1        0        -M1 (rows I) ] [u1    ]   [f1]
//! [ 0         K2         M2 R21     ] [u2    ] = [f2]
//! [ I (cols I)  -R12          0     ] [lambda]   [d ]
//! ```
//!
//! `K_k`, `f_k` are Dirichlet-constrained (rows and columns of prescribed dofs hold only their
//! diagonal, and carry no coupling). `lambda` is the traction on body 1 at its active nodes I;
//! body 2 receives `lambda_2 = -R21 lambda` on its whole candidate surface. `M1`, `M2` are the
//! lumped interface mass matrices (`super::surface`). Tied: one vector multiplier per node and the vector
//! constraint `u1 - R12 u2 = d`. Frictionless: `lambda = lambda_n n1`, one scalar per node, and
//! only the normal constraint `n1 . (u1 - R12 u2) = n1 . d`.
//!
//! A multiplier whose constraint only restates a Dirichlet condition of body 1 (tied: its dof
//! is prescribed; frictionless: every dof of its node is) is dropped: its row becomes
//! `lambda = 0` and it acts on neither body. Keeping it would leave an empty column, since the
//! rows of prescribed dofs carry no coupling.
//!
//! Scaling: the multiplier columns are multiplied by `s = k / m` and the constraint rows by `k`,
//! with `k` the largest diagonal entry of `K1` and `K2` and `m` that of `M1`, so that every block has
//! the magnitude of `K`; the solution is unscaled on return.

use faer::sparse::{SparseColMat, Triplet};

use super::compliance::MultiplierKey;
use super::{ContactError, Formulation};
use crate::elastic::AssembledBody;
use crate::linalg::mat_vec;

/// The interface operators of one iteration, on the active primary nodes I (built by
/// `super::interface::InterfaceOperators::coupling`).
pub struct Coupling {
    pub formulation: Formulation,
    /// Body-local node of each active primary node.
    pub primary_nodes: Vec<usize>,
    /// Normal at each active node (pointing out of body 1). Frictionless: the normal of the
    /// secondary facet the node is held on, the direction of both its constraint row (the
    /// gradient of its gap, `super::gap`) and its traction `lambda_n n`. Tied: the
    /// contact normal along which the gap is held.
    pub normals: Vec<[f64; 3]>,
    /// Lumped interface mass of each active node: its area `A_i`.
    pub areas1: Vec<f64>,
    /// Constraint row of each active node: `(secondary body node, weight)`, a row of `R12`
    /// (tied) or the P1 weights of the secondary facet it projects onto (frictionless).
    pub r12: Vec<Vec<(usize, f64)>>,
    /// Column of `M2 R21` of each active node: `(secondary body node, A2_j R21[j, i])`, the
    /// force a unit traction at node `i` puts on body 2's nodes (with the sign of `lambda_2 =
    /// -R21 lambda` applied by the system).
    pub loads2: Vec<Vec<(usize, f64)>>,
    /// Gap each active node is held at, as a vector along its contact normal.
    pub gaps: Vec<[f64; 3]>,
}

/// The solution of one iteration.
pub struct CoupledSolution {
    pub u1: Vec<f64>,
    pub u2: Vec<f64>,
    /// Traction on body 1 at I, one vector per node (for frictionless, `lambda_n n1`).
    pub traction: Vec<[f64; 3]>,
    /// Forces the interface applies to each body's dofs: `M1 lambda`, `-M2 R21 lambda`.
    pub contact_force1: Vec<f64>,
    pub contact_force2: Vec<f64>,
    pub relative_residual: f64,
}

impl CoupledSolution {
    /// The total contact force on each body, `[F1, F2]` (components beyond `dim` are 0).
    pub fn total_forces(&self, dim: usize) -> [[f64; 3]; 2] {
        let total = |force: &[f64]| -> [f64; 3] {
            std::array::from_fn(|c| match c < dim {
                true => force.iter().skip(c).step_by(dim).sum(),
                false => 0.0,
            })
        };
        [total(&self.contact_force1), total(&self.contact_force2)]
    }
}

impl Coupling {
    fn num_multipliers(&self, dim: usize) -> usize {
        match self.formulation {
            Formulation::Tied => dim * self.primary_nodes.len(),
            Formulation::Frictionless => self.primary_nodes.len(),
        }
    }

    /// Whether multiplier `col` restates a Dirichlet condition of body 1 (see the module doc).
    fn is_dropped(&self, col: usize, body1: &AssembledBody, dim: usize) -> bool {
        match self.formulation {
            Formulation::Tied => body1
                .constraints
                .is_fixed(dim * self.primary_nodes[col / dim] + col % dim),
            Formulation::Frictionless => (0..dim).all(|c| {
                body1
                    .constraints
                    .is_fixed(dim * self.primary_nodes[col] + c)
            }),
        }
    }

    /// Column `(multiplier, component)` coefficients of the traction at node `b`:
    /// tied `lambda(b, c)` is its own unknown; frictionless `lambda(b) n_b[c]`.
    fn multiplier_terms(&self, b: usize, c: usize, dim: usize) -> (usize, f64) {
        match self.formulation {
            Formulation::Tied => (dim * b + c, 1.0),
            Formulation::Frictionless => (b, self.normals[b][c]),
        }
    }
}

/// The coupled system of one iteration, kept in blocks so that it can be solved either as one
/// sparse matrix or through the bodies' own factorizations:
///
/// ```text
/// [ K  B ] [u     ]   [f]      K = diag(K1, K2) (constrained), B the scaled coupling columns,
/// [ C  D ] [lambda] = [g]      C the scaled constraint rows, D = t on dropped multipliers
/// ```
pub struct CoupledSystem {
    pub n1: usize,
    pub n2: usize,
    /// Number of multipliers.
    pub m: usize,
    /// The column of `B` of each multiplier over `s`, as a combination of the unit forces of
    /// [`Self::unit_loads`]: for tied contact the force of one component at one primary node,
    /// for frictionless contact the sum of the components weighted by the node's normal
    /// (`super::compliance` keeps the bodies' responses to the unit forces, which depend on
    /// nothing else).
    pub columns: Vec<Vec<(MultiplierKey, f64)>>,
    /// The force that a unit traction of one component at one active primary node puts on
    /// the bodies (rows `< n1 + n2`, unscaled).
    pub unit_loads: Vec<(MultiplierKey, Vec<(usize, f64)>)>,
    /// Multiplier scaling: the unknown is `lambda / s`.
    pub s: f64,
    /// Constraint row scaling: a row's residual is `t` times the gap error of its node.
    pub t: f64,
    /// Entries `(row < n1 + n2, multiplier, value)` of B.
    pub b: Vec<(usize, usize, f64)>,
    /// Entries `(multiplier, column < n1 + n2, value)` of C.
    pub c: Vec<(usize, usize, f64)>,
    /// Diagonal of D.
    pub d: Vec<f64>,
    /// `[f1; f2]` (constrained) and `g`.
    pub f: Vec<f64>,
    /// The factor `f` is scaled by: `f = load_factor [f1(1); f2(1)]`.
    pub load_factor: f64,
    pub g: Vec<f64>,
}

impl CoupledSystem {
    /// Assembles the blocks of the coupled system (`docs/method.md` 2.5), with the loads and
    /// prescribed displacements scaled by `load_factor`.
    pub fn assemble(
        body1: &AssembledBody,
        body2: &AssembledBody,
        coupling: &Coupling,
        dim: usize,
        load_factor: f64,
    ) -> Result<Self, ContactError> {
        let n1 = body1.f_c.len();
        let n2 = body2.f_c.len();
        let m = coupling.num_multipliers(dim);
        let k_scale = diagonal_max(&body1.k_c).max(diagonal_max(&body2.k_c));
        let m_scale = coupling.areas1.iter().cloned().fold(0.0, f64::max);
        if m > 0 && m_scale <= 0.0 {
            return Err(ContactError::EmptyInterfaceMass);
        }
        let s = if m > 0 { k_scale / m_scale } else { 1.0 };
        let t = k_scale;
        let dropped: Vec<bool> = (0..m)
            .map(|col| coupling.is_dropped(col, body1, dim))
            .collect();
        let columns = CouplingColumns::assemble(body1, body2, coupling, dim, &dropped, s);
        let (c_entries, g) = constraint_rows(coupling, dim, n1, &dropped, t);
        let d: Vec<f64> = dropped.iter().map(|&x| if x { t } else { 0.0 }).collect();
        // Loads and prescribed displacements scale the constrained right-hand side linearly.
        let f: Vec<f64> = body1
            .f_c
            .iter()
            .chain(&body2.f_c)
            .map(|v| load_factor * v)
            .collect();
        Ok(Self {
            n1,
            n2,
            m,
            columns: columns.columns,
            unit_loads: columns.unit_loads,
            s,
            t,
            b: columns.b,
            c: c_entries,
            d,
            f,
            load_factor,
            g,
        })
    }

    /// The whole matrix, for the monolithic solve and the residual check of every solve.
    pub fn matrix(
        &self,
        body1: &AssembledBody,
        body2: &AssembledBody,
    ) -> Result<SparseColMat<usize, f64>, ContactError> {
        let (n1, n) = (self.n1, self.n1 + self.n2);
        let mut triplets = Vec::new();
        for (body, offset) in [(body1, 0), (body2, n1)] {
            let (symbolic, values) = body.k_c.parts();
            let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
            for j in 0..symbolic.ncols() {
                for p in col_ptr[j]..col_ptr[j + 1] {
                    if values[p] != 0.0 {
                        triplets.push(Triplet::new(offset + row_idx[p], offset + j, values[p]));
                    }
                }
            }
        }
        triplets.extend(self.b.iter().map(|&(i, k, v)| Triplet::new(i, n + k, v)));
        triplets.extend(self.c.iter().map(|&(k, j, v)| Triplet::new(n + k, j, v)));
        triplets.extend(
            self.d
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(k, &v)| Triplet::new(n + k, n + k, v)),
        );
        SparseColMat::<usize, f64>::try_new_from_triplets(n + self.m, n + self.m, &triplets)
            .map_err(|e| ContactError::Linalg(format!("assembling the coupled system: {e:?}")))
    }

    /// `||A x - [f; g]|| / ||[f; g]||` for the whole matrix `A` of [`Self::matrix`], applied
    /// block by block without assembling it.
    pub fn relative_residual(
        &self,
        body1: &AssembledBody,
        body2: &AssembledBody,
        x: &[f64],
    ) -> f64 {
        let (n1, n) = (self.n1, self.n1 + self.n2);
        let mut ax = mat_vec(&body1.k_c, &x[..n1]);
        ax.extend(mat_vec(&body2.k_c, &x[n1..n]));
        ax.extend(self.d.iter().zip(&x[n..]).map(|(d, l)| d * l));
        for &(row, k, value) in &self.b {
            ax[row] += value * x[n + k];
        }
        for &(k, col, value) in &self.c {
            ax[n + k] += value * x[col];
        }
        let rhs = self.rhs();
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|e| e * e).sum::<f64>().sqrt();
        let r = norm(&mut ax.iter().zip(&rhs).map(|(a, b)| a - b));
        let nb = norm(&mut rhs.iter().copied());
        if nb > 0.0 { r / nb } else { r }
    }

    /// `[f; g]`.
    pub fn rhs(&self) -> Vec<f64> {
        let mut rhs = self.f.clone();
        rhs.extend_from_slice(&self.g);
        rhs
    }

    /// Unscales the solution `x = [u1; u2; lambda / s]` and forms the tractions and the
    /// interface forces.
    pub fn solution(
        &self,
        x: &[f64],
        coupling: &Coupling,
        dim: usize,
        relative_residual: f64,
    ) -> CoupledSolution {
        let (n1, n2) = (self.n1, self.n2);
        let traction: Vec<[f64; 3]> = (0..coupling.primary_nodes.len())
            .map(|k| {
                let mut lambda = [0.0; 3];
                for (c, value) in lambda.iter_mut().enumerate().take(dim) {
                    let (col, weight) = coupling.multiplier_terms(k, c, dim);
                    *value = self.s * x[n1 + n2 + col] * weight;
                }
                lambda
            })
            .collect();
        let mut contact_force1 = vec![0.0; n1];
        let mut contact_force2 = vec![0.0; n2];
        for (k, lambda) in traction.iter().enumerate() {
            let node = coupling.primary_nodes[k];
            for c in 0..dim {
                contact_force1[dim * node + c] += coupling.areas1[k] * lambda[c];
                for &(node2, load) in &coupling.loads2[k] {
                    contact_force2[dim * node2 + c] -= load * lambda[c];
                }
            }
        }
        CoupledSolution {
            u1: x[..n1].to_vec(),
            u2: x[n1..n1 + n2].to_vec(),
            traction,
            contact_force1,
            contact_force2,
            relative_residual,
        }
    }
}

/// The coupling columns of the multipliers: `-M1 lambda` on body 1, `+M2 R21 lambda` on body
/// 2, one unit force per active node and component, combined per multiplier.
struct CouplingColumns {
    /// [`CoupledSystem::b`].
    b: Vec<(usize, usize, f64)>,
    /// [`CoupledSystem::columns`].
    columns: Vec<Vec<(MultiplierKey, f64)>>,
    /// [`CoupledSystem::unit_loads`].
    unit_loads: Vec<(MultiplierKey, Vec<(usize, f64)>)>,
}

impl CouplingColumns {
    /// The columns of the multipliers not `dropped`, scaled by `s`; rows of prescribed dofs
    /// carry no coupling.
    fn assemble(
        body1: &AssembledBody,
        body2: &AssembledBody,
        coupling: &Coupling,
        dim: usize,
        dropped: &[bool],
        s: f64,
    ) -> Self {
        let n1 = body1.f_c.len();
        let free1 = |dof: usize| !body1.constraints.is_fixed(dof);
        let free2 = |dof: usize| !body2.constraints.is_fixed(dof);
        let mut b = Vec::new();
        let mut columns = vec![Vec::new(); dropped.len()];
        let mut unit_loads = Vec::new();
        for (k, &node) in coupling.primary_nodes.iter().enumerate() {
            for c in 0..dim {
                let (col, weight) = coupling.multiplier_terms(k, c, dim);
                if dropped[col] || weight == 0.0 {
                    continue;
                }
                let mut load = Vec::new();
                let dof = dim * node + c;
                if free1(dof) {
                    load.push((dof, -coupling.areas1[k]));
                }
                for &(node2, value) in &coupling.loads2[k] {
                    let dof2 = dim * node2 + c;
                    if free2(dof2) {
                        load.push((n1 + dof2, value));
                    }
                }
                b.extend(load.iter().map(|&(row, v)| (row, col, s * v * weight)));
                let key = (node, Some(c));
                columns[col].push((key, weight));
                unit_loads.push((key, load));
            }
        }
        Self {
            b,
            columns,
            unit_loads,
        }
    }
}

/// The constraint rows `C` and right-hand side `g`, scaled by `t`: `u1 - R12 u2 = d` (tied),
/// or its normal component (frictionless), for the multipliers not `dropped`; body 2's dofs
/// follow body 1's `n1`.
fn constraint_rows(
    coupling: &Coupling,
    dim: usize,
    n1: usize,
    dropped: &[bool],
    t: f64,
) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let mut c_entries = Vec::new();
    let mut g = vec![0.0; dropped.len()];
    for (a, &node) in coupling.primary_nodes.iter().enumerate() {
        for c in 0..dim {
            let (row, weight) = coupling.multiplier_terms(a, c, dim);
            if dropped[row] || weight == 0.0 {
                continue;
            }
            c_entries.push((row, dim * node + c, t * weight));
            for &(node2, w) in &coupling.r12[a] {
                c_entries.push((row, n1 + dim * node2 + c, -t * w * weight));
            }
            g[row] += t * weight * coupling.gaps[a][c];
        }
    }
    (c_entries, g)
}

fn diagonal_max(k: &SparseColMat<usize, f64>) -> f64 {
    let (symbolic, values) = k.parts();
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    (0..symbolic.ncols())
        .flat_map(|j| (col_ptr[j]..col_ptr[j + 1]).filter(move |&p| row_idx[p] == j))
        .map(|p| values[p].abs())
        .fold(0.0, f64::max)
}
