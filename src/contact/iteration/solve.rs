//! The INTERNODES active-set loop: a primal-dual active set method (a semismooth Newton method
//! on the nodal complementarity conditions; Hüeber and Wohlmuth 2005) over interface operators
//! built once (`crate::contact::coupled::interface`), with its answer checked by independent
//! measures ([`crate::contact::verify::checks`]).
//!
//! ```text
//! A <- primary candidates that touch or penetrate in the reference configuration
//! L <- the gap of every primary candidate linearized at u = 0            (frictionless)
//! repeat
//!   1. coupling of A: constraint rows from L (frictionless: node to segment on the secondary
//!      facet each node projects onto; tied: rows of R12 with the correction e), traction
//!      columns through the transfer (R21 or R12^T), lumped M1
//!   2. solve the coupled system for u1, u2, lambda
//!   3. gaps of every candidate: geometric g (closest point, deformed); L <- linearized at u
//!      (tied: e <- g - g_lin); the slide s of the surfaces over each other
//!   4. A' <- {i in A : p_i >= -tol_t p_max}  +  {i not in A : g_i < -tol_p h_i}
//!   5. if A' = A, settled, and s rounded to the pairing grid (0.05 h; none below 0.05 h) is
//!      not the operators' pairing, nor one this solve left: pair the operators again for it
//!      (each node moved by it), A' <- A
//! until A' = A and every active node lies on the other surface (|g_i| <= 0.01 tol_p h_i),
//!   or A' = A and |g_i| stopped shrinking (by half, twice): converged within tol_p h_i,
//!   stalled beyond
//! check: the residuals of the discrete problem (penetration of both bodies, tension,
//!   complementarity, equilibrium) decide the status; the accuracy indicators are reported
//! ```
//!
//! Under the penalty method (`crate::contact::method`) every row carries its own term `p_i / eps`
//! and "on the other surface" reads `|g_i + p_i / eps|`: the loop is the same.
//!
//! **Why it converges.** On a fixed active set, step 3 linearizes the very gap step 4 and the
//! checks measure (`crate::contact::geometry::gap`): steps 1-3 are Newton's method on `g_A(u) = 0`,
//! exact in one step where the secondary surface is flat and quadratic where it is smooth; on
//! a P1 surface the gap is piecewise linear, and a node on an edge can hold the error at the
//! size of the kink, which the stall test accepts within the tolerance. Over active sets,
//! step 4 is the semismooth Newton step of the complementarity function (below). The former
//! constraint, the rows of `R12` with the gap correction `e = g - g_lin` of the last iterate,
//! is a fixed-point iteration on `e` that contracts only where `R12` reproduces the P1
//! surface; it diverged at the ends of two blocks pressed together, and tied contact, which
//! keeps it, is judged by the same stall test.
//!
//! Step 5 is what lets the bodies slide: the operators pair each node with the point of the
//! other surface it faces, and a body pushed sideways touches the other elsewhere than where it
//! started. The operators change only when the active set has settled, so each pairing is a
//! fixed complementarity problem for the update of step 4.
//!
//! Step 4 is the primal-dual active set update for the nodal complementarity function
//! `C_i = p_i - max(0, p_i - c g_i)`, `c = E*/h`: a node is active next when `p_i - c g_i > 0`.
//! At an active node the constraint holds `g_i = 0`, at an inactive one `p_i = 0`, so the test
//! reads `p_i > 0` on A and `g_i < 0` off it, and `c` drops out; the tolerances make the two
//! tests robust to round-off. Removal and addition happen in one update (`docs/method.md` 3.3).
//! What differs from earlier INTERNODES contact loops: the operators do not change with A
//! (rebuilding them for every active set moves the discrete problem from one iteration to the
//! next), the pressure `p_i = -lambda_i . n_i` tested is the unknown of the system (lumped
//! interface mass, `crate::contact::geometry::surface`), and the gap is the geometric one, for the
//! loop and the checks alike.
//!
//! An update that would return to an active set seen before first keeps active (pins, for the
//! rest of the solve) the nodes it removes for tension that had been removed before and came
//! back for penetration, and leaves their tension to the certificate: at the rim of a contact
//! zone a node can be in tension while active and penetrate while inactive (seen with tied
//! contact between dissimilar materials: 2% of the peak pressure, then 4e-3 h), and no active
//! set satisfies both tests. If the set still repeats, it takes a single switch instead:
//! only the node with the largest violation (penetration over `h`, tension over `p_max`)
//! changes; if that set was seen too the loop stops as [`ContactStatus::Cycling`]. It never
//! declares convergence. A gap error that stops contracting on one active set beyond the
//! tolerance is [`ContactStatus::Stalled`]; running out of iterations is
//! [`ContactStatus::IterationLimit`]; active nodes held a spacing or more off the other
//! surface on two solves in a row, the second not contracting (or followed by an interface
//! system that cannot be solved accurately), is [`ContactStatus::Unstable`].

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::time::Instant;

use crate::contact::ContactError;
use crate::contact::active_set::{ActiveSet, FrictionHistory, SETTLED, Update};
use crate::contact::coupled::coupled_krylov::Tightness;
use crate::contact::coupled::coupled_solver::{self, BodyFactors};
use crate::contact::coupled::half_space::{compliance_factor, force_controlled_set, predicted_set};
use crate::contact::coupled::interface::{Constraint, InterfaceOperators};
use crate::contact::coupled::row_ownership::Keepers;
use crate::contact::coupled::system::{CoupledSolution, CoupledSystem, Coupling, Pair};
use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::gap::{GapRow, RowNormal, gap_rows, gaps_and_rows, geometric_gaps};
use crate::contact::geometry::rbf_patch::BlockShare;
use crate::contact::geometry::surface::ContactSurface;
use crate::contact::geometry::walls::{HeldWall, walls};
use crate::contact::iteration::safeguard::{CONTRACTION, Safeguard, Step};
use crate::contact::iteration::walls::PairWalls;
use crate::contact::law::coulomb::Turning;
use crate::contact::law::{ContactLaw, NodeStates, Tangential, coulomb};
use crate::contact::method::Enforcement;
use crate::contact::problem::{CORNER_TURN, ContactProblem};
use crate::contact::settings::{ContactSettings, CoupledSolver, Transfer};
use crate::contact::solution::{
    ContactSolution, ContactStatus, FrictionFields, FrictionState, IterationRecord, LinearSolvers,
    PhaseSeconds,
};
use crate::contact::verify::checks::{self, certify, contact_status};
use crate::contact::verify::post::{self, LastIterate};
use crate::elastic::{
    AssembledBody, ElasticProblem, SolveStats, SolverSettings, StepFactors, assemble,
};
use crate::fem::LoadVector;
use crate::fem::rigid_modes::RigidModes;
use crate::linalg::{BodySolverKind, NodeGather};
use crate::mesh::BodyMesh;
use crate::progress::Heartbeat;

/// [`ContactSolver::check_held`]: a free motion is held when the Gram matrix's eigenvalue along
/// it, per row, exceeds this. Measured (2026-11-28): a block resting flat, its rotation 0.15; a
/// half-disc turning about its centre, with the disc's own normals 0 (2D) and a hemisphere's
/// 3e-8 to 6e-8 (3D: P1 vertex normals are radial to about 2e-4); along the flat block's
/// normals the hemisphere's turn still reads 3e-6 to 3e-4, which is why the body's own normals
/// are tested too. A rotation held by a zone 2% of the body's size across reads about 3e-5.
const HELD_PER_ROW: f64 = 1e-6;

/// The rigid motions (combinations of [`RigidModes`], one per column) that `body`'s supports
/// leave free: those that vanish on its prescribed dofs and move each force-controlled group
/// uniformly along its component (the group is one plate); its rigid-mode pins hold nothing.
/// They are the null space of the Gram matrix of those conditions' rows.
fn motions_left_free(mesh: &BodyMesh, body: &AssembledBody) -> nalgebra::DMatrix<f64> {
    let (dim, coords) = (body.dim, &mesh.coords);
    let modes = RigidModes::of(mesh);
    let count = modes.count();
    let value = |dof: usize| -> Vec<f64> {
        let at = modes.at(&coords[dof / dim]);
        at.iter().map(|m| m[dof % dim]).collect()
    };
    let mut gram = nalgebra::DMatrix::<f64>::zeros(count, count);
    let mut add = |row: Vec<f64>| {
        let row = nalgebra::DVector::from_vec(row);
        gram += &row * row.transpose();
    };
    let rigid: HashMap<usize, usize> = (body.rigid.iter().enumerate())
        .flat_map(|(r, rigid)| rigid.dofs.iter().map(move |&dof| (dof, r)))
        .collect();
    for dof in (0..body.f_c.len()).filter(|&d| body.constraints.is_fixed(d)) {
        if !rigid.contains_key(&dof) {
            add(value(dof));
        }
    }
    for group in body.rigid.iter().filter(|rigid| !rigid.pin) {
        let first = value(group.dofs[0]);
        for &dof in &group.dofs[1..] {
            add(value(dof).iter().zip(&first).map(|(a, b)| a - b).collect());
        }
    }
    let eigen = nalgebra::SymmetricEigen::new(gram);
    let largest = eigen.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let free: Vec<usize> = (0..count)
        .filter(|&i| eigen.eigenvalues[i] <= 1e-10 * largest || largest == 0.0)
        .collect();
    nalgebra::DMatrix::from_fn(count, free.len(), |r, c| eigen.eigenvectors[(r, free[c])])
}

/// A point of an active node and the directions its contact holds there
/// ([`ContactSolver::check_held`]).
type HeldRow = ([f64; 3], Vec<[f64; 3]>);

/// The grid the pairing follows the slide on, and the slide below which the surfaces are
/// paired unslid, in spacings of the active primary nodes (the smallest): [`pairing_slide`].
const PAIRING_STEP_OVER_H: f64 = 0.05;

/// The slide the interface operators of a pair whose surfaces have slid by `slide`
/// ([`InterfaceOperators::slide`]) are paired for, `h` the smallest spacing of its `active`
/// primary nodes: none while `|slide| <= PAIRING_STEP_OVER_H h`, otherwise each component
/// rounded to a multiple of `PAIRING_STEP_OVER_H h`. A function of the answer (its slide and
/// its contact zone), the same on every path to it (one solve or load steps, force or
/// displacement control), so that two paths to one answer solve the same discrete problem;
/// within 0.043 spacings of the slide (half a step along each of three components). Following
/// the slide itself (pairing again once it moved 0.05 spacings from the last pairing) left
/// each path on a pairing made where it happened to settle. Unslid below one step, as that
/// rule was: the Poisson expansion of flush blocks slides their surfaces by a few hundredths of
/// a spacing, and pairing a flush block's end node past the other's end unbalanced a stack's
/// forces by 2%.
fn pairing_slide(slide: &[f64; 3], primary: &ContactSurface, active: &[usize]) -> [f64; 3] {
    let h = smallest_spacing(primary, active);
    let step = PAIRING_STEP_OVER_H * h;
    let length = slide.iter().map(|s| s * s).sum::<f64>().sqrt();
    if !(step.is_finite() && step > 0.0) || length <= step {
        return [0.0; 3];
    }
    slide.map(|s| (s / step).round() * step)
}

