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

use std::ops::Range;
use std::path::Path;

use super::OutputError;
use crate::contact::SurfaceFields;
use crate::fem::Material;
use crate::fem::stress::cell_field;
use crate::mesh::BodyMesh;

/// One body's mesh and fields, as written.
pub struct BodyFields<'a> {
    pub mesh: &'a BodyMesh,
    /// Interleaved, `dim` per node, laid out like the mesh's kept coordinates (every node's
    /// on one process: `crate::elastic::ElasticSolution::displacement`).
    pub displacement: &'a [f64],
    /// What the cell fields (strain, stress, von Mises) are computed with, a chunk of cells
    /// at a time as they are written.
    pub material: &'a Material,
    /// Interface fields on the body's contact candidate surfaces (one per pair it is in), in
    /// contact runs.
    pub surfaces: Vec<&'a SurfaceFields>,
}

/// The rows of the cell datasets for some cells of one body: each cell's nodes (the body's
/// node indices), its strain and stress (9 values each, row-major 3 x 3) and its von Mises
/// stress ([`cell_field`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CellRows {
    pub topology: Vec<u32>,
    pub strain: Vec<f64>,
    pub stress: Vec<f64>,
    pub von_mises: Vec<f64>,
}

impl CellRows {
    /// The rows of `body`'s cells `cells` (indices of the cells its mesh holds).
    pub fn of(body: &BodyFields, cells: impl Iterator<Item = usize>) -> Self {
        let mut rows = Self::default();
        for c in cells {
            let (strain, stress, von_mises) =
                cell_field(body.mesh, body.material, body.displacement, c);
            let n = body.mesh.nodes_per_cell();
            rows.topology
                .extend_from_slice(&body.mesh.cells[n * c..n * c + n]);
            rows.strain.extend(strain);
            rows.stress.extend(stress);
            rows.von_mises.push(von_mises);
        }
        rows
    }

    /// The number of cells.
    pub fn len(&self) -> usize {
        self.von_mises.len()
    }

    pub fn is_empty(&self) -> bool {
        self.von_mises.is_empty()
    }
}

/// What gives the cell rows of body `k`'s cells `cells` (indices in the whole body), one
/// chunk at a time ([`row_chunks`]); an error is a message.
pub type CellRowsOf<'a> = dyn FnMut(usize, Range<usize>) -> Result<CellRows, String> + 'a;

/// The node datasets of three values a node that a distributed run's rank 0 receives from the
/// nodes' owners, a chunk at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeTable {
    /// `/mesh/geometry`: each node's coordinates.
    Geometry,
    /// `/fields/displacement`: each node's displacement (`z` 0 in 2D).
    Displacement,
}

impl NodeTable {
    /// The dataset's name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Geometry => "geometry",
            Self::Displacement => "displacement",
        }
    }
}

impl BodyFields<'_> {
    /// Node `node`'s row of `table`, where this process keeps the node (its coordinates and
    /// displacement: [`Self::displacement`]'s layout).
    pub fn node_row(&self, table: NodeTable, node: usize) -> Option<[f64; 3]> {
        let at = self.mesh.coords.position(node)?;
        Some(match table {
            NodeTable::Geometry => *self.mesh.coords.get(node)?,
            NodeTable::Displacement => {
                let dim = self.mesh.dim;
                let u = self.displacement.get(dim * at..dim * (at + 1))?;
                std::array::from_fn(|c| if c < dim { u[c] } else { 0.0 })
            }
        })
    }
}

/// What gives the rows of `table` for body `k`'s nodes `nodes` (indices in the whole body),
/// one chunk at a time ([`row_chunks`]); an error is a message.
pub type NodeRowsOf<'a> =
    dyn FnMut(usize, NodeTable, Range<usize>) -> Result<Vec<[f64; 3]>, String> + 'a;

