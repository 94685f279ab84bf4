//! The linear system of one active-set iteration (`docs/method.md`, section 2.5), assembled in
//! one place, for any number of bodies and contact pairs.
//!
//! Pair `p` couples its primary body `a` (which carries the multiplier `lambda_p`, the contact
//! traction on `a` at the pair's active nodes `I_p`) and its secondary body `b` (which receives
//! `lambda_b = -R_ba lambda_p` on its candidate surface). For one pair of bodies 1 and 2:
//!
//! ```text
//! [ K1        0        -M1 (rows I) ] [u1    ]   [f1]
//! [ 0         K2         M2 R21     ] [u2    ] = [f2]
//! [ I (cols I)  -R12          0     ] [lambda]   [d ]
//! ```
//!
//! and with more bodies and pairs, one block row per body and one per pair: body `k`'s row
//! holds `K_k` and the columns of every pair it is in (`-M_a` where it is the primary, `M_b
//! R_ba` where it is the secondary); pair `p`'s row holds its constraint on its two bodies'
//! columns. The bodies are coupled only through the pairs: a body in no pair is its own block.
//!
//! `K_k`, `f_k` are Dirichlet-constrained (rows and columns of prescribed dofs hold only their
//! diagonal, and carry no coupling). `M_a`, `M_b` are the lumped interface mass matrices
//! (`crate::contact::geometry::surface`). Tied: one vector multiplier per node and the vector
//! constraint `u_a - R_ab u_b = d`. Frictionless: `lambda = lambda_n n_a`, one scalar per node, and
//! only the normal constraint `n_a . (u_a - R_ab u_b) = n_a . d`.
//!
//! A multiplier whose constraint only restates a Dirichlet condition of its primary body (tied:
//! its dof is prescribed; frictionless: every dof of its node is) is dropped: its row becomes
//! `lambda = 0` and it acts on neither body. Keeping it would leave an empty column, since the
//! rows of prescribed dofs carry no coupling.
//!
//! A multiplier may have a term of its own in its row, `r . (u_a - u_b(point)) + c lambda = r .
//! d` (a slipping Coulomb node's row across its direction, `crate::contact::law::coulomb`): its
//! entry `t s c` of `D`.
//!
//! A force-controlled group (`crate::elastic::RigidColumn`) adds one unknown per controlled
//! component after all the pairs' multipliers: its displacement `a`, with its column `k` in
//! its body's rows, the same `k` as its row, `d` (and the couplings to the body's other such
//! components) in `D`, and the prescribed force in `g`:
//!
//! ```text
//! [ K_k  ...  k   ] [u_k]   [f_k              ]
//! [ k^T  ...  d   ] [a  ] = [s (force + applied)]
//! ```
//!
//! A contact node in such a group moves with `a`: its constraint row reads `a`, and the force a
//! multiplier puts on it enters the group's reaction, both through entries of `D` between the
//! multiplier and `a` (`d_coupled`).
//!
//! Scaling: the multiplier columns are multiplied by `s = k / m` and the constraint rows by `k`,
//! with `k` the largest diagonal entry of the bodies' `K` and `m` the largest lumped mass of an
//! active primary node, so that every block has the magnitude of `K`; the solution is unscaled
//! on return. A rigid unknown is a displacement, of the scale of `u`: it is not scaled (its
//! unit load carries the weight `1 / s`, which cancels the multipliers' `s`).

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

use faer::sparse::{SparseColMat, Triplet};

use crate::contact::ContactError;
use crate::contact::coupled::compliance::MultiplierKey;
use crate::contact::coupled::row_ownership::RowOwnership;
use crate::contact::geometry::displacement::{BodyDisplacement, NodeValues};
use crate::contact::law::{Multiplier, Reads, Restates};
use rayon::prelude::*;

use crate::elastic::{AssembledBody, StepFactors};
use crate::fem::LoadVector;
use crate::linalg::{BodySolver, Distribution, NodeGather, mat_vec};

/// The interface operators of one pair in one iteration, on its active primary nodes I (built
/// by `crate::contact::coupled::interface::InterfaceOperators::coupling`, each node's multipliers
/// laid out by the pair's contact law, `crate::contact::law`).
pub struct Coupling {
    /// Body-local node of each active primary node.
    pub primary_nodes: Vec<usize>,
    /// Reference position of each active primary node: the points of the half-space model
    /// (`crate::contact::coupled::half_space`).
    pub points: Vec<[f64; 3]>,
    /// Normal at each active node (pointing out of the primary), along which its pressure
    /// `p = -lambda . n` is measured. Frictionless and Coulomb: the normal of the secondary
    /// facet the node is held on, the direction of its normal constraint row (the gradient of
    /// its gap, `crate::contact::geometry::gap`). Tied: the contact normal along which the gap is
    /// held.
    pub normals: Vec<[f64; 3]>,
    /// Lumped interface mass of each active node: its area `A_i`.
    pub areas1: Vec<f64>,
    /// The multipliers of each active node ([`Multiplier`]): their columns and rows.
    pub multipliers: Vec<Vec<Multiplier>>,
    /// The secondary point a geometric row of each active node reads: `(secondary body node,
    /// weight)`, the P1 weights of the secondary facet it projects onto (empty where no row
    /// of the node reads it).
    pub geometric: Vec<Vec<(usize, f64)>>,
    /// The same through the interpolation: the row of `R12` of each active node (empty where
    /// no row of the node reads it).
    pub interpolated: Vec<Vec<(usize, f64)>>,
    /// The same for the wall a node holds beside its closest facet: the P1 weights of the
    /// node's closest point on the wall's facet (`crate::contact::geometry::walls`; empty where
    /// the node holds none).
    pub walls: Vec<Vec<(usize, f64)>>,
    /// Column of `M2 R21` of each active node: `(secondary body node, A2_j R21[j, i])`, the
    /// force a unit traction at node `i` puts on the secondary's nodes (with the sign of
    /// `lambda_2 = -R21 lambda` applied by the system).
    pub loads2: Vec<Vec<(usize, f64)>>,
    /// The target of each active node's rows, as a vector: row `r` holds `r . (u1_i -
    /// u2(point)) = r . target_i` (the gap along its normal, and for a sticking node the
    /// tangential jump at the start of the step).
    pub gaps: Vec<[f64; 3]>,
}

