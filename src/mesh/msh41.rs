//! A parser of gmsh MSH 4.1 files, ASCII and binary: `$MeshFormat`, `$PhysicalNames`,
//! `$Entities`, `$Nodes` and `$Elements`; other sections are skipped.
//!
//! Our own parser rather than the `mshio` crate, for three reasons found by hostile inputs and
//! fuzzing (`fuzz/README.md`): `mshio` numbers the nodes of a file with a dense tag range by their
//! position and never reads the tags written there (gmsh's API writes blocks in any order, so a
//! valid file was read with its nodes permuted), it accepts a node tag defined twice, and it
//! panics on some corrupt headers (a data size other than 8, one that overflows an `i32`).
//!
//! Every count in the file is checked against the bytes left before anything is allocated or
//! looped over, every number is parsed with checks, and every error names the line (in binary
//! files also the byte offset) where the offending value starts.

use std::borrow::Cow;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::path::Path;

use rustc_hash::FxHashMap;

use super::{Dim, MeshError};

/// The raw contents of a file, before it is split into bodies.
#[derive(Debug, Default)]
pub(super) struct MshContents {
    /// `$PhysicalNames`, in file order.
    pub physical_names: Vec<PhysicalName>,
    /// (entity dimension, entity tag) -> physical tags, from `$Entities`.
    pub entity_groups: HashMap<(Dim, i32), Vec<i32>>,
    /// Number of volume entities in `$Entities` (a 3D geometry even when no volume is saved).
    pub num_volumes: u64,
    /// gmsh node tag -> coordinates, with the tags the file holds.
    pub nodes: FxHashMap<u64, [f64; 3]>,
    pub element_blocks: Vec<ElementBlock>,
}

/// One line of `$PhysicalNames`.
#[derive(Debug, Clone)]
pub(super) struct PhysicalName {
    pub dim: Dim,
    pub tag: i32,
    pub name: String,
}

/// One block of `$Elements`: elements of one type on one entity.
#[derive(Debug)]
pub(super) struct ElementBlock {
    pub entity_dim: Dim,
    pub entity_tag: i32,
    pub element_type: i32,
    /// Nodes per element of `element_type`.
    pub nodes_per_element: usize,
    pub element_tags: Vec<u64>,
    /// `nodes_per_element` node tags per element, flat.
    pub node_tags: Vec<u64>,
}

/// Parses the bytes of an MSH 4.1 file.
pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<MshContents, MeshError> {
    let mut cursor = Cursor {
        path,
        bytes,
        pos: 0,
        binary: false,
    };
    let mut contents = MshContents::default();
    let mut seen: Vec<String> = Vec::new();
    let mut first = true;
    while let Some(start) = cursor.next_token_start() {
        let header = cursor.ascii_token();
        let Some(name) = header.strip_prefix('$') else {
            return Err(cursor.error_at(
                start,
                format!(
                    "expected a section header such as '$Nodes', found '{}'",
                    clip(&header)
                ),
            ));
        };
        let name = name.to_string();
        if first && name != "MeshFormat" {
            return Err(cursor.error_at(
                start,
                "expected '$MeshFormat': this is not a gmsh MSH file".into(),
            ));
        }
        first = false;
        let known = matches!(
            name.as_str(),
            "MeshFormat" | "PhysicalNames" | "Entities" | "Nodes" | "Elements"
        );
        if known && seen.contains(&name) {
            return Err(cursor.error_at(start, format!("a second ${name} section")));
        }
        cursor.end_of_line();
        match name.as_str() {
            "MeshFormat" => cursor.binary = mesh_format(&mut cursor)?,
            "PhysicalNames" => contents.physical_names = physical_names(&mut cursor)?,
            "Entities" => entities(&mut cursor, &mut contents)?,
            "Nodes" => contents.nodes = nodes(&mut cursor)?,
            "Elements" => contents.element_blocks = elements(&mut cursor)?,
            // Its elements would be skipped as belonging to no physical group, and the file
            // rejected as holding no body: say why instead.
            "PartitionedEntities" => {
                return Err(MeshError::Partitioned {
                    path: path.to_owned(),
                    line: cursor.line_at(start),
                });
            }
            _ => {
                cursor.skip_section(start, &name)?;
                continue;
            }
        }
        cursor.expect_end(&name)?;
        seen.push(name);
    }
    if first {
        return Err(cursor.error_at(0, "the file is empty: expected '$MeshFormat'".into()));
    }
    Ok(contents)
}