/// Writes `<dir>/<stem>.h5` and `<dir>/<stem>.xdmf` from the bodies' own nodes and cells
/// (every body's mesh holds all of them).
pub fn write_xdmf(dir: &Path, stem: &str, bodies: &[BodyFields]) -> Result<(), OutputError> {
    let mut node_rows = |k: usize, table: NodeTable, nodes: Range<usize>| {
        (nodes.clone())
            .map(|a| bodies[k].node_row(table, a))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| {
                format!(
                    "body {k}: the {} of its nodes {nodes:?} is not here",
                    table.name()
                )
            })
    };
    write_xdmf_with(dir, stem, bodies, &mut node_rows, &mut |k, cells| {
        Ok(CellRows::of(&bodies[k], cells))
    })
}

/// Writes `<dir>/<stem>.h5` and `<dir>/<stem>.xdmf`, the geometry and the displacement from
/// `node_rows` and the cell datasets from `cell_rows`: where the bodies' meshes hold only
/// some of their nodes and cells (rank 0 of a distributed run), the rows of the others come
/// from the ranks that hold them. The other node datasets (tags, interface fields) are
/// written from the bodies' own arrays, which hold every node.
///
/// Each dataset is written body by body, a bounded chunk of rows at a time
/// (`CHUNK_ROWS`), straight from the bodies' own arrays or as `node_rows` and
/// `cell_rows` give them: the writer never holds a copy of the whole grid (at 1M DOFs that
/// copy was 470 MB beside the fields themselves, on the process that writes).
pub fn write_xdmf_with(
    dir: &Path,
    stem: &str,
    bodies: &[BodyFields],
    node_rows: &mut NodeRowsOf,
    cell_rows: &mut CellRowsOf,
) -> Result<(), OutputError> {
    let h5_path = dir.join(format!("{stem}.h5"));
    let dim = bodies.first().map_or(3, |b| b.mesh.dim);
    let nodes: Vec<usize> = bodies.iter().map(|b| b.mesh.num_nodes()).collect();
    let cells: Vec<usize> = bodies.iter().map(|b| b.mesh.total_cells()).collect();
    let contact = bodies.iter().any(|b| !b.surfaces.is_empty());
    let friction = (bodies.iter().flat_map(|b| &b.surfaces)).any(|s| s.friction.is_some());
    let grid = Grid {
        bodies,
        dim,
        nodes: &nodes,
        cells: &cells,
        contact,
        friction,
        chunk_rows: CHUNK_ROWS,
    };
    grid.write_h5(&h5_path, node_rows, cell_rows)
        .map_err(|source| OutputError::Hdf5 {
            path: h5_path.clone(),
            source,
        })?;

    let xdmf_path = dir.join(format!("{stem}.xdmf"));
    let (num_nodes, num_cells) = (nodes.iter().sum(), cells.iter().sum());
    std::fs::write(
        &xdmf_path,
        xdmf_text(stem, dim, num_nodes, num_cells, contact, friction),
    )
    .map_err(|source| OutputError::Io {
        path: xdmf_path,
        source,
    })
}

/// Rows of a dataset written at a time: what the writer holds of a field beyond the bodies'
/// own arrays (at most 4.7 MB, for the 9 values of a strain or stress row).
const CHUNK_ROWS: usize = 1 << 16;

/// The chunks the geometry and the cell datasets are written in, for bodies of `rows[k]`
/// nodes or cells: (body, its rows), the bodies in order. Every rank of a distributed run
/// sends its rows in these.
pub fn row_chunks(rows: &[usize]) -> Vec<(usize, Range<usize>)> {
    chunks(rows, CHUNK_ROWS)
}

fn chunks(rows: &[usize], chunk_rows: usize) -> Vec<(usize, Range<usize>)> {
    (rows.iter().enumerate())
        .flat_map(|(k, &count)| {
            (0..count)
                .step_by(chunk_rows)
                .map(move |start| (k, start..count.min(start + chunk_rows)))
        })
        .collect()
}

/// The first row of each body when bodies of `rows[k]` rows are written one after the other.
fn first_rows(rows: &[usize]) -> Vec<usize> {
    (rows.iter())
        .scan(0, |first, &n| {
            let this = *first;
            *first += n;
            Some(this)
        })
        .collect()
}

