//! Post-processing of the last iterate: each body's solution (reactions, cell strains and
//! stresses), the interface fields of both surfaces, total forces and the Hertz fit.

use crate::contact::ContactError;
use crate::contact::active_set::ActiveSet;
use crate::contact::certificate::{Certificate, CheckKind};
use crate::contact::coupled::system::{CoupledSolution, Coupling};
use crate::contact::geometry::surface::ContactSurface;
use crate::contact::problem::ContactProblem;
use crate::contact::solution::{
    ContactSolution, ContactStatus, ForcedDisplacement, FrictionFields, IterationRecord,
    LinearSolvers, SurfaceFields,
};
use crate::contact::verify::hertz;
use crate::elastic::{
    AssembledBody, ElasticProblem, ElasticSolution, SolveStats, StepFactors, reactions,
};
use crate::fem::LoadVector;

/// What an active-set loop hands over: the problem with its assembled bodies, and how the loop
/// ended with its last iterate and that iterate's certificate.
pub(in crate::contact) struct LastIterate<'a> {
    pub problem: &'a ContactProblem<'a>,
    /// The primary's and the secondary's assembly, with its statistics.
    pub bodies: [(&'a AssembledBody, &'a SolveStats); 2],
    /// The forces every pair puts on each of the two bodies (the reactions balance them);
    /// `solution` has this pair's alone.
    pub body_contact_force: [&'a LoadVector; 2],
    pub linear_solvers: LinearSolvers,
    pub factors: &'a StepFactors,
    pub status: ContactStatus,
    pub history: Vec<IterationRecord>,
    pub certificate: Certificate,
    /// The certificate's geometric gaps of the primary and secondary surfaces.
    pub gaps: [Vec<f64>; 2],
    pub coupling: &'a Coupling,
    pub solution: CoupledSolution,
    /// Where the next load step starts.
    pub active_set: ActiveSet,
    /// A Coulomb pair's tangential answer.
    pub friction: Option<FrictionFields>,
}

/// The solution of the last iterate, with surface fields, forces and the Hertz fit.
pub(in crate::contact) fn finish(last: LastIterate) -> Result<ContactSolution, ContactError> {
    let LastIterate {
        problem,
        bodies: [(body1, stats1), (body2, stats2)],
        body_contact_force,
        linear_solvers,
        factors,
        status,
        history,
        certificate,
        gaps,
        coupling,
        solution,
        active_set,
        friction,
    } = last;
    let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
    let dim = s1.dim;
    let [gaps1, gaps2] = gaps;
    let mut primary_fields = surface_fields(s1, &solution.contact_force[0], gaps1, |s| {
        active_set.nodes.contains(&s)
    });
    primary_fields.friction = friction;
    let mut secondary_fields = surface_fields(s2, &solution.contact_force[1], gaps2, |_| false);
    let touching = problem.settings.secondary_penetration_tolerance;
    secondary_fields.active = secondary_in_contact(s2, &secondary_fields, touching);
    let [force_primary, force_secondary] = solution.total_forces(dim)[..] else {
        unreachable!("a pair has two bodies")
    };
    let force_imbalance = certificate
        .checks
        .iter()
        .find(|c| c.name == CheckKind::Equilibrium)
        .map_or(f64::NAN, |c| c.value);
    let hertz_primary = hertz::fit(s1, &primary_fields);
    let max_tangential_traction = max_tangential(&solution.traction[0], &coupling.normals);
    let residual = solution.relative_residual;
    let forced = (
        problem.primary.body.name.as_str(),
        body1,
        &solution.rigid[0],
    );
    let forced = [
        forced,
        (&problem.secondary.body.name, body2, &solution.rigid[1]),
    ]
    .into_iter()
    .flat_map(|(name, body, a)| {
        (body.rigid.iter().enumerate())
            .zip(a)
            .filter(|((_, rigid), _)| !rigid.pin)
            .map(move |((r, rigid), &a)| ForcedDisplacement {
                body: name.to_string(),
                group: rigid.group.clone(),
                component: ["x", "y", "z"][rigid.component],
                force: body.rigid_force(r, factors),
                displacement: a,
            })
    })
    .collect();
    let Ok([u1, u2]) = <[Vec<f64>; 2]>::try_from(solution.u) else {
        unreachable!("a pair has two bodies")
    };
    let primary = body_solution(
        &problem.primary,
        (body1, stats1),
        u1,
        body_contact_force[0],
        factors,
        residual,
    );
    let secondary = body_solution(
        &problem.secondary,
        (body2, stats2),
        u2,
        body_contact_force[1],
        factors,
        residual,
    );
    Ok(ContactSolution {
        linear_solvers,
        status,
        history,
        primary,
        secondary,
        primary_fields,
        secondary_fields,
        force_primary,
        force_secondary,
        force_imbalance,
        max_tangential_traction,
        certificate,
        hertz_primary,
        load_factor: factors.default,
        path_factors: factors.paths.clone(),
        forced,
        active_set,
    })
}

