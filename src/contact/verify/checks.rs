//! The checks of a contact answer ([`Certificate`]), measured without the active-set loop's
//! operators (`docs/method.md`, section 4). They answer two questions apart, as a convex
//! solver's termination criteria and an error estimate do.
//!
//! **Is the discrete problem solved?** The residuals of its KKT conditions ([`CheckKind`]'s
//! first five; [`contact_status`] turns them into the status):
//! - **Penetration** (primal feasibility). Every candidate node of both bodies, active or not,
//!   is projected onto the other body's displaced P1 surface ([`geometric_gaps`]); the largest
//!   penetration (a primary node's beyond the penalty method's overlap `p / eps`) over the node's
//!   spacing must not exceed `penetration_tolerance` on the
//!   primary surface, whose nodes the constraint holds, and `secondary_penetration_tolerance`
//!   on the secondary one, whose nodes only the transfer holds, counted where no active
//!   primary node is within a facet ([`Held::Not`]: contact the active set missed; between
//!   and beside constrained nodes the secondary's penetration is the discretization's, judged
//!   by the accuracy indicators).
//! - **Tension** (dual feasibility). The normal force every surface node of both bodies (of
//!   the primary alone when the secondary is nearly rigid: only the resultant of its load
//!   acts on it) receives from the interface (active or not), over its area, is its mean pressure
//!   ([`ContactSurface::mean_pressure`], along the node's own outward normal); the largest
//!   tension over the largest pressure must not exceed `certificate_tension_tolerance`, a
//!   bound for the undershoot of the RBF transfer of the multiplier to the secondary surface.
//! - **Complementarity.** Every active node lies on the other surface (under the penalty method,
//!   `p / eps` inside it): the gap its constraint holds, measured again at the answer, within
//!   `penetration_tolerance` of its spacing.
//! - **Equilibrium.** `|F1 + F2| / |F1|`, the total contact forces on the two bodies, must not
//!   exceed `imbalance_tolerance`: the interpolation transfer `R21` conserves force only to its
//!   accuracy; the conservative transfer (`R12^T`, [`crate::contact::Transfer`]) balances to
//!   round-off.
//!
//! **Can the answer be trusted?** The accuracy indicators, each an error measure of what users
//! read (the contact force and zone); they never change the status:
//! - **Secondary sag.** The relative error of the contact force that the secondary's
//!   penetration between constrained primary nodes makes, estimated from the pressure-weighted
//!   sag over how far the bodies are pressed into each other (`secondary_sag`), must not
//!   exceed `accuracy_tolerance`.
//! - **Penalty overlap** (penalty pairs, `crate::contact::method`): the relative error of the
//!   force that the overlap `p / eps` makes, estimated as the sag's ([`penalty_overlap`]).
//! - **Resolution.** The contact zone must be at least `min_zone_width` primary spacings wide,
//!   and `secondary_min_zone_width` secondary spacings unless the secondary is nearly rigid
//!   ([`zone_resolution`]): with one or two nodes across it, the pressure profile has too few
//!   values, and the force is undetermined to the certificate's accuracy although every other
//!   check can pass (a stiff, coarse primary under a small zone). The secondary needs more: the
//!   primary sees it only through the interpolation `R12` of its displacement, whose error over
//!   a zone of three nodes is of the order of the force's (an explicit stiff primary on a
//!   compliant secondary three nodes across: 1.3% off dolfinx's rigid flat). In 3D against a
//!   secondary that is not nearly rigid, a zone's width is its width across its longest axis
//!   ([`aspect`]): along a line of contact (an edge) the load across the line is what the
//!   transfer spreads, however long the line.
//! - **Force centre.** The two bodies' contact forces act at the same place ([`ForceCentres`]).
//! - **Stick zone resolution** (Coulomb pairs in partial slip, [`friction`], which also measures
//!   the Coulomb law's two residuals, the friction cone and the slip rule): the stick zone
//!   at least `min_zone_width` spacings wide.
//! - **Primary agreement** (only for a primary named in the case file and at least twice
//!   stiffer than the other body, a choice `primary = "auto"` avoids):
//!   the contact force must agree with the one found with the other body as primary, within
//!   `accuracy_tolerance` ([`agreement`], solved by `crate::contact::driver`). Another multiplier
//!   space is an independent discretization of the same problem; a stiff block primary twice finer
//!   than a hemisphere passed every other check with a force 3% off, and the hemisphere as
//!   primary told it apart.
//! - **Transfer agreement** (only for a transfer named in the case file that `auto` would not
//!   choose): the same, against the automatic transfer.
//!
//! A failed check names the body, the gmsh node tag and the figure.

use std::collections::HashSet;

use crate::contact::certificate::{Certificate, CertificateCheck, CheckKind};
use crate::contact::coupled::system::CoupledSolution;
use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::gap::{GapRow, gap_rows, geometric_gaps};
use crate::contact::geometry::surface::ContactSurface;
use crate::contact::law::coulomb::norm;
use crate::contact::law::{ContactLaw, Tangential};
use crate::contact::method::Enforcement;
use crate::contact::problem::ContactProblem;
use crate::contact::solution::ContactStatus;
use crate::fem::LoadVector;

