//! XDMF 3 + HDF5: one grid holding every body, readable by ParaView (XDMF3 reader) and h5py.
//!
//! Layout of `<stem>.h5` (N nodes and C cells over all bodies, bodies one after the other):
//! `/mesh/geometry` (N, 3), `/mesh/topology` (C, dim + 1), `/mesh/node_tag` (N) gmsh node tags,
//! `/mesh/node_body` (N), `/mesh/cell_body` (C), `/mesh/cell_tag` (C) gmsh element tags,
//! `/fields/displacement` (N, 3), `/fields/strain` and `/fields/stress` (C, 9) row-major 3 x 3,
//! `/fields/von_mises` (C); in contact runs also `/fields/contact_traction` (N, 3),
//! `/fields/contact_pressure` (N), `/fields/contact_mean_pressure` (N), `/fields/normal_gap` (N)
//! and `/fields/contact_active` (N),
//! zero at nodes off the candidate surfaces (gap NaN where the other surface is out of range).

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
    /// Interface fields on the body's contact candidate surface, in contact runs.
    pub surface: Option<&'a SurfaceFields>,
}

/// Writes `<dir>/<stem>.h5` and `<dir>/<stem>.xdmf`.
pub fn write_xdmf(dir: &Path, stem: &str, bodies: &[BodyFields]) -> Result<(), OutputError> {
    let h5_path = dir.join(format!("{stem}.h5"));
    let dim = bodies.first().map_or(3, |b| b.mesh.dim);
    let num_nodes: usize = bodies.iter().map(|b| b.mesh.num_nodes()).sum();
    let num_cells: usize = bodies.iter().map(|b| b.mesh.num_cells()).sum();

    let mut geometry = Vec::with_capacity(3 * num_nodes);
    let mut displacement = Vec::with_capacity(3 * num_nodes);
    let mut node_tag = Vec::with_capacity(num_nodes);
    let mut node_body = Vec::with_capacity(num_nodes);
    let mut topology = Vec::with_capacity((dim + 1) * num_cells);
    let (mut cell_tag, mut cell_body) = (Vec::new(), Vec::new());
    let (mut strain, mut stress, mut von_mises) = (Vec::new(), Vec::new(), Vec::new());
    let contact = bodies.iter().any(|b| b.surface.is_some());
    let mut traction = vec![0.0; 3 * num_nodes];
    let mut pressure = vec![0.0; num_nodes];
    let mut mean_pressure = vec![0.0; num_nodes];
    let mut gap = vec![0.0; num_nodes];
    let mut active = vec![0i32; num_nodes];
    let mut offset = 0;
    for (id, body) in bodies.iter().enumerate() {
        if let Some(surface) = body.surface {
            for (s, &node) in surface.nodes.iter().enumerate() {
                let row = offset + node;
                traction[3 * row..3 * row + 3].copy_from_slice(&surface.traction[s]);
                pressure[row] = surface.pressure[s];
                mean_pressure[row] = surface.mean_pressure[s];
                gap[row] = surface.normal_gap[s];
                active[row] = i32::from(surface.active[s]);
            }
        }
        let m = body.mesh;
        for (a, x) in m.coords.iter().enumerate() {
            geometry.extend_from_slice(x);
            let mut u = [0.0; 3];
            u[..dim].copy_from_slice(&body.displacement[dim * a..dim * a + dim]);
            displacement.extend_from_slice(&u);
        }
        node_tag.extend(m.node_tags.iter().map(|&t| t as i64));
        node_body.extend(std::iter::repeat_n(id as i32, m.num_nodes()));
        topology.extend(m.cells.iter().map(|&n| (n + offset) as i64));
        cell_tag.extend(m.cell_tags.iter().map(|&t| t as i64));
        cell_body.extend(std::iter::repeat_n(id as i32, m.num_cells()));
        strain.extend(body.cell_fields.strain.iter().flatten());
        stress.extend(body.cell_fields.stress.iter().flatten());
        von_mises.extend_from_slice(&body.cell_fields.von_mises);
        offset += m.num_nodes();
    }

    let hdf5_error = |source| OutputError::Hdf5 {
        path: h5_path.clone(),
        source,
    };
    let write = || -> hdf5::Result<()> {
        let file = hdf5::File::create(&h5_path)?;
        let mesh = file.create_group("mesh")?;
        let fields = file.create_group("fields")?;
        let table = |v: Vec<f64>, cols: usize| {
            Array2::from_shape_vec((v.len() / cols, cols), v).expect("rows * cols")
        };
        mesh.new_dataset_builder()
            .with_data(&table(geometry, 3))
            .create("geometry")?;
        mesh.new_dataset_builder()
            .with_data(
                &Array2::from_shape_vec((num_cells, dim + 1), topology).expect("rows * cols"),
            )
            .create("topology")?;
        mesh.new_dataset_builder()
            .with_data(&Array1::from(node_tag))
            .create("node_tag")?;
        mesh.new_dataset_builder()
            .with_data(&Array1::from(node_body))
            .create("node_body")?;
        mesh.new_dataset_builder()
            .with_data(&Array1::from(cell_tag))
            .create("cell_tag")?;
        mesh.new_dataset_builder()
            .with_data(&Array1::from(cell_body))
            .create("cell_body")?;
        fields
            .new_dataset_builder()
            .with_data(&table(displacement, 3))
            .create("displacement")?;
        fields
            .new_dataset_builder()
            .with_data(&table(strain, 9))
            .create("strain")?;
        fields
            .new_dataset_builder()
            .with_data(&table(stress, 9))
            .create("stress")?;
        fields
            .new_dataset_builder()
            .with_data(&Array1::from(von_mises))
            .create("von_mises")?;
        if contact {
            fields
                .new_dataset_builder()
                .with_data(&table(traction, 3))
                .create("contact_traction")?;
            fields
                .new_dataset_builder()
                .with_data(&Array1::from(pressure))
                .create("contact_pressure")?;
            fields
                .new_dataset_builder()
                .with_data(&Array1::from(mean_pressure))
                .create("contact_mean_pressure")?;
            fields
                .new_dataset_builder()
                .with_data(&Array1::from(gap))
                .create("normal_gap")?;
            fields
                .new_dataset_builder()
                .with_data(&Array1::from(active))
                .create("contact_active")?;
        }
        file.close()
    };
    write().map_err(hdf5_error)?;

    let xdmf_path = dir.join(format!("{stem}.xdmf"));
    std::fs::write(
        &xdmf_path,
        xdmf_text(stem, dim, num_nodes, num_cells, contact),
    )
    .map_err(|source| OutputError::Io {
        path: xdmf_path,
        source,
    })
}

