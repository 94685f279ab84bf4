//! Hostile but fair meshes, found by review and by fuzzing (`fuzz/README.md`): node tags in any
//! order, corrupt or truncated sections, 2D bodies off the xy plane, ambiguous groups. Each case
//! once gave a misread mesh, a panic or a vague message; each test names what must happen
//! instead.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::case_builder::{Body, CaseFile, Dirichlet};
use common::hostile::{case_failure, displacement_by_tag, run_quiet, square_case};
use common::{edited_fixture, fixture, read_fixture};
use internodes::mesh::{Mesh, MeshError, MeshSummary, read_msh, read_msh_bytes};

/// The coordinates of every node of every body, by gmsh node tag.
fn coords_by_tag(mesh: &Mesh) -> HashMap<u64, [f64; 3]> {
    mesh.bodies
        .iter()
        .flat_map(|b| {
            b.node_tags
                .iter()
                .zip(b.coords.as_whole().unwrap().iter().copied())
        })
        .collect()
}

/// Every cell of every body as its gmsh node tags, by gmsh element tag.
fn cells_by_tag(mesh: &Mesh) -> HashMap<u64, Vec<u64>> {
    mesh.bodies
        .iter()
        .flat_map(|b| {
            (0..b.num_cells()).map(move |c| {
                (
                    b.cell_tags.get(c),
                    b.cell(c).iter().map(|&n| b.node_tags.get(n)).collect(),
                )
            })
        })
        .collect()
}

/// Rewrites every coordinate line of the `$Nodes` section of an ASCII MSH 4.1 text with
/// `edit(tag, [x, y, z])`.
fn edit_nodes(text: &str, edit: impl Fn(u64, [f64; 3]) -> String) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let start = lines.iter().position(|l| l == "$Nodes").unwrap();
    let num_blocks: usize = lines[start + 1]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let mut i = start + 2;
    for _ in 0..num_blocks {
        let count: usize = lines[i].split_whitespace().nth(3).unwrap().parse().unwrap();
        for k in 0..count {
            let tag: u64 = lines[i + 1 + k].trim().parse().unwrap();
            let line = &mut lines[i + 1 + count + k];
            let x: Vec<f64> = line
                .split_whitespace()
                .map(|v| v.parse().unwrap())
                .collect();
            *line = edit(tag, [x[0], x[1], x[2]]);
        }
        i += 1 + 2 * count;
    }
    lines.join("\n") + "\n"
}

/// The error of a mesh file that must be rejected, and its message.
fn mesh_error(path: &Path) -> (MeshError, String) {
    let e = read_msh(path).expect_err("the mesh must be rejected");
    let message = e.to_string();
    (e, message)
}

/// A unit square whose four nodes are written in the order 3, 4, 1, 2
/// (a dense tag range, so the old reader numbered them 1, 2, 3, 4 by position).
const SQUARE_3412: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
1 1 "left"
1 2 "right"
2 3 "square"
$EndPhysicalNames
$Entities
0 2 1 0
1 0 0 0 0 1 0 1 1 0
2 1 0 0 1 1 0 1 2 0
1 0 0 0 1 1 0 1 3 0
$EndEntities
$Nodes
1 4 1 4
2 1 0 4
3
4
1
2
1 1 0
0 1 0
0 0 0
1 0 0
$EndNodes
$Elements
3 4 1 4
1 1 1 1
1 4 1
1 2 1 1
2 2 3
2 1 2 2
3 1 2 3
4 1 3 4
$EndElements
"#;

/// A small deterministic generator (xorshift), so that the corruptions below are reproducible.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

/// A case on `unnamed_groups_2d.msh`: the body '1' clamped on `clamped`, pulled down by its
/// weight.
fn unnamed_groups_case(clamped: &str) -> CaseFile {
    CaseFile::on_fixture("unnamed_groups_2d.msh").body(
        Body::new("1", 1000.0, 0.3)
            .body_force(&[0.0, -1.0])
            .dirichlet(Dirichlet::clamped(clamped, 2)),
    )
}

#[test]
fn shuffled_node_tags_give_the_same_mesh_as_sorted_ones() {
    // Written by gmsh's Python API (tests/fixtures/shuffled_tags.py): the same nodes and
    // elements, added in increasing tag order or in a shuffled one.
    for (sorted, shuffled) in [
        ("square_sorted.msh", "square_shuffled.msh"),
        ("square_sorted.msh", "square_shuffled_bin.msh"),
        ("cube_sorted.msh", "cube_shuffled.msh"),
    ] {
        let a = read_fixture(sorted);
        let b = read_fixture(shuffled);
        assert_eq!(coords_by_tag(&a), coords_by_tag(&b), "{shuffled}");
        assert_eq!(cells_by_tag(&a), cells_by_tag(&b), "{shuffled}");
    }
}