/// `$MeshFormat`: version 4.1, file type 0 (ASCII) or 1 (binary), data size 8. Returns whether
/// the file is binary.
fn mesh_format(cursor: &mut Cursor) -> Result<bool, MeshError> {
    let start = cursor.next_token_start().unwrap_or(cursor.pos);
    let version = cursor.ascii_token();
    if version != "4.1" {
        return Err(MeshError::UnsupportedVersion {
            path: cursor.path.to_owned(),
            version: clip(&version),
        });
    }
    let file_type = cursor.ascii_number::<u8>("the file type (0 ASCII, 1 binary)")?;
    if file_type > 1 {
        return Err(cursor.error_at(
            start,
            format!("file type {file_type} in $MeshFormat: expected 0 (ASCII) or 1 (binary)"),
        ));
    }
    let size_start = cursor.next_token_start().unwrap_or(cursor.pos);
    let data_size = cursor.ascii_token();
    if data_size != "8" {
        return Err(cursor.error_at(
            size_start,
            format!(
                "data size '{}' in $MeshFormat: only 8 (64-bit size_t, as gmsh writes) is supported",
                clip(&data_size)
            ),
        ));
    }
    let binary = file_type == 1;
    if binary {
        cursor.end_of_line();
        let one_at = cursor.pos;
        let one = cursor.binary_bytes::<4>("the endianness check (binary int 1)")?;
        if i32::from_le_bytes(one) != 1 {
            return Err(cursor.error_at(
                one_at,
                "the binary endianness check is not the little-endian int 1: \
                 big-endian or corrupt files are not supported"
                    .into(),
            ));
        }
    }
    Ok(binary)
}

/// `$PhysicalNames` (ASCII even in binary files): a count, then `dim tag "name"` per line.
fn physical_names(cursor: &mut Cursor) -> Result<Vec<PhysicalName>, MeshError> {
    let binary = std::mem::replace(&mut cursor.binary, false);
    // Each name needs at least `0 1 ""` and a separator.
    let count = cursor.count("the number of physical names", 7)?;
    let mut names: Vec<PhysicalName> = Vec::new();
    let mut by_name: HashMap<String, usize> = HashMap::new();
    let mut by_group: HashMap<(Dim, i32), usize> = HashMap::new();
    for k in 0..count {
        let at = cursor.value_start();
        let dim = cursor.ascii_number::<i32>("the dimension of a physical name")?;
        let dim = entity_dim(cursor, dim, "a physical name")?;
        let tag = cursor.ascii_number::<i32>("the tag of a physical name")?;
        let name = cursor.quoted_string()?;
        // Case files name groups, whatever their dimension: a name must say which group.
        let twice = match (by_name.get(&name), by_group.get(&(dim, tag))) {
            (Some(&other), _) => Some((
                other,
                format!("physical name '{name}' is given to two groups"),
            )),
            (None, Some(&other)) => Some((
                other,
                format!("physical group (dim {dim}, tag {tag}) is named twice"),
            )),
            (None, None) => None,
        };
        if let Some((other, what)) = twice {
            let other = &names[other];
            return Err(cursor.error_at(
                at,
                format!(
                    "{what}: dim {} tag {} '{}' and dim {dim} tag {tag} '{name}'; \
                     case files refer to groups by name, so names must be unique",
                    other.dim, other.tag, other.name
                ),
            ));
        }
        by_name.insert(name.clone(), k);
        by_group.insert((dim, tag), k);
        names.push(PhysicalName { dim, tag, name });
    }
    cursor.binary = binary;
    Ok(names)
}

/// `$Entities`: the physical tags of every point, curve, surface and volume.
fn entities(cursor: &mut Cursor, contents: &mut MshContents) -> Result<(), MeshError> {
    let mut counts = [0usize; 4];
    for (dim, what) in ["points", "curves", "surfaces", "volumes"]
        .iter()
        .enumerate()
    {
        // A point is at least a tag, 3 coordinates and a count.
        counts[dim] = cursor.count(&format!("the number of {what}"), 5)?;
    }
    contents.num_volumes = counts[3] as u64;
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..count {
            let at = cursor.value_start();
            let tag = cursor.int("an entity tag")?;
            // A point has its coordinates, the others their bounding box.
            let coordinates = if dim == 0 { 3 } else { 6 };
            for _ in 0..coordinates {
                cursor.double("an entity coordinate")?;
            }
            let n = cursor.count("the number of physical tags of an entity", 1)?;
            let mut tags = Vec::new();
            for _ in 0..n {
                tags.push(cursor.int("a physical tag")?);
            }
            if dim > 0 {
                let n = cursor.count("the number of bounding entities", 1)?;
                for _ in 0..n {
                    cursor.int("a bounding entity tag")?;
                }
            }
            if contents.entity_groups.insert((dim, tag), tags).is_some() {
                return Err(cursor.error_at(
                    at,
                    format!("entity (dimension {dim}, tag {tag}) is defined twice in $Entities"),
                ));
            }
        }
    }
    Ok(())
}