fn xdmf_text(stem: &str, dim: usize, num_nodes: usize, num_cells: usize, contact: bool) -> String {
    let h5 = format!("{stem}.h5");
    let item = |dims: String, number: &str, precision: u8, path: &str| {
        format!(
            "<DataItem Dimensions=\"{dims}\" NumberType=\"{number}\" Precision=\"{precision}\" Format=\"HDF\">{h5}:{path}</DataItem>"
        )
    };
    let attribute = |name: &str,
                     kind: &str,
                     center: &str,
                     dims: String,
                     number: &str,
                     precision: u8,
                     path: &str| {
        format!(
            "      <Attribute Name=\"{name}\" AttributeType=\"{kind}\" Center=\"{center}\">\n        {}\n      </Attribute>\n",
            item(dims, number, precision, path)
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
    s += &attribute(
        "displacement",
        "Vector",
        "Node",
        format!("{n} 3"),
        "Float",
        8,
        "/fields/displacement",
    );
    s += &attribute(
        "gmsh_node_tag",
        "Scalar",
        "Node",
        n.to_string(),
        "Int",
        8,
        "/mesh/node_tag",
    );
    s += &attribute(
        "body_id",
        "Scalar",
        "Cell",
        c.to_string(),
        "Int",
        4,
        "/mesh/cell_body",
    );
    s += &attribute(
        "strain",
        "Tensor",
        "Cell",
        format!("{c} 9"),
        "Float",
        8,
        "/fields/strain",
    );
    s += &attribute(
        "stress",
        "Tensor",
        "Cell",
        format!("{c} 9"),
        "Float",
        8,
        "/fields/stress",
    );
    s += &attribute(
        "von_mises",
        "Scalar",
        "Cell",
        c.to_string(),
        "Float",
        8,
        "/fields/von_mises",
    );
    if contact {
        s += &attribute(
            "contact_traction",
            "Vector",
            "Node",
            format!("{n} 3"),
            "Float",
            8,
            "/fields/contact_traction",
        );
        s += &attribute(
            "contact_pressure",
            "Scalar",
            "Node",
            n.to_string(),
            "Float",
            8,
            "/fields/contact_pressure",
        );
        s += &attribute(
            "contact_mean_pressure",
            "Scalar",
            "Node",
            n.to_string(),
            "Float",
            8,
            "/fields/contact_mean_pressure",
        );
        s += &attribute(
            "normal_gap",
            "Scalar",
            "Node",
            n.to_string(),
            "Float",
            8,
            "/fields/normal_gap",
        );
        s += &attribute(
            "contact_active",
            "Scalar",
            "Node",
            n.to_string(),
            "Int",
            4,
            "/fields/contact_active",
        );
    }
    s += "    </Grid>\n  </Domain>\n</Xdmf>\n";
    s
}