/// How the loop's ending and the residual checks make the status: the one place that decides
/// it. A loop that stopped converged has solved the discrete problem only if every residual,
/// measured independently of the loop's operators, is within its tolerance; an empty active
/// set is then no contact. The accuracy indicators play no part.
pub fn contact_status(
    loop_end: ContactStatus,
    certificate: &Certificate,
    active_is_empty: bool,
) -> ContactStatus {
    use ContactStatus::{Converged, NoContact, NotSolved};
    match loop_end {
        Converged if !certificate.solved() => NotSolved,
        Converged if active_is_empty => NoContact,
        other => other,
    }
}

/// Certifies the displacements and interface forces of a solution (module doc) with the
/// active set `active`, the solution's tractions at the primary nodes `solved` (the same set
/// unless the loop stopped before settling); also returns the geometric gaps it measured on
/// the primary and secondary surfaces (the `normal_gap` output).
pub fn certify(
    problem: &ContactProblem,
    solution: &CoupledSolution,
    [active, solved]: [&[usize]; 2],
) -> (Certificate, [Vec<f64>; 2]) {
    let settings = &problem.settings;
    let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
    // The displacements at the surfaces' nodes (on a rank of a distributed run, the boundary's
    // values the loop gathered: `CoupledSolution::displacement`).
    let (u1, u2) = (solution.displacement(0), solution.displacement(1));
    let sides: [Side; 2] = [
        (s1, s2, u1, u2, &solution.contact_force[0]),
        (s2, s1, u2, u1, &solution.contact_force[1]),
    ];
    let gaps = sides.map(|(own, other, u_own, u_other, _)| {
        geometric_gaps(own, other, Some(u_own), Some(u_other))
    });
    let held = held_by_primary([s1, s2], [u1, u2], active);
    let mean: Vec<Vec<f64>> = sides
        .iter()
        .map(|&(own, _, _, _, force)| {
            (0..own.len())
                .map(|s| own.mean_pressure(force, s))
                .collect()
        })
        .collect();

    // The penalty method's overlap `p / eps` at each primary node: what its law allows
    // (`crate::contact::method`); zero under INTERNODES.
    let law = ContactLaw::of(settings);
    let row_normal = law.row_normal(problem.transfer().transfer);
    let rows = gap_rows(s1, s2, Some(u1), Some(u2), row_normal);
    let enforcement = Enforcement::of(problem);
    let mut overlap = vec![0.0; s1.len()];
    for (k, &i) in solved.iter().enumerate() {
        let n = rows[i].normal;
        let pressure = -(0..3)
            .map(|c| solution.traction[0][k][c] * n[c])
            .sum::<f64>();
        overlap[i] = enforcement.row_residual(0.0, pressure.max(0.0));
    }
    let [penetration1, penetration2] = penetration(&sides, &gaps, &held, &overlap);
    let indentation = indentation_depth(s1, s2, [u1, u2], &gaps[0], &mean[0])
        .max(elastic_approach(s1, &mean[0], problem.contact_modulus()));
    // A nearly rigid secondary's spacing does not bound the answer: only its position does.
    let secondary_width =
        (!problem.secondary_is_nearly_rigid()).then_some(settings.secondary_min_zone_width);
    let mut checks = vec![
        penetration1.check(CheckKind::Penetration, settings.penetration_tolerance),
        penetration2.check(
            CheckKind::SecondaryPenetration,
            settings.secondary_penetration_tolerance,
        ),
        tension(problem, &sides, &mean),
        complementarity(problem, &rows, &gaps[0], active, &overlap),
        equilibrium(solution, s1.dim, settings.imbalance_tolerance),
        secondary_sag(
            s2,
            &held,
            &gaps[1],
            &mean[1],
            indentation,
            settings,
            enforcement,
        ),
        zone_resolution(
            [(s1, Some(settings.min_zone_width)), (s2, secondary_width)],
            &mean,
            &held,
        ),
        force_centres(&sides, &mean).check(settings.force_centre_tolerance),
    ];
    if let Enforcement::Penalty { .. } = enforcement {
        checks.insert(
            6,
            penalty_overlap(s1, &overlap, &mean[0], indentation, settings),
        );
    }
    (Certificate { checks }, gaps)
}

/// The deepest penetration over the node's spacing on each surface: every primary node, beyond
/// the `overlap` its law allows (the penalty method's `p / eps`, zero under INTERNODES), and
/// the secondary nodes no active primary node holds ([`Held::Not`]).
fn penetration(
    sides: &[Side; 2],
    gaps: &[Vec<f64>; 2],
    held: &[Held],
    overlap: &[f64],
) -> [Worst; 2] {
    let mut worst = [Worst::default(), Worst::default()];
    for (b, (worst, &(own, ..))) in worst.iter_mut().zip(sides).enumerate() {
        for (s, g) in gaps[b].iter().enumerate() {
            if b == 0 {
                worst.offer((-g - overlap[s]) / own.spacing[s], own, s);
            } else if held[s] == Held::Not {
                worst.offer(-g / own.spacing[s], own, s);
            }
        }
    }
    worst
}