/// One contact pair of a coupled system: its two bodies (indices into the system's bodies) and
/// its coupling.
#[derive(Clone, Copy)]
pub struct Pair<'a> {
    pub primary: usize,
    pub secondary: usize,
    pub coupling: &'a Coupling,
}

/// The solution of one iteration.
pub struct CoupledSolution {
    /// Displacements of each body: whole on one process; on a rank of a distributed run, in
    /// the contact loop this rank's rows of it (PETSc's order;
    /// [`CoupledSystem::solution_on_ranks`]), and once the loop has ended its values at the
    /// nodes whose coordinates the body's mesh keeps, in their order (`dim` each:
    /// `crate::mesh::NodeCoords::position` finds a node's), which the output and the
    /// reactions read.
    pub u: Vec<Vec<f64>>,
    /// In a distributed run, each body's displacement at the nodes the contact geometry reads,
    /// from every rank ([`Self::displacement`]); `None` where `u` is whole.
    pub on_nodes: Option<Vec<NodeValues>>,
    /// Traction on each pair's primary at its active nodes, one vector per node (for
    /// frictionless, `lambda_n n`).
    pub traction: Vec<Vec<[f64; 3]>>,
    /// Forces the interfaces apply to each body's dofs: `M_a lambda` on a primary, `-M_b R_ba
    /// lambda` on a secondary, summed over the body's pairs. Nonzero at the interface nodes
    /// alone, so kept as those entries (`LoadVector::new`), not a vector of the body's size
    /// that every rank would hold for the loop's life.
    pub contact_force: Vec<LoadVector>,
    /// Each body's force-controlled displacements, one per `RigidColumn` of the body (they
    /// are also in `u`, at the group's dofs).
    pub rigid: Vec<Vec<f64>>,
    pub relative_residual: f64,
}

/// The forces pair `coupling`'s tractions `on_pair` put on its bodies, node by node in a fixed
/// order: `add(0, node, f)` adds `f` (its first `dim` components) to the primary's force at
/// `node` (`M_a lambda`), `add(1, node, f)` to the secondary's (`-M_b R_ba lambda`). Each
/// unknown receives its terms in the same order whatever `add` does with them.
fn add_pair_forces(
    coupling: &Coupling,
    on_pair: &[[f64; 3]],
    mut add: impl FnMut(usize, usize, [f64; 3]),
) {
    for (k, lambda) in on_pair.iter().enumerate() {
        add(
            0,
            coupling.primary_nodes[k],
            lambda.map(|l| coupling.areas1[k] * l),
        );
        for &(node2, load) in &coupling.loads2[k] {
            add(1, node2, lambda.map(|l| -(load * l)));
        }
    }
}

/// `force[dim * node + c] += f[c]` for the first `dim` components.
fn add_at(force: &mut [f64], dim: usize, node: usize, f: [f64; 3]) {
    (force[dim * node..dim * (node + 1)].iter_mut())
        .zip(f)
        .for_each(|(v, f)| *v += f);
}

impl CoupledSolution {
    /// Pair `p`'s part of the solution, as the solution of its two bodies alone: their
    /// displacements and force-controlled displacements, its tractions, and the forces of
    /// this pair alone on them (a body in several pairs receives the others' too).
    pub fn of_pair(&self, p: usize, pair: &Pair, dim: usize) -> CoupledSolution {
        let (a, b) = (pair.primary, pair.secondary);
        // The forces at the interface's dofs alone, each summed in the order of a whole
        // vector's (`u` need not be whole: [`Self::u`]).
        let mut forces = [BTreeMap::new(), BTreeMap::new()];
        add_pair_forces(pair.coupling, &self.traction[p], |side, node, f| {
            for (c, f) in f.iter().enumerate().take(dim) {
                *forces[side].entry(dim * node + c).or_insert(0.0) += f;
            }
        });
        let lengths = [self.contact_force[a].len(), self.contact_force[b].len()];
        let forces = [0, 1].map(|side| {
            let entries = std::mem::take(&mut forces[side]).into_iter();
            LoadVector::from_entries(lengths[side], entries.filter(|&(_, v)| v != 0.0).collect())
        });
        let on_nodes = (self.on_nodes.as_ref()).map(|on| vec![on[a].clone(), on[b].clone()]);
        CoupledSolution {
            u: vec![self.u[a].clone(), self.u[b].clone()],
            on_nodes,
            traction: vec![self.traction[p].clone()],
            contact_force: forces.into(),
            rigid: vec![self.rigid[a].clone(), self.rigid[b].clone()],
            relative_residual: self.relative_residual,
        }
    }

    /// Body `k`'s displacement as the contact geometry reads it: whole, or at the nodes it
    /// reads ([`Self::on_nodes`]).
    pub fn displacement(&self, k: usize) -> BodyDisplacement<'_> {
        match &self.on_nodes {
            Some(on_nodes) => BodyDisplacement::OnNodes(&on_nodes[k]),
            None => BodyDisplacement::Whole(&self.u[k]),
        }
    }

    /// The total contact force on each body (components beyond `dim` are 0).
    pub fn total_forces(&self, dim: usize) -> Vec<[f64; 3]> {
        let total = |force: &LoadVector| -> [f64; 3] {
            std::array::from_fn(|c| match c < dim {
                true => force.component_sum(c, dim),
                false => 0.0,
            })
        };
        self.contact_force.iter().map(total).collect()
    }
}

impl Coupling {
    fn num_multipliers(&self) -> usize {
        self.multipliers.iter().map(Vec::len).sum()
    }

    /// The first multiplier of each active node (within the pair), then their number.
    fn node_offsets(&self) -> Vec<usize> {
        let mut offsets = Vec::with_capacity(self.multipliers.len() + 1);
        offsets.push(0);
        for node in &self.multipliers {
            offsets.push(offsets.last().unwrap() + node.len());
        }
        offsets
    }

    /// Whether `multiplier` of active node `k` restates Dirichlet conditions of the
    /// `primary` (see the module doc).
    fn is_dropped(
        &self,
        k: usize,
        multiplier: &Multiplier,
        primary: &AssembledBody,
        dim: usize,
    ) -> bool {
        let prescribed = |dof: usize| {
            primary.constraints.is_fixed(dof)
                && !(primary.rigid.iter()).any(|rigid| rigid.dofs.contains(&dof))
        };
        let node = self.primary_nodes[k];
        match multiplier.restates {
            Restates::Component(c) => prescribed(dim * node + c),
            Restates::Node => (0..dim).all(|c| prescribed(dim * node + c)),
        }
    }