/// Every body's nodes and cells one after the other, as the datasets of the module doc.
struct Grid<'a> {
    bodies: &'a [BodyFields<'a>],
    dim: usize,
    /// Nodes and cells of each body.
    nodes: &'a [usize],
    cells: &'a [usize],
    /// Whether any body has interface fields (a contact run).
    contact: bool,
    /// Whether any surface has a Coulomb pair's tangential fields.
    friction: bool,
    /// Rows written at a time ([`CHUNK_ROWS`]).
    chunk_rows: usize,
}

/// Values per row of a dataset: one (a dataset of one dimension) or a table's columns.
#[derive(Clone, Copy)]
enum Width {
    Scalar,
    Columns(usize),
}

impl Grid<'_> {
    fn write_h5(
        &self,
        path: &Path,
        node_rows: &mut NodeRowsOf,
        cell_rows: &mut CellRowsOf,
    ) -> hdf5::Result<()> {
        let bodies = self.bodies;
        let file = hdf5::File::create(path)?;
        let mesh = file.create_group("mesh")?;
        let fields = file.create_group("fields")?;
        let (nodes, cells) = (self.nodes, self.cells);
        let body = |k: usize| &bodies[k];
        let first_nodes = first_rows(nodes);
        self.write_node_table(&mesh, NodeTable::Geometry, &first_nodes, node_rows)?;
        let node_tag = |k: usize| body(k).mesh.node_tags.iter().map(|t| t as i64);
        self.write_by_body(&mesh, "node_tag", Width::Scalar, nodes, node_tag)?;
        let node_body = |k: usize| std::iter::repeat_n(k as i32, nodes[k]);
        self.write_by_body(&mesh, "node_body", Width::Scalar, nodes, node_body)?;
        let mut tags = Vec::with_capacity(bodies.len());
        for (k, b) in bodies.iter().enumerate() {
            tags.push(match &b.mesh.part {
                None => &b.mesh.cell_tags,
                Some(part) => part.whole_cell_tags.as_ref().ok_or_else(|| {
                    hdf5::Error::from(format!("body {k}: its element tags are not on this rank"))
                })?,
            });
        }
        let cell_tag = |k: usize| tags[k].iter().map(|t| t as i64);
        self.write_by_body(&mesh, "cell_tag", Width::Scalar, cells, cell_tag)?;
        let cell_body = |k: usize| std::iter::repeat_n(k as i32, cells[k]);
        self.write_by_body(&mesh, "cell_body", Width::Scalar, cells, cell_body)?;
        self.write_node_table(&fields, NodeTable::Displacement, &first_nodes, node_rows)?;
        self.write_cells(&mesh, &fields, &first_nodes, cell_rows)?;
        if self.contact {
            let traction = |k: usize| {
                on_surfaces(body(k), 3, 0.0, |f, s, v| v.copy_from_slice(&f.traction[s]))
            };
            self.write_by_body(
                &fields,
                "contact_traction",
                Width::Columns(3),
                nodes,
                traction,
            )?;
            let pressure = |k: usize| on_surfaces(body(k), 1, 0.0, |f, s, v| v[0] = f.pressure[s]);
            self.write_by_body(&fields, "contact_pressure", Width::Scalar, nodes, pressure)?;
            let mean = |k: usize| on_surfaces(body(k), 1, 0.0, |f, s, v| v[0] = f.mean_pressure[s]);
            self.write_by_body(&fields, "contact_mean_pressure", Width::Scalar, nodes, mean)?;
            let gap = |k: usize| on_surfaces(body(k), 1, 0.0, |f, s, v| v[0] = f.normal_gap[s]);
            self.write_by_body(&fields, "normal_gap", Width::Scalar, nodes, gap)?;
            let active =
                |k: usize| on_surfaces(body(k), 1, 0i32, |f, s, v| v[0] = i32::from(f.active[s]));
            self.write_by_body(&fields, "contact_active", Width::Scalar, nodes, active)?;
        }
        if self.friction {
            // Each field only on the surfaces of a Coulomb pair (-1, or zero, elsewhere).
            let state = |k: usize| {
                on_surfaces(body(k), 1, -1i32, |f, s, v| {
                    if let Some(friction) = &f.friction {
                        v[0] = friction.state[s].code() as i32;
                    }
                })
            };
            self.write_by_body(&fields, "friction_state", Width::Scalar, nodes, state)?;
            let tangential = |k: usize| {
                on_surfaces(body(k), 3, 0.0, |f, s, v| {
                    if let Some(friction) = &f.friction {
                        v.copy_from_slice(&friction.tangential_traction[s]);
                    }
                })
            };
            let width = Width::Columns(3);
            self.write_by_body(&fields, "tangential_traction", width, nodes, tangential)?;
            let slip = |k: usize| {
                on_surfaces(body(k), 3, 0.0, |f, s, v| {
                    if let Some(friction) = &f.friction {
                        v.copy_from_slice(&friction.slip_increment[s]);
                    }
                })
            };
            self.write_by_body(&fields, "slip_increment", width, nodes, slip)?;
            let accumulated = |k: usize| {
                on_surfaces(body(k), 1, 0.0, |f, s, v| {
                    if let Some(friction) = &f.friction {
                        v[0] = friction.accumulated_slip[s];
                    }
                })
            };
            self.write_by_body(
                &fields,
                "accumulated_slip",
                Width::Scalar,
                nodes,
                accumulated,
            )?;
        }
        file.close()
    }

    /// Creates the dataset `name` in `group`, `width` values for each of the `rows[k]` rows of
    /// body `k`, the bodies one after the other, and writes it from `values(k)` (body `k`'s
    /// values, row after row), [`Self::chunk_rows`] rows at a time.
    fn write_by_body<T, I>(
        &self,
        group: &hdf5::Group,
        name: &str,
        width: Width,
        rows: &[usize],
        values: impl Fn(usize) -> I,
    ) -> hdf5::Result<()>
    where
        T: hdf5::H5Type + Copy,
        I: Iterator<Item = T>,
    {
        let (total, chunk_rows): (usize, usize) = (rows.iter().sum(), self.chunk_rows);
        let (dataset, columns) = match width {
            Width::Scalar => (group.new_dataset::<T>().shape(total).create(name)?, 1),
            Width::Columns(c) => (group.new_dataset::<T>().shape((total, c)).create(name)?, c),
        };
        let mut chunk = Vec::with_capacity(chunk_rows.min(total) * columns);
        let mut first = 0;
        for (k, &count) in rows.iter().enumerate() {
            let mut body = values(k);
            let mut written = 0;
            while written < count {
                let n = chunk_rows.min(count - written);
                chunk.clear();
                chunk.extend(body.by_ref().take(n * columns));
                if chunk.len() != n * columns {
                    return Err(hdf5::Error::from(format!(
                        "{name}: body {k} has {} values for {count} rows of {columns}",
                        written * columns + chunk.len()
                    )));
                }
                let rows = first..first + n;
                match width {
                    Width::Scalar => dataset.write_slice(&chunk[..], rows)?,
                    Width::Columns(c) => {
                        let table = ndarray::ArrayView2::from_shape((n, c), &chunk[..])
                            .expect("n rows of c values");
                        dataset.write_slice(table, ndarray::s![rows, ..])?
                    }
                }
                first += n;
                written += n;
            }
        }
        Ok(())
    }

    /// The dataset of `table` (`geometry` in `mesh`, or `displacement` in `fields`, as
    /// `group` is) of the bodies' nodes, from `node_rows`, [`Self::chunk_rows`] nodes at a
    /// time; `first_nodes[k]`: the grid's index of body `k`'s first node.
    fn write_node_table(
        &self,
        group: &hdf5::Group,
        table: NodeTable,
        first_nodes: &[usize],
        node_rows: &mut NodeRowsOf,
    ) -> hdf5::Result<()> {
        let total: usize = self.nodes.iter().sum();
        let name = table.name();
        let dataset = group.new_dataset::<f64>().shape((total, 3)).create(name)?;
        for (k, nodes) in chunks(self.nodes, self.chunk_rows) {
            let chunk = node_rows(k, table, nodes.clone()).map_err(hdf5::Error::from)?;
            if chunk.len() != nodes.len() {
                return Err(hdf5::Error::from(format!(
                    "body {k}: {} rows of {name} for its nodes {nodes:?}",
                    chunk.len()
                )));
            }
            let view = ndarray::ArrayView2::from_shape((chunk.len(), 3), chunk.as_flattened())
                .expect("3 values a node");
            let rows = first_nodes[k] + nodes.start..first_nodes[k] + nodes.end;
            dataset.write_slice(view, ndarray::s![rows, ..])?;
        }
        Ok(())
    }

    /// The datasets `topology` (in `mesh`), `strain`, `stress` (9 values a cell) and
    /// `von_mises` (in `fields`) of the bodies' cells, from `cell_rows`, [`Self::chunk_rows`]
    /// cells at a time; `first_nodes[k]`: the grid's index of body `k`'s first node.
    fn write_cells(
        &self,
        mesh: &hdf5::Group,
        fields: &hdf5::Group,
        first_nodes: &[usize],
        cell_rows: &mut CellRowsOf,
    ) -> hdf5::Result<()> {
        let total: usize = self.cells.iter().sum();
        let width = self.dim + 1;
        let topology = mesh
            .new_dataset::<i64>()
            .shape((total, width))
            .create("topology")?;
        let strain = fields
            .new_dataset::<f64>()
            .shape((total, 9))
            .create("strain")?;
        let stress = fields
            .new_dataset::<f64>()
            .shape((total, 9))
            .create("stress")?;
        let von_mises = fields
            .new_dataset::<f64>()
            .shape(total)
            .create("von_mises")?;
        let first_cells = first_rows(self.cells);
        let mut nodes = Vec::new();
        for (k, cells) in chunks(self.cells, self.chunk_rows) {
            let n = cells.len();
            let chunk = cell_rows(k, cells.clone()).map_err(hdf5::Error::from)?;
            if chunk.len() != n
                || chunk.topology.len() != width * n
                || chunk.strain.len() != 9 * n
                || chunk.stress.len() != 9 * n
            {
                return Err(hdf5::Error::from(format!(
                    "body {k}: {} cell rows for its cells {cells:?}",
                    chunk.len()
                )));
            }
            let rows = first_cells[k] + cells.start..first_cells[k] + cells.end;
            nodes.clear();
            nodes.extend((chunk.topology.iter()).map(|&a| (a as usize + first_nodes[k]) as i64));
            let table = |values| ndarray::ArrayView2::from_shape((n, 9), values).expect("9 a cell");
            let cell_nodes = ndarray::ArrayView2::from_shape((n, width), &nodes[..])
                .expect("dim + 1 nodes a cell");
            topology.write_slice(cell_nodes, ndarray::s![rows.clone(), ..])?;
            strain.write_slice(table(&chunk.strain[..]), ndarray::s![rows.clone(), ..])?;
            stress.write_slice(table(&chunk.stress[..]), ndarray::s![rows.clone(), ..])?;
            von_mises.write_slice(&chunk.von_mises[..], rows)?;
        }
        Ok(())
    }
}