/// `$Nodes`: blocks of node tags, then their coordinates. The tags are read as written (in any
/// order); a tag defined twice is an error naming both lines.
fn nodes(cursor: &mut Cursor) -> Result<FxHashMap<u64, [f64; 3]>, MeshError> {
    let num_blocks = cursor.count("the number of node blocks", 8)?;
    let num_nodes = cursor.count("the number of nodes", 4)?;
    cursor.size_t("the smallest node tag")?;
    cursor.size_t("the largest node tag")?;
    let mut nodes: FxHashMap<u64, [f64; 3]> = FxHashMap::default();
    let mut defined_at: FxHashMap<u64, usize> = FxHashMap::default();
    let mut read = 0usize;
    for _ in 0..num_blocks {
        let block_start = cursor.value_start();
        let dim = cursor.int("the entity dimension of a node block")?;
        let dim = entity_dim(cursor, dim, "a node block")?;
        cursor.int("the entity tag of a node block")?;
        let parametric = cursor.int("the parametric flag of a node block")?;
        if !(0..=1).contains(&parametric) {
            return Err(cursor.error_at(
                block_start,
                format!("node block: parametric flag {parametric}, expected 0 or 1"),
            ));
        }
        let values_per_node = 3 + if parametric == 1 { dim } else { 0 };
        // A tag and the coordinates.
        let count = cursor.count("the number of nodes in a block", 2 * (1 + values_per_node))?;
        let mut tags = Vec::new();
        for _ in 0..count {
            let at = cursor.value_start();
            let tag = cursor.size_t("a node tag")?;
            if tag == 0 {
                return Err(cursor.error_at(at, "node tag 0: gmsh tags start at 1".into()));
            }
            tags.push((tag, at));
        }
        for (tag, at) in tags {
            let coords_at = cursor.value_start();
            let mut x = [0.0; 3];
            for value in &mut x {
                *value = cursor.double("a node coordinate")?;
            }
            for _ in 3..values_per_node {
                cursor.double("a parametric node coordinate")?;
            }
            if x.iter().any(|v| !v.is_finite()) {
                return Err(cursor.error_at(
                    coords_at,
                    format!("node {tag} has a non-finite coordinate {x:?}"),
                ));
            }
            match defined_at.entry(tag) {
                Entry::Occupied(first) => {
                    let first_line = cursor.line_at(*first.get());
                    return Err(cursor.error_at(
                        at,
                        format!("node tag {tag} is defined twice (first on line {first_line})"),
                    ));
                }
                Entry::Vacant(slot) => {
                    slot.insert(at);
                }
            }
            nodes.insert(tag, x);
        }
        read = read.saturating_add(count);
    }
    if read != num_nodes {
        return Err(cursor.error_at(
            cursor.pos,
            format!("$Nodes announces {num_nodes} nodes but its blocks hold {read}"),
        ));
    }
    Ok(nodes)
}

/// `$Elements`: blocks of elements of one type on one entity, each an element tag and its node
/// tags. An element tag defined twice is an error.
fn elements(cursor: &mut Cursor) -> Result<Vec<ElementBlock>, MeshError> {
    let num_blocks = cursor.count("the number of element blocks", 8)?;
    let num_elements = cursor.count("the number of elements", 4)?;
    cursor.size_t("the smallest element tag")?;
    cursor.size_t("the largest element tag")?;
    let mut blocks = Vec::new();
    let mut seen: FxHashMap<u64, usize> = FxHashMap::default();
    let mut read = 0usize;
    for _ in 0..num_blocks {
        let dim = cursor.int("the entity dimension of an element block")?;
        let entity_dim = entity_dim(cursor, dim, "an element block")?;
        let entity_tag = cursor.int("the entity tag of an element block")?;
        let type_at = cursor.value_start();
        let element_type = cursor.int("the element type of an element block")?;
        let nodes_per_element = nodes_per_element(element_type).ok_or_else(|| {
            cursor.error_at(type_at, format!("unknown gmsh element type {element_type}"))
        })?;
        let count = cursor.count(
            "the number of elements in a block",
            2 * (1 + nodes_per_element),
        )?;
        let mut block = ElementBlock {
            entity_dim,
            entity_tag,
            element_type,
            nodes_per_element,
            element_tags: Vec::new(),
            node_tags: Vec::new(),
        };
        for _ in 0..count {
            let at = cursor.value_start();
            let tag = cursor.size_t("an element tag")?;
            // The whole element first: a line cut short is reported as such, not as a
            // duplicate of the tag its first digits make.
            for _ in 0..nodes_per_element {
                block
                    .node_tags
                    .push(cursor.size_t("a node tag of an element")?);
            }
            if let Some(&first) = seen.get(&tag) {
                let first_line = cursor.line_at(first);
                return Err(cursor.error_at(
                    at,
                    format!("element tag {tag} is defined twice (first on line {first_line})"),
                ));
            }
            seen.insert(tag, at);
            block.element_tags.push(tag);
        }
        read = read.saturating_add(count);
        blocks.push(block);
    }
    if read != num_elements {
        return Err(cursor.error_at(
            cursor.pos,
            format!("$Elements announces {num_elements} elements but its blocks hold {read}"),
        ));
    }
    Ok(blocks)
}

