//! Hostile but fair input, found by review and by fuzzing (`fuzz/README.md`): every case here
//! once gave a misread mesh, a panic, a stale result or a vague message. Each test names what
//! must happen instead; future fixes of bad-input handling add their case here.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{edited_fixture, fixture, read_fixture, write_case};
use internodes::mesh::{Mesh, MeshError, MeshSummary, read_msh, read_msh_bytes};
use internodes::run::{RunError, RunOptions, solve_case};

const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// The coordinates of every node of every body, by gmsh node tag.
fn coords_by_tag(mesh: &Mesh) -> HashMap<u64, [f64; 3]> {
    mesh.bodies
        .iter()
        .flat_map(|b| b.node_tags.iter().copied().zip(b.coords.iter().copied()))
        .collect()
}

/// Every cell of every body as its gmsh node tags, by gmsh element tag.
fn cells_by_tag(mesh: &Mesh) -> HashMap<u64, Vec<u64>> {
    mesh.bodies
        .iter()
        .flat_map(|b| {
            (0..b.num_cells()).map(move |c| {
                (
                    b.cell_tags[c],
                    b.cell(c).iter().map(|&n| b.node_tags[n]).collect(),
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

fn run_quiet(case: &Path) -> Result<internodes::run::RunReport, RunError> {
    solve_case(
        case,
        &RunOptions {
            quiet: true,
            ..Default::default()
        },
    )
}

/// The error of a case file that must fail; `why` says why it must.
fn run_error(case: &Path, why: &str) -> RunError {
    match run_quiet(case) {
        Ok(_) => panic!("{} should fail: {why}", case.display()),
        Err(e) => e,
    }
}

/// The message of a case that must fail.
fn case_failure(text: &str) -> String {
    let (_dir, path) = write_case(text);
    match run_quiet(&path) {
        Ok(_) => panic!("the case should fail:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The two bodies of `two_blocks_2d.msh` (or an edit of it at `mesh`), each supported on its own.
fn two_blocks_case(mesh: &Path, upper: &str, extra: &str) -> String {
    format!(
        r#"mesh = "{}"
output = "out"
{extra}

[[body]]
name = "lower"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "lower_base"
ux = 0.0
uy = 0.0
[[body.load]]
group = "lower_contact"
traction = [0.0, -1.0]

[[body]]
name = "{upper}"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "upper_top"
ux = 0.0
uy = 0.0
"#,
        mesh.display()
    )
}

/// The unit square of `square_*.msh`: clamped on `left`, pulled by `traction` on `right`.
fn square_case(mesh: &str, traction: &str) -> String {
    format!(
        r#"mesh = "{}"
output = "out"

[[body]]
name = "square"
youngs_modulus = 100.0
poisson_ratio = 0.25
[[body.dirichlet]]
group = "left"
ux = 0.0
uy = 0.0
[[body.load]]
group = "right"
traction = {traction}
"#,
        fixture(mesh).display()
    )
}

/// Displacement of every node of `solution.h5` in `dir`, by gmsh node tag. Opened without HDF5's
/// file lock: the concurrent-runs test runs its solves as threads of this process, which share one
/// HDF5 library, and opening a file that a just-finished run of this process wrote failed once in
/// nine runs on the lock (EAGAIN); separate `internodes` processes do not meet this.
fn displacement_by_tag(dir: &Path) -> HashMap<i64, Vec<f64>> {
    let file = hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(dir.join("solution.h5"))
        .unwrap();
    let tags: Vec<i64> = file.dataset("mesh/node_tag").unwrap().read_raw().unwrap();
    let u: Vec<f64> = file
        .dataset("fields/displacement")
        .unwrap()
        .read_raw()
        .unwrap();
    let width = u.len() / tags.len();
    tags.into_iter()
        .zip(u.chunks(width).map(<[f64]>::to_vec))
        .collect()
}

fn exists(dir: &Path, name: &str) -> bool {
    dir.join(name).exists()
}

// ---------------------------------------------------------------------------------------------
// 1. Node tags are read as written
// ---------------------------------------------------------------------------------------------

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
        let (dir, path) = write_case(&square_case(mesh, "[1.0, 0.5]"));
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

// ---------------------------------------------------------------------------------------------
// 2. Corrupt headers are errors, not panics
// ---------------------------------------------------------------------------------------------

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

/// A small deterministic generator (xorshift), so that the corruptions below are reproducible.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
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
fn info_into_a_closed_pipe_does_not_panic() {
    // `internodes info m.msh | head -1`: the reader stops early.
    let mut child = Command::new(BINARY)
        .args(["info", fixture("two_blocks_3d.msh").to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn solve_into_a_closed_stderr_pipe_does_not_panic() {
    // `internodes solve case 2>&1 | head -1`: the progress lines meet a closed pipe. A panic
    // exits with status 101; the process must end by SIGPIPE (or finish) instead.
    let (_dir, case) =
        common::write_case(&common::half_disc_on_block("half_disc_on_block.msh", ""));
    let mut child = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let status = child.wait().unwrap();
    assert_ne!(status.code(), Some(101), "{status:?}");
}

#[test]
fn exporting_matrices_with_a_dirichlet_point_group_does_not_panic() {
    let text = two_blocks_case(
        &fixture("two_blocks_2d.msh"),
        "upper",
        "export_matrices = true",
    )
    .replacen(
        "group = \"upper_top\"\nux = 0.0\nuy = 0.0",
        "group = \"upper_top\"\nuy = 0.0\n[[body.dirichlet]]\ngroup = \"upper_corner\"\nux = 0.0",
        1,
    );
    let (dir, path) = write_case(&text);
    run_quiet(&path).unwrap();
    let matrices = dir.path().join("out/matrices");
    assert!(matrices.join("upper__upper_top_mass.mtx").exists());
    assert!(!matrices.join("upper__upper_corner_mass.mtx").exists());
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

// ---------------------------------------------------------------------------------------------
// 3. The output folder holds one run's complete results, or a failure mark
// ---------------------------------------------------------------------------------------------

/// Asserts that `out` holds no result file and a failure mark naming `what`.
fn assert_failed_without_results(out: &Path, what: &str) {
    for name in internodes::output::RESULT_FILES {
        assert!(!exists(out, name), "{name} left in {}", out.display());
    }
    let mark = std::fs::read_to_string(out.join("FAILED.txt")).expect("FAILED.txt");
    assert!(mark.contains(what), "{mark}");
    let leftovers: Vec<_> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".internodes"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn a_failed_run_removes_earlier_results_and_marks_the_folder() {
    let (dir, good) = write_case(&two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", ""));
    let out = dir.path().join("out");
    run_quiet(&good).unwrap();
    assert!(exists(&out, "solution.h5") && exists(&out, "summary.json"));

    // The same case, now failing in the solve of its second body.
    let bad = dir.path().join("bad.toml");
    let text = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", "").replace(
        "[[body]]\nname = \"lower\"",
        "[solver]\nresidual_tolerance = 1e-300\n\n[[body]]\nname = \"lower\"",
    );
    std::fs::write(&bad, text).unwrap();
    let e = run_error(&bad, "the tolerance cannot be met");
    assert_failed_without_results(&out, &e.to_string());

    // The next successful run removes the mark.
    run_quiet(&good).unwrap();
    assert!(exists(&out, "summary.json") && !exists(&out, "FAILED.txt"));
}

#[test]
fn runs_remove_only_their_own_files_from_the_output_folder() {
    // An output folder the user keeps other files in, also inside matrices/.
    let (dir, good) = write_case(&two_blocks_case(
        &fixture("two_blocks_2d.msh"),
        "upper",
        "export_matrices = true",
    ));
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("matrices")).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("matrices/notes.txt"), "mine").unwrap();
    run_quiet(&good).unwrap();
    assert!(exists(&out, "matrices/lower_stiffness.mtx"));
    let text = std::fs::read_to_string(&good).unwrap();
    std::fs::write(
        &good,
        text.replace("name = \"upper\"", "name = \"nowhere\""),
    )
    .unwrap();
    run_error(&good, "no body 'nowhere'");
    assert!(!exists(&out, "matrices/lower_stiffness.mtx"));
    assert!(exists(&out, "notes.txt") && exists(&out, "matrices/notes.txt"));
}

#[test]
fn a_case_file_that_does_not_parse_marks_the_folder_it_names() {
    let (dir, good) = write_case(&two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", ""));
    run_quiet(&good).unwrap();
    let text = std::fs::read_to_string(&good).unwrap();
    std::fs::write(&good, text.replace("poisson_ratio", "poison_ratio")).unwrap();
    let e = run_error(&good, "misspelled key");
    assert_failed_without_results(&dir.path().join("out"), "poison_ratio");
    assert!(e.to_string().contains("poison_ratio"));
}

#[test]
fn a_run_failing_after_writing_the_solution_leaves_no_result() {
    // The first run succeeds; the second writes solution.h5 and then fails exporting the
    // matrices of a body whose name is too long for a file name (250 bytes and
    // `_stiffness.mtx` exceed the 255 of Linux file systems).
    let (dir, good) = write_case(&two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", ""));
    run_quiet(&good).unwrap();
    let long = "u".repeat(250);
    let mesh = dir.path().join("long.msh");
    let text = std::fs::read_to_string(fixture("two_blocks_2d.msh")).unwrap();
    std::fs::write(&mesh, text.replacen("\"upper\"", &format!("\"{long}\""), 1)).unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        two_blocks_case(&mesh, &long, "export_matrices = true"),
    )
    .unwrap();
    let e = run_error(&bad, "the file name is too long");
    assert!(e.to_string().contains("_stiffness.mtx"), "{e}");
    assert_failed_without_results(&dir.path().join("out"), &e.to_string());
}

#[test]
fn a_contact_case_with_a_bad_extra_body_fails_before_solving() {
    // The contact bodies are fine, a third [[body]] is not in the mesh: nothing may be solved
    // or written (the old run solved the contact and left force_displacement.csv).
    let text = common::half_disc_on_block("half_disc_on_block.msh", "")
        + "\n[[body]]\nname = \"third\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n";
    let (dir, path) = write_case(&text);
    let e = run_error(&path, "no body 'third'");
    assert!(e.to_string().contains("'third'"), "{e}");
    assert_failed_without_results(&dir.path().join("out"), "'third'");
}

#[test]
fn concurrent_runs_into_one_folder_leave_one_runs_complete_results() {
    // Two cases that differ in Young's modulus, run together into one folder, ten times.
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = ["100.0", "400.0"]
        .iter()
        .map(|e| {
            let path = dir.path().join(format!("e{e}.toml"));
            let text = square_case("square_sorted.msh", "[1.0, 0.0]")
                .replace("youngs_modulus = 100.0", &format!("youngs_modulus = {e}"))
                .replace("output = \"out\"", "output = \"shared\"");
            std::fs::write(&path, text).unwrap();
            path
        })
        .collect();
    let out = dir.path().join("shared");
    for _ in 0..10 {
        std::thread::scope(|s| {
            for case in &cases {
                s.spawn(move || run_quiet(case).unwrap());
            }
        });
        // The displacement scales with 1 / E: the HDF5 file and the summary are one run's.
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let e = summary["bodies"][0]["youngs_modulus"].as_f64().unwrap();
        let u = displacement_by_tag(&out);
        let largest = u.values().map(|v| v[0].abs()).fold(0.0, f64::max);
        // E = 100 gives a largest ux of about 1e-2, E = 400 a quarter of it.
        assert!(
            (largest * e - 1.0).abs() < 0.5,
            "E = {e}, largest ux {largest}"
        );
        assert!(!exists(&out, "FAILED.txt"));
    }
}

/// A folder holding `two_blocks_2d.msh` as `mesh` and the case `case` reading it, with the output
/// folder set to the folder itself (`output = "."`).
fn case_beside_its_outputs(mesh: &str, case: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = dir.path().join(mesh);
    std::fs::copy(fixture("two_blocks_2d.msh"), &mesh_path).unwrap();
    let text =
        two_blocks_case(Path::new(mesh), "upper", "").replace("output = \"out\"", "output = \".\"");
    let case_path = dir.path().join(case);
    std::fs::write(&case_path, text).unwrap();
    (dir, mesh_path, case_path)
}

#[test]
fn an_input_mesh_named_mesh_msh_in_the_output_folder_is_never_removed() {
    let original = std::fs::read(fixture("two_blocks_2d.msh")).unwrap();
    let (dir, mesh, case) = case_beside_its_outputs("mesh.msh", "case.toml");
    run_quiet(&case).unwrap();
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "the input mesh was changed"
    );
    assert!(exists(dir.path(), "summary.json"));

    // --output naming the mesh's folder, and a second run over the first one's results.
    solve_case(
        &case,
        &RunOptions {
            output: Some(dir.path().to_owned()),
            quiet: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "--output removed the input mesh"
    );

    // A case file that does not parse marks the folder, and the mesh stays.
    let text = std::fs::read_to_string(&case).unwrap();
    std::fs::write(&case, text.replace("youngs_modulus", "young_modulus")).unwrap();
    run_error(&case, "misspelled key");
    assert_failed_without_results(dir.path(), "young_modulus");
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "a failed run removed the input mesh"
    );
}

#[test]
fn an_output_folder_holding_an_input_under_a_result_name_is_refused() {
    // The mesh saved as summary.json beside the case, output = ".": the run would replace it.
    let original = std::fs::read(fixture("two_blocks_2d.msh")).unwrap();
    let (dir, mesh, case) = case_beside_its_outputs("summary.json", "case.toml");
    let message = run_error(&case, "the mesh has a result's name").to_string();
    assert!(
        message.contains("summary.json")
            && message.contains("`output` key")
            && message.contains("case.toml"),
        "{message}"
    );
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "the input mesh was changed"
    );
    assert!(!exists(dir.path(), "FAILED.txt") && !exists(dir.path(), "solution.h5"));

    // --output is named as such.
    let with_option = solve_case(
        &case,
        &RunOptions {
            output: Some(dir.path().to_owned()),
            quiet: true,
            ..Default::default()
        },
    );
    let Err(e) = with_option.map(|_| ()) else {
        panic!("--output holds the mesh under a result name");
    };
    let e = e.to_string();
    assert!(e.contains("--output") && e.contains("summary.json"), "{e}");

    // A case file named like the failure mark, that does not parse, is not overwritten by it.
    let (dir, _, case) = case_beside_its_outputs("lower.msh", "FAILED.txt");
    let broken = std::fs::read_to_string(&case)
        .unwrap()
        .replace("youngs_modulus", "young_modulus");
    std::fs::write(&case, &broken).unwrap();
    run_error(&case, "misspelled key");
    assert_eq!(
        std::fs::read_to_string(&case).unwrap(),
        broken,
        "the case file was overwritten"
    );
    assert!(exists(dir.path(), "lower.msh"));
}

/// Runs `internodes solve CASE --quiet` as a child process and kills it if it has not ended
/// within `limit` (`None` then): a run that waits forever fails the test instead of hanging it.
fn solve_within(case: &Path, limit: std::time::Duration) -> Option<std::process::Output> {
    let mut child = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap(), "--quiet"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Some(child.wait_with_output().unwrap())
}

#[test]
fn a_folder_named_as_the_commit_lock_is_an_error_naming_it() {
    // The run used to wait for it forever without a word.
    let (dir, case) = write_case(&two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", ""));
    let lock = dir.path().join("out/.internodes-commit.lock");
    std::fs::create_dir_all(&lock).unwrap();
    let output = solve_within(&case, std::time::Duration::from_secs(20))
        .expect("the run must end at once, not wait for a folder to go away");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!("the commit lock {} is a folder", lock.display()))
            && stderr.contains("rm -r"),
        "{stderr}"
    );
    assert!(lock.is_dir(), "the user's folder stays");
}

#[test]
fn a_commit_lock_dated_in_the_future_is_not_fresh_forever() {
    // A lock file left with a modification time a year ahead (a clock set back, a folder copied
    // from another machine) used to make every run wait for it forever.
    let (dir, case) = write_case(&two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", ""));
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let lock = out.join(".internodes-commit.lock");
    let file = std::fs::File::create(&lock).unwrap();
    let year = std::time::Duration::from_secs(365 * 86_400);
    file.set_modified(std::time::SystemTime::now() + year)
        .unwrap();
    drop(file);
    let output = solve_within(&case, std::time::Duration::from_secs(20))
        .expect("the run must not wait for a lock dated in the future");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(exists(&out, "summary.json") && !lock.exists());
}

#[test]
fn bodies_pulled_apart_leave_no_null_in_the_iteration_history() {
    // The upper block is lifted off the lower one: the first iteration finds every active node
    // in tension and none compressed, and its tension over the largest pressure was
    // p / f64::MIN_POSITIVE = inf, written as `null` into summary.json.
    let contact = "[contact]\nbodies = [\"upper\", \"lower\"]\nsurfaces = [\"upper_contact\", \"lower_contact\"]\n";
    let text = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", contact).replace(
        "group = \"upper_top\"\nux = 0.0\nuy = 0.0",
        "group = \"upper_top\"\nux = 0.0\nuy = 0.01",
    );
    assert!(text.contains("uy = 0.01"), "{text}");
    let (dir, case) = write_case(&text);
    run_quiet(&case).unwrap();
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap(),
    )
    .unwrap();
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "no-contact");
    let iterations = contact["iterations"].as_array().unwrap();
    assert!(!iterations.is_empty());
    // The first iteration starts with every facing node active (all of them then in tension).
    assert!(
        iterations[0]["removed"].as_u64().unwrap() > 0,
        "{iterations:?}"
    );
    for record in iterations {
        for (key, value) in record.as_object().unwrap() {
            assert!(!value.is_null(), "{key} is null in {record}");
        }
        let tension = record["max_tension_over_p"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&tension), "{record}");
    }
}

// ---------------------------------------------------------------------------------------------
// 4. 2D bodies must lie in the xy plane
// ---------------------------------------------------------------------------------------------

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
            let z = if upper.binary_search(&tag).is_ok() {
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

// ---------------------------------------------------------------------------------------------
// 5. Case files that are wrong but were accepted
// ---------------------------------------------------------------------------------------------

#[test]
fn a_body_in_two_body_tables_is_an_error() {
    let text = two_blocks_case(&fixture("two_blocks_2d.msh"), "lower", "");
    let message = case_failure(&text);
    assert!(
        message.contains("body 'lower' has two [[body]] tables"),
        "{message}"
    );
}

/// A case on `geo/block_2d.geo` with `parameters` as its `geo_parameters`.
fn geo_case(geo: &str, parameters: &str) -> String {
    let geo = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("geo")
        .join(geo);
    format!(
        r#"mesh = "{}"
geo_parameters = {parameters}
output = "out"

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "block_base"
ux = 0.0
uy = 0.0
"#,
        geo.display()
    )
}

#[test]
fn geo_parameters_the_script_does_not_use_are_errors() {
    let message = case_failure(&geo_case("block_2d.geo", "{ levle = 1 }"));
    assert!(
        message.contains("geo_parameters.levle") && message.contains("level"),
        "{message}"
    );
}

#[test]
fn non_finite_geo_parameters_are_errors() {
    let message = case_failure(&geo_case("block_2d.geo", "{ level = nan }"));
    assert!(
        message.contains("geo_parameters.level") && message.contains("finite"),
        "{message}"
    );
}

#[test]
fn geo_parameters_beside_a_msh_are_errors() {
    let text = square_case("square_sorted.msh", "[1.0, 0.0]").replace(
        "output = \"out\"",
        "output = \"out\"\ngeo_parameters = { level = 1 }",
    );
    let message = case_failure(&text);
    assert!(
        message.contains("geo_parameters") && message.contains("not a .geo"),
        "{message}"
    );
}

#[test]
fn load_steps_beyond_the_bound_are_errors() {
    let steps = vec!["1.0"; internodes::case::MAX_LOAD_STEPS + 1].join(", ");
    let text =
        common::half_disc_on_block("half_disc_on_block.msh", &format!("load_steps = [{steps}]"));
    let message = case_failure(&text);
    assert!(
        message.contains("load_steps") && message.contains("at most 1000"),
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

// ---------------------------------------------------------------------------------------------
// 6. Messages name the file, the line or key, and what was expected
// ---------------------------------------------------------------------------------------------

#[test]
fn non_finite_loads_are_errors_naming_the_load() {
    for load in [
        "traction = [nan, 0.0]",
        "pressure = nan",
        "pressure = inf",
        "hertz_pressure = { p0 = nan, a = 0.5, center = [0.0, 0.0] }",
    ] {
        let text =
            square_case("square_sorted.msh", "[1.0, 0.0]").replace("traction = [1.0, 0.0]", load);
        let message = case_failure(&text);
        assert!(
            message.contains("body 'square', load on 'right'") && message.contains("finite"),
            "{load}: {message}"
        );
    }
    let text = square_case("square_sorted.msh", "[1.0, 0.0]").replace(
        "poisson_ratio = 0.25",
        "poisson_ratio = 0.25\nbody_force = [0.0, nan]",
    );
    let message = case_failure(&text);
    assert!(
        message.contains("body_force") && message.contains("finite"),
        "{message}"
    );
}

#[test]
fn finite_values_that_overflow_downstream_are_rejected_naming_the_key_and_range() {
    // Each was accepted and failed in the solve with an unmet residual or a singular matrix
    // that named neither the key nor the value.
    let square = |from: &str, to: &str| {
        let text = square_case("square_sorted.msh", "[1.0, 0.0]");
        assert!(text.contains(from), "{from}");
        text.replace(from, to)
    };
    let range = "of magnitude at most 1e40";
    for (text, key, expected) in [
        (
            square("traction = [1.0, 0.0]", "traction = [1e308, 0.0]"),
            "load on 'right'",
            range,
        ),
        (
            square("traction = [1.0, 0.0]", "pressure = 1e308"),
            "load on 'right', pressure",
            range,
        ),
        (
            square(
                "traction = [1.0, 0.0]",
                "hertz_pressure = { p0 = 1e308, a = 0.5, center = [0.0, 0.0] }",
            ),
            "hertz_pressure.p0",
            range,
        ),
        (
            square(
                "poisson_ratio = 0.25",
                "poisson_ratio = 0.25\nbody_force = [1e308, 0.0]",
            ),
            "body_force",
            range,
        ),
        (
            square("ux = 0.0", "ux = 1e308"),
            "Dirichlet condition on 'left', ux",
            range,
        ),
        (
            square("youngs_modulus = 100.0", "youngs_modulus = 1e308"),
            "youngs_modulus",
            "from 1e-40 to 1e40",
        ),
        (
            square("youngs_modulus = 100.0", "youngs_modulus = 1e-300"),
            "youngs_modulus",
            "from 1e-40 to 1e40",
        ),
        (
            common::half_disc_on_block("half_disc_on_block.msh", "load_steps = [1e300]"),
            "load_steps",
            range,
        ),
        (
            common::half_disc_on_block("half_disc_on_block.msh", "rbf_radius = 1e300"),
            "rbf_radius",
            "<= 10",
        ),
        (
            common::half_disc_on_block("half_disc_on_block.msh", "rbf_radius = 1e9"),
            "rbf_radius",
            "<= 10",
        ),
        (
            common::half_disc_on_block("half_disc_on_block.msh", "krylov_max_iterations = 0"),
            "krylov_max_iterations",
            "between 1 and 10000",
        ),
    ] {
        let message = case_failure(&text);
        assert!(
            message.contains("case.toml") && message.contains(key) && message.contains(expected),
            "{key}: {message}"
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
fn a_load_on_a_point_group_says_a_boundary_group_is_needed() {
    let text = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper", "")
        .replace("group = \"lower_contact\"", "group = \"lower_corner\"");
    let message = case_failure(&text);
    assert!(
        message.contains("load on 'lower_corner'")
            && message.contains("group of points")
            && message.contains("physical curve"),
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

/// A case on `glued_blocks_{dim}d.msh` (`lower` below `upper`, their union, the `interface`
/// between them): `body` clamped on `lower_base`, `load` on `interface`.
fn glued_case(dim: usize, body: &str, load: &str) -> String {
    let clamp = if dim == 2 {
        "ux = 0.0\nuy = 0.0"
    } else {
        "ux = 0.0\nuy = 0.0\nuz = 0.0"
    };
    format!(
        r#"mesh = "{}"
output = "out"

[[body]]
name = "{body}"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "lower_base"
{clamp}
[[body.load]]
group = "interface"
{load}
"#,
        fixture(&format!("glued_blocks_{dim}d.msh")).display()
    )
}

#[test]
fn a_pressure_on_a_group_inside_the_body_is_an_error_in_2d_and_3d() {
    // The interface of the two blocks lies inside their union: its facets are shared by two
    // cells, and the run once succeeded with zero reaction.
    for dim in [2, 3] {
        for load in [
            "pressure = 1.0".to_string(),
            format!(
                "hertz_pressure = {{ p0 = 1.0, a = 0.5, center = {} }}",
                if dim == 2 {
                    "[0.5, 0.0]"
                } else {
                    "[0.5, 0.5, 0.0]"
                }
            ),
        ] {
            let message = case_failure(&glued_case(dim, "union", &load));
            assert!(
                message.contains("load on 'interface'")
                    && message.contains("inside the body")
                    && message.contains("two cells of 'union'")
                    && message.contains("a pressure needs a boundary group"),
                "{dim}D, {load}: {message}"
            );
        }
    }
}

/// The force in the direction `dim - 1` on `lower_base` of the run of `text`.
fn base_reaction(text: &str, dim: usize) -> f64 {
    let (_dir, path) = write_case(text);
    let report = run_quiet(&path).unwrap_or_else(|e| panic!("{e}\n{text}"));
    report.summary.bodies[0].reactions["lower_base"][dim - 1]
}

#[test]
fn a_pressure_on_the_interface_of_two_bodies_loads_each_as_a_boundary() {
    // The same interface is a boundary of `lower` alone (one cell per facet): a unit pressure on
    // its unit length (2D) or area (3D) is balanced by the clamped base, to round-off.
    for dim in [2, 3] {
        let reaction = base_reaction(&glued_case(dim, "lower", "pressure = 1.0"), dim);
        assert!((reaction - 1.0).abs() < 1e-10, "{dim}D: {reaction}");
    }
}

#[test]
fn a_traction_on_a_group_inside_the_body_is_a_line_or_surface_force() {
    // A traction vector does not depend on the side: inside the union it is a force of 2 per
    // unit length (area) over the unit interface, balanced by the base.
    for dim in [2, 3] {
        let traction = if dim == 2 {
            "[0.0, 2.0]"
        } else {
            "[0.0, 0.0, 2.0]"
        };
        let text = glued_case(dim, "union", &format!("traction = {traction}"));
        let reaction = base_reaction(&text, dim);
        assert!((reaction + 2.0).abs() < 1e-10, "{dim}D: {reaction}");
    }
}

/// A case on `unnamed_groups_2d.msh`: the body '1' clamped on `clamped`, pulled down by its
/// weight.
fn unnamed_groups_case(clamped: &str) -> String {
    format!(
        r#"mesh = "{}"
output = "out"

[[body]]
name = "1"
youngs_modulus = 1000.0
poisson_ratio = 0.3
body_force = [0.0, -1.0]
[[body.dirichlet]]
group = "{clamped}"
ux = 0.0
uy = 0.0
"#,
        fixture("unnamed_groups_2d.msh").display()
    )
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
    let (_dir, path) = write_case(&unnamed_groups_case("2"));
    let report = run_quiet(&path).unwrap();
    let reaction = report.summary.bodies[0].reactions["2"][1];
    assert!((reaction - 1.0).abs() < 1e-10, "{reaction}");
}

#[test]
fn an_error_and_its_causes_are_printed_once() {
    // The case error quotes the mesh error, which quotes the I/O error: each once on stderr and
    // in the failure mark (every cause used to be printed again under its own message).
    let (dir, case) = write_case(&square_case("square_sorted.msh", "[1.0, 0.0]").replace(
        &fixture("square_sorted.msh").display().to_string(),
        "missing.msh",
    ));
    std::fs::create_dir(dir.path().join("out")).unwrap();
    let output = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let mark = std::fs::read_to_string(dir.path().join("out/FAILED.txt")).unwrap();
    for text in [stderr.as_ref(), mark.as_str()] {
        assert_eq!(text.matches("cannot read mesh file").count(), 1, "{text}");
        assert_eq!(
            text.matches("No such file or directory").count(),
            1,
            "{text}"
        );
        assert!(!text.contains("caused by"), "{text}");
    }
}

#[test]
fn names_with_a_slash_are_refused_before_solving_when_matrices_are_exported() {
    // Body and group names go into matrices/<body>_stiffness.mtx and
    // matrices/<body>__<group>_mass.mtx: 'up/per' once failed after the solve, and a group
    // '../../base' would write outside the output folder.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("two_blocks_2d.msh")).unwrap();
    let body_mesh = dir.path().join("body.msh");
    std::fs::write(&body_mesh, text.replacen("\"upper\"", "\"up/per\"", 1)).unwrap();
    let message = case_failure(&two_blocks_case(
        &body_mesh,
        "up/per",
        "export_matrices = true",
    ));
    assert!(
        message.contains("body 'up/per', export_matrices")
            && message.contains("matrices/up/per_stiffness.mtx")
            && message.contains("rename"),
        "{message}"
    );

    let group_mesh = dir.path().join("group.msh");
    std::fs::write(
        &group_mesh,
        text.replacen("\"lower_base\"", "\"../../base\"", 1),
    )
    .unwrap();
    let with_group = |extra: &str| {
        two_blocks_case(&group_mesh, "upper", extra)
            .replace("group = \"lower_base\"", "group = \"../../base\"")
    };
    let message = case_failure(&with_group("export_matrices = true"));
    assert!(
        message.contains("group '../../base'") && message.contains("lower__../../base_mass.mtx"),
        "{message}"
    );
    // Without the export the names are fine: the solution files do not use them as paths.
    let (_dir, path) = write_case(&with_group(""));
    run_quiet(&path).unwrap();
}

#[test]
fn a_curve_of_a_3d_body_named_as_a_boundary_group_is_an_error_saying_so() {
    // The reader keeps no edges of a 3D mesh, so 'base_edge' was reported as missing from the
    // body, though `info` lists it.
    let clamped = |group: &str| {
        format!(
            r#"mesh = "{}"
output = "out"

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "{group}"
ux = 0.0
uy = 0.0
uz = 0.0
[[body.load]]
group = "block_top"
pressure = 1.0
"#,
            fixture("cube_edge_group.msh").display()
        )
    };
    let message = case_failure(&clamped("base_edge"));
    assert!(
        message.contains("group 'base_edge'")
            && message.contains("is a physical curve of")
            && message.contains("a curve of a 3D body, which is not a boundary group")
            && message.contains("physical surfaces"),
        "{message}"
    );
    let message = case_failure(&clamped("block"));
    assert!(
        message.contains("'block' is a physical volume") && message.contains("a body"),
        "{message}"
    );
    // The base itself is a boundary group: a unit pressure on the unit top is carried by it.
    let (_dir, path) = write_case(&clamped("block_base"));
    let report = run_quiet(&path).unwrap();
    let reaction = report.summary.bodies[0].reactions["block_base"][2];
    assert!((reaction - 1.0).abs() < 1e-10, "{reaction}");
}