#[test]
fn the_square_written_in_the_order_3_4_1_2_is_read_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("square_3412.msh");
    std::fs::write(&path, SQUARE_3412).unwrap();
    let mesh = read_msh(&path).unwrap();
    let expected: HashMap<u64, [f64; 3]> = [
        (1, [0.0, 0.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
        (3, [1.0, 1.0, 0.0]),
        (4, [0.0, 1.0, 0.0]),
    ]
    .into_iter()
    .collect();
    assert_eq!(coords_by_tag(&mesh), expected);
    // The clamped edge is x = 0, the loaded one x = 1 (not swapped by a 180 degree rotation).
    let body = &mesh.bodies[0];
    for (group, x) in [("left", 0.0), ("right", 1.0)] {
        for n in body.group_nodes(group).unwrap() {
            assert_eq!(body.coords[n][0], x, "{group}");
        }
    }
}

#[test]
fn a_solve_on_shuffled_node_tags_equals_the_solve_on_sorted_ones() {
    let solve = |mesh: &str| {
        let (dir, path) = square_case(mesh, &[1.0, 0.5]).write();
        run_quiet(&path).unwrap_or_else(|e| panic!("{mesh}: {e}"));
        displacement_by_tag(&dir.path().join("out"))
    };
    let sorted = solve("square_sorted.msh");
    for shuffled in ["square_shuffled.msh", "square_shuffled_bin.msh"] {
        let other = solve(shuffled);
        assert_eq!(sorted.len(), other.len());
        for (tag, u) in &sorted {
            let v = &other[tag];
            for k in 0..2 {
                // The same equations in another order: equal to round-off.
                assert!(
                    (u[k] - v[k]).abs() <= 1e-12,
                    "{shuffled} node {tag}: {u:?} {v:?}"
                );
            }
        }
    }
}

#[test]
fn a_node_tag_defined_twice_is_an_error_naming_the_tag_and_lines() {
    // Tag 2 replaces tag 1 in the node list of SQUARE_3412: tag 2 twice, tag 1 missing.
    let text = SQUARE_3412.replacen("4\n1\n2\n", "4\n2\n2\n", 1);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("twice.msh");
    std::fs::write(&path, text).unwrap();
    let (e, message) = mesh_error(&path);
    assert!(matches!(e, MeshError::Syntax { line: 22, .. }), "{message}");
    assert!(
        message.contains("node tag 2 is defined twice") && message.contains("first on line 21"),
        "{message}"
    );
}

#[test]
fn an_entity_defined_twice_is_an_error() {
    // The right edge's entity line with the left edge's tag: its physical tag would replace
    // the left edge's.
    let text = SQUARE_3412.replacen("2 1 0 0 1 1 0 1 2 0", "1 1 0 0 1 1 0 1 2 0", 1);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("entity.msh");
    std::fs::write(&path, text).unwrap();
    let (e, message) = mesh_error(&path);
    assert!(matches!(e, MeshError::Syntax { line: 13, .. }), "{message}");
    assert!(message.contains("defined twice in $Entities"), "{message}");
}

#[test]
fn a_physical_names_count_near_2_to_the_64_is_an_error() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        text.replacen(
            "$PhysicalNames\n4\n",
            "$PhysicalNames\n18446744073709551615\n",
            1,
        )
    });
    let (e, message) = mesh_error(&path);
    assert!(matches!(e, MeshError::Syntax { line: 5, .. }), "{message}");
    assert!(message.contains("18446744073709551615"), "{message}");
}

#[test]
fn binary_data_sizes_other_than_8_are_errors() {
    let binary = std::fs::read(fixture("block_2d_bin.msh")).unwrap();
    for size in ["4", "2147483648", "99999999999999999999"] {
        let bytes = [
            b"$MeshFormat\n4.1 1 ".as_slice(),
            size.as_bytes(),
            &binary[b"$MeshFormat\n4.1 1 8".len()..],
        ]
        .concat();
        let e = read_msh_bytes(Path::new("size.msh"), &bytes).expect_err(size);
        let message = e.to_string();
        assert!(matches!(e, MeshError::Syntax { line: 2, .. }), "{message}");
        assert!(message.contains("only 8"), "{message}");
    }
}