/// The smallest spacing of the `active` primary nodes (infinite when there is none): the
/// length the slide and the pairing are measured in.
fn smallest_spacing(primary: &ContactSurface, active: &[usize]) -> f64 {
    (active.iter().map(|&i| primary.spacing[i])).fold(f64::INFINITY, f64::min)
}

/// How far the slide `now` is from the operators' `slid`, over the smallest spacing of the
/// `active` primary nodes.
fn pairing_drift(
    slid: &[f64; 3],
    now: &[f64; 3],
    primary: &ContactSurface,
    active: &[usize],
) -> f64 {
    let h = smallest_spacing(primary, active);
    let distance = (0..3)
        .map(|k| (now[k] - slid[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    if h.is_finite() { distance / h } else { 0.0 }
}

/// Contact pairs set up once: each body in contact assembled once (and, on the Schur path,
/// factored), however many pairs it is in, and each pair's interface operators built. Every
/// load step reuses all of it: loads and prescribed displacements enter the system linearly,
/// `f_c(s) = sum_p s_p f_c_p` over the load paths `p`, while `K`, its factors and the interface
/// geometry do not change.
///
/// The loop decides all pairs together: one coupled system, one active set. That set numbers
/// the primary candidates of the pairs one after another (pair `p`'s node `i` is
/// `offsets[p] + i`), so that the safeguard against repeats sees the whole set; each pair
/// keeps its own operators, linearized gaps and tolerances.
pub struct ContactSolver<'a> {
    /// The contact pairs, in the case's order.
    pub(super) pairs: &'a [ContactProblem<'a>],
    solver: SolverSettings,
    /// Each body in contact, once, in the order the pairs first name it.
    bodies: Vec<AssembledBody>,
    stats: Vec<SolveStats>,
    /// Where each body's elastic problem is: the first pair that names it, and its side (0 the
    /// primary, 1 the secondary).
    origin: Vec<(usize, usize)>,
    /// Each pair's primary and secondary body (indices into `bodies`).
    pair_bodies: Vec<[usize; 2]>,
    /// The first index of each pair's candidates in the loop's active set, then their total.
    offsets: Vec<usize>,
    factors: Option<BodyFactors>,
    /// The force-controlled components `(body, index into its rigid columns)` that nothing but
    /// the contacts hold: with no node in contact the system is singular.
    held_by_contact: Vec<(usize, usize)>,
    /// Each body that only its contacts hold along some rigid motions, with those motions
    /// (combinations of `crate::fem::rigid_modes::RigidModes`, one per column): the motions
    /// its Dirichlet supports leave free.
    free_motions: Vec<(usize, nalgebra::DMatrix<f64>)>,
    /// Each pair's operators, paired for the slide of the last solve; a solve without a start
    /// pairs them again unslid, so that it does not depend on earlier solves.
    operators: Vec<InterfaceOperators>,
    /// Which ranks keep the transfers' entries at each pair's secondary candidates, in a
    /// distributed run (`crate::contact::coupled::row_ownership::Keepers`); `None`: this
    /// process keeps them all.
    kept: Vec<Option<Keepers>>,
    /// Each pair's contact law.
    laws: Vec<ContactLaw>,
    /// How each pair's law is enforced.
    methods: Vec<Enforcement>,
    /// How each pair's secondary receives its force (`crate::contact::Transfer`, resolved).
    transfers: Vec<Transfer>,
    /// In a distributed run, how each body's values at the nodes the contact geometry reads
    /// (its boundary's and its contact surfaces': [`geometry_nodes`]) reach every rank after a
    /// solve; `None` on one process.
    reads: Option<Vec<NodeGather>>,
}

/// The geometric gap and the gap row of every primary candidate at the displacements `u`
/// (`crate::contact::geometry::gap::gaps_and_rows`). With `shared` (a distributed run) rank `r`
/// of `N` measures the candidates `i` with `i % N == r` and receives the others' from the
/// ranks that measured them (collective: one `MPI_Allgatherv`), the same bits as measured
/// alone.
fn measure_gaps(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    u: [BodyDisplacement; 2],
    row_normal: RowNormal,
    shared: bool,
) -> Result<(Vec<f64>, Vec<GapRow>), ContactError> {
    let m = primary.len();
    let ranks = crate::parallel::ranks();
    if !shared || ranks.size == 1 {
        let all: Vec<usize> = (0..m).collect();
        return Ok(gaps_and_rows(primary, secondary, u, row_normal, &all)
            .into_iter()
            .unzip());
    }
    let of_rank = |r: usize| (r..m).step_by(ranks.size);
    let mine: Vec<usize> = of_rank(ranks.rank).collect();
    // Each candidate as `2 dim + 6` values: its gap, its row's normal, gap and target, and its
    // closest point's facet corners with their barycentric coordinates (`dim` of them).
    let dim = primary.dim;
    let width = 2 * dim + 6;
    let mut sent = Vec::with_capacity(width * mine.len());
    for (gap, row) in gaps_and_rows(primary, secondary, u, row_normal, &mine) {
        debug_assert_eq!(row.corners.len(), dim);
        sent.push(gap);
        sent.extend(row.normal);
        sent.extend([row.gap, row.target]);
        sent.extend(row.corners.iter().flat_map(|&(s, b)| [s as f64, b]));
    }
    let counts: Vec<usize> = (0..ranks.size).map(|r| width * of_rank(r).len()).collect();
    let arrived = crate::parallel::all_gather(&sent, &counts)
        .map_err(|e| ContactError::Linalg(format!("gathering the gaps of the candidates: {e}")))?;
    let mut measured: Vec<Option<(f64, GapRow)>> = vec![None; m];
    let order = (0..ranks.size).flat_map(of_rank);
    for (i, v) in order.zip(arrived.chunks_exact(width)) {
        let row = GapRow {
            normal: [v[1], v[2], v[3]],
            gap: v[4],
            target: v[5],
            corners: v[6..]
                .chunks_exact(2)
                .map(|c| (c[0] as usize, c[1]))
                .collect(),
        };
        measured[i] = Some((v[0], row));
    }
    Ok(measured
        .into_iter()
        .map(|g| g.expect("every candidate measured"))
        .unzip())
}

/// The nodes of a body at which the contact geometry reads its displacement and the interfaces
/// put their forces: its closed boundary's (inside or outside) and its contact surfaces', which
/// lie on the boundary unless a surface group is inside the body. Increasing.
fn geometry_nodes(surfaces: &[&ContactSurface]) -> Vec<u32> {
    let mut nodes: Vec<u32> = (surfaces.iter())
        .flat_map(|s| s.nodes.iter().chain(s.boundary.nodes()))
        .map(|&node| node as u32)
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// The interface operators of `problem`, paired with the primary surface slid by `slid` over
/// the secondary ([`InterfaceOperators::slide`]), their interpolations' rows shared among the
/// ranks as `share` says (collective in a distributed run).
fn pair(
    problem: &ContactProblem,
    slid: [f64; 3],
    share: BlockShare,
) -> Result<InterfaceOperators, ContactError> {
    InterfaceOperators::new(
        &problem.primary_surface,
        &problem.secondary_surface,
        problem.settings.rbf_radius,
        problem.normal_weights(),
        (problem.transfer().transfer, share),
        slid,
    )
}

/// How the ranks share the interpolations' rows: among all of them in a distributed run
/// (`shared`), on one process every row.
fn interface_share(shared: bool) -> BlockShare {
    let ranks = crate::parallel::ranks();
    match shared {
        true => BlockShare {
            rank: ranks.rank,
            size: ranks.size,
        },
        false => BlockShare::ALL,
    }
}

/// The nodes of a body whose displacements the constraint rows read: its candidate surfaces',
/// and the nodes a force-controlled group's row reads (its column `k`).
fn read_nodes(surfaces: &[&ContactSurface], body: &AssembledBody) -> Vec<usize> {
    let mut nodes: Vec<usize> = surfaces.iter().flat_map(|s| s.nodes.clone()).collect();
    for rigid in &body.rigid {
        nodes.extend(rigid.column.iter().map(|&(dof, _)| dof / body.dim));
    }
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// The settings the pairs share: the loop and its coupled solve are one for all of them.
fn check_shared_settings(pairs: &[ContactProblem]) -> Result<(), ContactError> {
    let Some(first) = pairs.first() else {
        return Err(ContactError::PairSettings(
            "no contact pair to solve".into(),
        ));
    };
    for (p, pair) in pairs.iter().enumerate().skip(1) {
        let (a, b) = (&first.settings, &pair.settings);
        let differs = [
            ("solver", a.solver != b.solver),
            ("max_iterations", a.max_iterations != b.max_iterations),
            (
                "krylov_max_iterations",
                a.krylov_max_iterations != b.krylov_max_iterations,
            ),
        ];
        if let Some((key, _)) = differs.iter().find(|(_, differs)| *differs) {
            return Err(ContactError::PairSettings(format!(
                "contact pair {} sets {key} otherwise than pair 1: the active-set loop and its \
                 coupled solve are shared by all pairs, give every pair the same {key}",
                p + 1
            )));
        }
    }
    Ok(())
}

impl<'a> ContactSolver<'a> {
    pub fn new(
        pairs: &'a [ContactProblem<'a>],
        solver: &SolverSettings,
    ) -> Result<Self, ContactError> {
        check_shared_settings(pairs)?;
        for problem in pairs {
            problem.settings.validate()?;
        }
        let settings = &pairs[0].settings;
        let mut origin: Vec<(usize, usize)> = Vec::new();
        let mut names: Vec<&str> = Vec::new();
        let mut pair_bodies = Vec::with_capacity(pairs.len());
        for (p, problem) in pairs.iter().enumerate() {
            let mut sides = [0; 2];
            for (side, elastic) in [&problem.primary, &problem.secondary].iter().enumerate() {
                let name = elastic.body.name.as_str();
                sides[side] = match names.iter().position(|&n| n == name) {
                    Some(k) => k,
                    None => {
                        names.push(name);
                        origin.push((p, side));
                        names.len() - 1
                    }
                };
            }
            pair_bodies.push(sides);
        }
        let elastic = |(p, side): (usize, usize)| match side {
            0 => &pairs[p].primary,
            _ => &pairs[p].secondary,
        };
        let mut stats = vec![SolveStats::default(); origin.len()];
        let mut bodies = (origin.iter().zip(&mut stats))
            .map(|(&at, stats)| assemble(elastic(at), stats, false))
            .collect::<Result<Vec<_>, _>>()?;
        let dofs = bodies.iter().map(|b| b.f_c.len()).max().unwrap_or(0);
        let dim = pairs[0].primary_surface.dim;
        let kind = solver.body.resolve(dim, dofs);
        let surfaces_of = |k: usize| -> Vec<&ContactSurface> {
            (pairs.iter().zip(&pair_bodies))
                .flat_map(|(problem, sides)| {
                    let primary = (sides[0] == k).then_some(&problem.primary_surface);
                    let secondary = (sides[1] == k).then_some(&problem.secondary_surface);
                    primary.into_iter().chain(secondary)
                })
                .collect()
        };
        // CG + AMG bodies hand their matrices to PETSc, and ours are released before the
        // multigrid hierarchies are built (`coupled_solver::petsc_solvers`).
        let start = Instant::now();
        let ready = match settings.solver {
            CoupledSolver::MonolithicLu => None,
            _ if kind == BodySolverKind::CgAmg => {
                Some(coupled_solver::petsc_solvers(&mut bodies, solver)?)
            }
            _ => None,
        };
        let body_refs: Vec<&AssembledBody> = bodies.iter().collect();
        let factors = match settings.solver {
            CoupledSolver::MonolithicLu => None,
            _ => {
                let candidates = (0..bodies.len())
                    .map(|k| read_nodes(&surfaces_of(k), &bodies[k]))
                    .collect();
                let compliance = pairs
                    .iter()
                    .map(|p| compliance_factor([&p.primary.material, &p.secondary.material], dim))
                    .collect();
                let factors = BodyFactors::new(
                    &body_refs, candidates, compliance, solver, kind, settings, ready,
                )?;
                if solver.verbose {
                    let what = match kind {
                        BodySolverKind::CgAmg => "CG + AMG set-up",
                        _ => "Cholesky",
                    };
                    let seconds = start.elapsed().as_secs_f64();
                    log::info!("  {what} of the {} bodies: {seconds:.3} s", bodies.len());
                }
                for (stats, shares) in stats.iter_mut().zip(factors.rank_dofs()) {
                    stats.rank_dofs = shares;
                }
                Some(factors)
            }
        };
        let reads = match factors
            .as_ref()
            .map(BodyFactors::distributions)
            .transpose()?
        {
            Some(Some(shared)) => Some(
                (shared.iter().enumerate())
                    .map(|(k, distribution)| {
                        (distribution.node_gather(geometry_nodes(&surfaces_of(k))))
                            .map_err(|e| ContactError::Linalg(e.to_string()))
                    })
                    .collect::<Result<Vec<_>, _>>()?,
            ),
            _ => None,
        };
        let share = interface_share(reads.is_some());
        let operators = (pairs.iter())
            .map(|problem| pair(problem, [0.0; 3], share))
            .collect::<Result<Vec<_>, _>>()?;
        let mut kept = Vec::with_capacity(pairs.len());
        for (problem, &[_, secondary]) in pairs.iter().zip(&pair_bodies) {
            let nodes = &problem.secondary_surface.nodes;
            kept.push(match &factors {
                Some(factors) => factors.keepers(&body_refs, secondary, nodes)?,
                None => None,
            });
        }
        let held_by_contact =
            coupled_solver::held_by_contacts_only(&body_refs, factors.as_ref(), solver.ordering)?
                .into_iter()
                .enumerate()
                .flat_map(|(k, held)| held.into_iter().map(move |r| (k, r)))
                .collect::<Vec<_>>();
        let held = |k: usize| held_by_contact.iter().any(|h| h.0 == k);
        // Each group of bodies linked by pairs needs a body its own supports hold.
        for k in 0..bodies.len() {
            // The group of `k`, in increasing order.
            let linked: Vec<usize> = linked(&pair_bodies, [k], |_| true).into_iter().collect();
            if linked.iter().all(|&j| held(j)) && linked[0] == k {
                let named: Vec<String> = linked
                    .iter()
                    .map(|&j| format!("'{}'", elastic(origin[j]).body.name))
                    .collect();
                return Err(ContactError::NothingHolds {
                    bodies: named.join(", "),
                });
            }
        }
        let mut free_motions = Vec::new();
        for k in (0..bodies.len()).filter(|&k| held(k)) {
            let motions = motions_left_free(elastic(origin[k]).body, &bodies[k]);
            free_motions.push((k, motions));
        }
        let mut offsets = vec![0];
        for problem in pairs {
            offsets.push(offsets.last().unwrap() + problem.primary_surface.len());
        }
        Ok(Self {
            pairs,
            solver: solver.clone(),
            bodies,
            stats,
            origin,
            pair_bodies,
            offsets,
            factors,
            held_by_contact,
            free_motions,
            operators,
            kept,
            laws: pairs.iter().map(|p| ContactLaw::of(&p.settings)).collect(),
            methods: pairs.iter().map(Enforcement::of).collect(),
            transfers: pairs.iter().map(|p| p.transfer().transfer).collect(),
            reads,
        })
    }

    /// The elastic problem of body `k`.
    fn elastic(&self, k: usize) -> &ElasticProblem<'a> {
        let (p, side) = self.origin[k];
        match side {
            0 => &self.pairs[p].primary,
            _ => &self.pairs[p].secondary,
        }
    }

    /// Whether pair `p`'s active nodes hold the walls of a concave vertex they sit in
    /// (`crate::contact::geometry::walls`): a frictionless pair ([`ContactLaw::holds_walls`])
    /// enforced by INTERNODES, in 2D. The penalty method's rows let a node overlap both planes by
    /// its pressure over `eps`, which the two rows' common target does not model. In 3D the walls
    /// are found (the groove a cube's edge digs, `crate::contact::geometry::walls`) but not
    /// held: the groove runs along the whole contact zone, every active node is in it, and on
    /// the edge sweep's cube pressed 2% of its side into a block of its own material no rule
    /// tried let the loop settle (the stops held off: one node switching between tension and
    /// penetration to the iteration cap; that node kept: the gap error swinging between 5e-3 and
    /// 5e-2 h as the pairing followed the slide; the pairing kept: swinging with period two),
    /// where without walls the loop ends `cycling`, named, in a second; at 1% no node crossed a
    /// wall (`docs/decisions.md`, 2026-12-07, "the 3D edge").
    fn holds_walls(&self, p: usize) -> bool {
        self.laws[p].holds_walls()
            && self.methods[p] == Enforcement::Internodes
            && self.pairs[p].primary_surface.dim == 2
            && self.transfers[p] != Transfer::NodeToFacet
    }

    /// The settings of the loop and its coupled solve, shared by the pairs.
    fn loop_settings(&self) -> &ContactSettings {
        &self.pairs[0].settings
    }

    /// Pair `p`'s active nodes (indices into its primary candidates) in the loop's `active`.
    fn pair_nodes(&self, active: &BTreeSet<usize>, p: usize) -> Vec<usize> {
        let offset = self.offsets[p];
        active
            .range(offset..self.offsets[p + 1])
            .map(|&i| i - offset)
            .collect()
    }

    /// The loop's active set with pair `p`'s nodes replaced by `nodes`.
    fn with_pair_nodes(
        &self,
        active: &BTreeSet<usize>,
        p: usize,
        nodes: impl IntoIterator<Item = usize>,
    ) -> BTreeSet<usize> {
        let (offset, end) = (self.offsets[p], self.offsets[p + 1]);
        let mut next: BTreeSet<usize> = active
            .iter()
            .copied()
            .filter(|i| !(offset..end).contains(i))
            .collect();
        next.extend(nodes.into_iter().map(|i| offset + i));
        next
    }

    /// The body and interface solvers that ran.
    pub fn linear_solvers(&self) -> LinearSolvers {
        match &self.factors {
            None => LinearSolvers {
                body: CoupledSolver::MonolithicLu.name(),
                interface: CoupledSolver::MonolithicLu.name(),
                krylov_failure: None,
                body_applications: None,
            },
            Some(factors) => LinearSolvers {
                body: factors.body_kind().name(),
                interface: match factors.is_krylov() {
                    true => CoupledSolver::Krylov.name(),
                    false => CoupledSolver::Schur.name(),
                },
                krylov_failure: factors.fell_back.clone(),
                body_applications: factors.body_applications(),
            },
        }
    }

    /// Each pair's primary candidates that touch or penetrate in the reference configuration,
    /// with their constraints linearized there.
    pub fn initial_active_set(&self) -> Vec<ActiveSet> {
        (self.pairs.iter().zip(&self.laws).zip(&self.transfers))
            .map(|((problem, law), &transfer)| {
                let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
                let tol = problem.settings.penetration_tolerance;
                let gaps = geometric_gaps(s1, s2, None, None);
                ActiveSet {
                    nodes: (0..s1.len())
                        .filter(|&i| gaps[i] < tol * s1.spacing[i])
                        .collect(),
                    rows: gap_rows(s1, s2, None, None, law.row_normal(transfer)),
                    corrections: vec![0.0; s1.len()],
                    slip: BTreeMap::new(),
                    history: None,
                }
            })
            .collect()
    }

    /// Runs the active-set loop with the loads and prescribed displacements scaled by the
    /// step's `factors` (each by its load path's), from `start` (one active set per pair; default:
    /// [`Self::initial_active_set`]). One answer per pair, in the pairs' order.
    pub fn solve(
        &mut self,
        factors: &StepFactors,
        start: Option<&[ActiveSet]>,
    ) -> Result<Vec<ContactSolution>, ContactError> {
        (self.pairs.iter()).try_for_each(|pair| pair.check_paths(factors))?;
        if start.is_none() {
            for p in 0..self.pairs.len() {
                if self.operators[p].slid != [0.0; 3] {
                    self.pair_again(p, [0.0; 3])?;
                }
            }
        }
        let cold = start.is_none();
        let start = match start {
            Some(start) => start.to_vec(),
            None => self.initial_active_set(),
        };
        let mut active = NodeStates::default();
        let mut directions = BTreeMap::new();
        let (mut rows, mut corrections, mut friction) = (Vec::new(), Vec::new(), Vec::new());
        for (p, set) in start.into_iter().enumerate() {
            let offset = self.offsets[p];
            active.contact.extend(set.nodes.iter().map(|&i| offset + i));
            active.slip.extend(set.slip.keys().map(|&i| offset + i));
            directions.extend(set.slip.iter().map(|(&i, &d)| (offset + i, d)));
            let start = self.laws[p].has_friction();
            friction.push(
                start
                    .then(|| self.start_of_step(p, set.history))
                    .transpose()?,
            );
            rows.push(set.rows);
            corrections.push(set.corrections);
        }
        let mut state = LoopState {
            solved: active.clone(),
            active,
            directions,
            turnings: BTreeMap::new(),
            friction,
            rows,
            corrections,
            safeguard: Safeguard::default(),
            history: Vec::new(),
            last: None,
            cold,
            first_contact: false,
            pairings: vec![Vec::new(); self.pairs.len()],
            slides: vec![None; self.pairs.len()],
            slide_change: None,
            walls: (0..self.pairs.len())
                .map(|_| PairWalls::default())
                .collect(),
            taken: vec![HashMap::new(); self.pairs.len()],
        };
        let mut status = ContactStatus::IterationLimit;
        for iteration in 1..=self.loop_settings().max_iterations {
            self.solver.cancel.check()?;
            let _beat = Heartbeat::start(self.solver.verbose, format!("  iteration {iteration}"));
            if let Some(end) = self.iteration(&mut state, iteration, factors)? {
                status = end;
                break;
            }
        }
        self.finish(factors, status, state)
    }
}

/// The bodies linked through pairs to the bodies `start`, each reached from one already in the
/// set through a pair, and only those that `admit` lets in (with `start`, in increasing order).
fn linked(
    pair_bodies: &[[usize; 2]],
    start: impl IntoIterator<Item = usize>,
    admit: impl Fn(usize) -> bool,
) -> BTreeSet<usize> {
    let mut linked: BTreeSet<usize> = start.into_iter().collect();
    loop {
        let before = linked.len();
        for pair in pair_bodies {
            for (from, to) in [(pair[0], pair[1]), (pair[1], pair[0])] {
                if linked.contains(&from) && admit(to) {
                    linked.insert(to);
                }
            }
        }
        if linked.len() == before {
            return linked;
        }
    }
}

/// The active-set loop between two iterations.
struct LoopState {
    /// The node states the next iteration solves on (all pairs: [`ContactSolver::offsets`]).
    active: NodeStates,
    /// The direction of the friction traction of each slipping node (and of nodes that
    /// slipped before: only those in `active.slip` are read).
    directions: BTreeMap<usize, [f64; 3]>,
    /// How each slipping node's direction is linearized (3D Coulomb; a node absent slipped in
    /// no iterate of this solve yet: [`Turning::HELD`]).
    turnings: BTreeMap<usize, Turning>,
    /// Each Coulomb pair's start of the load step.
    friction: Vec<Option<StepStart>>,
    /// Each pair's gap rows and tied corrections.
    rows: Vec<Vec<GapRow>>,
    corrections: Vec<Vec<f64>>,
    safeguard: Safeguard,
    history: Vec<IterationRecord>,
    /// The last iterate.
    last: Option<KeptIterate>,
    /// The node states `last` was solved on (`active` moves on to the next one).
    solved: NodeStates,
    /// Whether the solve started without an active set from an earlier one.
    cold: bool,
    /// Whether the loop has chosen where the bodies that only their contacts hold touch first
    /// ([`ContactSolver::first_contact`]).
    first_contact: bool,
    /// Each pair's pairings ([`pairing_slide`]) this solve has left, with the set it had
    /// settled on there.
    pairings: Vec<Vec<([f64; 3], NodeStates)>>,
    /// Each pair's slide at the last iterate, and the largest change of a pair's slide over
    /// the last iteration that the loop went on for (over the settling margin).
    slides: Vec<Option<[f64; 3]>>,
    slide_change: Option<f64>,
    /// Each pair's walls at the last iterate and those that pushed
    /// ([`ContactSolver::holds_walls`]), and the walls the next coupling holds (by candidate).
    walls: Vec<PairWalls>,
    taken: Vec<HashMap<usize, HeldWall>>,
}

/// The last iterate as the loop keeps it between solves: each pair's coupling and the solution,
/// whose displacements are, in a distributed run, this rank's rows and the values at the nodes
/// the contact geometry reads ([`CoupledSolution::on_nodes`]), so that no rank holds a whole
/// body's vector through the loop. Its displacements are read at the nodes each rank keeps
/// once the loop has ended ([`Self::into_answer`], collective).
struct KeptIterate {
    couplings: Vec<Coupling>,
    solution: CoupledSolution,
}

/// A sum over the ranks of the half-space model failed (collective: every rank meets it).
fn prediction_error(e: &crate::parallel::ParallelError) -> ContactError {
    ContactError::Linalg(format!(
        "a sum over the ranks in the half-space prediction: {e}"
    ))
}

impl KeptIterate {
    /// The couplings and the solution, its displacements whole on one process and on a rank
    /// of a distributed run at the nodes its mesh keeps (its own, its cells', the boundary's
    /// and the groups': what the output and the reactions read), so that no rank holds a
    /// whole body's vector at the end either (collective). The contact geometry's checks read
    /// the boundary's values the loop already holds ([`CoupledSolution::displacement`]).
    fn into_answer(
        mut self,
        factors: Option<&BodyFactors>,
    ) -> Result<(Vec<Coupling>, CoupledSolution), ContactError> {
        if let Some(factors) = factors {
            factors.at_read_nodes(&mut self.solution.u)?;
        }
        Ok((self.couplings, self.solution))
    }
}

impl LoopState {
    /// Moves on to the directions `update` finds for the nodes that slip next, and (3D) the
    /// linearizations of their directions at the iterate ([`Turning`]).
    fn turn_directions(
        &mut self,
        directions: &BTreeMap<usize, [f64; 3]>,
        turnings: &BTreeMap<usize, Turning>,
    ) {
        self.directions.extend(directions);
        self.turnings.extend(turnings);
    }

    /// Keeps an iteration's `record` and `last` iterate, and moves on to its `step`: the status
    /// the loop ends with, or `None` to go on with the next active set.
    fn advance(
        &mut self,
        record: IterationRecord,
        last: KeptIterate,
        step: Step,
    ) -> Option<ContactStatus> {
        self.history.push(record);
        self.last = Some(last);
        self.solved = self.active.clone();
        match step {
            Step::Solve(next) => {
                self.active = next;
                None
            }
            Step::Stop(end) => Some(end),
        }
    }
}

impl ContactSolver<'_> {
    /// One iteration of the loop on `state.active`, recorded in `state`: the status the loop
    /// ends with, or `None` to go on with the next active set.
    fn iteration(
        &mut self,
        state: &mut LoopState,
        iteration: usize,
        factors: &StepFactors,
    ) -> Result<Option<ContactStatus>, ContactError> {
        let mut seconds = PhaseSeconds::default();
        self.first_contact(state, iteration, factors)?;
        // 1. The coupling of the active set: rows and columns of the fixed operators.
        let nodes: Vec<Vec<usize>> = (0..self.pairs.len())
            .map(|p| self.pair_nodes(&state.active.contact, p))
            .collect();
        let tangential = self.tangential_states(&state.active, &state.directions, &state.turnings);
        // The walls each active node holds (frictionless 2D pairs: `ContactSolver::holds_walls`;
        // `found` is empty for the others).
        for (p, problem) in self.pairs.iter().enumerate() {
            let (s1, tol) = (
                &problem.primary_surface,
                problem.settings.penetration_tolerance,
            );
            state.taken[p] =
                (state.walls[p]).taken(&state.rows[p], &nodes[p], |i| tol * s1.spacing[i]);
        }
        let couplings = timed(&mut seconds.operators, || {
            self.couplings(&nodes, state, &tangential)
        })?;
        self.check_held(&couplings, &nodes, &tangential)?;
        // 2-4. The coupled solve, the gaps at the iterate, the node states' update.
        let iterate = self.iterate(&couplings, state, &tangential, factors, &mut seconds);
        let Iterate {
            solution,
            gaps,
            linear,
            slid,
            update,
            krylov_iterations,
        } = match iterate {
            // After a solve that left active nodes a spacing off the surface, an interface
            // system that cannot be solved accurately is the same diagnosis as `Unstable`:
            // the constraint does not control the geometry. The last iterate is the
            // answer, its certificate says what fails.
            Err(ContactError::Inaccurate { .. })
                if state.safeguard.off_surface() && state.last.is_some() =>
            {
                state.active = std::mem::take(&mut state.solved);
                return Ok(Some(ContactStatus::Unstable));
            }
            iterate => iterate?,
        };
        // Which walls pushed, read along the directions the coupling just solved held its
        // nodes (`state.rows` has moved on to the iterate).
        for p in (0..self.pairs.len()).filter(|&p| !state.taken[p].is_empty()) {
            let k_of: HashMap<usize, usize> = (nodes[p].iter().enumerate())
                .map(|(k, &i)| (i, k))
                .collect();
            let (normals, traction) = (&couplings[p].normals, &solution.traction[p]);
            state.walls[p].record_pushes(
                &state.taken[p],
                |i| normals[k_of[&i]],
                |i| traction[k_of[&i]],
            );
        }
        let drift: Vec<f64> = (0..self.pairs.len())
            .map(|p| {
                let s1 = &self.pairs[p].primary_surface;
                pairing_drift(&self.operators[p].slid, &slid[p], s1, &nodes[p])
            })
            .collect();
        for p in 0..self.pairs.len() {
            if !self.laws[p].holds_geometric_gap() {
                state.corrections[p] = (gaps[p].iter().zip(&linear[p]))
                    .map(|(g, l)| g - l)
                    .collect();
            }
        }
        state.turn_directions(&update.directions, &update.turnings);
        // 5. Stop, or go on with the next set (safeguarded against repeats); a set that
        //    settled on a pairing its slide no longer rounds to is paired again where the
        //    surfaces touch, and solved again. A pairing this solve has left on the same set
        //    is not taken again: the slide lies at the edge of a step, within what the pairing
        //    itself moves it, and going back would cycle.
        let pairings: Vec<[f64; 3]> = (0..self.pairs.len())
            .map(|p| pairing_slide(&slid[p], &self.pairs[p].primary_surface, &nodes[p]))
            .collect();
        let drifted: Vec<usize> = (0..self.pairs.len())
            .filter(|&p| {
                let left = (state.pairings[p].iter())
                    .any(|(slid, set)| *slid == pairings[p] && *set == state.active);
                pairings[p] != self.operators[p].slid && !left
            })
            .collect();
        //    The gaps settle before the slide does: each row holds its node along the normal
        //    of the iterate it was linearized at, and the traction's tangential part follows
        //    that normal. A slid pair (paired for a slide other than none) whose gaps settled
        //    but whose slide still moved by more than the settling margin is solved again,
        //    while that motion at least halves from one iteration to the next. (Unslid, the
        //    slide is the mesh's asymmetry, and the pairing does not follow it.)
        let slid_pairs = (0..self.pairs.len()).filter(|&p| self.operators[p].slid != [0.0; 3]);
        let slide_change = (slid_pairs.filter(|_| update.settled))
            .filter_map(|p| {
                let before = state.slides[p]?;
                let margin = SETTLED * self.pairs[p].settings.penetration_tolerance;
                let s1 = &self.pairs[p].primary_surface;
                Some(pairing_drift(&before, &slid[p], s1, &nodes[p]) / margin)
            })
            .fold(0.0, f64::max);
        let slide_moving = slide_change > 1.0
            && (state.slide_change).is_none_or(|last| slide_change <= CONTRACTION * last);
        state.slides = slid.iter().copied().map(Some).collect();
        //    A pair whose active nodes sit in a groove (they have walls) is paired again at
        //    every iteration its slide rounds to another pairing, settled or not: in the
        //    crater a corner digs, the corner slides a spacing or two before any set settles,
        //    and the transfer would carry its force to where it was, the crater forming beside
        //    the node that digs it. A new pairing is a new linear problem, so the safeguard,
        //    which judges repeats and progress on one, starts again, as after the settled
        //    rule's pairing; the pairings left are not taken again on the same set, and the
        //    iteration cap bounds the rest (the safeguard's stops are held off in a groove).
        let in_groove: Vec<bool> = (0..self.pairs.len())
            .map(|p| {
                nodes[p]
                    .iter()
                    .any(|i| state.walls[p].found.contains_key(i))
            })
            .collect();
        let repaired: Vec<usize> = (drifted.iter().copied())
            .filter(|&p| !update.settled && in_groove[p])
            .collect();
        for &p in &repaired {
            self.pair_from_iterate(
                p,
                pairings[p],
                state,
                (&solution, &gaps[p][..]),
                &mut seconds,
            )?;
        }
        let mut paired_again = !repaired.is_empty();
        if paired_again {
            state.safeguard = Safeguard::default();
        }
        state.safeguard.in_groove = in_groove.iter().any(|&g| g);
        let step = match state.safeguard.next(&state.active, &update) {
            Step::Stop(ContactStatus::Converged) if !drifted.is_empty() => {
                for &p in &drifted {
                    let iterate = (&solution, &gaps[p][..]);
                    self.pair_from_iterate(p, pairings[p], state, iterate, &mut seconds)?;
                }
                paired_again = true;
                state.safeguard = Safeguard::default();
                state.slide_change = None;
                Step::Solve(state.active.clone())
            }
            Step::Stop(ContactStatus::Converged) if slide_moving => {
                state.slide_change = Some(slide_change);
                Step::Solve(state.active.clone())
            }
            // The first iteration of a solve goes on with the set the half-space model
            // predicts, rather than with every penetrating node.
            Step::Solve(next) if iteration == 1 && !update.penetrating.is_empty() => {
                Step::Solve(self.predicted(&next, &update, &nodes, &solution, &couplings, &gaps)?)
            }
            step => step,
        };
        let residual = solution.relative_residual;
        let drift = drift.iter().copied().fold(0.0, f64::max);
        let mut record = record(
            &update,
            iteration,
            residual,
            drift,
            krylov_iterations,
            seconds,
        );
        record.paired_again = paired_again;
        if self.laws.iter().any(ContactLaw::has_friction) {
            record.slipping = Some(update.next.slip.len());
            record.max_direction_change = Some(update.max_direction_change);
        }
        if self.solver.verbose {
            log::debug!("{}", record.line(log::log_enabled!(log::Level::Trace)));
        }
        let last = KeptIterate {
            couplings,
            solution,
        };
        Ok(state.advance(record, last, step))
    }

    /// Where the bodies that nothing but their contacts hold (along a force-controlled
    /// component, or along the rigid motions their supports leave free) touch first, when the
    /// loop starts cold or such a body has no node in contact: with no node in contact its
    /// system is singular (the force would move it without bound), and from the nodes that
    /// merely touch (a sphere's pole) the first iterate would carry the whole force on them.
    /// Each pair of such a body starts on the half-space model's zone for the largest
    /// resultant of the loads and forces that reach it through the bodies only their contacts
    /// hold ([`linked`]; `crate::contact::coupled::half_space::force_controlled_set`);
    /// where the model finds none (no force: a floating block between two others), on the nodes
    /// that touch already, or the closest node. If the loop lets go of every contact of such a
    /// body after that, its loads pull it off: an error that names it.
    fn first_contact(
        &self,
        state: &mut LoopState,
        iteration: usize,
        factors: &StepFactors,
    ) -> Result<(), ContactError> {
        if self.held_by_contact.is_empty() {
            return Ok(());
        }
        let touches = |k: usize| {
            (0..self.pairs.len()).any(|p| {
                self.pair_bodies[p].contains(&k)
                    && !self.pair_nodes(&state.active.contact, p).is_empty()
            })
        };
        let untouched = (self.held_by_contact.iter()).find(|&&(k, _)| !touches(k));
        if !(untouched.is_some() || (iteration == 1 && state.cold)) {
            return Ok(());
        }
        if state.first_contact {
            let Some(&(k, index)) = untouched else {
                return Ok(());
            };
            let name = self.elastic(k).body.name.clone();
            let rigid = &self.bodies[k].rigid[index];
            return Err(match rigid.pin {
                true => ContactError::FloatsAway { body: name },
                false => ContactError::PulledAway {
                    body: name,
                    group: rigid.group.clone(),
                    component: ["x", "y", "z"][rigid.component],
                },
            });
        }
        let held = |k: usize| self.held_by_contact.iter().any(|h| h.0 == k);
        for (p, problem) in self.pairs.iter().enumerate() {
            let sides = self.pair_bodies[p];
            if !sides.iter().any(|&k| held(k)) {
                continue;
            }
            let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
            let gaps = match &state.last {
                Some(last) => {
                    let u = |k: usize| Some(last.solution.displacement(k));
                    geometric_gaps(s1, s2, u(sides[0]), u(sides[1]))
                }
                None => geometric_gaps(s1, s2, None, None),
            };
            // The force the contact carries, at most: the largest resultant of the loads and
            // of the forces on the force-controlled groups of the bodies held by their contacts
            // alone that push through it: its own sides and those linked to them through such
            // bodies (a floating ball between two plates passes the force on one plate to its
            // other contact; its supports may carry part of it; the zone then errs on the large
            // side, which the loop corrects).
            // The held bodies among its sides, and those linked to them through held bodies:
            // the bodies whose forces reach it through bodies nothing else supports.
            let chain = linked(
                &self.pair_bodies,
                sides.into_iter().filter(|&k| held(k)),
                held,
            );
            let force = (chain.into_iter())
                .map(|k| self.bodies[k].resultant(factors))
                .fold(0.0, f64::max);
            let materials = [&problem.primary.material, &problem.secondary.material];
            let c0 = compliance_factor(materials, s1.dim);
            let mut zone =
                force_controlled_set(s1, &gaps, force, c0).map_err(|e| prediction_error(&e))?;
            if zone.is_empty() {
                // No force to place: the nodes that touch already, or the closest one.
                zone = self.pair_nodes(&state.active.contact, p);
            }
            if zone.is_empty() {
                let closest = (0..s1.len()).min_by(|&a, &b| gaps[a].total_cmp(&gaps[b]));
                zone.extend(closest);
            }
            if self.solver.verbose {
                log::debug!(
                    "  '{}' and '{}': a body only the contacts hold starts on {} nodes (the zone \
                     where two half-spaces carry the force {force:.6e}, or those that touch)",
                    problem.primary.body.name,
                    problem.secondary.body.name,
                    zone.len()
                );
            }
            let contact = self.with_pair_nodes(&state.active.contact, p, zone);
            state.active = state.active.with_contact(contact);
        }
        state.first_contact = true;
        Ok(())
    }

    /// An error unless the contacts of the active nodes (with their `couplings`) hold each
    /// body that only its contacts hold along the motions its supports leave free: each
    /// motion must move some active node of its pairs along a direction its constraint holds
    /// (the normal; every direction for tied contact). Without it the coupled system is
    /// singular along that motion, and a Krylov solve may still return one of its infinitely
    /// many answers.
    ///
    /// The test: with `h_i = [d . r_j(x_i)]_j` for each held direction `d` at each active node
    /// `x_i` and the free motions `V`, the Gram matrix `sum (h_i V)^T (h_i V)` must have no
    /// eigenvalue below [`HELD_PER_ROW`] times the number of rows (each `h_i` has a unit
    /// translation part, and the rotations are scaled by the body's size).
    fn check_held(
        &self,
        couplings: &[Coupling],
        nodes: &[Vec<usize>],
        tangential: &[Option<Vec<Tangential>>],
    ) -> Result<(), ContactError> {
        for (k, motions) in &self.free_motions {
            let free = motions.ncols();
            if free == 0 {
                continue;
            }
            let elastic = self.elastic(*k);
            let modes = RigidModes::of(elastic.body);
            // Two sets of (point, held directions): the constraints' and the body's own.
            let mut sets: [Vec<HeldRow>; 2] = [Vec::new(), Vec::new()];
            for p in (0..self.pairs.len()).filter(|&p| self.pair_bodies[p].contains(k)) {
                let side = usize::from(self.pair_bodies[p][0] != *k);
                for (set, rows) in sets.iter_mut().zip(self.held_rows(
                    p,
                    side,
                    &couplings[p],
                    &nodes[p],
                    tangential[p].as_deref(),
                )) {
                    set.extend(rows);
                }
            }
            if sets[0].is_empty() {
                continue;
            }
            let mut unheld = 0;
            for set in sets {
                let mut gram = nalgebra::DMatrix::<f64>::zeros(free, free);
                let mut rows = 0.0;
                for (at, directions) in set {
                    let at = modes.at(&at);
                    for d in directions {
                        let h = nalgebra::DVector::from_iterator(
                            at.len(),
                            at.iter().map(|r| (0..3).map(|c| d[c] * r[c]).sum::<f64>()),
                        );
                        let hv = motions.transpose() * h;
                        gram += &hv * hv.transpose();
                        rows += 1.0;
                    }
                }
                let eigenvalues = nalgebra::SymmetricEigen::new(gram).eigenvalues;
                let held = |e: &&f64| **e > HELD_PER_ROW * rows;
                unheld = unheld.max(eigenvalues.iter().filter(|e| !held(e)).count());
            }
            if unheld > 0 {
                let active = nodes.iter().map(Vec::len).sum();
                return Err(ContactError::NotHeld {
                    body: elastic.body.name.clone(),
                    free: unheld,
                    active,
                });
            }
        }
        Ok(())
    }

    /// The points and directions pair `p`'s active `nodes` hold on its body of `side` (0 the
    /// primary): once the constraints' and once the body's own (module doc of
    /// [`Self::check_held`]). Frictionless: the normal, taken as the secondary facet's (the
    /// constraint's) and as the body's own surface's: a round body turning about its centre
    /// moves its nodes along the other body's normal but maps its surface onto itself, so only
    /// its own normals show that nothing holds it. Tied: every direction.
    fn held_rows(
        &self,
        p: usize,
        side: usize,
        coupling: &Coupling,
        nodes: &[usize],
        tangential: Option<&[Tangential]>,
    ) -> [Vec<HeldRow>; 2] {
        let problem = &self.pairs[p];
        let s1 = &problem.primary_surface;
        let dim = s1.dim;
        let law = self.laws[p];
        let points: Vec<[f64; 3]> = nodes.iter().map(|&i| s1.coords[i]).collect();
        let axes: Vec<[f64; 3]> = (0..dim)
            .map(|c| std::array::from_fn(|j| f64::from(u8::from(j == c))))
            .collect();
        let state = |i: usize| tangential.map_or(Tangential::Stick, |states| states[i]);
        if law == ContactLaw::Tied {
            let rows: Vec<_> = points.iter().map(|&x| (x, axes.clone())).collect();
            return [rows.clone(), rows];
        }
        let own: Vec<[f64; 3]> = match side {
            0 => nodes.iter().map(|&i| s1.normals[i]).collect(),
            // The secondary's own normal where each active node touches it: its nodes'
            // normals weighted as the constraint row weighs them.
            _ => {
                let s2 = &problem.secondary_surface;
                let surface_index: HashMap<usize, usize> =
                    s2.nodes.iter().enumerate().map(|(s, &n)| (n, s)).collect();
                (coupling.geometric.iter())
                    .map(|row| {
                        let mut n = [0.0; 3];
                        for &(node, w) in row {
                            if let Some(&s) = surface_index.get(&node) {
                                (0..3).for_each(|c| n[c] += w * s2.normals[s][c]);
                            }
                        }
                        let length = (0..3).map(|c| n[c] * n[c]).sum::<f64>().sqrt();
                        n.map(|v| if length > 0.0 { v / length } else { 0.0 })
                    })
                    .collect()
            }
        };
        // A sticking node (Coulomb) holds every direction, a sliding one its normal alone.
        let held = |i: usize, n: [f64; 3]| match law.holds_every_direction(state(i)) {
            true => axes.clone(),
            false => vec![n],
        };
        let constraint = (nodes.iter().zip(&points).zip(&coupling.normals))
            .map(|((&i, &x), &n)| (x, held(i, n)))
            .collect();
        let own = (nodes.iter().zip(&points).zip(own))
            .map(|((&i, &x), n)| (x, held(i, n)))
            .collect();
        [constraint, own]
    }

    /// The active set the half-space model predicts
    /// (`crate::contact::coupled::half_space::predicted_set`) for each frictionless pair from the
    /// iterate `solution` on the active `nodes` with their `couplings`, over the nodes the update
    /// keeps or adds (`next`) and those it removes; `next`'s nodes of a pair where the model
    /// predicts no contact.
    fn predicted(
        &self,
        next: &NodeStates,
        update: &Update,
        nodes: &[Vec<usize>],
        solution: &CoupledSolution,
        couplings: &[Coupling],
        gaps: &[Vec<f64>],
    ) -> Result<NodeStates, ContactError> {
        let mut predicted_all = next.contact.clone();
        let next = &next.contact;
        for (p, problem) in self.pairs.iter().enumerate() {
            if !self.laws[p].predicts_zone() {
                continue;
            }
            let s1 = &problem.primary_surface;
            let mut pressure = vec![0.0; s1.len()];
            for ((&i, t), n) in (nodes[p].iter())
                .zip(&solution.traction[p])
                .zip(&couplings[p].normals)
            {
                pressure[i] = -(t[0] * n[0] + t[1] * n[1] + t[2] * n[2]);
            }
            let (offset, end) = (self.offsets[p], self.offsets[p + 1]);
            let mut candidates: BTreeSet<usize> = self.pair_nodes(next, p).into_iter().collect();
            candidates.extend(
                (update.tension.iter())
                    .filter(|&&(i, _)| (offset..end).contains(&i))
                    .map(|&(i, _)| i - offset),
            );
            let candidates: Vec<usize> = candidates.into_iter().collect();
            let materials = [&problem.primary.material, &problem.secondary.material];
            let c0 = compliance_factor(materials, s1.dim);
            let started = std::time::Instant::now();
            let (predicted, model) = predicted_set(s1, &candidates, &gaps[p], &pressure, c0)
                .map_err(|e| prediction_error(&e))?;
            if self.solver.verbose {
                log::debug!(
                    "  half-space prediction: {} nodes active next (the update's {}); its model \
                     {} in {} products, {:.3} s",
                    predicted.len(),
                    self.pair_nodes(next, p).len(),
                    match model.converged {
                        true => "solved",
                        false => "not solved",
                    },
                    model.products,
                    started.elapsed().as_secs_f64()
                );
            }
            if !predicted.is_empty() {
                predicted_all = self.with_pair_nodes(&predicted_all, p, predicted);
            }
        }
        Ok(NodeStates::in_contact(predicted_all))
    }

    /// Pair `p`'s tied corrections of its current operators at `solution`, whose geometric
    /// gaps are `gaps`: each gap less its linearization.
    fn corrections(
        &self,
        p: usize,
        solution: &CoupledSolution,
        gaps: &[f64],
    ) -> Result<Vec<f64>, ContactError> {
        let problem = &self.pairs[p];
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let [a, b] = self.pair_bodies[p];
        let (u1, u2) = (solution.displacement(a), solution.displacement(b));
        let jumps = self.operators[p].jumps(s1, s2, u1, u2)?;
        let linear = self.operators[p].linearized_gaps(&jumps);
        Ok(gaps.iter().zip(&linear).map(|(g, l)| g - l).collect())
    }
}

