//! The interface operators of a contact solve, built over ALL candidate nodes (once, and
//! again when the surfaces have slid over each other: [`InterfaceOperators::slide`]): the
//! transfers `R12`, `R21`, the (lumped) interface mass, the contact normal, and the gaps.
//!
//! **Interpolation along the surfaces.** Every primary candidate `x_i` is projected onto the
//! secondary surface along the contact normal below (point `p_i`, reference geometry,
//! [`crate::contact::geometry::projection`]), and `R12`
//! is the rescaled Wendland interpolation (`docs/method.md` 2.2) from all secondary candidates to
//! the points `p_i`; likewise `R21` from all primary candidates to the projections of the
//! secondary candidates onto the primary surface. The targets lie on the source surface, so
//! every node is covered however far apart the two surfaces start (a rim many spacings from
//! the other body, or bodies meshed overlapping), and the interpolation runs along the surface,
//! not across the gap. An active set only selects rows of these operators: the complementarity
//! problem the active-set loop solves does not change from one iteration to the next.
//!
//! **The contact normal** at a primary candidate combines its outward normal and the secondary
//! surface's outward normal interpolated at `p_i`, weighted by the bodies' contact moduli,
//! `n_i = (w1 n1_i - w2 R12 n2) / |...|` ([`contact_normal`]): the normal of the deformed
//! interface, which lies nearer the stiffer body. With the primary's own normal, a node of a
//! curved primary sliding by `u_t` on a flat ends `(x / R) u_t` off it (the rigid-flat force
//! was 1.2% low); between two equal bodies it is the symmetry plane's normal.
//!
//! **Gaps.** The reference gap `d_i = n_i . (p_i - x_i)` is exact against a flat at any
//! distance. The linearized gap of a displacement is
//! `g_i(u) = d_i - n_i . (u1_i - (R12 u2)_i)` ([`InterfaceOperators::linearized_gaps`]). It is
//! the constraint of tied contact, `g_i(u) + e_i = 0` with `e_i` the difference between the
//! geometric gap of the last iterate ([`geometric_gaps`]) and its linearized gap, so that an
//! active node ends ON the other body's discrete surface, not on the RBF reconstruction of it.
//! Frictionless contact constrains the geometric gap itself, linearized node to segment
//! ([`crate::contact::geometry::gap`]); `R12` then only measures how far the pairing has slid.
//!
//! **Lumped interface mass.** Node `s` stands for its area `A_s` ([`ContactSurface`]): the
//! multiplier `lambda_i` exerts `-A_i lambda_i` on body 1 and, on body 2, either
//! `+A2_j (R21 lambda)_j` (interpolation, which balances to the interpolation's accuracy) or
//! `+(R12^T A1 lambda)_j` (conservative, which balances exactly; [`crate::contact::Transfer`]).

use std::collections::HashMap;

use crate::contact::ContactError;
use crate::contact::coupled::row_ownership::{Keepers, send_to_keepers};
use crate::contact::coupled::system::Coupling;
use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::gap::GapRow;
use crate::contact::geometry::rbf::{Interpolation, interpolation_radii};
use crate::contact::geometry::rbf_patch::BlockShare;
use crate::contact::geometry::surface::ContactSurface;
use crate::contact::geometry::walls::HeldWall;
use crate::contact::law::{ContactLaw, Multiplier, Reads, Restates, Tangential, coulomb};
use crate::contact::method::Enforcement;
use crate::contact::settings::Transfer;

/// `R12`, `R21`, the contact normals and reference gaps of every primary candidate, and the
/// rows and columns of the transfers computed so far (an explicit cache: callers hold it `mut`).
pub struct InterfaceOperators {
    /// From the secondary candidates to the projections of the primary candidates.
    r12: Interpolation,
    /// From the primary candidates to the projections of the secondary candidates that face
    /// the primary surface, `receiving` (surface indices). Built for the interpolation
    /// transfer alone: under the others a secondary node outside every primary support is
    /// loaded through `R12^T` or the rows' own weights, and is no error.
    r21: Option<Interpolation>,
    /// How the secondary receives the force (never `Auto`: `crate::contact::Transfer`).
    transfer: Transfer,
    receiving: Vec<usize>,
    /// How far the primary surface has slid over the secondary when the operators were
    /// built ([`Self::slide`]): the pairing's offset.
    pub slid: [f64; 3],
    /// Contact normal at each primary candidate (pointing out of body 1).
    pub normals: Vec<[f64; 3]>,
    /// Reference gap `d_i` of each primary candidate along its contact normal.
    pub reference_gaps: Vec<f64>,
    /// Row of `R12` of each primary candidate used so far: `(secondary surface index, weight)`.
    rows12: HashMap<usize, Vec<(usize, f64)>>,
    /// Column of `R21` of each primary candidate used so far: `(secondary surface index, weight)`.
    columns21: HashMap<usize, Vec<(usize, f64)>>,
}

