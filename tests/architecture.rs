//! The shape of `src/contact/`: its module docs list the parts of a solve in order (`mod.rs`
//! its folders and files, each folder's `mod.rs` the folder's files), and each file imports only
//! files listed before it. The imports then run one way (no cycle), and a newcomer can read the
//! files in that order. Across the whole crate, no files import each other, directly or through
//! others.

use std::collections::BTreeMap;
use std::path::Path;

const CONTACT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src/contact");
/// How a file of `src/contact` names the others: `crate::contact::...` (or `super::`).
const CONTACT_ROOT: &str = "crate::contact::";
const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src");

/// Every `.rs` file under `dir`, by its path from there (`geometry/gap.rs`).
fn rust_files(dir: &Path, under: &str, files: &mut BTreeMap<String, String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if path.is_dir() {
            rust_files(&path, &format!("{under}{name}/"), files);
        } else if name.ends_with(".rs") {
            files.insert(
                format!("{under}{name}"),
                std::fs::read_to_string(&path).unwrap(),
            );
        }
    }
}

/// The module of a file, as its path from `contact` (`geometry/gap.rs` is `geometry::gap`, a
/// folder's `mod.rs` the folder, `src/contact/mod.rs` the empty path).
fn module_of(file: &str) -> String {
    let path = file.strip_suffix(".rs").unwrap();
    let path = match path {
        "mod" | "lib" => "",
        path => path.strip_suffix("/mod").unwrap_or(path),
    };
    path.replace('/', "::")
}

/// The file of a module, the inverse of [`module_of`].
fn file_of(module: &str, files: &BTreeMap<String, String>) -> String {
    let path = module.replace("::", "/");
    let file = format!("{path}.rs");
    if files.contains_key(&file) {
        file
    } else {
        format!("{path}/mod.rs")
    }
}

/// The `name.rs` files (as `name`) and `name/` folders a module doc names, in order of first
/// mention (a path through a folder, `docs/method.md` or `coupled/system.rs`, names neither).
fn documented_entries(mod_rs: &str) -> Vec<String> {
    let plain = |n: &&str| {
        !n.is_empty() && *n != "mod" && n.chars().all(|c| c.is_alphanumeric() || c == '_')
    };
    let mut entries: Vec<String> = Vec::new();
    for line in mod_rs.lines().take_while(|l| l.starts_with("//!")) {
        for piece in line.split('`').skip(1).step_by(2) {
            let entry =
                (piece.strip_suffix(".rs").filter(plain).map(str::to_string)).or_else(|| {
                    piece
                        .strip_suffix('/')
                        .filter(plain)
                        .map(|n| format!("{n}/"))
                });
            if let Some(entry) = entry.filter(|e| !entries.contains(e)) {
                entries.push(entry);
            }
        }
    }
    entries
}

/// The modules of `src/contact` in the documented order: the entries of `mod.rs`'s doc, a
/// folder standing for its own `mod.rs` followed by the entries of that file's doc.
fn documented_order(files: &BTreeMap<String, String>) -> Vec<String> {
    fn walk(files: &BTreeMap<String, String>, folder: &str, order: &mut Vec<String>) {
        let Some(mod_rs) = files.get(&format!("{folder}mod.rs")) else {
            return;
        };
        for entry in documented_entries(mod_rs) {
            let module = match entry.strip_suffix('/') {
                Some(sub) => module_of(&format!("{folder}{sub}/mod.rs")),
                None => module_of(&format!("{folder}{entry}.rs")),
            };
            if !order.contains(&module) {
                order.push(module);
                if entry.ends_with('/') {
                    walk(files, &format!("{folder}{entry}"), order);
                }
            }
        }
    }
    let mut order = Vec::new();
    walk(files, "", &mut order);
    order
}