impl ContactSolver<'_> {
    /// The coupling of each pair's active primary nodes `nodes` (surface indices): rows and
    /// columns of its fixed operators, each node's multipliers as its pair's law lays them
    /// out, the constraint linearized by the state's gap rows (frictionless, Coulomb) or
    /// corrected by its corrections (tied); a Coulomb pair's sticking nodes hold their
    /// tangential jumps at the start of the step.
    fn couplings(
        &mut self,
        nodes: &[Vec<usize>],
        state: &LoopState,
        tangential: &[Option<Vec<Tangential>>],
    ) -> Result<Vec<Coupling>, ContactError> {
        let mut couplings = Vec::with_capacity(self.pairs.len());
        for (p, problem) in self.pairs.iter().enumerate() {
            let law = self.laws[p];
            let constraint = match law.holds_geometric_gap() {
                true => Constraint::Geometric {
                    rows: &state.rows[p],
                    start_jumps: state.friction[p].as_ref().map(|start| &start.jumps[..]),
                    tangential: tangential[p].as_deref(),
                    walls: &state.taken[p],
                },
                false => Constraint::Interpolated {
                    corrections: &state.corrections[p],
                },
            };
            let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
            let operators = &mut self.operators[p];
            let enforced = (law, self.methods[p]);
            let kept = self.kept[p].as_ref();
            couplings.push(operators.coupling(s1, s2, enforced, &nodes[p], constraint, kept)?);
        }
        Ok(couplings)
    }

    /// Each Coulomb pair's tangential state of every primary candidate in `states` (a
    /// slipping node's direction from `directions`); `None` for the other pairs.
    fn tangential_states(
        &self,
        states: &NodeStates,
        directions: &BTreeMap<usize, [f64; 3]>,
        turnings: &BTreeMap<usize, Turning>,
    ) -> Vec<Option<Vec<Tangential>>> {
        (0..self.pairs.len())
            .map(|p| {
                self.laws[p].has_friction().then(|| {
                    let offset = self.offsets[p];
                    (offset..self.offsets[p + 1])
                        .map(|i| match (states.slip.contains(&i), directions.get(&i)) {
                            (true, Some(&direction)) => Tangential::Slip {
                                direction,
                                turning: turnings.get(&i).copied().unwrap_or(Turning::HELD),
                            },
                            _ => Tangential::Stick,
                        })
                        .collect()
                })
            })
            .collect()
    }

    /// Coulomb pair `p`'s tangential answer on every primary candidate at the last iterate
    /// `view` (the pair's own solution) on the active `nodes` in `tangential` states.
    fn friction_fields(
        &self,
        p: usize,
        nodes: &[usize],
        view: &CoupledSolution,
        coupling: &Coupling,
        start: &StepStart,
        tangential: &[Tangential],
    ) -> Result<PairFriction, ContactError> {
        let problem = &self.pairs[p];
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let (u1, u2) = (view.displacement(0), view.displacement(1));
        let jumps = self.operators[p].jumps(s1, s2, u1, u2)?;
        let len = s1.len();
        let mut answer = PairFriction {
            state: vec![None; len],
            tangential_traction: vec![[0.0; 3]; len],
            pressure: vec![0.0; len],
            normal: vec![[0.0; 3]; len],
            own_normal: s1.normals.clone(),
            slip_increment: vec![[0.0; 3]; len],
            accumulated_slip: start.accumulated_slip.clone(),
            area: s1.nodal_area.clone(),
        };
        for (k, &i) in nodes.iter().enumerate() {
            let (t, n) = (view.traction[0][k], coupling.normals[k]);
            let increment: [f64; 3] = std::array::from_fn(|c| jumps[i][c] - start.jumps[i][c]);
            let slip = coulomb::tangential_part(increment, n);
            answer.state[i] = Some(tangential[i]);
            answer.tangential_traction[i] = coulomb::tangential_part(t, n);
            answer.pressure[i] = -(0..3).map(|c| t[c] * n[c]).sum::<f64>();
            answer.normal[i] = n;
            answer.slip_increment[i] = slip;
            answer.accumulated_slip[i] += coulomb::norm(slip);
        }
        Ok(answer)
    }

    /// Where a Coulomb pair `p`'s load step starts: the displacements the last step ended
    /// with (`history`; none: at rest), and the jumps there through the current operators.
    fn start_of_step(
        &self,
        p: usize,
        history: Option<FrictionHistory>,
    ) -> Result<StepStart, ContactError> {
        let problem = &self.pairs[p];
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let history = history.unwrap_or_else(|| FrictionHistory {
            displacements: [vec![0.0; 3 * s1.len()], vec![0.0; 3 * s2.len()]],
            accumulated_slip: vec![0.0; s1.len()],
        });
        Ok(StepStart {
            jumps: self.operators[p].jumps_of(&history.displacements)?,
            displacements: history.displacements,
            accumulated_slip: history.accumulated_slip,
        })
    }

    /// The tangential part of the update (`crate::contact::law::coulomb`) of Coulomb pair `p`'s
    /// active `nodes` at the iterate whose jumps are `jumps`, gap-row normals `normals` and
    /// geometric gaps `gaps`, added to the pair's `update`: which nodes in contact next slip,
    /// and along which direction. A node the update adds (it penetrates by `-g`) has no
    /// traction yet: it is judged as the complementarity function of Hüeber, Stadler and
    /// Wohlmuth judges it, by its augmented pressure `c (-g)` (`c = E* / h`, as `c_t`): it
    /// slips, against its slip over the step, if `|v| > mu |g|`, and sticks otherwise.
    #[allow(clippy::too_many_arguments)]
    fn friction_update(
        &self,
        p: usize,
        nodes: &[usize],
        traction: &[[f64; 3]],
        coupling: &Coupling,
        [jumps, normals]: [&[[f64; 3]]; 2],
        gaps: &[f64],
        start: &StepStart,
        tangential: &[Tangential],
        update: &mut Update,
    ) {
        let ContactLaw::Coulomb {
            friction_coefficient: mu,
        } = self.laws[p]
        else {
            return;
        };
        let problem = &self.pairs[p];
        let s1 = &problem.primary_surface;
        let e_star = problem.contact_modulus();
        let pressure = |t: &[f64; 3], n: &[f64; 3]| -(0..3).map(|k| t[k] * n[k]).sum::<f64>();
        let p_max = (traction.iter().zip(&coupling.normals))
            .map(|(t, n)| pressure(t, n))
            .fold(0.0, f64::max);
        let slack = problem.settings.tension_tolerance * mu * p_max;
        let active: HashMap<usize, usize> =
            nodes.iter().enumerate().map(|(k, &i)| (i, k)).collect();
        let next: Vec<usize> = update.next.contact.iter().copied().collect();
        for i in next {
            let c = e_star / s1.spacing[i];
            let increment: [f64; 3] = std::array::from_fn(|k| jumps[i][k] - start.jumps[i][k]);
            let (state, p_i, t_t, n) = match active.get(&i) {
                Some(&k) => {
                    let (t, n) = (traction[k], coupling.normals[k]);
                    let t_t = coulomb::tangential_part(t, n);
                    (tangential[i], pressure(&t, &n), t_t, n)
                }
                None => (Tangential::Stick, -c * gaps[i], [0.0; 3], normals[i]),
            };
            let v = coulomb::tangential_part(increment, n);
            // A slipping node sticks again only if it slips along its own traction by more
            // than the loop's settled gap tolerance, 0.01 penetration_tolerance h.
            let settled = SETTLED * problem.settings.penetration_tolerance * s1.spacing[i];
            let node = coulomb::update(state, p_i, t_t, v, mu, c, slack, settled);
            // A direction error turns the node's friction traction mu p_i d by as much: weighed
            // by p_i / p_max, the change is the traction's error over mu p_max.
            let weight = if p_max > 0.0 {
                (p_i / p_max).clamp(0.0, 1.0)
            } else {
                1.0
            };
            update.max_direction_change =
                (update.max_direction_change).max(weight * node.direction_change);
            let slips = |s: Tangential| matches!(s, Tangential::Slip { .. });
            if active.contains_key(&i) && slips(state) != slips(node.next) && p_max > 0.0 {
                update.switching.push((i, node.margin / (mu * p_max)));
            }
            if let Tangential::Slip { direction, turning } = node.next {
                update.next.slip.insert(i);
                update.directions.insert(i, direction);
                update.turnings.insert(i, turning);
            }
        }
    }

    /// Steps 2-4 of the loop on the active set `active` with the pairs' `couplings`: the
    /// coupled solve; the gaps of every primary candidate of each pair, geometric (the search)
    /// and linearized at the iterate (into `rows`), and how far each pair's active nodes have
    /// slid; the primal-dual active set update. On the Krylov path the solve is first loose
    /// ([`Tightness::Loose`]; [`Tightness::Reduced`] where a Coulomb pair's slip directions are
    /// iterated on) and solved again tightly when its update would keep the node
    /// states (and no slipping direction still turns) or return to states seen before, unless
    /// it only feeds the next linearization (`Safeguard::only_linearizes`): no answer, status
    /// or check rests on a loose solve.
    /// The time of each phase is added to `seconds`.
    fn iterate(
        &mut self,
        couplings: &[Coupling],
        state: &mut LoopState,
        tangential: &[Option<Vec<Tangential>>],
        factors: &StepFactors,
        seconds: &mut PhaseSeconds,
    ) -> Result<Iterate, ContactError> {
        let (active, safeguard) = (&state.active, &state.safeguard);
        let mut loose = self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
        let mut krylov_iterations = None;
        loop {
            let solution = timed(&mut seconds.solve, || {
                let tightness = match (loose, self.laws.iter().any(ContactLaw::has_friction)) {
                    (false, _) => Tightness::Tight,
                    (true, false) => Tightness::Loose,
                    (true, true) => Tightness::Reduced,
                };
                self.coupled_solve(couplings, factors, tightness)
            })?;
            if let Some(stats) = self.factors.as_ref().and_then(|f| f.last_krylov) {
                *krylov_iterations.get_or_insert(0) += stats.iterations;
            }
            let (mut gaps, mut linear, mut slid) = (Vec::new(), Vec::new(), Vec::new());
            let mut updates = Vec::new();
            for (p, problem) in self.pairs.iter().enumerate() {
                let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
                let [a, b] = self.pair_bodies[p];
                let (u1, u2) = (solution.displacement(a), solution.displacement(b));
                let nodes = self.pair_nodes(&active.contact, p);
                let operators = &self.operators[p];
                let row_normal = self.laws[p].row_normal(self.transfers[p]);
                let rows = &mut state.rows[p];
                let shared = self.reads.is_some();
                let (pair_gaps, jumps, pair_slid) = timed(&mut seconds.search, || {
                    let (gaps, pair_rows) = measure_gaps(s1, s2, [u1, u2], row_normal, shared)?;
                    *rows = pair_rows;
                    let jumps = operators.jumps(s1, s2, u1, u2)?;
                    let slid = operators.slide(s1, &jumps, &nodes);
                    Ok::<_, ContactError>((gaps, jumps, slid))
                })?;
                if self.holds_walls(p) {
                    let digging = s1.beside_corners(CORNER_TURN);
                    state.walls[p].found = walls(s1, s2, [u1, u2], rows, &digging);
                }
                let pair_linear = operators.linearized_gaps(&jumps);
                // The gap each active node's constraint holds: the gap of its linearization (under
                // the penalty method, less the overlap its pressure allows).
                let mut held: Vec<f64> = match self.laws[p].holds_geometric_gap() {
                    true => rows.iter().map(|r| r.gap).collect(),
                    false => pair_gaps.clone(),
                };
                let (traction, normals) = (&solution.traction[p], &couplings[p].normals);
                for (k, &i) in nodes.iter().enumerate() {
                    let pressure = -(0..3).map(|c| traction[k][c] * normals[k][c]).sum::<f64>();
                    held[i] = self.methods[p].row_residual(held[i], pressure);
                }
                let offset = self.offsets[p];
                let update = timed(&mut seconds.checks, || {
                    let (traction, normals) = (&solution.traction[p], &couplings[p].normals);
                    let pinned: HashSet<usize> = (safeguard.pinned.iter())
                        .filter(|&&i| (offset..self.offsets[p + 1]).contains(&i))
                        .map(|&i| i - offset)
                        .collect();
                    let mut update = Update::new(
                        problem,
                        &nodes,
                        traction,
                        normals,
                        [&pair_gaps, &held],
                        &pinned,
                    );
                    if let (Some(start), Some(states)) = (&state.friction[p], &tangential[p]) {
                        let normals: Vec<[f64; 3]> = rows.iter().map(|r| r.normal).collect();
                        self.friction_update(
                            p,
                            &nodes,
                            traction,
                            &couplings[p],
                            [&jumps, &normals],
                            &pair_gaps,
                            start,
                            states,
                            &mut update,
                        );
                    }
                    update
                });
                updates.push((offset, update));
                gaps.push(pair_gaps);
                linear.push(pair_linear);
                slid.push(pair_slid);
            }
            let update = Update::merge(updates);
            // An iterate that keeps the node states while slipping nodes' directions still turn
            // (3D Coulomb) only turns them further: the loop goes on from it, so a loose solve
            // serves until they settle and the loop would stop on it. Its solves are
            // `Tightness::Reduced`, each a hundred times below its start, and the start's
            // residual falls with the directions' change: their own error falls with it. (Plain
            // loose solves, to a fixed 1e-6, turned the directions of the 3D sphere by about
            // 1e-6 themselves and held the loop there to its cap.) A partition seen before is
            // a repeat only once the directions turn by less than `coulomb::STILL_TURNING`,
            // the safeguard's rule.
            let settled = update.max_direction_change <= coulomb::DIRECTION_SETTLED;
            let turning = update.max_direction_change > coulomb::STILL_TURNING;
            let keeps = update.next == *active && settled;
            let seen = safeguard.seen.contains(&update.next) && !turning;
            // A kept set whose gaps are far from settled only feeds the next linearization
            // (Newton on the gap, the safeguard's counters reset): a tight solve of it would
            // be replaced by the next one's (at 1M DOFs, 19 s of a 77 s loop). Not with a tied
            // pair: its correction is a fixed point, which carries a loose iterate's error on.
            let newton = self.laws.iter().all(ContactLaw::holds_geometric_gap);
            let only_linearizes = newton && safeguard.only_linearizes(active, &update);
            if loose && (keeps || seen) && !only_linearizes {
                loose = false;
                continue;
            }
            return Ok(Iterate {
                solution,
                gaps,
                linear,
                slid,
                update,
                krylov_iterations,
            });
        }
    }

    /// The answers of a loop that ended `loop_end` in `state`, one per pair: each certified
    /// without the loop's operators (`crate::contact::verify::checks`), which decides its status,
    /// with the fields and forces of `crate::contact::verify::post`.
    fn finish(
        &self,
        factors: &StepFactors,
        loop_end: ContactStatus,
        state: LoopState,
    ) -> Result<Vec<ContactSolution>, ContactError> {
        let last = state.last.expect("max_iterations >= 1 is validated");
        let (couplings, solution) = last.into_answer(self.factors.as_ref())?;
        let dim = self.pairs[0].primary_surface.dim;
        let mut answers = Vec::with_capacity(self.pairs.len());
        // Each Coulomb pair's tangential states the last iterate was solved with.
        let tangential = self.tangential_states(&state.solved, &state.directions, &state.turnings);
        for (p, problem) in self.pairs.iter().enumerate() {
            let [a, b] = self.pair_bodies[p];
            let nodes = self.pair_nodes(&state.active.contact, p);
            // The nodes the last iterate was solved on, which its tractions belong to: the
            // active set unless the loop stopped before settling (`active` then holds the next).
            let solved = self.pair_nodes(&state.solved.contact, p);
            let pair = Pair {
                primary: a,
                secondary: b,
                coupling: &couplings[p],
            };
            let mut view = solution.of_pair(p, &pair, dim);
            if let Some(factors) = self.factors.as_ref() {
                let mut forces: Vec<&mut LoadVector> = view.contact_force.iter_mut().collect();
                factors.complete_forces(&[a, b], &mut forces)?;
            }
            let (mut certificate, gaps) = certify(problem, &view, [&nodes, &solved]);
            let (slip, history, friction) = match (&state.friction[p], self.laws[p]) {
                (
                    Some(start),
                    ContactLaw::Coulomb {
                        friction_coefficient,
                    },
                ) => {
                    let fields = self.friction_fields(
                        p,
                        &solved,
                        &view,
                        &couplings[p],
                        start,
                        tangential[p].as_deref().unwrap_or(&[]),
                    )?;
                    for check in checks::friction(
                        problem,
                        friction_coefficient,
                        &fields.state,
                        &fields.pressure,
                        &fields.tangential_traction,
                        &fields.slip_increment,
                    ) {
                        certificate.push(check);
                    }
                    let slip = (fields.state.iter().enumerate())
                        .filter_map(|(i, s)| match s {
                            Some(Tangential::Slip { direction, .. }) => Some((i, *direction)),
                            _ => None,
                        })
                        .collect();
                    let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
                    let history = FrictionHistory {
                        displacements: [
                            s1.values(view.displacement(0)),
                            s2.values(view.displacement(1)),
                        ],
                        accumulated_slip: fields.accumulated_slip.clone(),
                    };
                    (slip, Some(history), Some(fields.into_solution()))
                }
                _ => (BTreeMap::new(), None, None),
            };
            let status = contact_status(loop_end, &certificate, nodes.is_empty());
            let active_set = ActiveSet {
                nodes: nodes.into_iter().collect(),
                rows: state.rows[p].clone(),
                corrections: state.corrections[p].clone(),
                slip,
                history,
            };
            answers.push(post::finish(LastIterate {
                problem,
                bodies: [
                    (&self.bodies[a], &self.stats[a]),
                    (&self.bodies[b], &self.stats[b]),
                ],
                body_contact_force: [&solution.contact_force[a], &solution.contact_force[b]],
                linear_solvers: self.linear_solvers(),
                factors,
                status,
                history: state.history.clone(),
                certificate,
                gaps,
                coupling: &couplings[p],
                solution: view,
                active_set,
                friction,
            })?);
        }
        Ok(answers)
    }

    /// Pairs `p` again for the slide `slid` from the loop's iterate (`solution`, and the
    /// pair's geometric `gaps` there): the pairing it leaves is remembered with the active set
    /// (not taken again on that set), and what the iterate gives the new operators is read
    /// again through them (the tied corrections, a Coulomb step's starting jumps).
    fn pair_from_iterate(
        &mut self,
        p: usize,
        slid: [f64; 3],
        state: &mut LoopState,
        (solution, gaps): (&CoupledSolution, &[f64]),
        seconds: &mut PhaseSeconds,
    ) -> Result<(), ContactError> {
        let left = (self.operators[p].slid, state.active.clone());
        state.pairings[p].push(left);
        timed(&mut seconds.operators, || self.pair_again(p, slid))?;
        state.corrections[p] = self.corrections(p, solution, gaps)?;
        if let Some(start) = state.friction[p].as_mut() {
            start.jumps = self.operators[p].jumps_of(&start.displacements)?;
        }
        Ok(())
    }

    /// Builds pair `p`'s interface operators again, paired with its primary surface slid by
    /// `slid`; the bodies' responses computed with the old ones are forgotten.
    fn pair_again(&mut self, p: usize, slid: [f64; 3]) -> Result<(), ContactError> {
        let share = interface_share(self.reads.is_some());
        self.operators[p] = pair(&self.pairs[p], slid, share)?;
        if let Some(factors) = self.factors.as_mut() {
            factors.forget_responses();
        }
        Ok(())
    }

    /// The coupled system of the pairs' `couplings`, solved and checked by its relative
    /// residual; or, a loose solve on the Krylov path, its residual only recorded.
    fn coupled_solve(
        &mut self,
        couplings: &[Coupling],
        factors: &StepFactors,
        tightness: Tightness,
    ) -> Result<CoupledSolution, ContactError> {
        let dim = self.pairs[0].primary_surface.dim;
        let bodies: Vec<&AssembledBody> = self.bodies.iter().collect();
        let pairs: Vec<Pair> = (couplings.iter().zip(&self.pair_bodies))
            .map(|(coupling, &[primary, secondary])| Pair {
                primary,
                secondary,
                coupling,
            })
            .collect();
        let ownership = self.factors.as_ref().and_then(BodyFactors::ownership);
        let system = CoupledSystem::assemble_on(&bodies, &pairs, dim, factors, ownership)?;
        let x = match self.factors.as_mut() {
            None => coupled_solver::solve_monolithic(&system, &bodies)?,
            Some(factors) => factors.solve(&system, &pairs, &bodies, tightness)?,
        };
        let loose = tightness != Tightness::Tight
            && self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
        let residual = match self.factors.as_ref() {
            Some(factors) => factors.relative_residual(&system, &pairs, &bodies, &x)?,
            None => system.relative_residual(&bodies, None, &x)?,
        };
        if residual.is_nan() || (!loose && residual > self.solver.residual_tolerance) {
            return Err(ContactError::Inaccurate {
                residual,
                tolerance: self.solver.residual_tolerance,
            });
        }
        match (self.factors.as_ref(), &self.reads) {
            (Some(factors), Some(reads)) => {
                let shared = (factors.distributions()?).ok_or_else(|| {
                    ContactError::Linalg("a distributed run's bodies are not shared".into())
                })?;
                let on_ranks = (&bodies[..], &shared[..], &reads[..]);
                system.solution_on_ranks(&x, on_ranks, &pairs, dim, residual)
            }
            _ => Ok(system.solution(&x, &bodies, &pairs, dim, residual)),
        }
    }
}