    /// The secondary point the row of `multiplier` of active node `k` reads.
    fn reads(&self, k: usize, multiplier: &Multiplier) -> &[(usize, f64)] {
        match multiplier.reads {
            Reads::Geometric => &self.geometric[k],
            Reads::Interpolated => &self.interpolated[k],
            Reads::Wall => &self.walls[k],
        }
    }
}

/// The coupled system of one iteration, kept in blocks so that it can be solved either as one
/// sparse matrix or through the bodies' own solvers:
///
/// ```text
/// [ K  B ] [u     ]   [f]      K = diag(K_1 .. K_N) (constrained), B the scaled coupling
/// [ C  D ] [lambda] = [g]      columns, C the scaled constraint rows, D = t on dropped
///                              multipliers, a multiplier's own term in its row
///                              (`Multiplier::compliance`), force control
/// ```
///
/// The unknowns are the bodies' displacements one body after another, then the pairs'
/// multipliers one pair after another.
pub struct CoupledSystem {
    /// Body `k`'s dofs are the unknowns `offsets[k]..offsets[k + 1]`; the multipliers follow
    /// `offsets[N]`.
    pub offsets: Vec<usize>,
    /// What the rows of `B` and the columns of `C` number: every unknown of the bodies, or
    /// this rank's rows of them in a distributed run.
    pub unknowns: Unknowns,
    /// Pair `p`'s multipliers are `multiplier_offsets[p]..multiplier_offsets[p + 1]` of the
    /// multiplier block.
    pub multiplier_offsets: Vec<usize>,
    /// Number of multipliers.
    pub m: usize,
    /// The column of `B` of each multiplier over `s`, as a combination of the unit forces of
    /// [`Self::unit_loads`]: for tied contact the force of one component at one primary node,
    /// for frictionless contact the sum of the components weighted by the node's normal
    /// (`crate::contact::coupled::compliance` keeps the bodies' responses to the unit forces, which
    /// depend on nothing else).
    pub columns: Vec<Vec<(MultiplierKey, f64)>>,
    /// The force that a unit traction of one component at one active primary node puts on
    /// the bodies, with the multipliers whose columns it is part of: `B` itself, each unit
    /// load kept once ([`Self::b_entries`], [`Self::add_b_product`]). Through the
    /// interpolation transfer a unit load reaches most of the facing secondary surface, so
    /// these are the bulk of the system's coupling memory, and of a product with `B`: a
    /// sticking node's three multipliers share its three unit loads.
    pub unit_loads: Vec<UnitLoad>,
    /// Multiplier scaling: the unknown is `lambda / s`.
    pub s: f64,
    /// Constraint row scaling: a row's residual is `t` times the gap error of its node.
    pub t: f64,
    /// Entries `(multiplier, column < offsets[N], value)` of C, but for the rows in
    /// [`Self::shared_jumps`] ([`Self::c_entries`] lists them all).
    pub c: Vec<(usize, usize, f64)>,
    /// The rows of C that read one node's jump together ([`SharedJump`]).
    pub shared_jumps: Vec<SharedJump>,
    /// The direction of each pair multiplier's constraint row (zero for a force-controlled
    /// component): the half-space preconditioner (`crate::contact::coupled::half_space`) pairs it
    /// with the columns' directions, which differ from it at a slipping node
    /// (`crate::contact::law::coulomb`).
    pub rows: Vec<[f64; 3]>,
    /// Diagonal of D.
    pub d: Vec<f64>,
    /// Off-diagonal entries `(row, column, value)` of D: the couplings between the
    /// force-controlled components of one body, and between a multiplier and the
    /// force-controlled displacement of a contact node it reads or loads (module doc).
    pub d_coupled: Vec<(usize, usize, f64)>,
    /// The multiplier of each body's first force-controlled component: body `k`'s `r`-th
    /// `RigidColumn` is multiplier `rigid_offsets[k] + r`; they follow every pair's
    /// multipliers.
    pub rigid_offsets: Vec<usize>,
    /// The bodies' `f_k` (constrained), one after another, numbered as [`Self::unknowns`]
    /// says: whole, or in a distributed run this rank's rows alone, in the order of its Krylov
    /// vectors (`crate::contact::coupled::krylov_layout`), so that no rank holds the whole
    /// right-hand side through the solve.
    pub f: Vec<f64>,
    /// The load step's factors `f` and `g` are scaled by (each body's `f_k` by
    /// `AssembledBody::rhs`).
    pub factors: StepFactors,
    pub g: Vec<f64>,
}

/// What the rows of `B` and the columns of `C` of a [`CoupledSystem`] number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unknowns {
    /// Every unknown of the bodies, one body after another (`offsets`).
    Whole,
    /// This rank's rows of each body, by their place in its Krylov vectors
    /// (`crate::contact::coupled::krylov_layout`): the entries of `B` on other ranks' rows and
    /// of `C` on their columns are theirs. Only the coupled GMRES reads such a system.
    RankRows,
}

impl CoupledSystem {
    /// Assembles the blocks of the coupled system of `bodies` and `pairs` (`docs/method.md`
    /// 2.5), with the loads and prescribed displacements scaled by the step's `factors`.
    pub fn assemble(
        bodies: &[&AssembledBody],
        pairs: &[Pair],
        dim: usize,
        factors: &StepFactors,
    ) -> Result<Self, ContactError> {
        Self::assemble_on(bodies, pairs, dim, factors, None)
    }

