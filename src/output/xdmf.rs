//! XDMF 3 + HDF5: one grid holding every body, readable by ParaView (XDMF3 reader) and h5py.
//!
//! Layout of `<stem>.h5` (N nodes and C cells over all bodies, bodies one after the other):
//! `/mesh/geometry` (N, 3), `/mesh/topology` (C, dim + 1), `/mesh/node_tag` (N) gmsh node tags,
//! `/mesh/node_body` (N), `/mesh/cell_body` (C), `/mesh/cell_tag` (C) gmsh element tags,
//! `/fields/displacement` (N, 3), `/fields/strain` and `/fields/stress` (C, 9) row-major 3 x 3,
//! `/fields/von_mises` (C); in contact runs also `/fields/contact_traction` (N, 3),
//! `/fields/contact_pressure` (N), `/fields/contact_mean_pressure` (N), `/fields/normal_gap` (N)
//! and `/fields/contact_active` (N),
//! zero at nodes off the candidate surfaces (gap NaN where the other surface is out of range);
//! in runs with a Coulomb pair also, on its primary surface, `/fields/friction_state` (N: 0
//! open, 1 stick, 2 slip, -1 off a Coulomb primary surface), `/fields/tangential_traction`
//! (N, 3), `/fields/slip_increment` (N, 3: over the last load step) and
//! `/fields/accumulated_slip` (N: the slip path's length over all steps).

use std::path::Path;

use ndarray::{Array1, Array2};

use super::OutputError;
use crate::contact::SurfaceFields;
use crate::fem::stress::CellFields;
use crate::mesh::BodyMesh;

/// One body's mesh and fields, as written.
pub struct BodyFields<'a> {
    pub mesh: &'a BodyMesh,
    /// Interleaved, `dim` per node.
    pub displacement: &'a [f64],
    pub cell_fields: &'a CellFields,
    /// Interface fields on the body's contact candidate surfaces (one per pair it is in), in
    /// contact runs.
    pub surfaces: Vec<&'a SurfaceFields>,
}

/// Writes `<dir>/<stem>.h5` and `<dir>/<stem>.xdmf`.
pub fn write_xdmf(dir: &Path, stem: &str, bodies: &[BodyFields]) -> Result<(), OutputError> {
    let h5_path = dir.join(format!("{stem}.h5"));
    let dim = bodies.first().map_or(3, |b| b.mesh.dim);
    let grid = Grid::gather(bodies, dim);
    let (num_nodes, num_cells, contact) = (grid.num_nodes, grid.num_cells, grid.contact);
    let friction = grid.friction;
    grid.write_h5(&h5_path, dim)
        .map_err(|source| OutputError::Hdf5 {
            path: h5_path.clone(),
            source,
        })?;

    let xdmf_path = dir.join(format!("{stem}.xdmf"));
    std::fs::write(
        &xdmf_path,
        xdmf_text(stem, dim, num_nodes, num_cells, contact, friction),
    )
    .map_err(|source| OutputError::Io {
        path: xdmf_path,
        source,
    })
}

/// Every body's nodes and cells one after the other, as the datasets of the module doc.
struct Grid {
    num_nodes: usize,
    num_cells: usize,
    /// Whether any body has interface fields (a contact run).
    contact: bool,
    geometry: Vec<f64>,
    displacement: Vec<f64>,
    node_tag: Vec<i64>,
    node_body: Vec<i32>,
    topology: Vec<i64>,
    cell_tag: Vec<i64>,
    cell_body: Vec<i32>,
    strain: Vec<f64>,
    stress: Vec<f64>,
    von_mises: Vec<f64>,
    traction: Vec<f64>,
    pressure: Vec<f64>,
    mean_pressure: Vec<f64>,
    gap: Vec<f64>,
    active: Vec<i32>,
    /// Whether any surface has a Coulomb pair's tangential fields.
    friction: bool,
    friction_state: Vec<i32>,
    tangential_traction: Vec<f64>,
    slip_increment: Vec<f64>,
    accumulated_slip: Vec<f64>,
}

