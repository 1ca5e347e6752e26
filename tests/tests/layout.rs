//! The house stays readable: no source file over 500 lines, and no import cycle between sibling
//! modules of a crate (`a::x` naming `b` through a `crate::`, `super::` or `self::` path while
//! `b` names `a`), in every crate a newcomer reads. How the sources are read is in
//! `needle_e2e::module_graph`; test code is not counted for cycles.

use needle_e2e::module_graph::{
    between_siblings, find_cycle, graph, graph_of, rust_files, tangles,
};
use needle_e2e::workspace;
use std::collections::BTreeSet;

const CRATES: &[&str] = &[
    "planner-core/src",
    "host-cli/src",
    "hil-sim/src",
    "sim/src",
    "firmware/src",
    "link/src",
    "devtools/src",
    "python/src",
    "anatomy/src",
    "scenario/src",
    "report/src",
    "device/src",
    "analysis/src",
    "simulate/src",
    "lab/src",
    "xtask/src",
    "motion/src",
];
const MAX_LINES: usize = 500;

/// Test code counts for length too (not for cycles).
const TESTS: &[&str] = &[
    "tests/src",
    "tests/tests",
    "planner-core/tests",
    "sim/tests",
    "igtl/src",
    "igtl/tests",
    "link/tests",
    "hil-sim/tests",
];

#[test]
fn no_source_file_is_over_500_lines() {
    let mut long = Vec::new();
    for dir in CRATES.iter().chain(TESTS) {
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
fn no_crate_has_an_import_cycle_between_sibling_modules() {
    let mut tangled = Vec::new();
    for dir in CRATES {
        for group in tangles(&between_siblings(&graph(&workspace().join(dir)))) {
            tangled.push(format!("{dir}: {group:?}"));
        }
    }
    assert!(
        tangled.is_empty(),
        "modules that import each other: {tangled:#?}"
    );
}

fn sources(files: &[(&str, &str)]) -> Vec<(String, String)> {
    files
        .iter()
        .map(|(m, s)| (m.to_string(), s.to_string()))
        .collect()
}

fn set(names: &[&str]) -> BTreeSet<String> {
    names.iter().map(|s| s.to_string()).collect()
}

#[test]
fn the_reader_follows_crate_super_and_self_paths_and_use_groups() {
    let g = graph_of(&sources(&[
        ("", "mod a; mod b;"),
        ("a", "mod x; mod y; mod z; pub use self::y::Thing;"),
        (
            "a::x",
            "use super::{y::{self, Y as Why}, super::b};\nfn f() { crate::b::z::go() }",
        ),
        (
            "a::y",
            "// use crate::b; in a comment\nconst S: &str = \"crate::b\";",
        ),
        (
            "a::z",
            "/// Drawn by [`super::x`], see [the steps](crate::b::z).\nfn f() {}",
        ),
        ("b", "mod z;"),
        ("b::z", "use crate::a::Thing;"),
    ]));
    assert_eq!(g["a::x"], set(&["a::y", "b", "b::z"]));
    assert_eq!(g["a::y"], set(&[]), "comments and strings are not imports");
    assert_eq!(
        g["b::z"],
        set(&["a::y"]),
        "a re-export is followed to where it is defined"
    );
    assert_eq!(g["a"], set(&["a::y"]));
    assert_eq!(g["a::z"], set(&[]), "an intra-doc link is no import");
}

#[test]
fn the_reader_leaves_test_code_out() {
    let g = graph_of(&sources(&[
        ("", "mod a; mod b;"),
        (
            "a",
            "#[cfg(test)]\nmod tests;\nuse crate::b::B;\n#[cfg(test)]\nfn t() { crate::c::C }",
        ),
        ("a::tests", "use crate::c;"),
        ("b", ""),
        ("c", ""),
    ]));
    assert_eq!(
        g["a"],
        set(&["b"]),
        "code after a test item is read, the test item is not"
    );
    assert!(
        !g.contains_key("a::tests"),
        "a module declared under #[cfg(test)] is not read"
    );
}

#[test]
fn the_cycle_finder_sees_a_cycle_between_siblings_through_super() {
    let mut files = vec![
        ("", "mod s;"),
        ("s", "mod replan; mod aimed;"),
        ("s::replan", "fn r() { super::aimed::aim() }"),
        ("s::aimed", "use super::replan::Input;"),
    ];
    let g = between_siblings(&graph_of(&sources(&files)));
    assert!(find_cycle(&g).is_some(), "{g:?}");
    assert_eq!(tangles(&g), vec![set(&["s::aimed", "s::replan"])]);
    files[2] = ("s::replan", "fn r() {}");
    let g = between_siblings(&graph_of(&sources(&files)));
    assert_eq!(find_cycle(&g), None);
    assert!(tangles(&g).is_empty());
}

#[test]
fn a_module_naming_its_parent_or_child_is_no_sibling_cycle() {
    let g = graph_of(&sources(&[
        ("", "mod a;"),
        ("a", "mod x; pub use x::X; pub struct P;"),
        ("a::x", "use super::P;"),
    ]));
    assert_eq!(find_cycle(&between_siblings(&g)), None);
}

#[test]
fn a_cycle_through_nested_modules_is_a_cycle_of_their_ancestors() {
    let g = graph_of(&sources(&[
        ("", "mod a; mod b;"),
        ("a", "mod x;"),
        ("a::x", "use crate::b::B;"),
        ("b", "use crate::a::x::X;"),
    ]));
    assert_eq!(tangles(&between_siblings(&g)), vec![set(&["a", "b"])]);
}