    /// [`Self::assemble`], holding only this rank's entries of `B` and `C` where `ownership`
    /// is given ([`Unknowns::RankRows`]): a distributed run's coupled system.
    pub fn assemble_on(
        bodies: &[&AssembledBody],
        pairs: &[Pair],
        dim: usize,
        factors: &StepFactors,
        ownership: Option<&RowOwnership>,
    ) -> Result<Self, ContactError> {
        let mut offsets = vec![0];
        for body in bodies {
            offsets.push(offsets.last().unwrap() + body.f_c.len());
        }
        let mut multiplier_offsets = vec![0];
        for pair in pairs {
            let count = pair.coupling.num_multipliers();
            multiplier_offsets.push(multiplier_offsets.last().unwrap() + count);
        }
        let m_pairs = *multiplier_offsets.last().unwrap();
        let mut rigid_offsets = vec![m_pairs];
        for body in bodies {
            rigid_offsets.push(rigid_offsets.last().unwrap() + body.rigid.len());
        }
        let m = *rigid_offsets.last().unwrap();
        let k_scale = bodies.iter().map(|b| b.k_scale).fold(0.0, f64::max);
        let m_scale = (pairs.iter())
            .flat_map(|pair| pair.coupling.areas1.iter().copied())
            .fold(0.0, f64::max);
        if m_pairs > 0 && m_scale <= 0.0 {
            return Err(ContactError::EmptyInterfaceMass);
        }
        let s = if m_pairs > 0 { k_scale / m_scale } else { 1.0 };
        let t = k_scale;
        let mut blocks = PairBlocks::new(m, ownership);
        for (p, pair) in pairs.iter().enumerate() {
            let place = Placement {
                pair: p,
                first_multiplier: multiplier_offsets[p],
                primary: offsets[pair.primary],
                secondary: offsets[pair.secondary],
                primary_rigid: rigid_offsets[pair.primary],
                secondary_rigid: rigid_offsets[pair.secondary],
            };
            let [primary, secondary] = [bodies[pair.primary], bodies[pair.secondary]];
            blocks.add(pair.coupling, primary, secondary, &place, dim, s, t);
        }
        for (k, body) in bodies.iter().enumerate() {
            let first = rigid_offsets[k];
            blocks.add_rigid(k, body, first, offsets[k], s, factors);
        }
        // Loads and prescribed displacements scale the constrained right-hand side linearly.
        let f = match ownership {
            None => (bodies.iter()).flat_map(|body| body.rhs(factors)).collect(),
            Some(ownership) => {
                let mut f = vec![0.0; ownership.num_local()];
                for (k, body) in bodies.iter().enumerate() {
                    for (place, dof) in ownership.own_rows(k) {
                        f[place] = body.rhs_at(dof, factors);
                    }
                }
                f
            }
        };
        Ok(Self {
            offsets,
            unknowns: match ownership {
                None => Unknowns::Whole,
                Some(_) => Unknowns::RankRows,
            },
            multiplier_offsets,
            m,
            columns: blocks.columns,
            unit_loads: blocks.unit_loads,
            s,
            t,
            c: blocks.c,
            shared_jumps: blocks.shared_jumps,
            rows: blocks.rows,
            d: blocks.d,
            d_coupled: blocks.d_coupled,
            rigid_offsets,
            f,
            factors: factors.clone(),
            g: blocks.g,
        })
    }

