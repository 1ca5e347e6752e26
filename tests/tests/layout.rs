//! The house stays readable: no source file over 500 lines and no import cycle between the
//! modules of a crate (module A naming `crate::b` while b names `crate::a`), in every crate a
//! newcomer reads. Test code (after `#[cfg(test)]`) is not counted for cycles.

use needle_e2e::workspace;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CRATES: [&str; 8] = [
    "planner-core/src",
    "host-cli/src",
    "hil-sim/src",
    "sim/src",
    "firmware/src",
    "link/src",
    "devtools/src",
    "python/src",
];
const MAX_LINES: usize = 500;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("source folder").flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `a/b/mod.rs` and `a/b.rs` are module `a::b`; `lib.rs` and `main.rs` the crate root.
fn module_name(root: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(root).unwrap().with_extension("");
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .filter(|p| p != "mod")
        .collect();
    match parts.as_slice() {
        [only] if only == "lib" || only == "main" => String::new(),
        _ => parts.join("::"),
    }
}

/// The modules `source` names through `crate::` paths, resolved to the longest known module.
fn dependencies(source: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let code = source.split("#[cfg(test)]").next().unwrap_or("");
    let mut deps = BTreeSet::new();
    for (at, _) in code.match_indices("crate::") {
        let path: String = code[at + 7..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect();
        let parts: Vec<&str> = path.split("::").filter(|p| !p.is_empty()).collect();
        for k in (1..=parts.len()).rev() {
            let candidate = parts[..k].join("::");
            if modules.contains(&candidate) {
                deps.insert(candidate);
                break;
            }
        }
    }
    deps
}

/// A cycle in `graph`, if there is one, as the modules along it.
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(i) = path.iter().position(|p| p == node) {
            let mut cycle = path[i..].to_vec();
            cycle.push(node.to_string());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, graph, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|n| visit(n, graph, &mut Vec::new(), &mut done))
}

#[test]
fn no_source_file_is_over_500_lines() {
    let mut long = Vec::new();
    for dir in CRATES {
        let mut files = Vec::new();
        rust_files(&workspace().join(dir), &mut files);
        assert!(!files.is_empty(), "{dir} has no sources");
        for f in files {
            let lines = std::fs::read_to_string(&f).unwrap().lines().count();
            if lines > MAX_LINES {
                long.push(format!("{}: {lines} lines", f.display()));
            }
        }
    }
    assert!(long.is_empty(), "split by concern: {long:#?}");
}

#[test]
fn no_crate_has_an_import_cycle_between_its_modules() {
    for dir in CRATES {
        let root = workspace().join(dir);
        let mut files = Vec::new();
        rust_files(&root, &mut files);
        let sources: Vec<(String, String)> = files
            .iter()
            .map(|f| (module_name(&root, f), std::fs::read_to_string(f).unwrap()))
            .collect();
        let modules: BTreeSet<String> = sources.iter().map(|(m, _)| m.clone()).collect();
        let graph: BTreeMap<String, BTreeSet<String>> = sources
            .iter()
            .map(|(m, src)| {
                let mut deps = dependencies(src, &modules);
                deps.remove(m);
                deps.remove("");
                (m.clone(), deps)
            })
            .collect();
        assert_eq!(find_cycle(&graph), None, "{dir}");
    }
}

#[test]
fn the_cycle_finder_sees_a_cycle() {
    let modules: BTreeSet<String> = ["a", "b", "b::c"].iter().map(|s| s.to_string()).collect();
    let deps = dependencies("use crate::b::c::Thing;\nuse crate::a;", &modules);
    assert_eq!(deps, ["a", "b::c"].iter().map(|s| s.to_string()).collect());
    let mut graph = BTreeMap::new();
    graph.insert("a".to_string(), BTreeSet::from(["b::c".to_string()]));
    graph.insert("b::c".to_string(), BTreeSet::from(["a".to_string()]));
    assert!(find_cycle(&graph).is_some());
    graph.insert("b::c".to_string(), BTreeSet::new());
    assert_eq!(find_cycle(&graph), None);
}