/// The secondary surface has no active set of its own: a node is in contact where it receives
/// a compressive force and touches the primary body to within `touching` of its spacing (the
/// certified accuracy).
fn secondary_in_contact(s2: &ContactSurface, fields: &SurfaceFields, touching: f64) -> Vec<bool> {
    (0..s2.len())
        .map(|j| {
            fields.mean_pressure[j] > 0.0 && fields.normal_gap[j].abs() <= touching * s2.spacing[j]
        })
        .collect()
}

/// The largest traction tangential to the contact normal the constraint used: zero for
/// frictionless, the glue's shear for tied.
fn max_tangential(traction: &[[f64; 3]], normals: &[[f64; 3]]) -> f64 {
    traction
        .iter()
        .zip(normals)
        .map(|(t, n)| {
            let normal = dot(t, n);
            let tangential: [f64; 3] = std::array::from_fn(|k| t[k] - normal * n[k]);
            dot(&tangential, &tangential).sqrt()
        })
        .fold(0.0, f64::max)
}

/// One body's part of the answer: displacement `u` and the reactions of its Dirichlet groups
/// (with the interface's `contact_force` on it); the coupled system's `residual` replaces the
/// body's own.
fn body_solution(
    problem: &ElasticProblem,
    (body, stats): (&AssembledBody, &SolveStats),
    u: Vec<f64>,
    contact_force: &LoadVector,
    factors: &StepFactors,
    residual: f64,
) -> ElasticSolution {
    ElasticSolution {
        reactions: reactions(problem, body, &u, factors, Some(contact_force)),
        displacement: u,
        stats: SolveStats {
            relative_residual: residual,
            ..stats.clone()
        },
    }
}

/// The interface fields of a surface from the nodal forces the interface puts on its body:
/// with the lumped interface mass the traction of node `s` is its force over its area.
fn surface_fields(
    surface: &ContactSurface,
    force: &LoadVector,
    gaps: Vec<f64>,
    active: impl Fn(usize) -> bool,
) -> SurfaceFields {
    let dim = surface.dim;
    let traction: Vec<[f64; 3]> = (0..surface.len())
        .map(|s| {
            let node = surface.nodes[s];
            std::array::from_fn(|c| {
                if c < dim {
                    force.get(dim * node + c) / surface.nodal_area[s]
                } else {
                    0.0
                }
            })
        })
        .collect();
    SurfaceFields {
        nodes: surface.nodes.clone(),
        pressure: traction
            .iter()
            .zip(&surface.normals)
            .map(|(t, n)| -dot(t, n))
            .collect(),
        mean_pressure: (0..surface.len())
            .map(|s| surface.mean_pressure(force, s))
            .collect(),
        traction,
        normal_gap: gaps,
        active: (0..surface.len()).map(active).collect(),
        friction: None,
    }
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