    /// The entries `(row < offsets[N], multiplier, value)` of `B`: each unit load times `s`
    /// and its weight in its multiplier.
    pub fn b_entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let s = self.s;
        self.unit_loads.iter().flat_map(move |unit| {
            (unit.multipliers.iter()).flat_map(move |&(multiplier, weight)| {
                (unit.load.iter()).map(move |&(row, v)| (row, multiplier, s * v * weight))
            })
        })
    }

    /// The entries `(multiplier, column < offsets[N], value)` of C.
    pub fn c_entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let shared = self.shared_jumps.iter().flat_map(|jump| {
            (jump.rows.iter()).flat_map(move |&(multiplier, row)| {
                (jump.reads.iter())
                    .filter(move |&&(c, _, _)| row[c] != 0.0)
                    .map(move |&(c, column, coefficient)| {
                        (multiplier, column, row[c] * coefficient)
                    })
            })
        });
        self.c.iter().copied().chain(shared)
    }

    /// `out[k] += (C x)_k` over the multipliers (`x` the displacements): each shared jump
    /// read once.
    pub fn add_c_product(&self, x: &[f64], out: &mut [f64]) {
        for &(k, col, value) in &self.c {
            out[k] += value * x[col];
        }
        for jump in &self.shared_jumps {
            let mut jump_value = [0.0; 3];
            for &(c, column, coefficient) in &jump.reads {
                jump_value[c] += coefficient * x[column];
            }
            for &(multiplier, row) in &jump.rows {
                out[multiplier] += (0..3).map(|c| row[c] * jump_value[c]).sum::<f64>();
            }
        }
    }

    /// `out += sign B y` on the displacement rows (`sign` is 1 or -1): each unit load once,
    /// times the traction component its multipliers' `y` make together.
    pub fn add_b_product(&self, y: &[f64], sign: f64, out: &mut [f64]) {
        let s = self.s;
        for unit in &self.unit_loads {
            match unit.multipliers[..] {
                // One multiplier: the product of its entries of `B` (the arithmetic of
                // `b_entries`, term by term).
                [(multiplier, weight)] => {
                    for &(row, v) in &unit.load {
                        out[row] += sign * (s * v * weight * y[multiplier]);
                    }
                }
                _ => {
                    let traction: f64 = (unit.multipliers.iter())
                        .map(|&(multiplier, weight)| weight * y[multiplier])
                        .sum();
                    for &(row, v) in &unit.load {
                        out[row] += sign * (s * v * traction);
                    }
                }
            }
        }
    }

    /// The number of bodies.
    pub fn num_bodies(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The unknowns of body `k`.
    pub fn body_dofs(&self, k: usize) -> Range<usize> {
        self.offsets[k]..self.offsets[k + 1]
    }

    /// The displacement unknowns of all bodies (the multipliers follow).
    pub fn num_displacements(&self) -> usize {
        *self.offsets.last().expect("offsets start with 0")
    }

    /// The bodies' part of `v` (a vector of the system's unknowns, or of its displacements
    /// alone) cut into one slice per body.
    pub fn body_parts<'v>(&self, v: &'v mut [f64]) -> Vec<&'v mut [f64]> {
        let mut rest = &mut v[..self.num_displacements()];
        let mut parts = Vec::with_capacity(self.num_bodies());
        for k in 0..self.num_bodies() {
            let (part, tail) = rest.split_at_mut(self.body_dofs(k).len());
            parts.push(part);
            rest = tail;
        }
        parts
    }

    /// The multipliers of pair `p`, within the multiplier block.
    pub fn pair_multipliers(&self, p: usize) -> Range<usize> {
        self.multiplier_offsets[p]..self.multiplier_offsets[p + 1]
    }

    /// The whole matrix, for the monolithic solve.
    pub fn matrix(
        &self,
        bodies: &[&AssembledBody],
    ) -> Result<SparseColMat<usize, f64>, ContactError> {
        self.whole("the whole matrix")?;
        let n = self.num_displacements();
        let mut triplets = Vec::new();
        for (body, &offset) in bodies.iter().zip(&self.offsets) {
            let (symbolic, values) = assembled(body)?.parts();
            let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
            for j in 0..symbolic.ncols() {
                for p in col_ptr[j]..col_ptr[j + 1] {
                    if values[p] != 0.0 {
                        triplets.push(Triplet::new(offset + row_idx[p], offset + j, values[p]));
                    }
                }
            }
        }
        triplets.extend(self.b_entries().map(|(i, k, v)| Triplet::new(i, n + k, v)));
        triplets.extend(self.c_entries().map(|(k, j, v)| Triplet::new(n + k, j, v)));
        triplets.extend(
            self.d
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(k, &v)| Triplet::new(n + k, n + k, v)),
        );
        triplets.extend((self.d_coupled.iter()).map(|&(k, l, v)| Triplet::new(n + k, n + l, v)));
        SparseColMat::<usize, f64>::try_new_from_triplets(n + self.m, n + self.m, &triplets)
            .map_err(|e| ContactError::Linalg(format!("assembling the coupled system: {e:?}")))
    }

    /// `[f; g] - A x` for the whole matrix `A` of [`Self::matrix`], applied block by block
    /// without assembling it (`solvers`: the bodies' solvers, for the products of a body whose
    /// `K_c` a distributed solver holds).
    pub fn residual(
        &self,
        bodies: &[&AssembledBody],
        solvers: Option<&[BodySolver]>,
        x: &[f64],
    ) -> Result<Vec<f64>, ContactError> {
        self.whole("its residual")?;
        let n = self.num_displacements();
        let mut ax = vec![0.0; n];
        for (k, body) in bodies.iter().enumerate() {
            let range = self.body_dofs(k);
            match (body.stiffness.whole(), solvers) {
                (Some(k_c), _) => ax[range.clone()].copy_from_slice(&mat_vec(k_c, &x[range])),
                (None, Some(solvers)) => {
                    stiffness_product(body, Some(&solvers[k]), &x[range.clone()], &mut ax[range])?
                }
                (None, None) => return Err(released()),
            }
        }
        ax.extend(self.d.iter().zip(&x[n..]).map(|(d, l)| d * l));
        for &(k, l, value) in &self.d_coupled {
            ax[n + k] += value * x[n + l];
        }
        self.add_b_product(&x[n..], 1.0, &mut ax);
        self.add_c_product(&x[..n], &mut ax[n..]);
        let rhs = self.rhs();
        Ok(rhs.iter().zip(&ax).map(|(b, a)| b - a).collect())
    }

    /// `||A x - [f; g]|| / ||[f; g]||` ([`Self::residual`]).
    pub fn relative_residual(
        &self,
        bodies: &[&AssembledBody],
        solvers: Option<&[BodySolver]>,
        x: &[f64],
    ) -> Result<f64, ContactError> {
        let norm = |v: &[f64]| v.iter().map(|e| e * e).sum::<f64>().sqrt();
        let r = norm(&self.residual(bodies, solvers, x)?);
        let nb = norm(&self.rhs());
        Ok(if nb > 0.0 { r / nb } else { r })
    }

    /// Fails unless the system holds every entry of `B` and `C` ([`Unknowns::Whole`]): what
    /// `purpose` needs.
    fn whole(&self, purpose: &str) -> Result<(), ContactError> {
        match self.unknowns {
            Unknowns::Whole => Ok(()),
            Unknowns::RankRows => Err(ContactError::Linalg(format!(
                "{purpose} needs the whole coupled system, and this rank holds its own rows of it"
            ))),
        }
    }

    /// `[f; g]`, `f` numbered as [`Self::f`] is. Allocated to its length: a copy of `f`
    /// extended by `g` would double its room, a second right-hand side's worth held through
    /// the solve.
    pub fn rhs(&self) -> Vec<f64> {
        let mut rhs = Vec::with_capacity(self.f.len() + self.g.len());
        rhs.extend_from_slice(&self.f);
        rhs.extend_from_slice(&self.g);
        rhs
    }

    /// Unscales the solution `x = [u_1; ...; u_N; lambda / s]` and forms each pair's tractions
    /// and each body's interface forces.
    ///
    /// A force-controlled group's displacement `a` is put at its dofs of `u` (where `x` holds
    /// 0, the value `K_c` holds them at).
    pub fn solution(
        &self,
        x: &[f64],
        bodies: &[&AssembledBody],
        pairs: &[Pair],
        dim: usize,
        relative_residual: f64,
    ) -> CoupledSolution {
        let n = self.num_displacements();
        let rigid = self.rigid_values(&x[n..]);
        let u: Vec<Vec<f64>> = (0..self.num_bodies())
            .map(|k| {
                let mut u = x[self.body_dofs(k)].to_vec();
                for (column, a) in bodies[k].rigid.iter().zip(&rigid[k]) {
                    column.dofs.iter().for_each(|&dof| u[dof] = *a);
                }
                u
            })
            .collect();
        let traction = self.tractions(&x[n..], pairs, dim);
        let mut contact_force: Vec<Vec<f64>> = u.iter().map(|u| vec![0.0; u.len()]).collect();
        for (pair, on_pair) in pairs.iter().zip(&traction) {
            let (a, b) = (pair.primary, pair.secondary);
            add_pair_forces(pair.coupling, on_pair, |side, node, f| {
                add_at(&mut contact_force[[a, b][side]], dim, node, f);
            });
        }
        CoupledSolution {
            u,
            on_nodes: None,
            traction,
            contact_force: contact_force.into_iter().map(LoadVector::new).collect(),
            rigid,
            relative_residual,
        }
    }

    /// [`Self::solution`] on a rank of a distributed run, from its part `x` of the answer
    /// (this rank's rows of each body, PETSc's order, then every multiplier:
    /// `crate::contact::coupled::krylov_layout`), with no vector of a body's size: `u` holds
    /// this rank's rows, and each body's displacement and interface forces at the nodes
    /// `reads[k]` gathers (its boundary's and its contact surfaces') are received from the
    /// ranks that own them (collective). The forces are the serial run's to the bit: each
    /// node's terms are all made on the rank that owns it (`row_ownership::Keepers`), in
    /// the same order.
    pub fn solution_on_ranks(
        &self,
        x: &[f64],
        (bodies, distributions, reads): (&[&AssembledBody], &[&Distribution], &[NodeGather]),
        pairs: &[Pair],
        dim: usize,
        relative_residual: f64,
    ) -> Result<CoupledSolution, ContactError> {
        let mut local = vec![0];
        for distribution in distributions {
            local.push(local.last().unwrap() + distribution.local());
        }
        let n = *local.last().unwrap();
        let rigid = self.rigid_values(&x[n..]);
        let u: Vec<Vec<f64>> = (0..self.num_bodies())
            .map(|k| {
                let mut u = x[local[k]..local[k + 1]].to_vec();
                for (column, a) in bodies[k].rigid.iter().zip(&rigid[k]) {
                    for row in column
                        .dofs
                        .iter()
                        .filter_map(|&d| distributions[k].own_row(d))
                    {
                        u[row] = *a;
                    }
                }
                u
            })
            .collect();
        let traction = self.tractions(&x[n..], pairs, dim);
        let mut forces: Vec<Vec<f64>> = (reads.iter())
            .map(|read| vec![0.0; dim * read.nodes().len()])
            .collect();
        for (pair, on_pair) in pairs.iter().zip(&traction) {
            let (a, b) = (pair.primary, pair.secondary);
            add_pair_forces(pair.coupling, on_pair, |side, node, f| {
                let k = [a, b][side];
                let place = (reads[k].place(node))
                    .expect("the interface forces act at the contact surfaces' nodes");
                add_at(&mut forces[k], dim, place, f);
            });
        }
        let gathered = |what: &str, result: Result<Vec<f64>, crate::linalg::LinalgError>| {
            result.map_err(|e| ContactError::Linalg(format!("gathering a body's {what}: {e}")))
        };
        let mut on_nodes = Vec::with_capacity(reads.len());
        let mut contact_force = Vec::with_capacity(reads.len());
        for (k, read) in reads.iter().enumerate() {
            let values = gathered("displacement", read.from_rows(&u[k]))?;
            on_nodes.push(NodeValues::new(read.nodes().to_vec(), values, dim));
            let force = gathered("interface forces", read.from_owners(&forces[k]))?;
            let entries = (read.nodes().iter())
                .flat_map(|&node| (0..dim).map(move |c| dim * node as usize + c))
                .zip(force)
                .filter(|&(_, v)| v != 0.0);
            let len = bodies[k].f.len();
            contact_force.push(LoadVector::from_entries(len, entries.collect()));
        }
        Ok(CoupledSolution {
            u,
            on_nodes: Some(on_nodes),
            traction,
            contact_force,
            rigid,
            relative_residual,
        })
    }

    /// Each body's force-controlled displacements from `x`'s part after the displacements.
    fn rigid_values(&self, after: &[f64]) -> Vec<Vec<f64>> {
        (0..self.num_bodies())
            .map(|k| after[self.rigid_offsets[k]..self.rigid_offsets[k + 1]].to_vec())
            .collect()
    }

    /// Each pair's tractions at its active nodes from the multipliers `lambda / s` (the part of
    /// `x` after the displacements).
    fn tractions(&self, multipliers: &[f64], pairs: &[Pair], dim: usize) -> Vec<Vec<[f64; 3]>> {
        let mut traction = Vec::with_capacity(pairs.len());
        for (p, pair) in pairs.iter().enumerate() {
            let coupling = pair.coupling;
            let multipliers = &multipliers[self.multiplier_offsets[p]..];
            let first = coupling.node_offsets();
            let on_pair: Vec<[f64; 3]> = (0..coupling.primary_nodes.len())
                .map(|k| {
                    let mut lambda = [0.0; 3];
                    for (c, value) in lambda.iter_mut().enumerate().take(dim) {
                        for (j, multiplier) in coupling.multipliers[k].iter().enumerate() {
                            let term = self.s * multipliers[first[k] + j] * multiplier.force[c];
                            *value = if j == 0 { term } else { *value + term };
                        }
                    }
                    lambda
                })
                .collect();
            traction.push(on_pair);
        }
        traction
    }
}

