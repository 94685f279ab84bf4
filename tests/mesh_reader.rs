//! The gmsh reader on the committed fixtures: bodies, groups, local numbering, orientation,
//! and a clear error for every kind of bad file.

mod common;

use common::{edited_fixture, fixture, read_fixture};
use internodes::fem::kernels::facet_measure_and_normal;
use internodes::mesh::{MeshError, read_msh};

#[test]
fn ascii_and_binary_files_give_the_same_mesh() {
    for (ascii, binary) in [
        ("block_2d.msh", "block_2d_bin.msh"),
        ("block_3d.msh", "block_3d_bin.msh"),
    ] {
        let a = read_fixture(ascii);
        let b = read_fixture(binary);
        assert_eq!(a.dim, b.dim);
        assert_eq!(a.bodies.len(), b.bodies.len());
        for (x, y) in a.bodies.iter().zip(&b.bodies) {
            assert_eq!(x.name, y.name);
            assert_eq!(x.node_tags, y.node_tags);
            assert_eq!(x.cells, y.cells);
            // The ASCII file prints coordinates with 16 significant digits.
            for (p, q) in x
                .coords
                .as_whole()
                .unwrap()
                .iter()
                .zip(y.coords.as_whole().unwrap())
            {
                for k in 0..3 {
                    assert!((p[k] - q[k]).abs() <= 1e-14 * (1.0 + q[k].abs()));
                }
            }
            assert_eq!(
                x.boundary_groups.keys().collect::<Vec<_>>(),
                y.boundary_groups.keys().collect::<Vec<_>>()
            );
        }
    }
}

#[test]
fn bodies_and_groups_come_from_physical_names() {
    let mesh = read_fixture("two_blocks_3d.msh");
    assert_eq!(mesh.dim, 3);
    let names: Vec<&str> = mesh.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["lower", "upper"]);
    let lower = mesh.body("lower").unwrap();
    let groups: Vec<&String> = lower.boundary_groups.keys().collect();
    assert_eq!(groups, ["lower_base", "lower_contact", "lower_sides"]);
    // Bodies are numbered locally and never share a gmsh node.
    let upper = mesh.body("upper").unwrap();
    assert!(
        lower
            .node_tags
            .iter()
            .all(|t| upper.node_tags.position(t).is_none())
    );
    assert!(
        lower
            .cells()
            .flat_map(|c| c.to_vec())
            .all(|n| n < lower.num_nodes())
    );
    assert!(mesh.physical_group("upper_top").is_some());
}

#[test]
fn facet_normals_point_out_of_the_body() {
    // The blocks' top faces lie on y = 0 (2D) / z = 0 (3D) with the body below: normal +e_dim.
    for (file, group) in [
        ("block_2d.msh", "block_top"),
        ("block_3d.msh", "block_top"),
        ("block_3d_bin.msh", "block_base"),
    ] {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let dim = body.dim;
        let facets = body.boundary_group(group).unwrap();
        let expected = if group == "block_top" { 1.0 } else { -1.0 };
        for f in 0..facets.num_facets(dim) {
            let x: Vec<[f64; 3]> = facets
                .facet(f, dim)
                .iter()
                .map(|&n| body.coords[n])
                .collect();
            let (_, normal) = facet_measure_and_normal(&x, dim);
            assert!(
                (normal[dim - 1] - expected).abs() < 1e-12,
                "{file} {group} facet {f}: normal {normal:?}"
            );
        }
    }
}

#[test]
fn two_dimensional_and_three_dimensional_contact_geometries_read() {
    let m = read_fixture("half_disc_on_block.msh");
    assert_eq!(m.dim, 2);
    assert!(
        m.body("disc")
            .unwrap()
            .boundary_group("disc_contact")
            .is_some()
    );
    let m = read_fixture("hemisphere_on_block.msh");
    assert_eq!(m.dim, 3);
    assert!(
        m.body("block")
            .unwrap()
            .boundary_group("block_contact")
            .is_some()
    );
}

#[test]
fn facets_between_two_cells_of_a_body_are_told_from_its_boundary() {
    // The interface of the glued blocks is a boundary of `lower` and of `upper` (one cell of
    // each), and lies inside `union` (every facet between a cell of each half).
    for (name, dim) in [("glued_blocks_2d.msh", 2), ("glued_blocks_3d.msh", 3)] {
        let mesh = read_fixture(name);
        for body in ["lower", "upper"] {
            let group = mesh
                .body(body)
                .unwrap()
                .boundary_group("interface")
                .unwrap();
            assert!(
                group.is_boundary(),
                "{name}, {body}: {:?}",
                group.interior_facets
            );
        }
        let union = mesh.body("union").unwrap();
        let interface = union.boundary_group("interface").unwrap();
        assert_eq!(
            interface.interior_facets.len(),
            interface.num_facets(dim),
            "{name}"
        );
        for outer in ["lower_base", "upper_top"] {
            assert!(
                union.boundary_group(outer).unwrap().is_boundary(),
                "{name}, {outer}"
            );
        }
    }
}