/// The paths (from `contact`) a use tree or a path names: `gap::{self, GapRow}` names `gap`
/// and `gap::GapRow`.
fn tree_paths(rest: &str, prefix: &str, paths: &mut Vec<String>) {
    let mut path = prefix.trim_end_matches("::").to_string();
    let mut at = rest.trim_start();
    loop {
        if let Some(group) = at.strip_prefix('{') {
            let (mut depth, mut start) = (0, 0);
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth > 0 => depth -= 1,
                    ',' | '}' if depth == 0 => {
                        let part = group[start..i].trim();
                        if part == "self" {
                            paths.push(path.clone());
                        } else if !part.is_empty() {
                            let prefix = if path.is_empty() {
                                String::new()
                            } else {
                                format!("{path}::")
                            };
                            tree_paths(part, &prefix, paths);
                        }
                        start = i + 1;
                        if c == '}' {
                            return;
                        }
                    }
                    _ => {}
                }
            }
            return;
        }
        let end = (at.find(|c: char| !(c.is_alphanumeric() || c == '_'))).unwrap_or(at.len());
        let (segment, tail) = at.split_at(end);
        if segment == "super" {
            path = path
                .rsplit_once("::")
                .map_or(String::new(), |(up, _)| up.to_string());
        } else if !segment.is_empty() {
            path = if path.is_empty() {
                segment.to_string()
            } else {
                format!("{path}::{segment}")
            };
        }
        match tail.strip_prefix("::") {
            Some(tail) => at = tail,
            None => break,
        }
    }
    paths.push(path);
}