/// Where one pair's blocks go in the system: its index, its first multiplier, and the first
/// unknown of its primary and secondary bodies.
struct Placement {
    pair: usize,
    first_multiplier: usize,
    primary: usize,
    secondary: usize,
    /// The first rigid unknown (multiplier) of the primary and of the secondary.
    primary_rigid: usize,
    secondary_rigid: usize,
}

/// The force a unit traction of one component at one active primary node puts on the bodies.
pub struct UnitLoad {
    pub key: MultiplierKey,
    /// The multipliers whose columns it is part of, each with its weight there.
    pub multipliers: Vec<(usize, f64)>,
    /// `(row < offsets[N], force)`, unscaled; rows of prescribed dofs left out.
    pub load: Vec<(usize, f64)>,
}

/// Rows of C that read the same jump of one active node through the interpolation, `J_i = u1_i
/// - (R12 u2)_i`: a sticking node's two tangential rows in 3D, which read each of its
/// components. The jump is read once and each row takes its projection, where entries of `C`
/// would read the `R12` row once per row (a row of `R12` reaches hundreds of secondary nodes).
/// A node's rows share a read only when two of them read a component in common: tied rows
/// (one component each) stay entries of `C`.
pub struct SharedJump {
    /// `(multiplier, t * row)` of each row: its direction, scaled.
    pub rows: Vec<(usize, [f64; 3])>,
    /// `(component, unknown, coefficient)`: component `c` of the jump is the sum of the
    /// coefficients times the unknowns (`1` at the node's own dof, `-w` at the secondary's; a
    /// force-controlled dof's part is in `D`).
    pub reads: Vec<(usize, usize, f64)>,
}