impl InterfaceOperators {
    /// Pairs each surface's candidates with the points of the other they face, and builds the
    /// two interpolations; `radius` is the RBF support radius in units of each source node's
    /// nearest-node distance. `slid` is how far the primary surface has slid over the
    /// secondary ([`Self::slide`]; zero in the reference configuration): the primary nodes
    /// are paired from their positions moved by it, the secondary's by its opposite
    /// ([`paired_points`]). `share`: how the ranks of a distributed run share the
    /// interpolations' rows ([`Interpolation`]; collective with several ranks), one process
    /// [`BlockShare::ALL`].
    pub fn new(
        primary: &ContactSurface,
        secondary: &ContactSurface,
        radius: f64,
        weights: [f64; 2],
        (transfer, share): (Transfer, BlockShare),
        slid: [f64; 3],
    ) -> Result<Self, ContactError> {
        let [w1, w2] = weights;
        let back = slid.map(|v| -v);
        let (targets12, _) = paired_points(primary, secondary, [w1, w2], slid)?;
        let (on_primary, facing2) = paired_points(secondary, primary, [w2, w1], back)?;
        let r12 = covering_interpolation(secondary, radius, &targets12, share, (primary, |t| t))?;
        // Only the secondary nodes that face the primary surface receive its traction.
        let receiving: Vec<usize> = (0..secondary.len()).filter(|&j| facing2[j]).collect();
        let r21 = if !transfer.interpolates() {
            None
        } else {
            let targets: Vec<[f64; 3]> = receiving.iter().map(|&j| on_primary[j]).collect();
            Some(covering_interpolation(
                primary,
                radius,
                &targets,
                share,
                (secondary, |t| receiving[t]),
            )?)
        };
        let n2_flat: Vec<f64> = secondary.normals.iter().flatten().copied().collect();
        let n2_at_1 = r12.apply(&n2_flat, 3)?;
        let normals: Vec<[f64; 3]> = (0..primary.len())
            .map(|i| contact_normal(&primary.normals[i], &n2_at_1[3 * i..3 * i + 3], weights))
            .collect();
        let reference_gaps = (0..primary.len())
            .map(|i| {
                let (x, p, n) = (primary.coords[i], targets12[i], normals[i]);
                (0..3).map(|k| n[k] * (p[k] - x[k])).sum()
            })
            .collect();
        Ok(Self {
            r12,
            r21,
            transfer,
            receiving,
            slid,
            normals,
            reference_gaps,
            rows12: HashMap::new(),
            columns21: HashMap::new(),
        })
    }

    /// How far the primary surface has slid over the secondary: the area-weighted mean over
    /// the `active` primary nodes (surface indices) of the tangential part of their jumps
    /// ([`Self::jumps`]). Only the mean, the zone's rigid slide: the tangential strain of the
    /// surfaces (the Poisson expansion of a body pressed onto another) is of the order of the
    /// strains the linear theory neglects, and pairing the nodes where that strain moved them
    /// unbalanced the interpolation transfer by 2% on a half-disc (its multiplier is a traction
    /// per unit reference area).
    pub fn slide(
        &self,
        primary: &ContactSurface,
        jumps: &[[f64; 3]],
        active: &[usize],
    ) -> [f64; 3] {
        let (mut sum, mut area) = ([0.0; 3], 0.0);
        for &i in active {
            let (jump, n, a) = (jumps[i], self.normals[i], primary.nodal_area[i]);
            let along: f64 = (0..3).map(|k| jump[k] * n[k]).sum();
            (0..3).for_each(|k| sum[k] += a * (jump[k] - along * n[k]));
            area += a;
        }
        if area > 0.0 {
            sum.map(|v| v / area)
        } else {
            self.slid
        }
    }