/// What steps 2-4 of one iteration found.
struct Iterate {
    solution: CoupledSolution,
    /// The geometric gap of every primary candidate of each pair at the iterate.
    gaps: Vec<Vec<f64>>,
    /// Their gaps through the interpolation operators (tied contact's corrections).
    linear: Vec<Vec<f64>>,
    /// The slide of each pair's active nodes' pairing ([`InterfaceOperators::slide`]).
    slid: Vec<[f64; 3]>,
    update: Update,
    /// GMRES iterations of the solves (Krylov path).
    krylov_iterations: Option<usize>,
}

/// A Coulomb pair's tangential answer on every primary candidate
/// ([`ContactSolver::friction_fields`]).
struct PairFriction {
    /// `None` where open.
    state: Vec<Option<Tangential>>,
    tangential_traction: Vec<[f64; 3]>,
    pressure: Vec<f64>,
    /// The normal each node's pressure and tangential traction are measured against (zero
    /// where open).
    normal: Vec<[f64; 3]>,
    /// Each node's own outward normal (of the primary's surface): what the zone's mean normal
    /// averages.
    own_normal: Vec<[f64; 3]>,
    slip_increment: Vec<[f64; 3]>,
    accumulated_slip: Vec<f64>,
    area: Vec<f64>,
}