/// The coupling blocks of the pairs, added one pair at a time.
struct PairBlocks<'o> {
    /// Where this rank's rows are, in a distributed run (`None`: every unknown, as it is).
    ownership: Option<&'o RowOwnership>,
    /// [`CoupledSystem::columns`].
    columns: Vec<Vec<(MultiplierKey, f64)>>,
    /// [`CoupledSystem::unit_loads`].
    unit_loads: Vec<UnitLoad>,
    /// [`CoupledSystem::c`].
    c: Vec<(usize, usize, f64)>,
    /// [`CoupledSystem::shared_jumps`].
    shared_jumps: Vec<SharedJump>,
    /// [`CoupledSystem::rows`].
    rows: Vec<[f64; 3]>,
    /// [`CoupledSystem::d`].
    d: Vec<f64>,
    /// [`CoupledSystem::d_coupled`].
    d_coupled: Vec<(usize, usize, f64)>,
    /// [`CoupledSystem::g`].
    g: Vec<f64>,
}

impl<'o> PairBlocks<'o> {
    fn new(m: usize, ownership: Option<&'o RowOwnership>) -> Self {
        Self {
            ownership,
            columns: vec![Vec::new(); m],
            unit_loads: Vec::new(),
            c: Vec::new(),
            shared_jumps: Vec::new(),
            rows: vec![[0.0; 3]; m],
            d: vec![0.0; m],
            d_coupled: Vec::new(),
            g: vec![0.0; m],
        }
    }

    /// Where the entry of the bodies' unknown `global` goes: `global` itself, or its place
    /// among this rank's rows (`None`: another rank's).
    fn place(&self, global: usize) -> Option<usize> {
        match self.ownership {
            None => Some(global),
            Some(ownership) => ownership.place(global),
        }
    }

    /// The blocks of one pair at `place`, its rows scaled by `t` (its columns are scaled by `s`
    /// as they are read, [`CoupledSystem::b_entries`]):
    /// `-M_a lambda` on the primary and `+M_b R_ba lambda` on the secondary, one unit force
    /// per active node and component combined per multiplier; the constraint `u_a - R_ab u_b =
    /// d` (tied) or its normal component (frictionless). Rows of prescribed dofs carry no
    /// coupling; a dropped multiplier gets `D = t` and nothing else. At a dof of a
    /// force-controlled group the displacement is the group's unknown `a`, so the constraint's
    /// coefficient there and the force on it (which the group's reaction includes) go to the
    /// entries of `D` between the multiplier and `a` (scaled by `t` and `s` as the row and
    /// column they stand for).
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        coupling: &Coupling,
        primary: &AssembledBody,
        secondary: &AssembledBody,
        place: &Placement,
        dim: usize,
        s: f64,
        t: f64,
    ) {
        let first = place.first_multiplier;
        let sides = [
            Side::new(primary, place.primary, place.primary_rigid),
            Side::new(secondary, place.secondary, place.secondary_rigid),
        ];
        let node_offsets = coupling.node_offsets();
        for (k, &node) in coupling.primary_nodes.iter().enumerate() {
            // The unit loads of this node so far, by key: its multipliers share them.
            let mut node_loads: HashMap<MultiplierKey, usize> = HashMap::new();
            let mut shared = shares_jump(&coupling.multipliers[k]).then(|| SharedJump {
                rows: Vec::new(),
                reads: Vec::new(),
            });
            // The components of the shared jump read so far.
            let mut components_read: Vec<usize> = Vec::new();
            for (j, law_multiplier) in coupling.multipliers[k].iter().enumerate() {
                let multiplier = first + node_offsets[k] + j;
                self.rows[multiplier] = law_multiplier.row;
                if coupling.is_dropped(k, law_multiplier, primary, dim) {
                    self.d[multiplier] = t;
                    continue;
                }
                // The multiplier's own term in its row (the unknown is `lambda / s`).
                self.d[multiplier] = t * s * law_multiplier.compliance;
                for c in 0..dim {
                    let (weight, row_weight) = (law_multiplier.force[c], law_multiplier.row[c]);
                    if weight == 0.0 && row_weight == 0.0 {
                        continue;
                    }
                    let dof = dim * node + c;
                    if weight != 0.0 {
                        // The column: the unit force of component c at the node, on both
                        // bodies.
                        let key = MultiplierKey::Traction {
                            pair: place.pair,
                            node,
                            component: c,
                        };
                        self.columns[multiplier].push((key, weight));
                        // The node's unit load of component c, made by its first multiplier
                        // that has one and shared by the others; the forces on a
                        // force-controlled group are each multiplier's own entries of `D`.
                        let shared_load = node_loads.get(&key).copied();
                        let mut load = Vec::new();
                        let forces = std::iter::once((0, dof, -coupling.areas1[k])).chain(
                            (coupling.loads2[k].iter())
                                .map(|&(node2, value)| (1, dim * node2 + c, value)),
                        );
                        for (side, dof, value) in forces {
                            match sides[side].unknown(dof) {
                                Unknown::Free(row) if shared_load.is_none() => {
                                    load.extend(self.place(row).map(|row| (row, value)))
                                }
                                Unknown::Forced(a) => {
                                    self.d_coupled.push((a, multiplier, s * value * weight));
                                }
                                _ => {}
                            }
                        }
                        match shared_load {
                            Some(unit) => {
                                self.unit_loads[unit].multipliers.push((multiplier, weight))
                            }
                            None => {
                                node_loads.insert(key, self.unit_loads.len());
                                self.unit_loads.push(UnitLoad {
                                    key,
                                    multipliers: vec![(multiplier, weight)],
                                    load,
                                });
                            }
                        }
                    }
                    if row_weight == 0.0 {
                        continue;
                    }
                    // The row: component c of the jump between the node and its secondary
                    // point, along the row's direction.
                    self.g[multiplier] += t * row_weight * coupling.gaps[k][c];
                    if let Some(jump) = shared
                        .as_mut()
                        .filter(|_| law_multiplier.reads == Reads::Interpolated)
                    {
                        if jump.rows.last().is_none_or(|&(last, _)| last != multiplier) {
                            jump.rows
                                .push((multiplier, law_multiplier.row.map(|r| t * r)));
                        }
                        let first_read = !components_read.contains(&c);
                        let reads = std::iter::once((0, dof, 1.0)).chain(
                            (coupling.reads(k, law_multiplier).iter())
                                .map(|&(node2, w)| (1, dim * node2 + c, -w)),
                        );
                        for (side, dof, coefficient) in reads {
                            match sides[side].unknown(dof) {
                                Unknown::Forced(a) => (self.d_coupled).push((
                                    multiplier,
                                    a,
                                    t * row_weight * coefficient,
                                )),
                                _ if first_read => (jump.reads).extend(
                                    (self.place(sides[side].offset + dof))
                                        .map(|column| (c, column, coefficient)),
                                ),
                                _ => {}
                            }
                        }
                        if first_read {
                            components_read.push(c);
                        }
                        continue;
                    }
                    let reads = std::iter::once((0, dof, t * row_weight)).chain(
                        (coupling.reads(k, law_multiplier).iter())
                            .map(|&(node2, w)| (1, dim * node2 + c, -t * w * row_weight)),
                    );
                    for (side, dof, value) in reads {
                        match sides[side].unknown(dof) {
                            Unknown::Forced(a) => self.d_coupled.push((multiplier, a, value)),
                            // A prescribed dof's unknown holds its value (`K_c`'s row is its
                            // diagonal).
                            _ => self.c.extend(
                                (self.place(sides[side].offset + dof))
                                    .map(|column| (multiplier, column, value)),
                            ),
                        }
                    }
                }
            }
            // A jump none of whose reads is this rank's adds nothing here.
            self.shared_jumps
                .extend(shared.filter(|jump| !jump.rows.is_empty() && !jump.reads.is_empty()));
        }
    }
}

