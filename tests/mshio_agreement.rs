//! Our MSH 4.1 reader against the `mshio` crate, an independent parser, on every committed
//! gmsh-written fixture whose node tags ascend in file order (the files `mshio` reads right: it
//! numbers the nodes of a dense tag range by position, which is why the solver reads with its
//! own parser, `src/mesh/msh41.rs`). Every node of every body must have the coordinates `mshio`
//! gives its gmsh tag, and every cell the nodes of the `mshio` element with its tag.

use std::collections::HashMap;

use internodes::mesh::read_msh;

mod common;

/// The fixtures written by gmsh itself (sorted tags); the `*_shuffled*` ones are not.
const FIXTURES: [&str; 18] = [
    "block_2d.msh",
    "block_2d_bin.msh",
    "block_3d.msh",
    "block_3d_bin.msh",
    "cube_sorted.msh",
    "glued_blocks_2d.msh",
    "glued_blocks_3d.msh",
    "half_disc_on_block.msh",
    "half_disc_on_block_coarse_block.msh",
    "half_disc_on_block_hertz.msh",
    "half_disc_on_block_overlap.msh",
    "hemisphere_on_block.msh",
    "hemisphere_on_block_hertz.msh",
    "hemisphere_on_block_overlap.msh",
    "square_sorted.msh",
    "two_blocks_2d.msh",
    "two_blocks_3d.msh",
    "two_half_discs.msh",
];

#[test]
fn every_body_node_and_cell_agrees_with_mshio() {
    for name in FIXTURES {
        let path = common::fixture(name);
        let bytes = std::fs::read(&path).unwrap();
        let msh = mshio::parse_msh_bytes(&bytes).unwrap_or_else(|e| panic!("{name}: mshio: {e:?}"));
        let nodes = msh.data.nodes.expect("a $Nodes section");
        // mshio's numbering of a dense tag range: min tag + position over the blocks in order.
        let mut coordinates: HashMap<u64, [f64; 3]> = HashMap::new();
        let mut next = nodes.min_node_tag;
        for block in &nodes.node_blocks {
            let tags: Vec<u64> = match &block.node_tags {
                Some(map) => {
                    let mut by_index: Vec<(usize, u64)> =
                        map.iter().map(|(&tag, &i)| (i, tag)).collect();
                    by_index.sort_unstable();
                    by_index.into_iter().map(|(_, tag)| tag).collect()
                }
                None => (0..block.nodes.len() as u64).map(|k| next + k).collect(),
            };
            next += block.nodes.len() as u64;
            for (tag, node) in tags.into_iter().zip(&block.nodes) {
                coordinates.insert(tag, [node.x, node.y, node.z]);
            }
        }
        let elements: HashMap<u64, Vec<u64>> = msh
            .data
            .elements
            .expect("an $Elements section")
            .element_blocks
            .into_iter()
            .flat_map(|block| block.elements)
            .map(|e| (e.element_tag, e.nodes))
            .collect();

        let mesh = read_msh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut cells = 0;
        for body in &mesh.bodies {
            for (x, tag) in body
                .coords
                .as_whole()
                .unwrap()
                .iter()
                .zip(body.node_tags.iter())
            {
                assert_eq!(Some(x), coordinates.get(&tag), "{name}: node {tag}");
            }
            for c in 0..body.num_cells() {
                let ours: Vec<u64> = body
                    .cell(c)
                    .iter()
                    .map(|&n| body.node_tags.get(n))
                    .collect();
                let tag = body.cell_tags.get(c);
                assert_eq!(Some(&ours), elements.get(&tag), "{name}: element {tag}");
                cells += 1;
            }
        }
        assert!(cells > 0, "{name}: no cell compared");
    }
}