/// A node field of `body` over all its nodes, `width` values a node: `default` off its
/// candidate surfaces, and where `set(surface, s, values)` puts them at candidate `s` of each
/// (a later surface's over an earlier one's at a shared node).
fn on_surfaces<T: Copy>(
    body: &BodyFields,
    width: usize,
    default: T,
    set: impl Fn(&SurfaceFields, usize, &mut [T]),
) -> std::vec::IntoIter<T> {
    let mut values = vec![default; width * body.mesh.num_nodes()];
    for surface in &body.surfaces {
        for (s, &node) in surface.nodes.iter().enumerate() {
            set(surface, s, &mut values[width * node..width * node + width]);
        }
    }
    values.into_iter()
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

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::fem::stress::cell_fields;
    use crate::mesh::NodeCoords;

    /// A strip of `n` unit squares (two triangles each) from `x0`.
    fn strip(name: &str, x0: f64, n: usize) -> BodyMesh {
        let coords = (0..=n)
            .flat_map(|i| [[x0 + i as f64, 0.0, 0.0], [x0 + i as f64, 1.0, 0.0]])
            .collect::<Vec<_>>()
            .into();
        let cells: Vec<u32> = (0..n as u32)
            .flat_map(|i| [2 * i, 2 * i + 2, 2 * i + 3, 2 * i, 2 * i + 3, 2 * i + 1])
            .collect();
        BodyMesh {
            name: name.into(),
            physical_tag: 1,
            dim: 2,
            coords,
            node_tags: (0..2 * (n + 1)).map(|a| 100 + a as u64).collect(),
            cell_tags: (0..2 * n).map(|c| 500 + c as u64).collect(),
            cells,
            boundary_groups: BTreeMap::new(),
            point_groups: BTreeMap::new(),
            part: None,
        }
    }

    #[test]
    fn written_in_chunks_the_datasets_are_the_bodies_one_after_the_other() {
        // Chunks of 3 rows: bodies of 14 and 10 cells cross chunk ends inside each body.
        let meshes = [strip("a", 0.0, 7), strip("b", 10.0, 5)];
        let material = Material::new(1000.0, 0.3).unwrap();
        let displacements: Vec<Vec<f64>> = (meshes.iter())
            .map(|m| {
                (m.coords.kept().map(|(_, x)| x))
                    .flat_map(|x| [1e-3 * x[0] * x[1], -2e-3 * x[1]])
                    .collect()
            })
            .collect();
        let bodies: Vec<BodyFields> = (meshes.iter().zip(&displacements))
            .map(|(mesh, u)| BodyFields {
                mesh,
                displacement: u,
                material: &material,
                surfaces: Vec::new(),
            })
            .collect();
        let (nodes, cells) = ([16, 12], [14, 10]);
        let grid = Grid {
            bodies: &bodies,
            dim: 2,
            nodes: &nodes,
            cells: &cells,
            contact: false,
            friction: false,
            chunk_rows: 3,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grid.h5");
        // The geometry as a distributed run's rank 0 receives it: a chunk at a time, each
        // asked for once.
        let mut asked = Vec::new();
        let mut node_rows = |k: usize, table, nodes: Range<usize>| {
            asked.push((table, k, nodes.clone()));
            Ok(nodes
                .map(|a| bodies[k].node_row(table, a).unwrap())
                .collect())
        };
        let mut rows = |k: usize, cells| Ok(CellRows::of(&bodies[k], cells));
        grid.write_h5(&path, &mut node_rows, &mut rows).unwrap();
        let each = |table| {
            chunks(&nodes, 3)
                .into_iter()
                .map(move |(k, n)| (table, k, n))
        };
        let expected: Vec<_> = (each(NodeTable::Geometry))
            .chain(each(NodeTable::Displacement))
            .collect();
        assert_eq!(asked, expected);

        let file = hdf5::File::open(&path).unwrap();
        let read = |name: &str| file.dataset(name).unwrap().read_raw::<f64>().unwrap();
        let topology = file
            .dataset("mesh/topology")
            .unwrap()
            .read_raw::<i64>()
            .unwrap();
        let expected: Vec<i64> = (meshes[0].cells.iter().map(|&n| n as i64))
            .chain(meshes[1].cells.iter().map(|&n| (n + 16) as i64))
            .collect();
        assert_eq!(topology, expected);
        let cell_body = file
            .dataset("mesh/cell_body")
            .unwrap()
            .read_raw::<i32>()
            .unwrap();
        assert_eq!(cell_body, [vec![0; 14], vec![1; 10]].concat());
        let geometry: Vec<f64> = (meshes.iter())
            .flat_map(|m| m.coords.kept().flat_map(|(_, x)| *x))
            .collect();
        assert_eq!(read("mesh/geometry"), geometry);
        let tags = file
            .dataset("mesh/node_tag")
            .unwrap()
            .read_raw::<i64>()
            .unwrap();
        assert_eq!(
            tags,
            [(100..116).collect::<Vec<i64>>(), (100..112).collect()].concat()
        );
        let padded: Vec<f64> = (displacements.iter())
            .flat_map(|u| u.chunks_exact(2).flat_map(|u| [u[0], u[1], 0.0]))
            .collect();
        assert_eq!(read("fields/displacement"), padded);
        let whole: Vec<_> = (meshes.iter().zip(&displacements))
            .map(|(mesh, u)| cell_fields(mesh, &material, u))
            .collect();
        let strain: Vec<f64> = (whole.iter())
            .flat_map(|f| f.strain.iter().flatten().copied())
            .collect();
        let stress: Vec<f64> = (whole.iter())
            .flat_map(|f| f.stress.iter().flatten().copied())
            .collect();
        let von_mises: Vec<f64> = whole.iter().flat_map(|f| f.von_mises.clone()).collect();
        assert_eq!(read("fields/strain"), strain);
        assert_eq!(read("fields/stress"), stress);
        assert_eq!(read("fields/von_mises"), von_mises);
    }

    #[test]
    fn a_displacement_held_at_the_kept_nodes_gives_the_whole_ones_rows_there() {
        // A rank of a distributed run keeps some nodes (here those of cells 2 to 5) and the
        // displacement at them, in their order: its rows are the whole body's.
        let whole_mesh = strip("a", 0.0, 5);
        let material = Material::new(1000.0, 0.3).unwrap();
        let u: Vec<f64> = (whole_mesh.coords.kept().map(|(_, x)| x))
            .flat_map(|x| [1e-3 * x[0] * x[1] + 2e-4 * x[0], -2e-3 * x[1] * x[0]])
            .collect();
        let cells = 2..6;
        let mut kept: Vec<u32> = whole_mesh.cells[3 * cells.start..3 * cells.end].to_vec();
        kept.sort_unstable();
        kept.dedup();
        let mut part_mesh = strip("a", 0.0, 5);
        part_mesh.coords = NodeCoords::of_nodes(
            whole_mesh.num_nodes(),
            kept.clone(),
            kept.iter()
                .map(|&a| whole_mesh.coords[a as usize])
                .collect(),
        );
        let kept_u = part_mesh.coords.kept_values(u.clone(), 2);
        assert_eq!(kept_u.len(), 2 * kept.len());
        let body = |mesh, displacement| BodyFields {
            mesh,
            displacement,
            material: &material,
            surfaces: Vec::new(),
        };
        let (whole, part) = (body(&whole_mesh, &u[..]), body(&part_mesh, &kept_u[..]));
        for table in [NodeTable::Geometry, NodeTable::Displacement] {
            for a in 0..whole_mesh.num_nodes() {
                match kept.contains(&(a as u32)) {
                    true => assert_eq!(part.node_row(table, a), whole.node_row(table, a)),
                    false => assert_eq!(part.node_row(table, a), None),
                }
            }
        }
        assert_eq!(
            CellRows::of(&part, cells.clone()),
            CellRows::of(&whole, cells)
        );
    }

    #[test]
    fn a_body_with_fewer_values_than_rows_is_an_error_not_a_short_dataset() {
        let meshes = [strip("a", 0.0, 2)];
        let material = Material::new(1000.0, 0.3).unwrap();
        let u = vec![0.0; 12];
        let bodies = [BodyFields {
            mesh: &meshes[0],
            displacement: &u,
            material: &material,
            surfaces: Vec::new(),
        }];
        let grid = Grid {
            bodies: &bodies,
            dim: 2,
            nodes: &[6],
            cells: &[4],
            contact: false,
            friction: false,
            chunk_rows: 3,
        };
        let dir = tempfile::tempdir().unwrap();
        let file = hdf5::File::create(dir.path().join("short.h5")).unwrap();
        let group = file.create_group("g").unwrap();
        let short = |_| [1.0, 2.0].into_iter();
        let error = grid
            .write_by_body(&group, "short", Width::Columns(3), &[1], short)
            .unwrap_err();
        assert!(
            error
                .to_string()
                .contains("short: body 0 has 2 values for 1 rows of 3")
        );
        // So is a chunk of the geometry with a node missing.
        let mut short_geometry = |_, _, nodes: Range<usize>| Ok(vec![[0.0; 3]; nodes.len() - 1]);
        let error = grid
            .write_node_table(&group, NodeTable::Geometry, &[0], &mut short_geometry)
            .unwrap_err();
        assert!(
            error
                .to_string()
                .contains("body 0: 2 rows of geometry for its nodes 0..3")
        );
    }
}
