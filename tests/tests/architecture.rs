//! Module dependencies point one way: inside `voxel-render` and inside `voxel-lab`, a module
//! may only reach (through `crate::` paths, or items the crate root re-exports) the modules
//! listed before it in its crate's layer list. Checked on the source text, so a new
//! back-edge, and with it a cycle, fails here.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use std::path::{Path, PathBuf};

/// voxel-render, bottom up (its lib.rs docs give the same order).
const RENDER: &[&str] = &[
    "error",
    "context",
    "ladder",
    "camera",
    "readback",
    "submission",
    "timing",
    "cost",
    "fetch",
    "gpu",
    "bindings",
    "textures",
    "arena",
    "layers",
    "chunks",
    "medium",
    "stages",
    "oit",
    "renderer",
    "content",
    "stream",
    "low_level",
];

/// voxel-lab, bottom up: the model, then the runs, then the report (its lib.rs docs).
const LAB: &[&str] = &[
    "error",
    "files",
    "limits",
    "progress",
    "random",
    "edges",
    "content",
    "overlaps",
    "raymarch",
    "summary",
    "metrics",
    "scene",
    "headless",
    "eval",
    "stability",
    "distribution",
    "charts",
    "costs",
    "report",
    "stream",
    "gallery",
    "backends",
];

/// The module each item re-exported by lib.rs (`pub use module::{A, B};`) comes from.
fn reexports(lib: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for stmt in lib.split("pub use ").skip(1) {
        let stmt = &stmt[..stmt.find(';').unwrap_or(stmt.len())];
        let Some((module, items)) = stmt.split_once("::") else {
            continue;
        };
        for item in items.split(|c: char| "{}, \n".contains(c)) {
            let item = item.rsplit("::").next().unwrap_or("").trim();
            if !item.is_empty() {
                out.push((item.to_owned(), module.trim().to_owned()));
            }
        }
    }
    out
}

/// The modules `source` reaches through `crate::module` paths, or through items lib.rs
/// re-exports (`crate::Renderer` is `renderer`).
fn uses(source: &str, reexported: &[(String, String)]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for (i, _) in source.match_indices("crate::") {
        let rest = &source[i + 7..];
        let names: Vec<&str> = match rest.strip_prefix('{') {
            Some(group) => group[..group.find('}').unwrap_or(0)]
                .split(',')
                .map(str::trim)
                .collect(),
            None => vec![rest],
        };
        for n in names {
            let name: String = n
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            let module = if name.starts_with(|c: char| c.is_ascii_lowercase()) {
                Some(name)
            } else {
                reexported
                    .iter()
                    .find(|(item, _)| *item == name)
                    .map(|(_, m)| m.clone())
            };
            if let Some(m) = module.filter(|m| !out.contains(m)) {
                out.push(m);
            }
        }
    }
    out
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every back-edge of crate `name`: `file uses crate::x, above its module`.
fn back_edges(name: &str, layers: &[&str]) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name)
        .join("src");
    let reexported = reexports(&std::fs::read_to_string(src.join("lib.rs")).unwrap());
    let rank = |m: &str| layers.iter().position(|l| *l == m);
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut out = Vec::new();
    for path in files {
        let rel = path.strip_prefix(&src).unwrap().to_path_buf();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let top = top.trim_end_matches(".rs");
        if top == "lib" || top == "wgsl_layout" {
            continue;
        }
        let own = rank(top).unwrap_or_else(|| panic!("{name}: module {top} is not in the layers"));
        // Test code may reach anywhere: test modules in files of their own too.
        if rel
            .components()
            .any(|c| c.as_os_str() == "tests" || c.as_os_str() == "tests.rs")
        {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        // Test code may reach anywhere.
        let text = text.split("#[cfg(test)]").next().unwrap_or("");
        for used in uses(text, &reexported) {
            if used == "wgsl_layout" || used == "chain" {
                continue;
            }
            match rank(&used) {
                Some(r) if r <= own => {}
                _ => out.push(format!(
                    "{}: uses crate::{used}, above {top}",
                    rel.display()
                )),
            }
        }
    }
    out
}

#[test]
fn voxel_render_modules_depend_one_way() {
    let reexported = reexports(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../voxel-render/src/lib.rs"),
        )
        .unwrap(),
    );
    assert!(
        reexported
            .iter()
            .any(|(i, m)| i == "Renderer" && m == "renderer"),
        "the re-export parser reads lib.rs"
    );
    let edges = back_edges("voxel-render", RENDER);
    assert!(edges.is_empty(), "{edges:#?}");
}

#[test]
fn voxel_lab_modules_depend_one_way() {
    let edges = back_edges("voxel-lab", LAB);
    assert!(edges.is_empty(), "{edges:#?}");
}

#[test]
fn a_back_edge_is_found() {
    // The checker itself: report uses eval (fine), eval pretending to use report is not.
    let reexported = vec![("Report".to_owned(), "report".to_owned())];
    assert_eq!(
        uses("use crate::{eval::x, Report};", &reexported),
        ["eval", "report"]
    );
}