/// The largest tension (negative mean pressure) of a surface node over the largest pressure.
fn tension(problem: &ContactProblem, sides: &[Side; 2], mean: &[Vec<f64>]) -> CertificateCheck {
    let p_max = mean.iter().flatten().copied().fold(0.0, f64::max);
    // A nearly rigid secondary's nodal forces are the transfer's spreading of the multiplier,
    // of which only the resultant acts on it (`ContactProblem::transfer` chooses the
    // conservative transfer there for that reason): its nodes are not judged for tension.
    let judged = if problem.secondary_is_nearly_rigid() {
        1
    } else {
        2
    };
    let mut tension = Worst::default();
    if p_max > 0.0 {
        for (&(own, ..), pressures) in sides.iter().zip(mean).take(judged) {
            for (s, p) in pressures.iter().enumerate() {
                tension.offer(-p / p_max, own, s);
            }
        }
    }
    let tolerance = problem.settings.certificate_tension_tolerance;
    tension.check(CheckKind::Tension, tolerance)
}

/// Complementarity: the gap each active node's constraint holds, measured again at the
/// answer (frictionless: the gap of its linearization, `crate::contact::geometry::gap`, which is
/// the geometric gap wherever the node faces the inside of a secondary facet; tied: the geometric
/// gap `gaps1`), plus the `overlap` its law allows (the penalty method's `p / eps`), over the
/// node's spacing.
fn complementarity(
    problem: &ContactProblem,
    rows: &[GapRow],
    gaps1: &[f64],
    active: &[usize],
    overlap: &[f64],
) -> CertificateCheck {
    let s1 = &problem.primary_surface;
    let held: Vec<f64> = match ContactLaw::of(&problem.settings).holds_geometric_gap() {
        true => rows.iter().map(|row| row.gap).collect(),
        false => gaps1.to_vec(),
    };
    let mut worst = Worst::default();
    for &i in active {
        worst.offer((held[i] + overlap[i]).abs() / s1.spacing[i], s1, i);
    }
    let tolerance = problem.settings.penetration_tolerance;
    worst.check(CheckKind::Complementarity, tolerance)
}

/// The residuals of the Coulomb law at the answer of a Coulomb pair with coefficient `mu`,
/// on every primary candidate in `state` (`None`: open) with its `pressure`, tangential
/// traction `t_t` and slip increment `slip` over the step (`crate::contact::law::coulomb`):
/// - **Friction cone** (dual feasibility): `(|t_T| - mu p) / (mu p_max)` at every node in
///   contact, within `tension_tolerance` (the slack of the update);
/// - **Slip**: a sticking node's slip `|v|`, and a slipping node's slip along its own
///   friction traction `v . d` (it must slip against it), over its spacing, within
///   `penetration_tolerance` (the bound that holds the normal gap).
///
/// And, where some nodes stick and others slip, an accuracy indicator: the **stick zone's
/// resolution**, the mean spacing of its nodes times `min_zone_width` over its width (the
/// largest distance between two sticking nodes), at most 1: the rule the contact zone's
/// resolution follows (its edge lies between a sticking and a slipping node, a spacing apart).
pub fn friction(
    problem: &ContactProblem,
    mu: f64,
    state: &[Option<Tangential>],
    pressure: &[f64],
    t_t: &[[f64; 3]],
    slip: &[[f64; 3]],
) -> Vec<CertificateCheck> {
    let s1 = &problem.primary_surface;
    let settings = &problem.settings;
    let p_max = pressure.iter().copied().fold(0.0, f64::max);
    let (mut cone, mut slipping) = (Worst::default(), Worst::default());
    for (i, state) in state.iter().enumerate() {
        let Some(state) = state else { continue };
        if p_max > 0.0 {
            cone.offer((norm(t_t[i]) - mu * pressure[i]) / (mu * p_max), s1, i);
        }
        let along = match state {
            Tangential::Stick => norm(slip[i]),
            Tangential::Slip { direction, .. } => (0..3).map(|k| slip[i][k] * direction[k]).sum(),
        };
        slipping.offer(along / s1.spacing[i], s1, i);
    }
    let mut checks = vec![
        cone.check(CheckKind::FrictionCone, settings.tension_tolerance),
        slipping.check(CheckKind::Slip, settings.penetration_tolerance),
    ];
    let sticking: Vec<usize> = (state.iter().enumerate())
        .filter(|(_, s)| matches!(s, Some(Tangential::Stick)))
        .map(|(i, _)| i)
        .collect();
    let slips = state
        .iter()
        .any(|s| matches!(s, Some(Tangential::Slip { .. })));
    if slips && !sticking.is_empty() {
        let mut width = 0.0_f64;
        for (k, &i) in sticking.iter().enumerate() {
            for &j in &sticking[k + 1..] {
                let (a, b) = (s1.coords[i], s1.coords[j]);
                width = width.max(norm(std::array::from_fn(|c| a[c] - b[c])));
            }
        }
        let spacing = sticking.iter().map(|&i| s1.spacing[i]).sum::<f64>() / sticking.len() as f64;
        let value = spacing * settings.min_zone_width / width;
        checks.push(CertificateCheck {
            name: CheckKind::StickResolution,
            value,
            tolerance: 1.0,
            passed: value <= 1.0,
            body: None,
            node_tag: None,
            note: Some(format!(
                "{} sticking nodes across {width:.3e}",
                sticking.len()
            )),
        });
    }
    checks
}

