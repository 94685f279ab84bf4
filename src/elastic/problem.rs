//! What to solve on one body: material, Dirichlet conditions, surface loads, body force.

use std::collections::HashMap;

use thiserror::Error;

use crate::fem::loads::SurfaceLoad;
use crate::fem::{Constraints, Material};
use crate::mesh::BodyMesh;

/// Prescribed displacement components on a boundary group (`None` = free).
#[derive(Debug, Clone, PartialEq)]
pub struct DirichletCondition {
    pub group: String,
    pub components: [Option<f64>; 3],
    /// The load path the values follow ([`super::StepFactors`]): `None` the default one.
    pub path: Option<String>,
}

/// A prescribed total force on a group, along some components (`None` = not force-controlled).
/// Along each given component the group's nodes move together, by one displacement that is an
/// unknown of the solve (a rigid loading plate), and the force the group passes to the body is
/// the given one: the group's reaction `sum (K u - f)` over its dofs of that component.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceCondition {
    pub group: String,
    pub components: [Option<f64>; 3],
    /// The load path the force follows ([`super::StepFactors`]): `None` the default one.
    pub path: Option<String>,
}

/// A surface load on a boundary group.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCondition {
    pub group: String,
    pub load: SurfaceLoad,
    /// The load path the load follows ([`super::StepFactors`]): `None` the default one.
    pub path: Option<String>,
}

/// Linear elasticity on one body. Built with [`ElasticProblem::new`], which checks that every
/// group exists on the body and that the Dirichlet conditions remove all rigid-body motions.
#[derive(Debug, Clone)]
pub struct ElasticProblem<'m> {
    pub body: &'m BodyMesh,
    pub material: Material,
    pub dirichlet: Vec<DirichletCondition>,
    /// Force-controlled groups ([`ElasticProblem::with_forces`]; none by default).
    pub forces: Vec<ForceCondition>,
    /// Rigid-mode pins `(node, component)` of a body in contact that its supports do not hold
    /// ([`ElasticProblem::floating`]; none otherwise): dofs whose displacements are unknowns
    /// with zero force, like a force-controlled group of one node with no force. They keep
    /// `K_c` regular and leave the body exactly as free as without them.
    pub pins: Vec<(usize, usize)>,
    pub loads: Vec<LoadCondition>,
    pub body_force: Option<[f64; 3]>,
}

/// The letter of a component in the case file's keys (`ux`, `fx`): components are named by it.
const AXES: [char; 3] = ['x', 'y', 'z'];

#[derive(Debug, Error, PartialEq)]
pub enum ProblemError {
    #[error("body '{body}' has no group '{group}' (groups on this body: {})", .on_body.join(", "))]
    UnknownGroup {
        body: String,
        group: String,
        on_body: Vec<String>,
    },
    #[error(
        "Dirichlet condition on group '{group}' of body '{body}' prescribes no component (give ux, uy or uz)"
    )]
    NoComponent { body: String, group: String },
    #[error(
        "Dirichlet condition on group '{group}' of body '{body}' prescribes uz, but the mesh is 2D"
    )]
    ComponentOutOfRange { body: String, group: String },
    #[error(
        "body '{body}': node {node_tag}'s u{} is prescribed {first} by one Dirichlet group and {second} by '{group}'",
        AXES[*.component]
    )]
    ConflictingDirichlet {
        body: String,
        group: String,
        node_tag: u64,
        component: usize,
        first: f64,
        second: f64,
    },
    #[error(
        "body '{body}' has no Dirichlet condition: its stiffness is singular (rigid-body motions are free); fix a boundary group"
    )]
    NoDirichlet { body: String },
    #[error(
        "body '{body}': the Dirichlet conditions leave {count} rigid-body motion(s) free, so its stiffness is singular; constrain more components or groups"
    )]
    FreeRigidModes { body: String, count: usize },
    #[error(
        "body '{body}': node {node_tag}'s u{axis} is force-controlled (f{axis}) by group \
         '{group}' and also {other}; a component of a node is either prescribed or \
         force-controlled, by one group",
        axis = AXES[*.component]
    )]
    ForcedTwice {
        body: String,
        group: String,
        node_tag: u64,
        component: usize,
        other: String,
    },
    #[error("force on group '{group}' of body '{body}' gives no component (give fx, fy or fz)")]
    NoForceComponent { body: String, group: String },
    #[error("force on group '{group}' of body '{body}' gives fz, but the mesh is 2D")]
    ForceComponentOutOfRange { body: String, group: String },
    #[error("body '{body}': {what} is not finite")]
    NotFinite { body: String, what: String },
    #[error(
        "body '{body}': node {node_tag}'s u{} is prescribed {value} by Dirichlet \
         conditions that follow {paths}; a prescribed value follows one load path (conditions \
         that prescribe 0 may share a dof)",
        AXES[*.component]
    )]
    ConflictingPath {
        body: String,
        node_tag: u64,
        component: usize,
        value: f64,
        /// The two paths and groups: "the default load path (on 'top') and load path 'press'
        /// (on 'edge')".
        paths: String,
    },
}