    /// The coupling of the active primary candidates `active` (surface indices) under
    /// `constraint`: each node's multipliers as `law` lays them out, the traction columns of
    /// the transfers, and the constraint rows.
    ///
    /// `kept` (`None`: this process keeps every entry) says which ranks keep the transfers'
    /// entries at each secondary candidate: in a distributed run a rank keeps those of its own
    /// nodes (the rows of `B` and columns of `C` it holds) and of force-controlled groups; each
    /// rank computes its share of the missing rows and columns, and sends each entry to the
    /// ranks that keep it (`crate::contact::coupled::row_ownership`; collective). The cache
    /// holds what the first call kept, so every call of one solve passes the same `kept`.
    pub fn coupling(
        &mut self,
        primary: &ContactSurface,
        secondary: &ContactSurface,
        (law, enforcement): (ContactLaw, Enforcement),
        active: &[usize],
        constraint: Constraint,
        kept: Option<&Keepers>,
    ) -> Result<Coupling, ContactError> {
        let missing: Vec<usize> = active
            .iter()
            .copied()
            .filter(|i| !self.rows12.contains_key(i))
            .collect();
        let rows = match kept {
            None => self.r12.rows(&missing)?,
            Some(kept) => {
                let computed = self.r12.rows_of_share(&missing, kept.share())?;
                send_to_keepers(computed, |j| kept.ranks_keeping(j))?
            }
        };
        self.rows12.extend(missing.iter().copied().zip(rows));
        if let Some(r21) = &self.r21 {
            let receiving = &self.receiving;
            let columns = match kept {
                None => r21.columns(&missing)?,
                Some(kept) => {
                    let computed = r21.columns_of_share(&missing, kept.share())?;
                    send_to_keepers(computed, |t| kept.ranks_keeping(receiving[t]))?
                }
            };
            self.columns21.extend(missing.iter().copied().zip(columns));
        }
        let to_body2 = |entries: &[(usize, f64)], weight: &dyn Fn(usize, f64) -> f64| {
            entries
                .iter()
                .map(|&(j, w)| (secondary.nodes[j], weight(j, w)))
                .collect()
        };
        let gap_compliance = enforcement.gap_compliance();
        let node_to_facet = match (self.transfer, &constraint) {
            (Transfer::NodeToFacet, Constraint::Geometric { rows, .. }) => Some(*rows),
            _ => None,
        };
        let loads2 = active
            .iter()
            .map(|&i| {
                if let Some(rows) = node_to_facet {
                    // The node-to-facet transfer: the transpose of the node's gap row, the P1
                    // weights of its closest point times A1_i ([`crate::contact::Transfer`]).
                    to_body2(&rows[i].corners, &|_, b| primary.nodal_area[i] * b)
                } else if self.r21.is_none() {
                    // The conservative transfer, `-R12^T M1 lambda` ([`crate::contact::Transfer`]):
                    // row i of R12 times A1_i is column i of R12^T M1.
                    to_body2(&self.rows12[&i], &|_, w| primary.nodal_area[i] * w)
                } else {
                    let column: Vec<(usize, f64)> = self.columns21[&i]
                        .iter()
                        .map(|&(t, w)| (self.receiving[t], w))
                        .collect();
                    to_body2(&column, &|j, w| secondary.nodal_area[j] * w)
                }
            })
            .collect();
        let dim = primary.dim;
        let interpolated = |i: usize| to_body2(&self.rows12[&i], &|_, w| w);
        let mut wall_reads = vec![Vec::new(); active.len()];
        let (geometric, interpolated, normals, gaps, multipliers) = match constraint {
            Constraint::Interpolated { corrections } => (
                vec![Vec::new(); active.len()],
                active.iter().map(|&i| interpolated(i)).collect(),
                active.iter().map(|&i| self.normals[i]).collect::<Vec<_>>(),
                // Only the normal part is a gap: the tied constraint would otherwise impose
                // the tangential offset between x_i and p_i (nonzero off a flat) as a
                // spurious jump.
                active
                    .iter()
                    .map(|&i| {
                        let g = self.reference_gaps[i] + corrections[i];
                        self.normals[i].map(|n| g * n)
                    })
                    .collect(),
                active
                    .iter()
                    .map(|&i| {
                        law.multipliers(self.normals[i], Tangential::Stick, dim, gap_compliance)
                    })
                    .collect(),
            ),
            Constraint::Geometric {
                rows,
                start_jumps,
                tangential,
                walls,
            } => {
                let state = |i: usize| tangential.map_or(Tangential::Stick, |states| states[i]);
                let mut multipliers: Vec<Vec<Multiplier>> = (active.iter())
                    .map(|&i| law.multipliers(rows[i].normal, state(i), dim, gap_compliance))
                    .collect();
                // A node held by a wall too has the wall's multiplier after the law's, its
                // column and row the wall's normal (`crate::contact::geometry::walls`).
                for (node, &i) in multipliers.iter_mut().zip(active) {
                    if let Some(held) = walls.get(&i) {
                        node.push(Multiplier {
                            force: held.wall.normal,
                            row: held.wall.normal,
                            reads: Reads::Wall,
                            restates: Restates::Node,
                            compliance: gap_compliance,
                        });
                    }
                }
                // A node whose rows read its tangential jump (a sticking node, a slipping one's
                // direction in 3D) holds it against the jump at the start of the step.
                let reads_jump: Vec<bool> = (multipliers.iter())
                    .map(|node| node.iter().any(|m| m.reads == Reads::Interpolated))
                    .collect();
                wall_reads = (active.iter())
                    .map(|i| {
                        walls
                            .get(i)
                            .map_or_else(Vec::new, |held| to_body2(&held.wall.corners, &|_, b| b))
                    })
                    .collect();
                (
                    active
                        .iter()
                        .map(|&i| to_body2(&rows[i].corners, &|_, b| b))
                        .collect(),
                    (active.iter().zip(&reads_jump))
                        .map(|(&i, &reads)| match reads {
                            true => interpolated(i),
                            false => Vec::new(),
                        })
                        .collect(),
                    active.iter().map(|&i| rows[i].normal).collect(),
                    (active.iter().zip(&reads_jump))
                        .map(|(&i, &reads)| {
                            if let Some(held) = walls.get(&i) {
                                return held.target;
                            }
                            let n = rows[i].normal;
                            let normal = n.map(|n| rows[i].target * n);
                            match (reads, start_jumps) {
                                (true, Some(jumps)) => {
                                    let t = coulomb::tangential_part(jumps[i], n);
                                    std::array::from_fn(|k| normal[k] + t[k])
                                }
                                _ => normal,
                            }
                        })
                        .collect(),
                    multipliers,
                )
            }
        };
        Ok(Coupling {
            primary_nodes: active.iter().map(|&i| primary.nodes[i]).collect(),
            points: active.iter().map(|&i| primary.coords[i]).collect(),
            normals,
            areas1: active.iter().map(|&i| primary.nodal_area[i]).collect(),
            multipliers,
            geometric,
            interpolated,
            walls: wall_reads,
            loads2,
            gaps,
        })
    }