#[test]
fn a_nodes_section_announcing_zero_nodes_is_an_error_not_an_overflow() {
    // numNodes = 0 with tags 1..1: mshio computed numNodes - 1 and overflowed (a panic in debug
    // builds). The elements then refer to nodes the file does not define.
    let (_dir, path) = edited_fixture("square_sorted.msh", |text| {
        let start = text.find("$Nodes").unwrap();
        let end = text.find("$EndNodes").unwrap();
        format!(
            "{}$Nodes\n1 0 1 1\n2 1 0 0\n{}",
            &text[..start],
            &text[end..]
        )
    });
    let (e, message) = mesh_error(&path);
    assert!(matches!(e, MeshError::UndefinedNode { .. }), "{message}");
}

#[test]
fn node_and_element_counts_beyond_the_file_are_errors() {
    for (from, to) in [
        (
            "$Nodes\n11 490 1 490\n",
            "$Nodes\n11 18446744073709551615 1 490\n",
        ),
        (
            "$Nodes\n11 490 1 490\n",
            "$Nodes\n4611686018427387904 490 1 490\n",
        ),
        ("$Elements\n", "$Elements\n9223372036854775807 "),
    ] {
        let (_dir, path) = edited_fixture("block_2d.msh", |text| {
            assert!(text.contains(from), "{from}");
            text.replacen(from, to, 1)
        });
        let (e, message) = mesh_error(&path);
        assert!(matches!(e, MeshError::Syntax { .. }), "{message}");
    }
}

#[test]
fn truncated_and_bit_flipped_meshes_give_errors_or_meshes_never_panics() {
    // The fuzz target's property on a few thousand reproducible inputs, in every `cargo test`.
    let mut state = 0x9e37_79b9_7f4a_7c15;
    for name in [
        "block_2d_bin.msh",
        "square_shuffled.msh",
        "square_shuffled_bin.msh",
    ] {
        let bytes = std::fs::read(fixture(name)).unwrap();
        for cut in (0..bytes.len()).step_by(bytes.len() / 200 + 1) {
            let _ = read_msh_bytes(Path::new(name), &bytes[..cut]);
        }
        // Every single-bit flip of the header (the data size of '4.1 1 8' among them).
        for at in 0..64 {
            for bit in 0..8 {
                let mut flipped = bytes.clone();
                flipped[at] ^= 1 << bit;
                let _ = read_msh_bytes(Path::new(name), &flipped);
            }
        }
        for _ in 0..1000 {
            let mut flipped = bytes.clone();
            for _ in 0..1 + xorshift(&mut state) % 4 {
                let at = (xorshift(&mut state) % bytes.len() as u64) as usize;
                flipped[at] ^= 1 << (xorshift(&mut state) % 8);
            }
            if let Err(e) = read_msh_bytes(Path::new(name), &flipped) {
                assert!(e.to_string().contains(name));
            }
        }
    }
}

#[test]
fn an_ascii_mesh_cut_inside_an_element_line_is_reported_truncated_not_duplicate() {
    // Cut in the middle of the tag of an element line near the end: '976 80 471 472' becomes
    // '97', a tag defined earlier, and the file was reported as defining it twice.
    let text = std::fs::read_to_string(fixture("block_2d.msh")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().position(|l| *l == "$EndElements").unwrap() - 2;
    let tag = lines[at].split_whitespace().next().unwrap();
    assert!(tag.len() >= 3, "{}", lines[at]);
    let kept: usize = lines[..at].iter().map(|l| l.len() + 1).sum();
    for cut in [&tag[..2], &format!("{} ", &tag[..2]), tag] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("block_2d.msh");
        std::fs::write(&path, format!("{}{cut}", &text[..kept])).unwrap();
        let (e, message) = mesh_error(&path);
        assert!(
            matches!(e, MeshError::Syntax { line, .. } if line == at + 1),
            "'{cut}': {message}"
        );
        assert!(
            message.contains(&format!("block_2d.msh:{}", at + 1))
                && message.contains("the file ends")
                && message.contains("truncated")
                && !message.contains("twice"),
            "'{cut}': {message}"
        );
    }
}

#[test]
fn a_nan_node_coordinate_is_an_error_naming_the_node_and_line() {
    let (_dir, path) = edited_fixture("square_sorted.msh", |text| {
        edit_nodes(&text, |tag, x| {
            if tag == 13 {
                format!("{} nan 0", x[0])
            } else {
                format!("{} {} {}", x[0], x[1], x[2])
            }
        })
    });
    let text = std::fs::read_to_string(&path).unwrap();
    let line = 1 + text.lines().position(|l| l.contains("nan")).unwrap();
    let (e, message) = mesh_error(&path);
    assert!(
        matches!(e, MeshError::Syntax { line: l, .. } if l == line),
        "{message}"
    );
    assert!(
        message.contains("node 13") && message.contains("non-finite"),
        "{message}"
    );
}