impl<'m> ElasticProblem<'m> {
    pub fn new(
        body: &'m BodyMesh,
        material: Material,
        dirichlet: Vec<DirichletCondition>,
        loads: Vec<LoadCondition>,
        body_force: Option<[f64; 3]>,
    ) -> Result<Self, ProblemError> {
        Self::with_forces(body, material, dirichlet, Vec::new(), loads, body_force)
    }

    /// [`Self::new`] with force-controlled groups `forces`. Their components count as held in
    /// the rigid-mode check: each moves by an unknown of its own, which the solve finds from
    /// the force (a single body must then be held along it by something else too; a body in
    /// contact may be held by its contacts).
    pub fn with_forces(
        body: &'m BodyMesh,
        material: Material,
        dirichlet: Vec<DirichletCondition>,
        forces: Vec<ForceCondition>,
        loads: Vec<LoadCondition>,
        body_force: Option<[f64; 3]>,
    ) -> Result<Self, ProblemError> {
        let problem = Self::unpinned(body, material, dirichlet, forces, loads, body_force);
        problem.check()?;
        Ok(problem)
    }

    /// The problem as given, without pins and unchecked.
    fn unpinned(
        body: &'m BodyMesh,
        material: Material,
        dirichlet: Vec<DirichletCondition>,
        forces: Vec<ForceCondition>,
        loads: Vec<LoadCondition>,
        body_force: Option<[f64; 3]>,
    ) -> Self {
        Self {
            body,
            material,
            dirichlet,
            forces,
            pins: Vec::new(),
            loads,
            body_force,
        }
    }

    /// [`Self::with_forces`] for a body in contact, which its supports may leave free to move
    /// (a floating body): the rigid motions they leave free are pinned ([`Self::pins`]) at
    /// dofs of three nodes far apart (the farthest from the centroid, the farthest from it,
    /// and in 3D the farthest from the line through both), each dof kept if it removes a
    /// free motion. The contacts must then hold those motions (the contact solve checks it).
    pub fn floating(
        body: &'m BodyMesh,
        material: Material,
        dirichlet: Vec<DirichletCondition>,
        forces: Vec<ForceCondition>,
        loads: Vec<LoadCondition>,
        body_force: Option<[f64; 3]>,
    ) -> Result<Self, ProblemError> {
        let mut problem = Self::unpinned(body, material, dirichlet, forces, loads, body_force);
        match problem.check() {
            Ok(()) => return Ok(problem),
            Err(ProblemError::NoDirichlet { .. } | ProblemError::FreeRigidModes { .. }) => {}
            Err(other) => return Err(other),
        }
        let mut constraints = constraints(&problem)?;
        let dim = body.dim;
        let mut free = crate::fem::rigid_modes::free_rigid_modes(body, &constraints);
        for node in body.extent().far_apart {
            for c in 0..dim {
                let dof = dim * node + c;
                if free == 0 || constraints.is_fixed(dof) {
                    continue;
                }
                let mut trial = constraints.clone();
                trial.prescribe(dof, 0.0).expect("a free dof");
                let left = crate::fem::rigid_modes::free_rigid_modes(body, &trial);
                if left < free {
                    (constraints, free) = (trial, left);
                    problem.pins.push((node, c));
                }
            }
        }
        if free > 0 {
            return Err(ProblemError::FreeRigidModes {
                body: body.name.clone(),
                count: free,
            });
        }
        Ok(problem)
    }