/// Equilibrium: `|F1 + F2| / |F1|`, the total contact forces on the two bodies.
fn equilibrium(solution: &CoupledSolution, dim: usize, tolerance: f64) -> CertificateCheck {
    let [f1, f2] = solution.total_forces(dim)[..] else {
        unreachable!("a pair has two bodies")
    };
    let norm = |f: [f64; 3]| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let imbalance = if norm(f1) > 0.0 {
        norm(std::array::from_fn(|c| f1[c] + f2[c])) / norm(f1)
    } else {
        norm(f2)
    };
    CertificateCheck {
        name: CheckKind::Equilibrium,
        value: imbalance,
        tolerance,
        passed: imbalance <= tolerance,
        body: None,
        node_tag: None,
        note: None,
    }
}

/// An agreement check (`kind`: primary or transfer agreement): the total contact force on
/// each body, `F_b`, against the force on the same body from the other discretization, `F'_b`,
/// solved `with` the other primary or transfer (`Ok`); the figure is the larger of
/// `|F_b - F'_b| / |F'_b|` over the two bodies, against `tolerance`. Both bodies, because a
/// user reads the force on each, and they differ by the interpolation transfer's imbalance
/// (within the equilibrium residual's 1%): a stiff block named primary had its own force 0.4%
/// from the sphere primary's, and the force on the sphere 1.1% (dolfinx's rigid flat: 1.1%).
/// `forces` and the reference are ordered [this solve's primary body, its secondary body].
/// Without a trusted answer to compare with (`Err`: how that solve ended), the check fails
/// with the figure 1 (the force is not confirmed to any fraction of itself), and the note says
/// why.
pub fn agreement(
    kind: CheckKind,
    forces: [[f64; 3]; 2],
    other: Result<[[f64; 3]; 2], String>,
    with: &str,
    tolerance: f64,
) -> CertificateCheck {
    let norm = |f: [f64; 3]| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let relative = |force: [f64; 3], reference: [f64; 3]| {
        let difference = norm(std::array::from_fn(|c| force[c] - reference[c]));
        if norm(reference) > 0.0 {
            difference / norm(reference)
        } else if difference > 0.0 {
            1.0
        } else {
            0.0
        }
    };
    let (value, note) = match other {
        Ok(reference) => (
            relative(forces[0], reference[0]).max(relative(forces[1], reference[1])),
            format!(
                "forces on the primary and the secondary {:.6e}, {:.6e} here, {:.6e}, {:.6e} \
                 with {with}",
                norm(forces[0]),
                norm(forces[1]),
                norm(reference[0]),
                norm(reference[1])
            ),
        ),
        Err(ended) => (
            1.0,
            format!("no trusted answer with {with} to compare with: it ended {ended}"),
        ),
    };
    CertificateCheck {
        name: kind,
        value,
        tolerance,
        passed: value <= tolerance,
        body: None,
        node_tag: None,
        note: Some(note),
    }
}

/// Where the normal contact forces on each body act: their centre `sum F_s x_s / sum F_s`, `F_s`
/// a node's compressive normal force (mean pressure times area) and `x_s` its displaced
/// position; and the coarser of the two surfaces' spacings where they are loaded (each the
/// `|F_s|`-weighted mean spacing of its nodes).
struct ForceCentres {
    centres: [Option<[f64; 3]>; 2],
    spacing: f64,
}

/// One body's side of the certificate: its surface, the other's, their displacements and the
/// contact force on it (body dofs).
type Side<'a> = (
    &'a ContactSurface,
    &'a ContactSurface,
    BodyDisplacement<'a>,
    BodyDisplacement<'a>,
    &'a LoadVector,
);

fn force_centres(sides: &[Side; 2], mean: &[Vec<f64>]) -> ForceCentres {
    let mut spacing = 0.0f64;
    let centres = std::array::from_fn(|b| {
        let (own, _, u_own, _, _) = sides[b];
        let force = |s: usize| mean[b][s] * own.nodal_area[s];
        let total: f64 = (0..own.len()).map(force).sum();
        let magnitude: f64 = (0..own.len()).map(|s| force(s).abs()).sum();
        if magnitude > 0.0 {
            let loaded = (0..own.len()).map(|s| force(s).abs() * own.spacing[s]);
            spacing = spacing.max(loaded.sum::<f64>() / magnitude);
        }
        (total > 0.0).then(|| {
            let mut moment = [0.0; 3];
            for s in 0..own.len() {
                let (f, x) = (force(s), own.deformed(u_own, s));
                (0..3).for_each(|k| moment[k] += f * x[k]);
            }
            moment.map(|m| m / total)
        })
    });
    ForceCentres { centres, spacing }
}

