//! Load vectors: surface tractions on boundary groups and body forces.
//!
//! A traction field `t` on a group `G` contributes `f_a = int_G t phi_a ds`. Non-constant
//! pressures are represented by their P1 nodal interpolant `p_h` and integrated exactly,
//! `f = -sum_facets n_F (M_F p)`, so that any other code given the same nodal values (dolfinx
//! with a P1 `Function`) assembles the same vector to round-off.

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

/// Adds the load of `load` on `group` to `f` (interleaved, `dim` per node).
pub fn add_surface_load(body: &BodyMesh, group: &FacetGroup, load: &SurfaceLoad, f: &mut [f64]) {
    let dim = body.dim;
    for k in 0..group.num_facets(dim) {
        let facet = group.facet(k, dim);
        let x: Vec<[f64; 3]> = facet.iter().map(|&n| body.coords[n]).collect();
        let (measure, normal) = facet_measure_and_normal(&x, dim);
        let m = facet_mass(measure, dim);
        for (a, &node) in facet.iter().enumerate() {
            for c in 0..dim {
                f[dim * node + c] += match load {
                    // sum_b M_ab t = t * measure / dim
                    SurfaceLoad::Traction(t) => t[c] * measure / dim as f64,
                    SurfaceLoad::Pressure(p) => {
                        let mp: f64 = (0..dim).map(|b| m[a][b] * p.at(&x[b])).sum();
                        -normal[c] * mp
                    }
                };
            }
        }
    }
}

/// Adds a constant body force `b` (per unit volume; per unit area in 2D): `f_a = b |T| / (d+1)`.
pub fn add_body_force(body: &BodyMesh, b: &[f64; 3], f: &mut [f64]) {
    let dim = body.dim;
    for c in 0..body.num_cells() {
        let cell = body.cell(c);
        let measure = if dim == 2 {
            triangle_gradients(&node_coords(&body.coords, &cell)).1
        } else {
            tetrahedron_gradients(&node_coords(&body.coords, &cell)).1
        };
        for &node in cell.iter() {
            for k in 0..dim {
                f[dim * node + k] += b[k] * measure / (dim + 1) as f64;
            }
        }
    }
}