fn error_of(path: &std::path::Path) -> (MeshError, String) {
    let e = read_msh(path).expect_err("the file is bad");
    let message = e.to_string();
    (e, message)
}

#[test]
fn missing_file_is_an_io_error_naming_the_file() {
    let (e, message) = error_of(&fixture("no_such_mesh.msh"));
    assert!(matches!(e, MeshError::Io { .. }));
    assert!(message.contains("no_such_mesh.msh"), "{message}");
}

#[test]
fn truncated_file_names_the_line_where_it_ends() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        let cut: Vec<&str> = text.lines().take(300).collect();
        cut.join("\n") + "\n"
    });
    let (e, message) = error_of(&path);
    assert!(
        matches!(e, MeshError::Syntax { line, .. } if line > 1),
        "{message}"
    );
    assert!(message.contains("block_2d.msh:"), "{message}");
}

#[test]
fn malformed_node_line_is_a_syntax_error() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        let start = text.find("$Nodes").unwrap();
        let line_end = |from: usize| from + text[from..].find('\n').unwrap() + 1;
        // Skip the section header, the summary line and the first block header; break a coordinate.
        let mut at = line_end(line_end(line_end(start)));
        at = line_end(at); // first node tag
        let end = line_end(at);
        format!("{}0.5 abc 0\n{}", &text[..at], &text[end..])
    });
    let (e, message) = error_of(&path);
    assert!(matches!(e, MeshError::Syntax { .. }), "{message}");
}

#[test]
fn msh2_files_are_rejected_with_the_fix() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        text.replacen("4.1 0 8", "2.2 0 8", 1)
    });
    let (e, message) = error_of(&path);
    assert!(
        matches!(e, MeshError::UnsupportedVersion { .. }),
        "{message}"
    );
    assert!(
        message.contains("2.2") && message.contains("msh41"),
        "{message}"
    );
}

#[test]
fn physical_names_section_errors_name_the_line() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        text.replacen("\"block_top\"", "block_top", 1)
    });
    let (e, message) = error_of(&path);
    match e {
        MeshError::Syntax { line, .. } => assert!((3..=10).contains(&line), "{message}"),
        other => panic!("unexpected {other}"),
    }
}

/// Rewrites the type of the first element block of dimension `dim` from `from` to `to`,
/// padding each element of that block with `extra_nodes` copies of its last node.
fn retype_first_block(text: &str, dim: &str, from: &str, to: &str, extra_nodes: usize) -> String {
    let start = text.find("$Elements").unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let first = text[..start].lines().count() + 2;
    let mut i = first;
    while i < lines.len() {
        let parts: Vec<&str> = lines[i].split_whitespace().collect();
        let count: usize = parts[3].parse().unwrap();
        if parts[0] == dim && parts[2] == from {
            lines[i] = format!("{} {} {} {}", parts[0], parts[1], to, parts[3]);
            for line in &mut lines[i + 1..=i + count] {
                let last = line.split_whitespace().last().unwrap().to_string();
                for _ in 0..extra_nodes {
                    line.push(' ');
                    line.push_str(&last);
                }
            }
            break;
        }
        i += count + 1;
    }
    lines.join("\n") + "\n"
}

#[test]
fn second_order_elements_are_unsupported() {
    // A quadrangle (type 3, 4 nodes) block where the body's triangles were.
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        retype_first_block(&text, "2", "2", "3", 1)
    });
    let (e, message) = error_of(&path);
    assert!(
        matches!(e, MeshError::UnsupportedElement { .. }),
        "{message}"
    );
    assert!(
        message.contains("Qua4") && message.contains("triangles"),
        "{message}"
    );
    // The group is named as the case file names it (the error once gave its tag list, '[1]').
    assert!(message.contains("physical group 'block'"), "{message}");
}

/// Moves node `tag` of an ASCII fixture to `x`.
fn move_node(text: &str, tag: u64, x: [f64; 3]) -> String {
    let start = text.find("$Nodes").unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut i = text[..start].lines().count() + 2;
    loop {
        let parts: Vec<usize> = lines[i]
            .split_whitespace()
            .map(|p| p.parse().unwrap())
            .collect();
        let count = parts[3];
        let tags: Vec<u64> = lines[i + 1..=i + count]
            .iter()
            .map(|l| l.trim().parse().unwrap())
            .collect();
        if let Some(k) = tags.iter().position(|&t| t == tag) {
            lines[i + 1 + count + k] = format!("{} {} {}", x[0], x[1], x[2]);
            return lines.join("\n") + "\n";
        }
        i += 2 * count + 1;
    }
}

#[test]
fn degenerate_cells_are_reported_with_their_element_tag() {
    let mesh = read_fixture("block_2d.msh");
    let body = &mesh.bodies[0];
    // Put node 2 of the first cell onto the midpoint of its other two nodes.
    let cell = body.cell(0);
    let (p, q) = (body.coords[cell[0]], body.coords[cell[1]]);
    let mid = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, 0.0];
    let tag = body.node_tags.get(cell[2]);
    // Only meaningful if the node belongs to no other cell that would fold first; the error
    // must name some element either way.
    let (_dir, path) = edited_fixture("block_2d.msh", |text| move_node(&text, tag, mid));
    let (e, message) = error_of(&path);
    assert!(
        matches!(e, MeshError::DegenerateCell { element_tag, .. } if element_tag == body.cell_tags.get(0)),
        "{message}"
    );
    assert!(message.contains("body 'block'"), "{message}");
}