impl ForceCentres {
    /// The "force centre" check: the distance between the two centres over the coarser
    /// surface's spacing. The interface exerts equal and opposite forces on the two bodies at
    /// the same place; forces that balance but act apart are the signature of surfaces paired
    /// where they no longer touch (a body slid sideways while the other received its reaction
    /// where the contact had started: centres 20 spacings apart, force 36% off, every other
    /// check passed). The interpolation places a coarse surface's load only to a fraction of
    /// its spacing (it reproduces constants, not linear fields, on a graded mesh): 0.45 of the
    /// block's spacing at the contact on the sweep's R/100 hemisphere over a twice coarser rigid
    /// block, whose force is dolfinx's to 1e-4; hence the coarser spacing. Without a compressive force on
    /// both bodies there is nothing to compare (figure 0).
    fn check(&self, tolerance: f64) -> CertificateCheck {
        let value = match self.centres {
            [Some(c1), Some(c2)] if self.spacing > 0.0 => {
                (0..3).map(|k| (c1[k] - c2[k]).powi(2)).sum::<f64>().sqrt() / self.spacing
            }
            _ => 0.0,
        };
        CertificateCheck {
            name: CheckKind::ForceCentre,
            value,
            tolerance,
            passed: value <= tolerance,
            body: None,
            node_tag: None,
            note: None,
        }
    }
}

/// How far the two surfaces moved into each other over the contact zone: over the primary
/// nodes that receive a compressive mean pressure, the largest change of the gap between the
/// node and the material point of the secondary it touches now (the closest point on the
/// displaced surface), from their reference separation along the node's outward normal to the
/// geometric gap. For a sphere pressed onto a flat it is the gap the rim had to close,
/// `a^2 / (2R)`, half the approach `delta = a^2 / R`; for a body meshed overlapping, the
/// overlap undone. Between the material points in contact, not the reference closest points:
/// a sphere slid sideways by `dx` over the flat closes `a^2 / (2R)` at its rim, not the
/// flat's reference distance to the sphere `dx` away (which made the sag of a coarse flat
/// primary look a third smaller, and pass, with the force 1% low).
fn indentation_depth(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    [u1, u2]: [BodyDisplacement; 2],
    gaps: &[f64],
    pressure: &[f64],
) -> f64 {
    let displaced = secondary.index(Some(u2));
    (0..primary.len())
        .filter(|&s| pressure[s] > 0.0)
        .map(|s| {
            let touching = (displaced.project(&primary.deformed(u1, s)))
                .expect("a contact surface has facets");
            let q = secondary.reference_point(touching.facet, &touching.barycentric);
            let (x, n) = (primary.coords[s], primary.normals[s]);
            let separation: f64 = (0..3).map(|k| n[k] * (q[k] - x[k])).sum();
            (separation - gaps[s]).abs()
        })
        .fold(0.0, f64::max)
}