/// An entity dimension, 0 to 3.
fn entity_dim(cursor: &Cursor, dim: i32, what: &str) -> Result<Dim, MeshError> {
    match Dim::try_from(dim) {
        Ok(d) if d <= 3 => Ok(d),
        _ => Err(cursor.error_at(
            cursor.pos,
            format!("{what}: entity dimension {dim}, expected 0 to 3"),
        )),
    }
}

/// Nodes per element of a gmsh element type (the types of gmsh's `GmshDefines.h` up to order
/// 4), or `None` for a type we do not know: in a binary file its elements could not be skipped.
pub(super) fn nodes_per_element(element_type: i32) -> Option<usize> {
    const NODES: [usize; 31] = [
        2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4,
        5, 6, 20, 35, 56,
    ];
    let index = usize::try_from(element_type).ok()?.checked_sub(1)?;
    NODES.get(index).copied()
}

/// The gmsh name of an element type, for messages.
pub(super) fn element_type_name(element_type: i32) -> String {
    const NAMES: [&str; 17] = [
        "Lin2", "Tri3", "Qua4", "Tet4", "Hex8", "Pri6", "Pyr5", "Lin3", "Tri6", "Qua9", "Tet10",
        "Hex27", "Pri18", "Pyr14", "Pnt", "Qua8", "Hex20",
    ];
    usize::try_from(element_type)
        .ok()
        .and_then(|t| t.checked_sub(1))
        .and_then(|i| NAMES.get(i))
        .map_or_else(|| format!("type {element_type}"), |n| (*n).to_string())
}

/// At most 40 characters of a token, for messages about corrupt files.
fn clip(token: &str) -> String {
    if token.chars().count() > 40 {
        format!("{}...", token.chars().take(40).collect::<String>())
    } else {
        token.to_string()
    }
}

/// A position in the file and how numbers are read there (ASCII tokens or little-endian binary).
struct Cursor<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
    binary: bool,
}

impl<'a> Cursor<'a> {
    /// The 1-based line of byte `pos`.
    fn line_at(&self, pos: usize) -> usize {
        let end = pos.min(self.bytes.len());
        1 + self.bytes[..end].iter().filter(|&&b| b == b'\n').count()
    }

    /// A syntax error at byte `pos`; in binary files it also gives the byte offset.
    fn error_at(&self, pos: usize, message: String) -> MeshError {
        let message = if self.binary {
            format!("{message} (byte offset {pos})")
        } else {
            message
        };
        MeshError::Syntax {
            path: self.path.to_owned(),
            line: self.line_at(pos),
            message,
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Skips whitespace; the start of the next token, if any.
    fn next_token_start(&mut self) -> Option<usize> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos < self.bytes.len()).then_some(self.pos)
    }

    /// Where the next value starts: after any whitespace in ASCII, here in binary data (where
    /// whitespace bytes are data).
    fn value_start(&mut self) -> usize {
        if !self.binary {
            self.next_token_start();
        }
        self.pos
    }