impl PairFriction {
    fn into_solution(self) -> FrictionFields {
        // The total contact force on the primary, split along the zone's mean normal (the
        // primary's own outward normals weighted by the nodes' normal forces): Johnson's P and
        // Q. Not along each node's contact normal, the normal of the facet of the other surface
        // it is held on: at a node on a vertex of the other surface that facet is either of two
        // whose normals differ by the kink (h / 2R on a P1 circle), and a Q split so differed by
        // 2% between two codes that agree on every force (the dolfinx frictional reference).
        let (mut force, mut mean_normal) = ([0.0; 3], [0.0; 3]);
        for i in 0..self.area.len() {
            let (t, p, a) = (self.tangential_traction[i], self.pressure[i], self.area[i]);
            let (n, own) = (self.normal[i], self.own_normal[i]);
            (0..3).for_each(|c| force[c] += a * (t[c] - p * n[c]));
            (0..3).for_each(|c| mean_normal[c] += a * p * own[c]);
        }
        let length = coulomb::norm(mean_normal);
        let mean_normal = mean_normal.map(|v| if length > 0.0 { v / length } else { 0.0 });
        let normal_force = -(0..3).map(|c| force[c] * mean_normal[c]).sum::<f64>();
        let tangential_force: [f64; 3] =
            std::array::from_fn(|c| force[c] + normal_force * mean_normal[c]);
        let count = |slips: bool| {
            (self.state.iter())
                .filter(|s| matches!(s, Some(Tangential::Slip { .. })) == slips && s.is_some())
                .count()
        };
        FrictionFields {
            stick_nodes: count(false),
            slip_nodes: count(true),
            state: (self.state.iter())
                .map(|s| match s {
                    None => FrictionState::Open,
                    Some(Tangential::Stick) => FrictionState::Stick,
                    Some(Tangential::Slip { .. }) => FrictionState::Slip,
                })
                .collect(),
            tangential_traction: self.tangential_traction,
            slip_increment: self.slip_increment,
            accumulated_slip: self.accumulated_slip,
            tangential_force,
            normal_force,
        }
    }
}