    /// The displacement jump `u1_i - (R12 u2)_i` of every primary candidate, for the bodies'
    /// displacements `u1`, `u2`: what the linearized gaps and the slide read.
    pub fn jumps(
        &self,
        primary: &ContactSurface,
        secondary: &ContactSurface,
        u1: BodyDisplacement,
        u2: BodyDisplacement,
    ) -> Result<Vec<[f64; 3]>, ContactError> {
        let on_surfaces = [primary.values(u1), secondary.values(u2)];
        self.jumps_of(&on_surfaces)
    }

    /// [`Self::jumps`] from the displacements at the two surfaces' nodes alone (`[primary,
    /// secondary]`, three components per node: `ContactSurface::values`), which is all it
    /// reads.
    pub fn jumps_of(&self, [u1, u2]: &[Vec<f64>; 2]) -> Result<Vec<[f64; 3]>, ContactError> {
        let u2_at_1 = self.r12.apply(u2, 3)?;
        Ok((0..u1.len() / 3)
            .map(|i| std::array::from_fn(|k| u1[3 * i + k] - u2_at_1[3 * i + k]))
            .collect())
    }

    /// The linearized gap of every primary candidate, `g_i(u) = d_i - n_i . (u1_i - (R12
    /// u2)_i)`, from its jump ([`Self::jumps`]).
    pub fn linearized_gaps(&self, jumps: &[[f64; 3]]) -> Vec<f64> {
        (jumps.iter().zip(&self.normals).zip(&self.reference_gaps))
            .map(|((jump, n), d)| d - (0..3).map(|k| n[k] * jump[k]).sum::<f64>())
            .collect()
    }
}

/// The constraint rows of an iteration.
#[derive(Clone, Copy)]
pub enum Constraint<'a> {
    /// Tied contact: the rows of `R12`, `u1_i - (R12 u2)_i = (d_i + e_i) n_i`, with the gap
    /// correction `e` of the last iterate (module doc).
    Interpolated { corrections: &'a [f64] },
    /// Frictionless and Coulomb contact: the geometric gap linearized at the last iterate, one
    /// row per primary candidate ([`crate::contact::geometry::gap`]); for Coulomb, the tangential
    /// state of every primary candidate and its jump at the start of the load step
    /// ([`Self::jumps`]), which a sticking node's tangential rows hold
    /// (`crate::contact::law::coulomb`); the wall each active node in a concave vertex holds
    /// besides (keyed by candidate; frictionless, `crate::contact::geometry::walls`).
    Geometric {
        rows: &'a [GapRow],
        start_jumps: Option<&'a [[f64; 3]]>,
        tangential: Option<&'a [Tangential]>,
        walls: &'a HashMap<usize, HeldWall>,
    },
}