#[test]
fn inverted_cells_are_reported_with_their_element_tag() {
    let mesh = read_fixture("block_2d.msh");
    let body = &mesh.bodies[0];
    let cell = body.cell(0).to_vec();
    let (a, b, c) = (
        body.coords[cell[0]],
        body.coords[cell[1]],
        body.coords[cell[2]],
    );
    // Reflect node c through the line (a, b): the cell flips orientation.
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = ((c[0] - a[0]) * dx + (c[1] - a[1]) * dy) / (dx * dx + dy * dy);
    let foot = [a[0] + t * dx, a[1] + t * dy];
    let reflected = [2.0 * foot[0] - c[0], 2.0 * foot[1] - c[1], 0.0];
    let tag = body.node_tags.get(cell[2]);
    let (_dir, path) = edited_fixture("block_2d.msh", |text| move_node(&text, tag, reflected));
    let (e, message) = error_of(&path);
    assert!(
        matches!(
            e,
            MeshError::InvertedCell { .. } | MeshError::DegenerateCell { .. }
        ),
        "{message}"
    );
    if let MeshError::InvertedCell { element_tag, .. } = e {
        assert!(body.cell_tags.iter().any(|t| t == element_tag));
    }
}

#[test]
fn a_file_without_bodies_is_rejected() {
    // Drop the body's physical tag from every surface entity: no cell is in a group then.
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        common::without_physical_tags(&text, 2)
    });
    let (e, message) = error_of(&path);
    assert!(matches!(e, MeshError::NoBodies { .. }), "{message}");
}

#[test]
fn a_partitioned_mesh_is_rejected_as_such_with_the_fix() {
    // gmsh -part 2 puts the elements on partition entities: the file once read as having no
    // physical groups at all.
    let (_, message) = error_of(&fixture("block_2d_partitioned.msh"));
    assert!(
        message.contains("block_2d_partitioned.msh:25:")
            && message.contains("partitioned")
            && message.contains("without -part"),
        "{message}"
    );
}

#[test]
fn a_facet_in_two_boundary_groups_belongs_to_both() {
    // A cube whose bottom face is in two physical groups, `base` and `bottom`, and whose
    // other faces are in `sides`: each group gets its facets, the two alike, the bottom's
    // outward normal pointing down; the groups' facets are the whole boundary once.
    let dir = tempfile::tempdir().expect("temporary folder");
    let geo = dir.path().join("cube.geo");
    std::fs::write(
        &geo,
        "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\n\
         Mesh.MeshSizeMax = 0.4;\nPhysical Volume(\"cube\") = {1};\n\
         Physical Surface(\"base\") = {5};\nPhysical Surface(\"bottom\") = {5};\n\
         Physical Surface(\"sides\") = {1, 2, 3, 4, 6};\n",
    )
    .expect("writes the geo script");
    let msh = dir.path().join("cube.msh");
    internodes::mesh::mesh_geo(&geo, &msh, &[]).expect("gmsh meshes");
    let mesh = read_msh(&msh).expect("the mesh reads");
    let cube = mesh.body("cube").unwrap();
    let base = cube.boundary_group("base").unwrap();
    let bottom = cube.boundary_group("bottom").unwrap();
    let sides = cube.boundary_group("sides").unwrap();
    assert!(base.num_facets(3) > 0);
    assert_eq!(base.facets, bottom.facets);
    assert_eq!(base.facet_cells, bottom.facet_cells);
    for facet in base.facets.chunks_exact(3) {
        let points: Vec<[f64; 3]> = facet.iter().map(|&n| cube.coords[n]).collect();
        let (area, normal) = facet_measure_and_normal(&points, 3);
        assert!(area > 0.0);
        assert!((normal[2] + 1.0).abs() < 1e-12, "{normal:?}");
    }
    // Every face of a cell that no other cell shares is in `base` or `sides`, once.
    let mut faces = std::collections::HashMap::<[usize; 3], usize>::new();
    for c in 0..cube.num_cells() {
        let cell = cube.cell(c);
        for opposite in 0..4 {
            let mut face: Vec<usize> = (0..4).filter(|&k| k != opposite).map(|k| cell[k]).collect();
            face.sort_unstable();
            *faces.entry([face[0], face[1], face[2]]).or_default() += 1;
        }
    }
    let mut grouped: Vec<[usize; 3]> = (base.facets.chunks_exact(3))
        .chain(sides.facets.chunks_exact(3))
        .map(|f| {
            let mut f = [f[0], f[1], f[2]];
            f.sort_unstable();
            f
        })
        .collect();
    grouped.sort_unstable();
    let mut boundary: Vec<[usize; 3]> = (faces.into_iter())
        .filter(|&(_, n)| n == 1)
        .map(|(f, _)| f)
        .collect();
    boundary.sort_unstable();
    assert_eq!(grouped, boundary);
}
