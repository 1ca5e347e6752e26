//! The import graph of a crate's modules, read from its sources, and the cycles in it.
//!
//! Each source file is one module (`a/b.rs` and `a/b/mod.rs` are `a::b`; `lib.rs` and `main.rs`
//! the crate root, named ""). A module depends on every module it names through a `crate::`,
//! `super::` or `self::` path (`use` groups such as `use super::{a, b::{c, D}}` included), or
//! through a `use` of its own child modules; a name that a module re-exports with `pub use` is
//! followed to the module that defines it, so a re-export in a parent cannot hide a dependency.
//! Comments, string literals and test code (the item after each `#[cfg(test)]`, and every module
//! declared under one) are not read.
//!
//! Two modules are siblings when they have the same parent. A dependency of `a::x` on `b::y`
//! (with `a` and `b` siblings) is a dependency of `a` on `b`; a module naming its own ancestor or
//! descendant is not a sibling dependency. [`sibling_cycle`] finds a cycle between siblings.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The module graph of one crate: each module's dependencies, by module path.
pub type Graph = BTreeMap<String, BTreeSet<String>>;

/// Every `.rs` file under `dir`.
pub fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
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
pub fn module_name(root: &Path, file: &Path) -> String {
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

fn parent(module: &str) -> String {
    module
        .rsplit_once("::")
        .map_or(String::new(), |(p, _)| p.to_string())
}

fn join(module: &str, name: &str) -> String {
    if module.is_empty() {
        name.to_string()
    } else {
        format!("{module}::{name}")
    }
}

/// `source` without comments (intra-doc links name no import) and with string and char literals
/// emptied.
fn code_only(source: &str) -> String {
    let s: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < s.len() {
        match (s[i], s.get(i + 1).copied()) {
            ('/', Some('/')) => {
                while i < s.len() && s[i] != '\n' {
                    i += 1;
                }
            }
            ('/', Some('*')) => {
                let mut depth = 0;
                while i < s.len() {
                    if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                        depth += 1;
                        i += 2;
                    } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
                out.push(' ');
            }
            ('r', Some('#' | '"')) if i == 0 || !ident_char(s[i - 1]) => {
                let hashes = s[i + 1..].iter().take_while(|c| **c == '#').count();
                if s.get(i + 1 + hashes) != Some(&'"') {
                    out.push(s[i]);
                    i += 1;
                    continue;
                }
                i += hashes + 2;
                while i < s.len()
                    && !(s[i] == '"' && s[i + 1..].iter().take(hashes).all(|c| *c == '#'))
                {
                    i += 1;
                }
                i += 1 + hashes;
                out.push_str("\"\"");
            }
            ('"', _) => {
                i += 1;
                while i < s.len() && s[i] != '"' {
                    i += if s[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            ('\'', Some('\\')) => {
                i += 2;
                while i < s.len() && s[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
            }
            ('\'', Some(_)) if s.get(i + 2) == Some(&'\'') => {
                i += 3;
                out.push_str("' '");
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

fn ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// `code` without the item after each `#[cfg(test)]`, and the names of the modules declared there.
fn without_tests(code: &str) -> (String, Vec<String>) {
    const MARK: &str = "#[cfg(test)]";
    let mut kept = String::new();
    let mut test_modules = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(MARK) {
        kept.push_str(&rest[..at]);
        let item = &rest[at + MARK.len()..];
        let Some(end) = item.find([';', '{']) else {
            return (kept, test_modules);
        };
        let head: Vec<&str> = item[..end].split_whitespace().collect();
        if let Some(i) = head.iter().position(|w| *w == "mod") {
            if let Some(name) = head.get(i + 1) {
                test_modules.push(name.to_string());
            }
        }
        let mut close = end + 1;
        if item.as_bytes()[end] == b'{' {
            let mut depth = 1;
            for (j, c) in item[end + 1..].char_indices() {
                depth += match c {
                    '{' => 1,
                    '}' => -1,
                    _ => 0,
                };
                if depth == 0 {
                    close = end + 1 + j + 1;
                    break;
                }
            }
            if depth != 0 {
                close = item.len();
            }
        }
        rest = &item[close..];
    }
    kept.push_str(rest);
    (kept, test_modules)
}

/// The leaves of the use tree at the start of `text`, each as its path segments, and how much of
/// `text` the tree took. `*` is a leaf of no more segments; `as` renames are dropped.
fn use_tree(text: &str) -> (Vec<Vec<String>>, usize) {
    let mut segments = Vec::new();
    let mut i = 0;
    let b = text.as_bytes();
    loop {
        while i < b.len() && (b[i] as char).is_whitespace() {
            i += 1;
        }
        if i < b.len() && b[i] == b'{' {
            let mut leaves = Vec::new();
            i += 1;
            loop {
                let (sub, used) = use_tree(&text[i..]);
                leaves.extend(sub.into_iter().map(|s| [segments.clone(), s].concat()));
                i += used;
                while i < b.len() && (b[i] as char).is_whitespace() {
                    i += 1;
                }
                match b.get(i) {
                    Some(b',') => i += 1,
                    Some(b'}') => return (leaves, i + 1),
                    _ => return (leaves, i),
                }
                while i < b.len() && (b[i] as char).is_whitespace() {
                    i += 1;
                }
                if b.get(i) == Some(&b'}') {
                    return (leaves, i + 1);
                }
            }
        }
        let start = i;
        while i < b.len() && (ident_char(b[i] as char) || b[i] == b'*') {
            i += 1;
        }
        if start == i {
            return (vec![segments], i);
        }
        segments.push(text[start..i].to_string());
        if text[i..].starts_with("::") {
            i += 2;
            continue;
        }
        let after = text[i..].trim_start();
        if let Some(alias) = after.strip_prefix("as ") {
            let alias = alias.trim_start();
            let name = alias.find(|c: char| !ident_char(c)).unwrap_or(alias.len());
            i = text.len() - alias.len() + name;
        }
        return (vec![segments], i);
    }
}

/// One module's source, read: the paths it names (absolute, as segments) and what it re-exports.
struct Read {
    paths: Vec<Vec<String>>,
    /// A re-exported name and the absolute path it stands for.
    exports: BTreeMap<String, Vec<String>>,
    test_modules: Vec<String>,
}

fn absolute(module: &str, first: &str, rest: &[String]) -> Option<Vec<String>> {
    let mut base: Vec<String> = match first {
        "crate" => Vec::new(),
        "self" => split(module),
        "super" => split(&parent(module)),
        _ => return None,
    };
    let mut rest = rest;
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

fn split(module: &str) -> Vec<String> {
    module
        .split("::")
        .filter(|p| !p.is_empty())
        .map(String::from)
        .collect()
}

fn read(module: &str, source: &str, modules: &BTreeSet<String>) -> Read {
    let (code, test_modules) = without_tests(&code_only(source));
    let mut paths = Vec::new();
    let mut exports = BTreeMap::new();
    let mut starts: Vec<usize> = ["crate::", "super::", "self::"]
        .iter()
        .flat_map(|p| code.match_indices(p).map(|(at, _)| at))
        .collect();
    starts.sort_unstable();
    // A path inside a group read before (`use super::{a, super::b}`) is a leaf of that group.
    let mut read_to = 0;
    for at in starts {
        let before = code[..at].chars().next_back();
        if at < read_to || before.is_some_and(|c| ident_char(c) || c == ':') {
            continue;
        }
        let (leaves, used) = use_tree(&code[at..]);
        read_to = at + used;
        for leaf in leaves {
            if let Some(path) = leaf.split_first().and_then(|(f, r)| absolute(module, f, r)) {
                paths.push(path);
            }
        }
    }
    // `use` items: bare paths through the module's own children, and `pub use` re-exports.
    for (at, _) in code.match_indices("use ") {
        let head = code[..at].trim_end();
        let line_start = head.rfind([';', '{', '}', ']']).map_or(0, |p| p + 1);
        let prefix = head[line_start..].trim();
        if !(prefix.is_empty() || prefix.starts_with("pub"))
            || code[..at].chars().next_back().is_some_and(ident_char)
        {
            continue;
        }
        let (leaves, _) = use_tree(&code[at + 4..]);
        for leaf in leaves {
            let Some((first, rest)) = leaf.split_first() else {
                continue;
            };
            let path = absolute(module, first, rest).or_else(|| {
                modules
                    .contains(&join(module, first))
                    .then(|| [split(module), leaf.clone()].concat())
            });
            let Some(path) = path else { continue };
            if absolute(module, first, rest).is_none() {
                paths.push(path.clone());
            }
            if prefix.starts_with("pub") {
                if let Some(name) = path.last().filter(|n| *n != "*" && *n != "self") {
                    exports.insert(name.clone(), path.clone());
                }
            }
        }
    }
    Read {
        paths,
        exports,
        test_modules,
    }
}

/// The module an absolute path lands in: the longest known module prefix, following re-exports
/// of the name after it (at most a few hops, so a re-export loop cannot hang the check).
fn resolve(path: &[String], modules: &BTreeSet<String>, reads: &BTreeMap<String, Read>) -> String {
    let mut path = path.to_vec();
    for _ in 0..8 {
        let k = (0..=path.len())
            .rev()
            .find(|k| modules.contains(&path[..*k].join("::")) || *k == 0)
            .unwrap_or(0);
        let module = path[..k].join("::");
        let next = path.get(k).and_then(|n| reads.get(&module)?.exports.get(n));
        match next {
            Some(target) if target[..] != path[..] => {
                path = [target.clone(), path[k + 1..].to_vec()].concat();
            }
            _ => return module,
        }
    }
    String::new()
}

/// The module graph of the crate whose sources are under `root`, test modules left out.
pub fn graph(root: &Path) -> Graph {
    let mut files = Vec::new();
    rust_files(root, &mut files);
    let sources: Vec<(String, String)> = files
        .iter()
        .map(|f| (module_name(root, f), std::fs::read_to_string(f).unwrap()))
        .collect();
    graph_of(&sources)
}

/// The module graph of `(module, source)` pairs, test modules left out.
pub fn graph_of(sources: &[(String, String)]) -> Graph {
    let modules: BTreeSet<String> = sources.iter().map(|(m, _)| m.clone()).collect();
    let reads: BTreeMap<String, Read> = sources
        .iter()
        .map(|(m, src)| (m.clone(), read(m, src, &modules)))
        .collect();
    let tests: Vec<String> = reads
        .iter()
        .flat_map(|(m, r)| r.test_modules.iter().map(move |t| join(m, t)))
        .collect();
    let is_test = |m: &str| {
        tests
            .iter()
            .any(|t| m == t || m.starts_with(&format!("{t}::")))
    };
    reads
        .iter()
        .filter(|(m, _)| !is_test(m))
        .map(|(m, r)| {
            let deps = r
                .paths
                .iter()
                .map(|p| resolve(p, &modules, &reads))
                .filter(|d| d != m && !is_test(d))
                .collect();
            (m.clone(), deps)
        })
        .collect()
}

/// `graph` seen between siblings: `a::x -> b::y` becomes `a -> b` for siblings `a` and `b`;
/// a dependency on an ancestor or a descendant is dropped.
pub fn between_siblings(graph: &Graph) -> Graph {
    let mut out = Graph::new();
    for (from, deps) in graph {
        for to in deps {
            let (a, b) = (split(from), split(to));
            let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
            if common == a.len() || common == b.len() {
                continue;
            }
            let sibling = |p: &[String]| p[..=common].join("::");
            out.entry(sibling(&a)).or_default().insert(sibling(&b));
        }
    }
    out
}

/// A cycle in `graph`, if there is one, as the modules along it.
pub fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
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

/// The groups of modules of `graph` that reach each other (the strongly connected components
/// of more than one module), each sorted, the groups in order.
pub fn tangles(graph: &Graph) -> Vec<BTreeSet<String>> {
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_string()];
        while let Some(n) = todo.pop() {
            for next in graph.get(&n).into_iter().flatten() {
                if seen.insert(next.clone()) {
                    todo.push(next.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> =
        graph.keys().map(|n| (n, reach(n))).collect();
    let mut groups: BTreeSet<BTreeSet<String>> = BTreeSet::new();
    for (n, seen) in &reached {
        let group: BTreeSet<String> = seen
            .iter()
            .filter(|m| reached.get(m).is_some_and(|back| back.contains(*n)))
            .cloned()
            .collect();
        if group.len() > 1 {
            groups.insert(group);
        }
    }
    groups.into_iter().collect()
}