/// The paths (from the tree's root) a file's code names through `root` (`crate::contact::`, or
/// `crate::` for the whole crate) or `super::` (comments and the unit tests left out); `module`
/// is the file's module (a folder's `mod.rs` is the folder, whose `super` is the folder above).
fn named_paths(source: &str, module: &str, root: &str) -> Vec<String> {
    let code: String = (source.split("#[cfg(test)]").next().unwrap().lines())
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let mut paths = Vec::new();
    let mut at = 0;
    loop {
        let next = ([root, "super::"].into_iter())
            .filter_map(|prefix| code[at..].find(prefix).map(|i| (at + i, prefix)))
            .min();
        let Some((i, prefix)) = next else {
            break;
        };
        let mut rest = &code[i + prefix.len()..];
        at = code.len() - rest.len();
        let before = code[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let mut base: Vec<&str> = Vec::new();
        if prefix == "super::" {
            base = module.split("::").filter(|s| !s.is_empty()).collect();
            base.pop();
            while let Some(tail) = rest.strip_prefix("super::") {
                base.pop();
                rest = tail;
            }
        }
        let base = if base.is_empty() {
            String::new()
        } else {
            base.join("::") + "::"
        };
        tree_paths(rest, &base, &mut paths);
    }
    paths
}

/// What the `pub use` lines of the `mod.rs` files (and `lib.rs`) re-export: each name, by the
/// module path it is reached through (`rbf` by `geometry::rbf`, `law::NodeStates` by
/// `law::state::NodeStates`); `root` as in [`named_paths`].
fn reexports(files: &BTreeMap<String, String>, root: &str) -> BTreeMap<String, String> {
    let mut aliases = BTreeMap::new();
    let roots = |f: &&String| f.ends_with("mod.rs") || *f == "lib.rs";
    for (file, source) in files.iter().filter(|(f, _)| roots(f)) {
        let module = module_of(file);
        let prefix = if module.is_empty() {
            String::new()
        } else {
            format!("{module}::")
        };
        let text: String = (source.lines())
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join(" ");
        for statement in text.split(';') {
            let statement = statement.trim();
            let Some(tree) = statement
                .strip_prefix("pub use ")
                .or_else(|| statement.strip_prefix("pub(crate) use "))
            else {
                continue;
            };
            let mut paths = Vec::new();
            match tree.strip_prefix(root) {
                Some(tree) => tree_paths(tree, "", &mut paths),
                None => tree_paths(tree, &prefix, &mut paths),
            }
            for path in paths {
                let name = path.rsplit("::").next().unwrap();
                aliases.insert(format!("{prefix}{name}"), path.clone());
            }
        }
    }
    aliases
}

/// The module of `modules` a path leads to, through re-exports (the root, `ContactError`, is
/// none of them).
fn resolve(path: &str, modules: &[String], aliases: &BTreeMap<String, String>) -> Option<String> {
    let mut path = path.to_string();
    for _ in 0..8 {
        let alias = (aliases.iter())
            .filter(|(from, _)| path == **from || path.starts_with(&format!("{from}::")))
            .max_by_key(|(from, _)| from.len());
        let Some((from, to)) = alias else {
            break;
        };
        path = format!("{to}{}", &path[from.len()..]);
    }
    (modules.iter())
        .filter(|m| path == **m || path.starts_with(&format!("{m}::")))
        .max_by_key(|m| m.len())
        .cloned()
}

/// The modules a file imports (re-exported items counted for the module that defines them).
fn imports(
    source: &str,
    module: &str,
    root: &str,
    modules: &[String],
    aliases: &BTreeMap<String, String>,
) -> Vec<String> {
    let mut found = Vec::new();
    for path in named_paths(source, module, root) {
        if let Some(target) = resolve(&path, modules, aliases).filter(|t| !found.contains(t)) {
            found.push(target);
        }
    }
    found
}

/// The documented order, and each import of a file listed later than the importing file (a
/// folder's `mod.rs` may use its own files: it declares them).
fn check(files: &BTreeMap<String, String>) -> (Vec<String>, Vec<String>) {
    let order = documented_order(files);
    let aliases = reexports(files, CONTACT_ROOT);
    let mut wrong = Vec::new();
    for (position, module) in order.iter().enumerate() {
        let file = file_of(module, files);
        let Some(source) = files.get(&file) else {
            continue;
        };
        let is_mod_rs = file.ends_with("mod.rs");
        for import in imports(source, module, CONTACT_ROOT, &order, &aliases) {
            let at = order.iter().position(|o| *o == import).unwrap();
            let own = is_mod_rs && import.starts_with(&format!("{module}::"));
            if at > position && !own {
                let imported = file_of(&import, files);
                wrong.push(format!("{file} imports {imported}, listed after it"));
            }
        }
    }
    (order, wrong)
}

#[test]
fn contact_files_import_only_files_listed_before_them() {
    let mut files = BTreeMap::new();
    rust_files(Path::new(CONTACT), "", &mut files);
    let (order, wrong) = check(&files);

    let mut listed = order.clone();
    listed.sort();
    let mut modules: Vec<String> = (files.keys().map(|f| module_of(f)))
        .filter(|m| !m.is_empty())
        .collect();
    modules.sort();
    assert_eq!(
        listed, modules,
        "the module docs of src/contact/mod.rs and of each folder's mod.rs list every file once"
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_import_reader_sees_grouped_and_reexported_imports() {
    // The check above must be able to fail: a file that imports a later one is found, through
    // a grouped import, through an item or a module re-exported by mod.rs, and through `super`.
    let modules: Vec<String> = [
        "law",
        "law::coulomb",
        "solution",
        "geometry::gap",
        "geometry::rbf",
        "iteration",
        "iteration::solve",
    ]
    .map(String::from)
    .to_vec();
    let aliases = BTreeMap::from([
        (
            "ContactSolution".to_string(),
            "solution::ContactSolution".to_string(),
        ),
        ("rbf".to_string(), "geometry::rbf".to_string()),
    ]);
    let source = "use crate::contact::{ContactSolution, geometry::gap::gap_rows};\n\
                  use super::Multiplier;\nuse crate::contact::rbf::{self, Interpolation};\n\
                  // crate::contact::iteration::solve in a comment\n\
                  fn f() { crate::contact::iteration::solve::run(); }\n#[cfg(test)]\n\
                  use crate::contact::nothing;";
    assert_eq!(
        imports(source, "law::coulomb", CONTACT_ROOT, &modules, &aliases),
        [
            "solution",
            "geometry::gap",
            "law",
            "geometry::rbf",
            "iteration::solve"
        ]
        .map(String::from)
    );
    // A folder's mod.rs is the folder: its `super` is the parent.
    assert_eq!(
        imports(
            "use super::solution::X;",
            "law",
            CONTACT_ROOT,
            &modules,
            &aliases
        ),
        ["solution"].map(String::from)
    );

    // On a whole (made-up) tree: the order comes from the module docs, and only the import of
    // a later file is wrong (the folder's mod.rs may use its own files).
    let files = BTreeMap::from(
        [
            (
                "mod.rs",
                "//! `geometry/`, `solution.rs` (see `docs/method.md`), `iteration/`.\n\
                 mod geometry;\npub use solution::Solution;\n",
            ),
            (
                "geometry/mod.rs",
                "//! Its files: `gap.rs`.\npub mod gap;\npub use gap::Gap;\n",
            ),
            ("geometry/gap.rs", "use crate::contact::Solution;\n"),
            ("solution.rs", "use crate::contact::geometry::Gap;\n"),
            (
                "iteration/mod.rs",
                "//! `solve.rs`\npub mod solve;\n\
                 fn go() { crate::contact::iteration::solve::run() }\n",
            ),
            (
                "iteration/solve.rs",
                "use super::super::solution::Solution;\n",
            ),
        ]
        .map(|(f, s)| (f.to_string(), s.to_string())),
    );
    let (order, wrong) = check(&files);
    assert_eq!(
        order,
        [
            "geometry",
            "geometry::gap",
            "solution",
            "iteration",
            "iteration::solve"
        ]
        .map(String::from)
    );
    assert_eq!(
        wrong,
        ["geometry/gap.rs imports solution.rs, listed after it"]
    );
}

/// The import graph of the whole crate (`src/`, the command line's `main.rs` aside): each
/// module with the modules it imports, re-exported items counted for the module that defines
/// them, a `mod.rs` not importing its own files (it declares them).
fn crate_imports() -> BTreeMap<String, Vec<String>> {
    let mut files = BTreeMap::new();
    rust_files(Path::new(SRC), "", &mut files);
    files.remove("main.rs");
    let modules: Vec<String> = files.keys().map(|f| module_of(f)).collect();
    let aliases = reexports(&files, "crate::");
    (files.iter())
        .map(|(file, source)| {
            let module = module_of(file);
            let own = |import: &String| {
                file.ends_with("mod.rs") && import.starts_with(&format!("{module}::"))
            };
            let imported = imports(source, &module, "crate::", &modules, &aliases);
            let imported = (imported.into_iter())
                .filter(|import| *import != module && !own(import))
                .collect();
            (module, imported)
        })
        .collect()
}

/// A cycle of `graph` (its modules in import order, the first repeated at the end), if any.
fn a_cycle(graph: &BTreeMap<String, Vec<String>>) -> Option<Vec<String>> {
    fn visit(
        module: &str,
        graph: &BTreeMap<String, Vec<String>>,
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|m| m == module) {
            let mut cycle = path[at..].to_vec();
            cycle.push(module.to_string());
            return Some(cycle);
        }
        if done.iter().any(|m| m == module) {
            return None;
        }
        path.push(module.to_string());
        for next in graph.get(module).into_iter().flatten() {
            if let Some(cycle) = visit(next, graph, path, done) {
                return Some(cycle);
            }
        }
        path.pop();
        done.push(module.to_string());
        None
    }
    let mut done = Vec::new();
    (graph.keys()).find_map(|m| visit(m, graph, &mut Vec::new(), &mut done))
}

#[test]
fn no_two_files_of_the_crate_import_each_other_even_through_others() {
    let graph = crate_imports();
    assert!(graph.len() > 50, "the reader found {} modules", graph.len());
    // The reader must see the crate's imports: one known edge of each kind (a `crate::` path
    // through a re-export, and a `super::` path).
    assert!(graph["contact::coupled::coupled_solver"].contains(&"parallel::ranks".to_string()));
    assert!(graph["elastic::solve"].contains(&"elastic::assemble".to_string()));
    assert_eq!(a_cycle(&graph), None, "an import circle");
    // And the search must be able to find one.
    let circle = BTreeMap::from([
        ("a".to_string(), vec!["b".to_string()]),
        ("b".to_string(), vec!["c".to_string()]),
        ("c".to_string(), vec!["a".to_string()]),
    ]);
    assert_eq!(
        a_cycle(&circle),
        Some(["a", "b", "c", "a"].map(String::from).to_vec())
    );
}