impl Grid {
    fn gather(bodies: &[BodyFields], dim: usize) -> Self {
        let num_nodes: usize = bodies.iter().map(|b| b.mesh.num_nodes()).sum();
        let num_cells: usize = bodies.iter().map(|b| b.mesh.num_cells()).sum();
        let mut grid = Self {
            num_nodes,
            num_cells,
            contact: bodies.iter().any(|b| !b.surfaces.is_empty()),
            geometry: Vec::with_capacity(3 * num_nodes),
            displacement: Vec::with_capacity(3 * num_nodes),
            node_tag: Vec::with_capacity(num_nodes),
            node_body: Vec::with_capacity(num_nodes),
            topology: Vec::with_capacity((dim + 1) * num_cells),
            cell_tag: Vec::new(),
            cell_body: Vec::new(),
            strain: Vec::new(),
            stress: Vec::new(),
            von_mises: Vec::new(),
            traction: vec![0.0; 3 * num_nodes],
            pressure: vec![0.0; num_nodes],
            mean_pressure: vec![0.0; num_nodes],
            gap: vec![0.0; num_nodes],
            active: vec![0i32; num_nodes],
            friction: (bodies.iter().flat_map(|b| &b.surfaces)).any(|s| s.friction.is_some()),
            friction_state: vec![-1i32; num_nodes],
            tangential_traction: vec![0.0; 3 * num_nodes],
            slip_increment: vec![0.0; 3 * num_nodes],
            accumulated_slip: vec![0.0; num_nodes],
        };
        let mut offset = 0;
        for (id, body) in bodies.iter().enumerate() {
            for surface in &body.surfaces {
                grid.add_surface(surface, offset);
            }
            let m = body.mesh;
            for (a, x) in m.coords.iter().enumerate() {
                grid.geometry.extend_from_slice(x);
                let mut u = [0.0; 3];
                u[..dim].copy_from_slice(&body.displacement[dim * a..dim * a + dim]);
                grid.displacement.extend_from_slice(&u);
            }
            grid.node_tag.extend(m.node_tags.iter().map(|&t| t as i64));
            grid.node_body
                .extend(std::iter::repeat_n(id as i32, m.num_nodes()));
            grid.topology
                .extend(m.cells.iter().map(|&n| (n + offset) as i64));
            grid.cell_tag.extend(m.cell_tags.iter().map(|&t| t as i64));
            grid.cell_body
                .extend(std::iter::repeat_n(id as i32, m.num_cells()));
            grid.strain.extend(body.cell_fields.strain.iter().flatten());
            grid.stress.extend(body.cell_fields.stress.iter().flatten());
            grid.von_mises
                .extend_from_slice(&body.cell_fields.von_mises);
            offset += m.num_nodes();
        }
        grid
    }

    /// The interface fields of a body whose first node is node `offset` of the grid.
    fn add_surface(&mut self, surface: &SurfaceFields, offset: usize) {
        for (s, &node) in surface.nodes.iter().enumerate() {
            let row = offset + node;
            self.traction[3 * row..3 * row + 3].copy_from_slice(&surface.traction[s]);
            self.pressure[row] = surface.pressure[s];
            self.mean_pressure[row] = surface.mean_pressure[s];
            self.gap[row] = surface.normal_gap[s];
            self.active[row] = i32::from(surface.active[s]);
            if let Some(friction) = &surface.friction {
                self.friction_state[row] = friction.state[s].code() as i32;
                let vector = 3 * row..3 * row + 3;
                self.tangential_traction[vector.clone()]
                    .copy_from_slice(&friction.tangential_traction[s]);
                self.slip_increment[vector].copy_from_slice(&friction.slip_increment[s]);
                self.accumulated_slip[row] = friction.accumulated_slip[s];
            }
        }
    }