/// Where a Coulomb pair's load step starts ([`ContactSolver::start_of_step`]).
struct StepStart {
    /// The primary's and the secondary's displacements at the end of the last step, at their
    /// contact surfaces' nodes (`FrictionHistory::displacements`).
    displacements: [Vec<f64>; 2],
    /// The jump `u1_i - (R12 u2)_i` of every primary candidate there, through the current
    /// operators (computed again when they are paired again).
    jumps: Vec<[f64; 3]>,
    /// The accumulated slip of every primary candidate at the end of the last step.
    accumulated_slip: Vec<f64>,
}

/// Runs `f`, adding its wall-clock seconds to `slot`.
fn timed<T>(slot: &mut f64, f: impl FnOnce() -> T) -> T {
    let clock = Instant::now();
    let value = f();
    *slot += clock.elapsed().as_secs_f64();
    value
}

/// The iteration's record of `update`; `pairing_drift_over_h` as [`pairing_drift`].
fn record(
    update: &Update,
    iteration: usize,
    residual: f64,
    pairing_drift_over_h: f64,
    krylov_iterations: Option<usize>,
    seconds: PhaseSeconds,
) -> IterationRecord {
    let max = |v: &[(usize, f64)]| v.iter().map(|x| x.1).fold(0.0, f64::max);
    IterationRecord {
        iteration,
        active: update.active,
        added: update.penetrating.len(),
        removed: update.tension.len(),
        max_penetration_over_h: max(&update.penetrating),
        max_tension_over_p: max(&update.tension),
        max_gap_error_over_h: update.max_gap_error_over_h,
        pairing_drift_over_h,
        paired_again: false,
        relative_residual: residual,
        krylov_iterations,
        slipping: None,
        max_direction_change: None,
        seconds,
    }
}