/// The contact normal at a node: `(w_own n_own - w_other n_other) / |...|`, its outward normal
/// and the other surface's outward normal there weighted by their bodies' contact moduli
/// `w = E / (1 - nu^2)` ([`crate::contact::ContactProblem::normal_weights`]); `n_own` if they
/// cancel, which facing surfaces cannot do. The deformed interface lies between the two undeformed
/// surfaces, nearer to the stiffer one: on a rigid flat it is the flat, between equal bodies the
/// bisector (the symmetry plane between two equal spheres).
pub fn contact_normal(own: &[f64; 3], other: &[f64], weights: [f64; 2]) -> [f64; 3] {
    let [w_own, w_other] = weights;
    let sum: [f64; 3] = std::array::from_fn(|k| w_own * own[k] - w_other * other[k]);
    let length = (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt();
    if length > 1e-12 * (w_own + w_other) {
        sum.map(|v| v / length)
    } else {
        *own
    }
}

/// The point of `other` (reference geometry) that each node of `own`, moved by `slid`, faces:
/// where the line through the moved node along the contact normal ([`contact_normal`], with
/// the other surface's normal at the node's closest point) meets `other` (the closest point
/// where it misses), and whether the node faces `other` there (the line meets it where its
/// outward normal opposes the node's). Along the contact normal, not to the closest point nor
/// along the node's own normal: between bodies meshed overlapping by `delta`, both of those
/// map a sphere of radius `R` onto a flat stretched or shrunk by `delta / R`, and the transfer
/// of the pressure with it (the contact forces were unbalanced by 1.6% in 3D with the closest
/// point, 2.4% in 2D with the own normal, both overlapping by about 0.017 R); the deformed
/// interface, along whose normal the bodies meet, is what the contact normal estimates. A
/// secondary node that does not face the primary surface (the far side of a disc, the block
/// beyond the sphere's candidate cap) receives no contact force through `R21`.
///
/// Moved by how far the surfaces have slid over each other, so that they are paired where they
/// touch, not where they started: paired where they started, a half-disc pushed sideways by
/// 20 spacings onto an equally stiff block was certified with its force 36% off, the block's
/// reaction applied where the contact had begun.
fn paired_points(
    own: &ContactSurface,
    other: &ContactSurface,
    weights: [f64; 2],
    slid: [f64; 3],
) -> Result<(Vec<[f64; 3]>, Vec<bool>), ContactError> {
    let index = other.index(None);
    let no_facets = || ContactError::NoFacets {
        body: other.body.clone(),
        group: other.group.clone(),
    };
    own.coords
        .iter()
        .zip(&own.normals)
        .map(|(x, n)| {
            let x: [f64; 3] = std::array::from_fn(|k| x[k] + slid[k]);
            let closest = index.project(&x).ok_or_else(no_facets)?;
            let direction = contact_normal(n, &index.normal(closest.facet), weights);
            let (p, hit) = index.project_along(&x, &direction).ok_or_else(no_facets)?;
            let m = index.normal(p.facet);
            Ok((
                p.point,
                hit && n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < 0.0,
            ))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.into_iter().unzip())
}

/// The interpolation from the nodes of `sources` to `targets` (points on that surface; target
/// `t` belongs to node `target_node(t)` of `target_surface`), its rows shared as `share` says;
/// a target outside every support is an error that names its node.
fn covering_interpolation(
    sources: &ContactSurface,
    radius: f64,
    targets: &[[f64; 3]],
    share: BlockShare,
    (target_surface, target_node): (&ContactSurface, impl Fn(usize) -> usize),
) -> Result<Interpolation, ContactError> {
    let radii = interpolation_radii(&sources.coords, radius)?;
    let interpolation = Interpolation::shared(&sources.coords, &radii, targets, share)?;
    if let Some(&t) = interpolation.uncovered_targets().first() {
        return Err(ContactError::Uncovered {
            body: target_surface.body.clone(),
            tag: target_surface.tags[target_node(t)],
            other: sources.body.clone(),
            count: interpolation.uncovered_targets().len(),
        });
    }
    Ok(interpolation)
}