    fn write_h5(self, path: &Path, dim: usize) -> hdf5::Result<()> {
        let file = hdf5::File::create(path)?;
        let mesh = file.create_group("mesh")?;
        let fields = file.create_group("fields")?;
        let table = |v: Vec<f64>, cols: usize| {
            Array2::from_shape_vec((v.len() / cols, cols), v).expect("rows * cols")
        };
        let topology =
            Array2::from_shape_vec((self.num_cells, dim + 1), self.topology).expect("rows * cols");
        write_dataset(&mesh, "geometry", &table(self.geometry, 3))?;
        write_dataset(&mesh, "topology", &topology)?;
        write_dataset(&mesh, "node_tag", &Array1::from(self.node_tag))?;
        write_dataset(&mesh, "node_body", &Array1::from(self.node_body))?;
        write_dataset(&mesh, "cell_tag", &Array1::from(self.cell_tag))?;
        write_dataset(&mesh, "cell_body", &Array1::from(self.cell_body))?;
        write_dataset(&fields, "displacement", &table(self.displacement, 3))?;
        write_dataset(&fields, "strain", &table(self.strain, 9))?;
        write_dataset(&fields, "stress", &table(self.stress, 9))?;
        write_dataset(&fields, "von_mises", &Array1::from(self.von_mises))?;
        if self.contact {
            write_dataset(&fields, "contact_traction", &table(self.traction, 3))?;
            write_dataset(&fields, "contact_pressure", &Array1::from(self.pressure))?;
            write_dataset(
                &fields,
                "contact_mean_pressure",
                &Array1::from(self.mean_pressure),
            )?;
            write_dataset(&fields, "normal_gap", &Array1::from(self.gap))?;
            write_dataset(&fields, "contact_active", &Array1::from(self.active))?;
        }
        if self.friction {
            let state = Array1::from(self.friction_state);
            write_dataset(&fields, "friction_state", &state)?;
            let traction = table(self.tangential_traction, 3);
            write_dataset(&fields, "tangential_traction", &traction)?;
            write_dataset(&fields, "slip_increment", &table(self.slip_increment, 3))?;
            let accumulated = Array1::from(self.accumulated_slip);
            write_dataset(&fields, "accumulated_slip", &accumulated)?;
        }
        file.close()
    }
}

/// Creates the dataset `name` in `group` holding `data`.
fn write_dataset<T: hdf5::H5Type, D: ndarray::Dimension>(
    group: &hdf5::Group,
    name: &str,
    data: &ndarray::Array<T, D>,
) -> hdf5::Result<()> {
    group.new_dataset_builder().with_data(data).create(name)?;
    Ok(())
}

/// One `<Attribute>` of the grid: a dataset of the `.h5` by its path.
struct Attribute {
    name: &'static str,
    /// `Scalar`, `Vector` or `Tensor`.
    kind: &'static str,
    /// `Node` or `Cell`.
    center: &'static str,
    /// Values per node or cell (1, 3 or 9).
    components: usize,
    /// `Int` or `Float`.
    number: &'static str,
    /// Bytes per value.
    precision: u8,
    path: &'static str,
}