    /// The named load paths its loads, forces and prescribed displacements follow, each once,
    /// in order of name.
    pub fn paths(&self) -> Vec<&str> {
        let dirichlet = self.dirichlet.iter().map(|d| d.path.as_deref());
        let forces = self.forces.iter().map(|f| f.path.as_deref());
        let loads = self.loads.iter().map(|l| l.path.as_deref());
        let named: std::collections::BTreeSet<&str> =
            dirichlet.chain(forces).chain(loads).flatten().collect();
        named.into_iter().collect()
    }

    /// The components of one condition: at least one (else `none`), no z in 2D (else
    /// `out_of_range`), all finite (else `NotFinite` naming `what`).
    fn check_components(
        &self,
        components: &[Option<f64>; 3],
        none: ProblemError,
        out_of_range: ProblemError,
        what: String,
    ) -> Result<(), ProblemError> {
        if components.iter().all(Option::is_none) {
            return Err(none);
        }
        if self.body.dim == 2 && components[2].is_some() {
            return Err(out_of_range);
        }
        if components.iter().flatten().any(|v| !v.is_finite()) {
            return Err(ProblemError::NotFinite {
                body: self.body.name.clone(),
                what,
            });
        }
        Ok(())
    }

    fn check(&self) -> Result<(), ProblemError> {
        let name = || self.body.name.clone();
        // Dirichlet conditions may sit on boundary or point groups, loads need facets.
        let unknown = |group: &String| ProblemError::UnknownGroup {
            body: name(),
            group: group.clone(),
            on_body: self.body.group_names(),
        };
        for d in &self.dirichlet {
            if self.body.group_nodes(&d.group).is_none() {
                return Err(unknown(&d.group));
            }
        }
        for l in &self.loads {
            if self.body.boundary_group(&l.group).is_none() {
                return Err(unknown(&l.group));
            }
        }
        for f in &self.forces {
            if self.body.group_nodes(&f.group).is_none() {
                return Err(unknown(&f.group));
            }
            self.check_components(
                &f.components,
                ProblemError::NoForceComponent {
                    body: name(),
                    group: f.group.clone(),
                },
                ProblemError::ForceComponentOutOfRange {
                    body: name(),
                    group: f.group.clone(),
                },
                format!("the force on '{}'", f.group),
            )?;
        }
        for d in &self.dirichlet {
            self.check_components(
                &d.components,
                ProblemError::NoComponent {
                    body: name(),
                    group: d.group.clone(),
                },
                ProblemError::ComponentOutOfRange {
                    body: name(),
                    group: d.group.clone(),
                },
                format!("the Dirichlet value on '{}'", d.group),
            )?;
        }
        if self.dirichlet.is_empty() && self.forces.is_empty() && self.pins.is_empty() {
            return Err(ProblemError::NoDirichlet { body: name() });
        }
        let constraints = constraints(self)?;
        let free = crate::fem::rigid_modes::free_rigid_modes(self.body, &constraints);
        if free > 0 {
            return Err(ProblemError::FreeRigidModes {
                body: name(),
                count: free,
            });
        }
        Ok(())
    }
}