/// How far the bodies' elastic compression moves them into each other to carry the contact
/// force, estimated from the primary's contact zone: `(3 pi / 16) p_mean W / E*`, with
/// `p_mean` the zone's mean pressure, `W` its width and `E*` the combined modulus. A zone of
/// width `W` loaded by `p_mean` compresses the bodies by the order of `p_mean W / E*`; the
/// factor makes it exactly the geometric indentation depth `a^2 / (2R)` of a 3D Hertz contact
/// (`p_mean = 4 a E* / (3 pi R)`, `W = 2a`), and 0.75 of the approach of a rigid circular flat
/// punch (`P = 2 a E* delta`). The sag's scale is the larger of the two: a flat punch moves
/// no geometric gap closed ([`indentation_depth`] is zero for it), yet its compression is what
/// a sag of the secondary makes softer.
fn elastic_approach(primary: &ContactSurface, pressure: &[f64], contact_modulus: f64) -> f64 {
    let zone: Vec<usize> = (0..primary.len()).filter(|&s| pressure[s] > 0.0).collect();
    let area: f64 = zone.iter().map(|&s| primary.nodal_area[s]).sum();
    if zone.is_empty() || area <= 0.0 {
        return 0.0;
    }
    let force: f64 = zone
        .iter()
        .map(|&s| pressure[s] * primary.nodal_area[s])
        .sum();
    let n = zone.len() as f64;
    let centroid: [f64; 3] =
        std::array::from_fn(|c| zone.iter().map(|&s| primary.coords[s][c]).sum::<f64>() / n);
    let radius = (zone.iter())
        .map(|&s| {
            (0..3)
                .map(|c| (primary.coords[s][c] - centroid[c]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    3.0 * std::f64::consts::PI / 16.0 * (force / area) * 2.0 * radius / contact_modulus
}

/// The relative error of the contact force that the secondary's sag between constrained
/// primary nodes makes, estimated (the "secondary sag" indicator):
///
/// ```text
/// eta = (3/4) sum_s F_s sag_s / (delta sum_s F_s)
/// ```
///
/// over the secondary nodes in contact, `F_s` a node's compressive force (mean pressure times
/// area), `sag_s` its penetration into the primary (less the penalty method's overlap `p_s /
/// eps` at its mean pressure) where it lies [`Held::Inside`] the zone
/// (beyond the primary's penetration tolerance times its spacing; 0 elsewhere), `delta` the
/// indentation depth (the larger of the geometric one and the [`elastic_approach`]). Only the
/// transfer holds the secondary nodes: between two constrained primary nodes `h_p` apart, a
/// secondary surface of curvature `1/R` sags into a flat primary by about `h_p^2 / (8R)`, and
/// the contact is that much shallower there than the secondary's own discretization makes it.
/// By reciprocity (Betti), a change `w(x)` of the indentation over a zone of fixed extent
/// changes the force by `integral p_1 w dA`, `p_1` the pressure of a unit approach: the
/// pressure-weighted mean sag over the approach. The factor 3/4 turns the indentation depth
/// into the approach for both kinds of contact: a Hertz zone's depth `a^2 / (2R)` is half its
/// approach and its force grows as `delta^(3/2)` (`dP / P = (3/2) d(delta) / delta`); the
/// elastic approach is 3/4 of a flat punch's. Weighted, not the largest sag: at a rounded punch
/// corner a few nodes sag by a quarter of the approach while the flat face, which carries the
/// force, has none (the largest sag over the depth read 0.24 on a 3D punch whose force is the
/// rigid punch's to 8e-4). Measured (half-disc on a block meshed twice coarser, the block as
/// primary): the estimate 1.4% for a force 2.0% below the disc primary's.
fn secondary_sag(
    secondary: &ContactSurface,
    held: &[Held],
    gaps: &[f64],
    pressure: &[f64],
    indentation: f64,
    settings: &crate::contact::settings::ContactSettings,
    enforcement: Enforcement,
) -> CertificateCheck {
    let mut deepest = Worst::default();
    let (mut weighted, mut total) = (0.0, 0.0);
    for (s, g) in gaps.iter().enumerate() {
        let force = pressure[s].max(0.0) * secondary.nodal_area[s];
        if held[s] != Held::Not {
            total += force;
        }
        // Under the penalty method the bodies overlap by `p / eps` where they touch: the
        // penalty overlap indicator's part, not the sag.
        let sag = -enforcement.row_residual(*g, pressure[s].max(0.0));
        let floor = settings.penetration_tolerance * secondary.spacing[s];
        if held[s] == Held::Inside && sag > floor {
            weighted += force * sag;
            deepest.offer(sag, secondary, s);
        }
    }
    let mut check = deepest.check(CheckKind::SecondarySag, settings.accuracy_tolerance);
    check.note = (check.value > 0.0).then(|| {
        format!(
            "deepest sag {:.3e} of an indentation depth {indentation:.3e}",
            check.value
        )
    });
    with_force_error(check, weighted, total, indentation)
}

/// `check` (its worst node and note kept) with the figure `(3/4) weighted / (total delta)`:
/// the relative error of the force that a pressure-weighted change of the indentation
/// (`weighted` over the forces' `total`) makes, over the indentation depth `delta`
/// ([`secondary_sag`]); 0 without a force or a depth.
fn with_force_error(
    mut check: CertificateCheck,
    weighted: f64,
    total: f64,
    indentation: f64,
) -> CertificateCheck {
    check.value = if total > 0.0 && indentation > 0.0 {
        0.75 * weighted / (total * indentation)
    } else {
        0.0
    };
    check.passed = check.value <= check.tolerance;
    check
}

/// The relative error of the contact force that the penalty method's overlap makes, estimated
/// (the "penalty overlap" indicator) as the secondary's sag is ([`secondary_sag`]):
///
/// ```text
/// eta = (3/4) sum_i F_i o_i / (delta sum_i F_i)
/// ```
///
/// over the primary nodes, `F_i` a node's compressive force (mean pressure times area), `o_i`
/// its overlap `p_i / eps`, `delta` the indentation depth. The overlap takes that much of the
/// bodies' approach at each node, and by reciprocity the force changes by the pressure-weighted
/// mean of it over the approach. The note gives the largest overlap over its node's spacing.
fn penalty_overlap(
    primary: &ContactSurface,
    overlap: &[f64],
    pressure: &[f64],
    indentation: f64,
    settings: &crate::contact::settings::ContactSettings,
) -> CertificateCheck {
    let (mut weighted, mut total) = (0.0, 0.0);
    let mut deepest = Worst::default();
    for (s, o) in overlap.iter().enumerate() {
        let force = pressure[s].max(0.0) * primary.nodal_area[s];
        weighted += force * o;
        total += force;
        deepest.offer(o / primary.spacing[s], primary, s);
    }
    let mut check = deepest.check(CheckKind::PenaltyOverlap, settings.accuracy_tolerance);
    check.note = Some(format!("overlap up to {:.2e} h", check.value));
    with_force_error(check, weighted, total, indentation)
}

/// How the constraint holds a secondary node: by the primary facet it faces (its closest
/// point on the displaced primary surface). Only primary nodes carry a constraint; a secondary
/// node is held through them, and how well depends on where it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Held {
    /// Every corner of the facet is active: the node lies between constrained nodes, and its
    /// penetration is the sag of the coupling (an accuracy indicator, [`secondary_sag`]).
    Inside,
    /// Some corners are active, or the facet touches one that has: the node is at the rim of
    /// the zone, which the primary resolves to one facet. A sharp secondary corner there (a
    /// flat punch's edge) crosses the facet that drops away from the zone: by 3% to 12% of a
    /// spacing on a 2D punch whose force is the rigid punch's to 0.1%, by 18% at the vertex of
    /// a 3D punch, which lies over a facet just outside the zone; a figure that grows as
    /// `1 / sqrt(h)` under refinement (the surface slope near the edge is singular) while the
    /// force converges. The zone's edge known to one spacing is the resolution indicator's
    /// measure ([`zone_resolution`]). A contact the active set missed there shows as a primary
    /// node penetrating, which the primary's penetration check bounds.
    Rim,
    /// The facet is more than one facet from the zone: nothing holds the node, and a
    /// penetration there is contact the active set missed (a residual of the discrete problem).
    Not,
}

/// How each secondary node is held ([`Held`]), at the displacements `u1`, `u2`, by the
/// `active` primary nodes (surface indices).
fn held_by_primary(
    [primary, secondary]: [&ContactSurface; 2],
    [u1, u2]: [BodyDisplacement; 2],
    active: &[usize],
) -> Vec<Held> {
    let is_active: HashSet<usize> = active.iter().copied().collect();
    // The nodes one facet from the zone: the corners of every facet with an active corner.
    let beside: HashSet<usize> = (0..primary.num_facets())
        .map(|f| primary.facet_nodes(f))
        .filter(|corners| corners.iter().any(|c| is_active.contains(c)))
        .flatten()
        .copied()
        .collect();
    let displaced = primary.index(Some(u1));
    (0..secondary.len())
        .map(|s| {
            let facet = (displaced.project(&secondary.deformed(u2, s)))
                .expect("a contact surface has facets")
                .facet;
            let corners = primary.facet_nodes(facet);
            let count = corners.iter().filter(|c| is_active.contains(c)).count();
            match count {
                n if n == corners.len() => Held::Inside,
                0 if !corners.iter().any(|c| beside.contains(c)) => Held::Not,
                _ => Held::Rim,
            }
        })
        .collect()
}

/// The resolution of the contact zone on each surface that has a minimum width (`None`: not
/// checked), as the spacing over the zone's width relative to that minimum; the check fails
/// above 1. A surface's zone is its nodes in contact: a compressive mean pressure and, on the
/// secondary, a node the active primary nodes hold ([`Held::Inside`] or [`Held::Rim`]: the
/// transfer loads a ring of nodes around the zone that do not touch). Its spacing is their mean
/// [`area_spacing`]; its width twice the largest distance of one of them from their centroid
/// (2a for a Hertz zone), and in 3D against a secondary that is not nearly rigid that times
/// the zone's [`aspect`], its width across its longest axis: the contact of an edge is one
/// node across however long the edge, and the load across it is the transfer's spreading, not
/// the solution's (the equal-material cube edge of the edge sweep, one primary node across, was
/// certified 1.9% off a same-mesh node-to-triangle reference before this). Against a nearly
/// rigid secondary the primary's nodes are held on its surface whatever spreads the load, and
/// the largest extent stays (the cube edge on a stiff block, one node across, within 0.04% of
/// the rigid plane). One node in contact has no width: its figure is capped at 1000 (JSON has
/// no infinity). No node in contact gives 0 (nothing to resolve).
fn zone_resolution(
    surfaces: [(&ContactSurface, Option<f64>); 2],
    pressures: &[Vec<f64>],
    held: &[Held],
) -> CertificateCheck {
    let across = surfaces[0].0.dim == 3 && surfaces[1].1.is_some();
    let mut check = Worst::default();
    for (b, ((surface, min_width), pressure)) in surfaces.into_iter().zip(pressures).enumerate() {
        let Some(min_width) = min_width else { continue };
        let zone: Vec<usize> = (0..surface.len())
            .filter(|&s| pressure[s] > 0.0 && (b == 0 || held[s] != Held::Not))
            .collect();
        if zone.is_empty() {
            continue;
        }
        let n = zone.len() as f64;
        let centroid: [f64; 3] =
            std::array::from_fn(|c| zone.iter().map(|&s| surface.coords[s][c]).sum::<f64>() / n);
        let distance = |s: usize| {
            let x = surface.coords[s];
            (0..3)
                .map(|c| (x[c] - centroid[c]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let rim = zone
            .iter()
            .copied()
            .max_by(|&a, &b| distance(a).total_cmp(&distance(b)));
        let rim = rim.expect("the zone is not empty");
        let spacing = zone.iter().map(|&s| area_spacing(surface, s)).sum::<f64>() / n;
        let narrowing = match across {
            true => aspect(&surface.coords, &zone, centroid),
            false => 1.0,
        };
        let width = (2.0 * distance(rim) * narrowing).max(spacing / 1000.0);
        check.offer(min_width * spacing / width, surface, rim);
    }
    check.check(CheckKind::Resolution, 1.0)
}

/// How much narrower a 3D zone is across its longest axis than along it: `sqrt(l2 / l1)`, `l1 >=
/// l2` the two largest eigenvalues of the spread of its nodes' positions about their centroid
/// (the third is the surface's normal). The zone's ellipse of inertia has this ratio of its
/// axes, so twice the largest distance from the centroid times it is the width across: a disc's
/// diameter (a ratio of 1, within the sampling of its nodes), an ellipse's minor axis, a
/// strip's width, a line's nothing.
fn aspect(coords: &[[f64; 3]], zone: &[usize], centroid: [f64; 3]) -> f64 {
    let offset = |s: usize| nalgebra::Vector3::from_fn(|c, _| coords[s][c] - centroid[c]);
    let spread = zone.iter().fold(nalgebra::Matrix3::zeros(), |m, &s| {
        m + offset(s) * offset(s).transpose()
    });
    let mut eigenvalues: Vec<f64> = spread.symmetric_eigenvalues().iter().copied().collect();
    eigenvalues.sort_by(|a, b| b.total_cmp(a));
    if eigenvalues[0] <= 0.0 {
        return 1.0; // one node: no axis (its width is capped by the caller)
    }
    (eigenvalues[1].max(0.0) / eigenvalues[0]).sqrt()
}

/// The edge length of a regular mesh whose nodes stand for node `s`'s area: the area itself in
/// 2D (a length), `sqrt(2 A / sqrt 3)` in 3D (six equilateral triangles share a node). The
/// distance to the nearest node is 0.6 to 0.8 of it on unstructured triangulations, which made
/// a 3D zone look twice as well resolved as a 2D zone with as many nodes across.
fn area_spacing(surface: &ContactSurface, s: usize) -> f64 {
    let area = surface.nodal_area[s];
    if surface.dim == 2 {
        area
    } else {
        (2.0 * area / 3f64.sqrt()).sqrt()
    }
}

/// The largest value seen and its node (0 with no node when nothing is positive).
#[derive(Default)]
struct Worst {
    value: f64,
    node: Option<(String, u64)>,
}

impl Worst {
    fn offer(&mut self, value: f64, surface: &ContactSurface, s: usize) {
        // A NaN fails: it must never read as "no violation".
        if value > self.value || value.is_nan() && !self.value.is_nan() {
            self.value = value;
            self.node = Some((surface.body.clone(), surface.tags[s]));
        }
    }

    fn check(self, name: CheckKind, tolerance: f64) -> CertificateCheck {
        let (body, node_tag) = self.node.map_or((None, None), |(b, t)| (Some(b), Some(t)));
        CertificateCheck {
            name,
            value: self.value,
            tolerance,
            passed: self.value <= tolerance,
            body,
            node_tag,
            note: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::aspect;

    fn centroid(points: &[[f64; 3]]) -> [f64; 3] {
        std::array::from_fn(|c| points.iter().map(|p| p[c]).sum::<f64>() / points.len() as f64)
    }

    fn aspect_of(points: &[[f64; 3]]) -> f64 {
        let zone: Vec<usize> = (0..points.len()).collect();
        aspect(points, &zone, centroid(points))
    }

    #[test]
    fn a_zone_narrows_by_its_width_across_over_its_length() {
        // A line of 41 nodes along a direction in no axis, on a plane tilted by 20 degrees: no
        // width, however long.
        let (turn, tilt) = (17f64.to_radians(), 20f64.to_radians());
        let along = [turn.cos(), turn.sin(), 0.0];
        let line: Vec<[f64; 3]> = (0..41)
            .map(|k| {
                let t = -0.2 + 0.01 * k as f64;
                [t * along[0], t * along[1], 0.3]
            })
            .collect();
        assert!(aspect_of(&line) < 1e-6, "a line: {}", aspect_of(&line));

        // Two such lines 0.04 apart across, on the tilted plane: a strip 0.4 long whose spread
        // across is 0.02 against 0.4 / sqrt(12) along it.
        let across = [
            -turn.sin() * tilt.cos(),
            turn.cos() * tilt.cos(),
            tilt.sin(),
        ];
        let strip: Vec<[f64; 3]> = (line.iter())
            .flat_map(|p| [-0.02, 0.02].map(|d| std::array::from_fn(|c| p[c] + d * across[c])))
            .collect();
        let length_spread = (line.iter().map(|p| (p[0] / along[0]).powi(2)).sum::<f64>()
            / line.len() as f64)
            .sqrt();
        let expected = 0.02 / length_spread;
        let ratio = aspect_of(&strip);
        assert!(
            (ratio / expected - 1.0).abs() < 1e-9,
            "a strip: {ratio} against {expected}"
        );

        // A disc of radius 0.1 sampled on rings: as wide across as along.
        let mut disc = vec![[0.0, 0.0, 0.0]];
        for ring in 1..=5 {
            let r = 0.02 * ring as f64;
            for k in 0..6 * ring {
                let a = 2.0 * std::f64::consts::PI * k as f64 / (6 * ring) as f64;
                disc.push([r * a.cos(), r * a.sin(), 0.0]);
            }
        }
        assert!(
            (aspect_of(&disc) - 1.0).abs() < 1e-9,
            "a disc: {}",
            aspect_of(&disc)
        );
        // One node: no axis, no narrowing.
        assert_eq!(aspect_of(&[[0.1, 0.2, 0.3]]), 1.0);
    }
}
