//! The shape of `src/contact/`: its module doc lists the files in the order of one solve, and
//! each file imports only files listed before it. The imports then run one way (no cycle), and
//! a newcomer can read the files in that order.

use std::collections::BTreeMap;
use std::path::Path;

const CONTACT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src/contact");

/// The `name.rs` files the module doc of `mod.rs` names, in order of first mention.
fn documented_order(mod_rs: &str) -> Vec<String> {
    let mut order: Vec<String> = Vec::new();
    for line in mod_rs.lines().take_while(|l| l.starts_with("//!")) {
        for (i, piece) in line.split('`').enumerate() {
            let name = piece.strip_suffix(".rs");
            let name = name.filter(|n| i % 2 == 1 && !n.contains('/'));
            if let Some(name) = name.filter(|n| !order.iter().any(|o| o == n)) {
                order.push(name.to_string());
            }
        }
    }
    order
}

/// The items `mod.rs` re-exports, by the module that defines them.
fn reexports(mod_rs: &str) -> BTreeMap<String, String> {
    let mut items = BTreeMap::new();
    let text = mod_rs.replace('\n', " ");
    for statement in text.split(';') {
        let Some(path) = statement.trim().strip_prefix("pub use ") else {
            continue;
        };
        let Some((module, names)) = path.split_once("::") else {
            continue;
        };
        for name in names.split(|c: char| !(c.is_alphanumeric() || c == '_')) {
            if !name.is_empty() {
                items.insert(name.to_string(), module.to_string());
            }
        }
    }
    items
}

/// The sibling modules a file's code refers to through `super::` (comments and the unit
/// tests left out; a re-exported item counts for the module that defines it).
fn imports(source: &str, modules: &[String], items: &BTreeMap<String, String>) -> Vec<String> {
    let code: String = (source.split("#[cfg(test)]").next().unwrap().lines())
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let mut found = Vec::new();
    for (_, rest) in code
        .match_indices("super::")
        .map(|(i, _)| code.split_at(i + 7))
    {
        let names: Vec<&str> = match rest.strip_prefix('{') {
            Some(group) => group[..group.find('}').unwrap_or(group.len())]
                .split(',')
                .map(|n| n.trim().split("::").next().unwrap_or(""))
                .collect(),
            None => vec![
                rest.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .next()
                    .unwrap(),
            ],
        };
        for name in names {
            let module = match items.get(name) {
                Some(module) => module.clone(),
                None => name.to_string(),
            };
            if modules.contains(&module) && !found.contains(&module) {
                found.push(module);
            }
        }
    }
    found
}

#[test]
fn contact_files_import_only_files_listed_before_them() {
    let mod_rs = std::fs::read_to_string(Path::new(CONTACT).join("mod.rs")).unwrap();
    let order = documented_order(&mod_rs);
    let mut files: Vec<String> = std::fs::read_dir(CONTACT)
        .unwrap()
        .map(|entry| entry.unwrap().file_name().into_string().unwrap())
        .filter_map(|name| name.strip_suffix(".rs").map(str::to_string))
        .filter(|name| name != "mod")
        .collect();
    files.sort();
    let mut listed = order.clone();
    listed.sort();
    assert_eq!(
        listed, files,
        "the module doc of src/contact/mod.rs lists every file once"
    );

    let items = reexports(&mod_rs);
    let mut wrong = Vec::new();
    for (position, file) in order.iter().enumerate() {
        let source = std::fs::read_to_string(Path::new(CONTACT).join(format!("{file}.rs")));
        for module in imports(&source.unwrap(), &order, &items) {
            let at = order.iter().position(|o| *o == module).unwrap();
            if at >= position && module != *file {
                wrong.push(format!("{file}.rs imports {module}.rs, listed after it"));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_import_reader_sees_grouped_and_reexported_imports() {
    // The check above must be able to fail: a file that imports a later one is found, through
    // a grouped import and through an item re-exported by mod.rs.
    let modules: Vec<String> = ["solve", "solution", "gap"].map(String::from).to_vec();
    let items = BTreeMap::from([("ContactSolution".to_string(), "solution".to_string())]);
    let source = "use super::{ContactSolution, gap::gap_rows};\n// super::solve in a comment\n\
                  fn f() { super::solve::run(); }\n#[cfg(test)]\nuse super::nothing;";
    assert_eq!(
        imports(source, &modules, &items),
        ["solution", "gap", "solve"].map(String::from)
    );
}
