//! Load vectors: surface tractions on boundary groups and body forces.
//!
//! A traction field `t` on a group `G` contributes `f_a = int_G t phi_a ds`. Non-constant
//! pressures are represented by their P1 nodal interpolant `p_h` and integrated exactly,
//! `f = -sum_facets n_F (M_F p)`, so that any other code given the same nodal values (dolfinx
//! with a P1 `Function`) assembles the same vector to round-off.

use super::LoadVector;
use super::assembly::node_coords;
use super::kernels::{
    facet_mass, facet_measure_and_normal, tetrahedron_gradients, triangle_gradients,
};
use crate::mesh::{BodyMesh, FacetGroup};

/// A surface load on one boundary group.
#[derive(Debug, Clone, PartialEq)]
pub enum SurfaceLoad {
    /// Constant traction vector (force per unit area; per unit length in 2D).
    Traction([f64; 3]),
    /// Pressure `p(x)` pushing along the inward normal: `t = -p n`, `n` the outward normal.
    Pressure(PressureField),
}

/// A scalar pressure field, evaluated at the nodes.
#[derive(Debug, Clone, PartialEq)]
pub enum PressureField {
    Uniform(f64),
    /// Hertz: `p(x) = p0 sqrt(1 - |x - center|^2 / a^2)` inside the contact radius, 0 outside.
    Hertz {
        p0: f64,
        a: f64,
        center: [f64; 3],
    },
}

impl PressureField {
    pub fn at(&self, x: &[f64; 3]) -> f64 {
        match *self {
            PressureField::Uniform(p) => p,
            PressureField::Hertz { p0, a, center } => {
                let r2: f64 = (0..3).map(|k| (x[k] - center[k]).powi(2)).sum();
                p0 * (1.0 - r2 / (a * a)).max(0.0).sqrt()
            }
        }
    }
}

/// Adds the load of `load` on `group` by `add(dof, value)` (dofs interleaved, `dim` per node),
/// facet after facet in the group's order.
pub fn add_surface_load(
    body: &BodyMesh,
    group: &FacetGroup,
    load: &SurfaceLoad,
    add: &mut impl FnMut(usize, f64),
) {
    let dim = body.dim;
    for k in 0..group.num_facets(dim) {
        let facet = group.facet(k, dim);
        let x: Vec<[f64; 3]> = facet.iter().map(|&n| body.coords[n]).collect();
        let (measure, normal) = facet_measure_and_normal(&x, dim);
        let m = facet_mass(measure, dim);
        for (a, &node) in facet.iter().enumerate() {
            for c in 0..dim {
                add(
                    dim * node + c,
                    match load {
                        // sum_b M_ab t = t * measure / dim
                        SurfaceLoad::Traction(t) => t[c] * measure / dim as f64,
                        SurfaceLoad::Pressure(p) => {
                            let mp: f64 = (0..dim).map(|b| m[a][b] * p.at(&x[b])).sum();
                            -normal[c] * mp
                        }
                    },
                );
            }
        }
    }
}

/// Adds a constant body force `b` (per unit volume; per unit area in 2D), `f_a = b |T| / (d+1)`,
/// by `add(dof, value)`, cell after cell of those the body's mesh keeps.
pub fn add_body_force(body: &BodyMesh, b: &[f64; 3], add: &mut impl FnMut(usize, f64)) {
    let dim = body.dim;
    for c in 0..body.num_cells() {
        let cell = body.cell(c);
        let measure = if dim == 2 {
            triangle_gradients(&node_coords(&body.coords, &cell)).1
        } else {
            tetrahedron_gradients(&node_coords(&body.coords, &cell)).1
        };
        for &node in cell.iter() {
            for (k, b_k) in b.iter().enumerate().take(dim) {
                add(dim * node + k, b_k * measure / (dim + 1) as f64);
            }
        }
    }
}

/// A load vector while it is summed: its values at the nodes whose coordinates this process
/// keeps (`crate::mesh::NodeCoords`: every node on one process; on a rank of a distributed
/// run the nodes it reads, which hold every node a load of it reaches: the groups' nodes and
/// its cells' nodes), so that no rank sums a vector of the whole body's size. Each dof's
/// contributions are added in the order they come, from `0.0`, as in a whole vector.
pub struct LoadSum<'a> {
    body: &'a BodyMesh,
    values: Vec<f64>,
}

impl<'a> LoadSum<'a> {
    /// Zero at every kept node of `body`.
    pub fn new(body: &'a BodyMesh) -> Self {
        let values = vec![0.0; body.dim * body.coords.kept().len()];
        Self { body, values }
    }

    /// Adds `value` at `dof`, whose node this process keeps (the partition keeps every node a
    /// load of the rank reaches: a dof elsewhere is a program error).
    pub fn add(&mut self, dof: usize, value: f64) {
        let dim = self.body.dim;
        let at = (self.body.coords.position(dof / dim)).expect("a loaded node is kept");
        self.values[dim * at + dof % dim] += value;
    }

    /// The value summed at `dof` (`0.0` at a node this process does not keep).
    pub fn get(&self, dof: usize) -> f64 {
        let dim = self.body.dim;
        (self.body.coords.position(dof / dim)).map_or(0.0, |at| self.values[dim * at + dof % dim])
    }

    /// Every dof's value, where every node is kept (one process); `None` on a rank.
    pub fn as_whole(&self) -> Option<&[f64]> {
        self.body.coords.is_whole().then_some(&self.values[..])
    }

    /// The nonzero values at the kept nodes, by increasing dof.
    fn nonzero(self) -> impl Iterator<Item = (usize, f64)> + 'a {
        let dim = self.body.dim;
        let nodes = self.body.coords.kept().map(|(node, _)| node);
        let dofs = nodes.flat_map(move |node| (0..dim).map(move |c| dim * node + c));
        dofs.zip(self.values).filter(|&(_, v)| v != 0.0)
    }

    /// The whole vector, kept as [`LoadVector::new`] keeps it: right where every value it
    /// reaches was summed here (one process, or loads on groups alone, whose facets every rank
    /// keeps).
    pub fn into_whole(self) -> LoadVector {
        let len = self.body.num_dofs();
        match self.body.coords.is_whole() {
            true => LoadVector::new(self.values),
            false => LoadVector::from_entries(len, self.nonzero().collect()),
        }
    }

    /// A rank's part of the vector ([`LoadVector::Part`]): its values at the dofs `known`
    /// selects (where this rank summed every cell around the node).
    pub fn into_part(self, known: impl Fn(usize) -> bool) -> LoadVector {
        let len = self.body.num_dofs();
        LoadVector::part(len, self.nonzero().filter(|&(d, _)| known(d)).collect())
    }
}