/// The prescribed dofs and values of a problem; conflicting values on shared nodes are errors.
pub(crate) fn constraints(problem: &ElasticProblem) -> Result<Constraints, ProblemError> {
    let body = problem.body;
    let dim = body.dim;
    let mut constraints = Constraints::new(body.num_dofs());
    // The load path of each nonzero prescribed value, when some condition names one: a value
    // follows one path (a 0 is 0 on every path).
    let with_paths = problem.dirichlet.iter().any(|d| d.path.is_some());
    let mut path_of: HashMap<usize, (Option<&str>, &str)> = HashMap::new();
    // The group that prescribes each dof, for a force on it to name.
    let mut prescribed_by: HashMap<usize, &str> = HashMap::new();
    for condition in &problem.dirichlet {
        let nodes = body
            .group_nodes(&condition.group)
            .expect("groups are checked first");
        for node in nodes {
            for (component, value) in condition.components.iter().enumerate().take(dim) {
                if let Some(value) = *value {
                    let dof = dim * node + component;
                    constraints.prescribe(dof, value).map_err(|first| {
                        ProblemError::ConflictingDirichlet {
                            body: body.name.clone(),
                            group: condition.group.clone(),
                            node_tag: body.node_tags.get(node),
                            component,
                            first,
                            second: value,
                        }
                    })?;
                    prescribed_by.entry(dof).or_insert(condition.group.as_str());
                    let path = condition.path.as_deref();
                    if with_paths && value != 0.0 {
                        let on = (path, condition.group.as_str());
                        match path_of.insert(dof, on) {
                            Some(first) if first.0 != path => {
                                let name = |(path, group): (Option<&str>, &str)| match path {
                                    None => format!("the default load path (on '{group}')"),
                                    Some(name) => format!("load path '{name}' (on '{group}')"),
                                };
                                return Err(ProblemError::ConflictingPath {
                                    body: body.name.clone(),
                                    node_tag: body.node_tags.get(node),
                                    component,
                                    value,
                                    paths: format!("{} and {}", name(first), name(on)),
                                });
                            }
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    // A force-controlled dof is held at 0 in `K_c`: its displacement is the group's unknown,
    // which enters through its column (`RigidColumn`).
    let mut forced_by: HashMap<usize, String> = HashMap::new();
    for forced in forced_components(problem) {
        for &dof in &forced.dofs {
            if let Some(value) = constraints.value(dof) {
                let other = match (forced_by.get(&dof), prescribed_by.get(&dof)) {
                    (Some(group), _) => format!("by group '{group}'"),
                    (None, Some(group)) => {
                        format!("prescribed {value} by the Dirichlet condition on group '{group}'")
                    }
                    (None, None) => format!("prescribed {value}"),
                };
                return Err(ProblemError::ForcedTwice {
                    body: body.name.clone(),
                    group: forced.group.clone(),
                    node_tag: body.node_tags.get(dof / dim),
                    component: forced.component,
                    other,
                });
            }
            constraints
                .prescribe(dof, 0.0)
                .expect("the dof was free: checked above");
            forced_by.insert(dof, forced.group.clone());
        }
    }
    Ok(constraints)
}

/// One force-controlled component of a group: its dofs (one per node of the group) and force;
/// or a rigid-mode pin (`ElasticProblem::pins`), one dof with no force.
pub(crate) struct ForcedComponent {
    pub group: String,
    pub component: usize,
    pub force: f64,
    pub dofs: Vec<usize>,
    pub pin: bool,
    /// The load path the force follows (`None`: the default one).
    pub path: Option<String>,
}

/// The force-controlled components of `problem`, group after group, component after component.
pub(crate) fn forced_components(problem: &ElasticProblem) -> Vec<ForcedComponent> {
    let body = problem.body;
    let dim = body.dim;
    let mut out = Vec::new();
    for condition in &problem.forces {
        let nodes = body
            .group_nodes(&condition.group)
            .expect("groups are checked first");
        for (component, force) in condition.components.iter().enumerate().take(dim) {
            if let Some(force) = *force {
                out.push(ForcedComponent {
                    group: condition.group.clone(),
                    component,
                    force,
                    dofs: nodes.iter().map(|&node| dim * node + component).collect(),
                    pin: false,
                    path: condition.path.clone(),
                });
            }
        }
    }
    for &(node, component) in &problem.pins {
        out.push(ForcedComponent {
            group: format!("rigid-mode pin at node {}", body.node_tags.get(node)),
            component,
            force: 0.0,
            dofs: vec![dim * node + component],
            pin: true,
            path: None,
        });
    }
    out
}