impl Attribute {
    const fn new(
        name: &'static str,
        kind: &'static str,
        center: &'static str,
        components: usize,
        (number, precision): (&'static str, u8),
        path: &'static str,
    ) -> Self {
        Self {
            name,
            kind,
            center,
            components,
            number,
            precision,
            path,
        }
    }
}

const INT32: (&str, u8) = ("Int", 4);
const INT64: (&str, u8) = ("Int", 8);
const FLOAT64: (&str, u8) = ("Float", 8);

/// The attributes of every run, in the order written.
const ATTRIBUTES: [Attribute; 6] = [
    Attribute::new(
        "displacement",
        "Vector",
        "Node",
        3,
        FLOAT64,
        "/fields/displacement",
    ),
    Attribute::new(
        "gmsh_node_tag",
        "Scalar",
        "Node",
        1,
        INT64,
        "/mesh/node_tag",
    ),
    Attribute::new("body_id", "Scalar", "Cell", 1, INT32, "/mesh/cell_body"),
    Attribute::new("strain", "Tensor", "Cell", 9, FLOAT64, "/fields/strain"),
    Attribute::new("stress", "Tensor", "Cell", 9, FLOAT64, "/fields/stress"),
    Attribute::new(
        "von_mises",
        "Scalar",
        "Cell",
        1,
        FLOAT64,
        "/fields/von_mises",
    ),
];

/// The attributes a contact run adds.
const CONTACT_ATTRIBUTES: [Attribute; 5] = [
    Attribute::new(
        "contact_traction",
        "Vector",
        "Node",
        3,
        FLOAT64,
        "/fields/contact_traction",
    ),
    Attribute::new(
        "contact_pressure",
        "Scalar",
        "Node",
        1,
        FLOAT64,
        "/fields/contact_pressure",
    ),
    Attribute::new(
        "contact_mean_pressure",
        "Scalar",
        "Node",
        1,
        FLOAT64,
        "/fields/contact_mean_pressure",
    ),
    Attribute::new(
        "normal_gap",
        "Scalar",
        "Node",
        1,
        FLOAT64,
        "/fields/normal_gap",
    ),
    Attribute::new(
        "contact_active",
        "Scalar",
        "Node",
        1,
        INT32,
        "/fields/contact_active",
    ),
];

/// The fields of a run with a Coulomb pair (module doc).
const FRICTION_ATTRIBUTES: [Attribute; 4] = [
    Attribute::new(
        "friction_state",
        "Scalar",
        "Node",
        1,
        INT32,
        "/fields/friction_state",
    ),
    Attribute::new(
        "tangential_traction",
        "Vector",
        "Node",
        3,
        FLOAT64,
        "/fields/tangential_traction",
    ),
    Attribute::new(
        "slip_increment",
        "Vector",
        "Node",
        3,
        FLOAT64,
        "/fields/slip_increment",
    ),
    Attribute::new(
        "accumulated_slip",
        "Scalar",
        "Node",
        1,
        FLOAT64,
        "/fields/accumulated_slip",
    ),
];

fn xdmf_text(
    stem: &str,
    dim: usize,
    num_nodes: usize,
    num_cells: usize,
    contact: bool,
    friction: bool,
) -> String {
    let h5 = format!("{stem}.h5");
    let item = |dims: String, number: &str, precision: u8, path: &str| {
        format!(
            "<DataItem Dimensions=\"{dims}\" NumberType=\"{number}\" Precision=\"{precision}\" Format=\"HDF\">{h5}:{path}</DataItem>"
        )
    };
    let (topology, per_cell) = if dim == 2 {
        ("Triangle", 3)
    } else {
        ("Tetrahedron", 4)
    };
    let (n, c) = (num_nodes, num_cells);
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n    <Grid Name=\"internodes\" GridType=\"Uniform\">\n",
    );
    s += &format!(
        "      <Topology TopologyType=\"{topology}\" NumberOfElements=\"{c}\" NodesPerElement=\"{per_cell}\">\n        {}\n      </Topology>\n",
        item(format!("{c} {per_cell}"), "Int", 8, "/mesh/topology")
    );
    s += &format!(
        "      <Geometry GeometryType=\"XYZ\">\n        {}\n      </Geometry>\n",
        item(format!("{n} 3"), "Float", 8, "/mesh/geometry")
    );
    let extra: &[Attribute] = if contact { &CONTACT_ATTRIBUTES } else { &[] };
    let frictional: &[Attribute] = if friction { &FRICTION_ATTRIBUTES } else { &[] };
    for a in ATTRIBUTES.iter().chain(extra).chain(frictional) {
        let rows = if a.center == "Node" { n } else { c };
        let dims = match a.components {
            1 => rows.to_string(),
            k => format!("{rows} {k}"),
        };
        s += &format!(
            "      <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{}\">\n        {}\n      </Attribute>\n",
            a.name,
            a.kind,
            a.center,
            item(dims, a.number, a.precision, a.path)
        );
    }
    s += "    </Grid>\n  </Domain>\n</Xdmf>\n";
    s
}