    /// The next whitespace-delimited token, as text (empty at the end of the file); borrowed
    /// from the file's bytes unless it is not UTF-8 (a copy per number took a tenth of the
    /// read).
    fn ascii_token(&mut self) -> Cow<'a, str> {
        self.next_token_start();
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let bytes: &'a [u8] = &self.bytes[start..self.pos];
        match std::str::from_utf8(bytes) {
            Ok(text) => Cow::Borrowed(text),
            Err(_) => String::from_utf8_lossy(bytes),
        }
    }

    /// Moves past the end of the current line (binary data starts on the next byte).
    fn end_of_line(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
        self.pos = (self.pos + 1).min(self.bytes.len());
    }

    /// An ASCII number of type `T`; `what` says what was expected.
    fn ascii_number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, MeshError> {
        let start = self.next_token_start().unwrap_or(self.pos);
        let token = self.ascii_token();
        if token.is_empty() {
            return Err(self.error_at(
                start,
                format!("the file ends where {what} was expected (truncated?)"),
            ));
        }
        // Every number of a file is followed by more (at least the section's `$End` line): one
        // that runs into the end of the file was cut, and its digits may well parse (a tag cut
        // to one defined before must not be reported as defined twice).
        if self.pos == self.bytes.len() {
            return Err(self.error_at(
                start,
                format!(
                    "the file ends inside {what} ('{}'): the line is incomplete (truncated?)",
                    clip(&token)
                ),
            ));
        }
        token
            .parse()
            .map_err(|_| self.error_at(start, format!("expected {what}, found '{}'", clip(&token))))
    }

    /// `N` raw bytes of binary data.
    fn binary_bytes<const N: usize>(&mut self, what: &str) -> Result<[u8; N], MeshError> {
        let end = self.pos.checked_add(N).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(self.error_at(
                self.pos,
                format!("the file ends where {what} was expected (truncated?)"),
            ));
        };
        let mut out = [0u8; N];
        out.copy_from_slice(&self.bytes[self.pos..end]);
        self.pos = end;
        Ok(out)
    }

    fn size_t(&mut self, what: &str) -> Result<u64, MeshError> {
        if self.binary {
            Ok(u64::from_le_bytes(self.binary_bytes::<8>(what)?))
        } else {
            self.ascii_number(what)
        }
    }

    fn int(&mut self, what: &str) -> Result<i32, MeshError> {
        if self.binary {
            Ok(i32::from_le_bytes(self.binary_bytes::<4>(what)?))
        } else {
            self.ascii_number(what)
        }
    }

    fn double(&mut self, what: &str) -> Result<f64, MeshError> {
        if self.binary {
            Ok(f64::from_le_bytes(self.binary_bytes::<8>(what)?))
        } else {
            self.ascii_number(what)
        }
    }

    /// A count of items that need at least `min_bytes` each (in ASCII; binary items are at
    /// least as long): a count the rest of the file cannot hold is an error before anything is
    /// allocated or looped over.
    fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, MeshError> {
        let start = self.value_start();
        let n = self.size_t(what)?;
        let fits = usize::try_from(n).ok().filter(|&n| {
            n.checked_mul(min_bytes)
                .is_some_and(|b| b <= self.remaining())
        });
        fits.ok_or_else(|| {
            self.error_at(
                start,
                format!(
                    "{what} is {n}, more than the {} bytes left in the file can hold \
                     (a corrupt or truncated file)",
                    self.remaining()
                ),
            )
        })
    }

    /// A double-quoted string on the current line (a physical name).
    fn quoted_string(&mut self) -> Result<String, MeshError> {
        let start = self.next_token_start().unwrap_or(self.pos);
        let line_end = self.bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(self.bytes.len(), |k| start + k);
        let line = &self.bytes[start..line_end];
        let closing = line.iter().skip(1).position(|&b| b == b'"');
        match (line.first(), closing) {
            (Some(b'"'), Some(k)) => {
                self.pos = start + k + 2;
                Ok(String::from_utf8_lossy(&line[1..k + 1]).into_owned())
            }
            _ => Err(self.error_at(
                start,
                format!(
                    "expected a double-quoted name in $PhysicalNames ('dim tag \"name\"'), found '{}'",
                    clip(&String::from_utf8_lossy(line))
                ),
            )),
        }
    }

    /// Expects `$End<name>` as the next token.
    fn expect_end(&mut self, name: &str) -> Result<(), MeshError> {
        let start = self.next_token_start().unwrap_or(self.pos);
        let token = self.ascii_token();
        if token != format!("$End{name}") {
            let found = if token.is_empty() {
                "the end of the file (truncated?)".to_string()
            } else {
                format!("'{}'", clip(&token))
            };
            return Err(self.error_at(
                start,
                format!(
                    "expected '$End{name}', found {found}: the section holds other data than its counts announce"
                ),
            ));
        }
        Ok(())
    }

    /// Skips a section we do not use, up to and including its `$End` line.
    fn skip_section(&mut self, start: usize, name: &str) -> Result<(), MeshError> {
        let end = format!("$End{name}");
        let found = self.bytes[self.pos..]
            .windows(end.len())
            .position(|w| w == end.as_bytes());
        match found {
            Some(k) => {
                self.pos += k + end.len();
                Ok(())
            }
            None => Err(self.error_at(start, format!("section ${name} is not closed by {end}"))),
        }
    }
}