#[test]
fn a_bad_section_header_names_its_own_line() {
    // The $Nodes summary line of block_2d.msh with a letter in its node count.
    let text = std::fs::read_to_string(fixture("block_2d.msh")).unwrap();
    let line = 2 + text.lines().position(|l| l == "$Nodes").unwrap();
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        text.replacen("$Nodes\n11 490 1 490\n", "$Nodes\n11 4x0 1 490\n", 1)
    });
    let (e, message) = mesh_error(&path);
    assert!(
        matches!(e, MeshError::Syntax { line: l, .. } if l == line),
        "{message}"
    );
    assert!(
        message.contains("the number of nodes") && message.contains("4x0"),
        "{message}"
    );
}

#[test]
fn a_2d_mesh_whose_z_varies_is_rejected() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        edit_nodes(&text, |tag, x| {
            format!("{} {} {}", x[0], x[1], if tag == 7 { 0.1 } else { 0.0 })
        })
    });
    let (_, message) = mesh_error(&path);
    assert!(
        message.contains("xy plane") && message.contains("'block'"),
        "{message}"
    );
}

#[test]
fn a_2d_mesh_in_the_xz_plane_is_rejected_as_such() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        edit_nodes(&text, |_, x| format!("{} {} {}", x[0], x[2], x[1]))
    });
    let (_, message) = mesh_error(&path);
    assert!(message.contains("xy plane"), "not 'degenerate': {message}");
}

#[test]
fn two_2d_bodies_on_different_planes_are_rejected() {
    let upper = read_fixture("two_blocks_2d.msh")
        .body("upper")
        .unwrap()
        .node_tags
        .clone();
    let (_dir, path) = edited_fixture("two_blocks_2d.msh", |text| {
        edit_nodes(&text, |tag, x| {
            let z = if upper.position(tag).is_some() {
                1.0
            } else {
                0.0
            };
            format!("{} {} {z}", x[0], x[1])
        })
    });
    let (_, message) = mesh_error(&path);
    assert!(
        message.contains("xy plane") && message.contains("'upper' z in [1e0, 1e0]"),
        "{message}"
    );
}

#[test]
fn a_3d_geometry_without_a_physical_volume_is_rejected_as_such() {
    // Drop the volume's physical tag: only the boundary triangles remain in groups.
    let (_dir, path) = edited_fixture("block_3d.msh", |text| {
        common::without_physical_tags(&text, 3)
    });
    let (_, message) = mesh_error(&path);
    assert!(message.contains("no physical volume"), "{message}");
}

#[test]
fn two_physical_groups_with_one_name_are_rejected() {
    let (_dir, path) = edited_fixture("block_2d.msh", |text| {
        text.replacen("\"block_sides\"", "\"block_top\"", 1)
    });
    let (e, message) = mesh_error(&path);
    assert!(matches!(e, MeshError::Syntax { .. }), "{message}");
    assert!(
        message.contains("'block_top' is given to two groups"),
        "{message}"
    );
}

#[test]
fn a_name_shared_by_unnamed_groups_of_two_dimensions_is_an_ambiguous_reference() {
    // Physical Curve(1) and Physical Point(1) have no names: both go by '1'.
    let message = case_failure(&unnamed_groups_case("1"));
    assert!(
        message.contains("group '1'")
            && message.contains("ambiguous")
            && message.contains("dimension 0 tag 1 (unnamed)")
            && message.contains("dimension 1 tag 1 (unnamed)")
            && message.contains("unnamed_groups_2d.msh"),
        "{message}"
    );
    // 'info' says so where it lists the groups.
    let info = MeshSummary(&read_fixture("unnamed_groups_2d.msh")).to_string();
    assert!(
        info.contains("dim 0  tag    1  1  (no name: goes by its tag)  (ambiguous in a case file: also dim 1 tag 1)"),
        "{info}"
    );

    // The unnamed curve 2 is the only group called '2': the weight of the unit square hangs on
    // it, to round-off.
    let (_dir, path) = unnamed_groups_case("2").write();
    let report = run_quiet(&path).unwrap();
    let reaction = report.summary.bodies[0].reactions["2"][1];
    assert!((reaction - 1.0).abs() < 1e-10, "{reaction}");
}