/// Whether two of a node's `multipliers` read a component of its interpolated jump in common
/// ([`SharedJump`]).
fn shares_jump(multipliers: &[Multiplier]) -> bool {
    let reading: Vec<&Multiplier> = (multipliers.iter())
        .filter(|m| m.reads == Reads::Interpolated)
        .collect();
    reading.iter().enumerate().any(|(a, first)| {
        reading[a + 1..]
            .iter()
            .any(|second| (0..3).any(|c| first.row[c] != 0.0 && second.row[c] != 0.0))
    })
}

/// What stands for a body dof in the coupled system.
enum Unknown {
    /// Its own unknown: this row of the system.
    Free(usize),
    /// A force-controlled group's displacement: this multiplier.
    Forced(usize),
    /// A Dirichlet value.
    Prescribed,
}

/// One body of a pair as the pair's blocks see it.
struct Side<'a> {
    body: &'a AssembledBody,
    /// Its first unknown.
    offset: usize,
    /// The rigid unknown of each of its force-controlled dofs.
    forced: HashMap<usize, usize>,
}

impl<'a> Side<'a> {
    /// `body`, its unknowns from `offset`, its rigid unknowns from multiplier `first_rigid`.
    fn new(body: &'a AssembledBody, offset: usize, first_rigid: usize) -> Self {
        let forced = (body.rigid.iter().enumerate())
            .flat_map(|(r, rigid)| rigid.dofs.iter().map(move |&dof| (dof, first_rigid + r)))
            .collect();
        Self {
            body,
            offset,
            forced,
        }
    }

    fn unknown(&self, dof: usize) -> Unknown {
        if !self.body.constraints.is_fixed(dof) {
            Unknown::Free(self.offset + dof)
        } else if let Some(&a) = self.forced.get(&dof) {
            Unknown::Forced(a)
        } else {
            Unknown::Prescribed
        }
    }
}

impl PairBlocks<'_> {
    /// The blocks of `body`'s force-controlled components (the module doc), body `k` of the
    /// system, its unknowns from `offset`, its rigid unknowns from multiplier `first`; `s` is
    /// the multipliers' scaling (which the weight `1 / s` cancels) and the step's `factors`
    /// scale the force.
    fn add_rigid(
        &mut self,
        k: usize,
        body: &AssembledBody,
        first: usize,
        offset: usize,
        s: f64,
        factors: &StepFactors,
    ) {
        for (r, rigid) in body.rigid.iter().enumerate() {
            let multiplier = first + r;
            let key = MultiplierKey::Rigid { body: k, index: r };
            self.columns[multiplier].push((key, 1.0 / s));
            let load: Vec<(usize, f64)> = (rigid.column.iter())
                .filter_map(|&(dof, v)| Some((self.place(offset + dof)?, v)))
                .collect();
            self.c
                .extend(load.iter().map(|&(row, v)| (multiplier, row, v)));
            self.unit_loads.push(UnitLoad {
                key,
                multipliers: vec![(multiplier, 1.0 / s)],
                load,
            });
            self.d[multiplier] = rigid.diagonal;
            (self.d_coupled).extend(
                rigid
                    .coupled
                    .iter()
                    .map(|&(b, v)| (multiplier, first + b, v)),
            );
            self.g[multiplier] = body.rigid_rhs(r, factors);
        }
    }
}

/// `out = K_c x` for one body: by its assembled `K_c`, or where a distributed solver holds it
/// instead (`AssembledBody::stiffness`), by that solver.
pub fn stiffness_product(
    body: &AssembledBody,
    solver: Option<&BodySolver>,
    x: &[f64],
    out: &mut [f64],
) -> Result<(), ContactError> {
    match (body.stiffness.whole(), solver) {
        (Some(k_c), _) => {
            symmetric_product(k_c, x, out);
            Ok(())
        }
        (None, Some(solver)) => solver
            .multiply(x, out)
            .map_err(|e| ContactError::Linalg(format!("a body's stiffness product: {e}"))),
        (None, None) => Err(released()),
    }
}

/// A body's assembled `K_c`, for what only it can do (a factor, an assembled matrix).
pub fn assembled(body: &AssembledBody) -> Result<&SparseColMat<usize, f64>, ContactError> {
    body.stiffness.whole().ok_or_else(released)
}

fn released() -> ContactError {
    ContactError::Linalg(
        "a body's stiffness is distributed among the ranks (PETSc holds it), and this step needs \
         it whole"
            .to_string(),
    )
}

/// `out = K x` for a symmetric `K` stored by compressed columns: entry `j` is column `j` dotted
/// with `x`, so the rows are independent and computed in parallel, each in a fixed order (the
/// same result for any number of threads).
pub fn symmetric_product(k: &SparseColMat<usize, f64>, x: &[f64], out: &mut [f64]) {
    let (symbolic, values) = k.parts();
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    out.par_iter_mut().enumerate().for_each(|(j, o)| {
        *o = (col_ptr[j]..col_ptr[j + 1])
            .map(|p| values[p] * x[row_idx[p]])
            .sum();
    });
}
