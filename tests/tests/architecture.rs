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
    "sun",
    "gpu",
    "light_volume",
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
    "far",
    "low_level",
];

/// voxel-lab, bottom up: the model, then the runs, then the report (its lib.rs docs).
const LAB: &[&str] = &[
    "error",
    "files",
    "limits",
    "progress",
    "random",
    "overlaps",
    "edges",
    "content",
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
    "far",
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

// Inside a module: the files of every module folder (a folder with a `mod.rs`) form a
// one-way stack. A file's sibling is a file `x.rs` or a folder `x/` of the same folder;
// `mod.rs` itself is the module's root, which its files may use and which uses them. A
// file uses a sibling through `super::x::…`, `crate::…::x::…`, or an item the module's
// `mod.rs` re-exports from it (`super::Item`). Doc-only (`#[cfg(doc)]`) and test code are
// left out: they may point anywhere.

/// `text` without comment lines and without the items behind `#[cfg(test)]` or
/// `#[cfg(doc)]` (a `mod x;`, a `use …;` or a `{ … }` block).
fn without_gated(text: &str) -> String {
    let mut text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    for attr in ["#[cfg(test)]", "#[cfg(doc)]"] {
        while let Some(at) = text.find(attr) {
            let after = at + attr.len();
            let semi = text[after..].find(';').map(|i| after + i);
            let brace = text[after..].find('{').map(|i| after + i);
            let end = match (semi, brace) {
                (Some(s), Some(b)) if s < b => s + 1,
                (Some(s), None) => s + 1,
                (_, Some(b)) => {
                    let mut depth = 0;
                    let mut end = text.len();
                    for (i, c) in text[b..].char_indices() {
                        match c {
                            '{' => depth += 1,
                            '}' => {
                                depth -= 1;
                                if depth == 0 {
                                    end = b + i + 1;
                                    break;
                                }
                            }
                            _ => {}
                        }
                    }
                    end
                }
                (None, None) => text.len(),
            };
            text.replace_range(at..end, "");
        }
    }
    text
}

/// The module path of a source file relative to its crate's `src/`: `stream/jobs.rs` is
/// `[stream, jobs]`, `stream/mod.rs` is `[stream]`, `lib.rs` is `[]`.
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(str::to_owned)
        .collect();
    if parts
        .last()
        .is_some_and(|p| p == "mod" || p == "lib" || p == "main")
    {
        parts.pop();
    }
    parts
}

fn ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The paths after each `crate::` or `super::` prefix of `text` (a `{…}` group gives one
/// per entry), made absolute from module `module`: `super::b::X` in `[m, a]` is `[m, b, X]`.
fn absolute_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < text.len() {
        let rest = &text[i..];
        let starts = (rest.starts_with("crate::") || rest.starts_with("super::"))
            && (i == 0 || !(ident_char(bytes[i - 1] as char) || bytes[i - 1] == b':'));
        if !starts {
            i += rest.chars().next().map_or(1, char::len_utf8);
            continue;
        }
        let mut base: Vec<String> = Vec::new();
        let mut rest = rest;
        if let Some(r) = rest.strip_prefix("crate::") {
            rest = r;
        } else {
            base = module.to_vec();
            while let Some(r) = rest.strip_prefix("super::") {
                base.pop();
                rest = r;
            }
        }
        // The path up to a `{…}` group, if any: `crate::m::{a::X, b}`.
        let head: String = rest
            .chars()
            .take_while(|c| ident_char(*c) || *c == ':')
            .collect();
        base.extend(
            head.split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_owned),
        );
        let rest = &rest[head.len()..];
        let entries: Vec<&str> = match rest.strip_prefix('{') {
            Some(group) => {
                // Top-level entries of the group (nested groups stay whole).
                let mut depth = 0;
                let mut start = 0;
                let mut entries = Vec::new();
                for (k, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => {
                            entries.push(&group[start..k]);
                            break;
                        }
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            entries.push(&group[start..k]);
                            start = k + 1;
                        }
                        _ => {}
                    }
                }
                entries
            }
            None => vec![""],
        };
        for e in entries {
            let e = e.trim_start();
            let path: String = e
                .chars()
                .take_while(|c| ident_char(*c) || *c == ':')
                .collect();
            let mut p = base.clone();
            p.extend(
                path.split("::")
                    .filter(|s| !s.is_empty())
                    .map(str::to_owned),
            );
            out.push(p);
        }
        i += 1;
    }
    out
}

/// Which child each name a module root (`mod.rs`) imports or re-exports comes from:
/// `pub use store::ChunkStore;` gives `ChunkStore → store`.
fn root_imports(root: &str, children: &[String]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for stmt in root.split(';') {
        let Some(at) = stmt.find("use ") else {
            continue;
        };
        if at > 0 && ident_char(stmt.as_bytes()[at - 1] as char) {
            continue;
        }
        let path = stmt[at + 4..].trim().trim_start_matches("self::");
        let Some((head, items)) = path.split_once("::") else {
            continue;
        };
        if !children.iter().any(|c| c == head.trim()) {
            continue;
        }
        for item in items.split(|c: char| "{}, \n".contains(c)) {
            let name = item.rsplit("::").next().unwrap_or("").trim();
            if !name.is_empty() && name != "self" && name != "as" && name != "*" {
                out.push((name.to_owned(), head.trim().to_owned()));
            }
        }
        // `X as Y`: the name is Y, which the split above also pushed.
    }
    out
}

/// The uses between siblings of every module folder of one crate, from its sources
/// (`(path relative to src/, text)`): folder → sorted `(from, to)` pairs.
fn sibling_uses(
    files: &[(String, String)],
) -> std::collections::BTreeMap<String, Vec<(String, String)>> {
    use std::collections::{BTreeMap, BTreeSet};
    let modules: Vec<Vec<String>> = files.iter().map(|(rel, _)| module_of(rel)).collect();
    // Children and root imports (item, child) of each module folder.
    type Folder = (Vec<String>, Vec<(String, String)>);
    let mut folders: BTreeMap<Vec<String>, Folder> = BTreeMap::new();
    for (rel, text) in files {
        if rel == "lib.rs" || rel.ends_with("/mod.rs") {
            let folder = module_of(rel);
            let children: Vec<String> = modules
                .iter()
                .filter(|m| m.len() == folder.len() + 1 && m.starts_with(&folder))
                .map(|m| m[folder.len()].clone())
                .collect();
            let imports = root_imports(&without_gated(text), &children);
            folders.insert(folder, (children, imports));
        }
    }
    // `[m, Alpha]`, where m's root imports Alpha from its file `a`, is `[m, a, Alpha]`
    // (the crate root's re-exports too: `crate::Alpha`).
    let resolve = |mut path: Vec<String>| {
        let mut k = 0;
        while k < path.len() {
            let Some((children, imports)) = folders.get(&path[..k]) else {
                break;
            };
            if !children.contains(&path[k]) {
                match imports.iter().find(|(item, _)| *item == path[k]) {
                    Some((_, child)) => path.insert(k, child.clone()),
                    None => break,
                }
            }
            k += 1;
        }
        path
    };
    let mut edges: BTreeMap<String, BTreeSet<(String, String)>> = BTreeMap::new();
    for ((rel, text), module) in files.iter().zip(&modules) {
        if rel.split('/').any(|p| p == "tests" || p == "tests.rs") {
            continue;
        }
        for path in absolute_paths(&without_gated(text), module) {
            let path = resolve(path);
            // Each module folder the file lies in (the crate root is the layer test's).
            for k in 1..module.len() {
                let folder = &module[..k];
                if !folders.contains_key(folder) || !path.starts_with(folder) || path.len() <= k {
                    continue;
                }
                let to = &path[k];
                if folders[folder].0.contains(to) && *to != module[k] {
                    edges
                        .entry(folder.join("/"))
                        .or_default()
                        .insert((module[k].clone(), to.clone()));
                }
            }
        }
    }
    edges
        .into_iter()
        .map(|(f, e)| (f, e.into_iter().collect()))
        .collect()
}

/// A cycle of `edges` as the names along it (`[a, b, a]`), if there is one.
fn find_cycle(edges: &[(String, String)]) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        edges: &[(String, String)],
        path: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == n) {
            let mut cycle = path[at..].to_vec();
            cycle.push(n.to_owned());
            return Some(cycle);
        }
        if done.iter().any(|d| d == n) {
            return None;
        }
        path.push(n.to_owned());
        for (_, to) in edges.iter().filter(|(from, _)| from == n) {
            if let Some(c) = visit(to, edges, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.push(n.to_owned());
        None
    }
    let mut done = Vec::new();
    edges
        .iter()
        .find_map(|(from, _)| visit(from, edges, &mut Vec::new(), &mut done))
}

/// Every source file of crate `name`, as `(path relative to src/, text)`.
fn crate_sources(name: &str) -> Vec<(String, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name)
        .join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let rel = p
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (rel, std::fs::read_to_string(&p).unwrap())
        })
        .collect()
}

#[test]
fn the_files_of_every_module_depend_one_way() {
    let mut cycles = Vec::new();
    let mut folders = 0;
    for name in [
        "voxel-core",
        "voxel-mesh",
        "voxel-render",
        "voxel-lab",
        "demo",
    ] {
        let files = crate_sources(name);
        folders += files.iter().filter(|(r, _)| r.ends_with("/mod.rs")).count();
        for (folder, edges) in sibling_uses(&files) {
            if let Some(c) = find_cycle(&edges) {
                cycles.push(format!("{name}/src/{folder}: {}", c.join(" -> ")));
            }
        }
    }
    assert!(folders >= 20, "the module folders are found: {folders}");
    assert!(
        cycles.is_empty(),
        "files of a module use each other: {cycles:#?}"
    );
}

#[test]
fn a_file_cycle_is_found() {
    let file = |rel: &str, text: &str| (rel.to_owned(), text.to_owned());
    // `a` uses `b` through the crate root's re-export, `b` uses `a` through its module's,
    // `c` uses `a` inside a group; `d`'s use of `c` is doc-only and a test of `c` may use `d`.
    let files = vec![
        file("lib.rs", "mod m;\npub use m::Beta;"),
        file(
            "m/mod.rs",
            "mod a;\nmod b;\nmod c;\nmod d;\n#[cfg(test)]\nmod tests;\npub use a::{Alpha, other as Renamed};\npub use b::Beta;\nuse c::Gamma;",
        ),
        file("m/a.rs", "use crate::Beta;\npub struct Alpha;"),
        file(
            "m/b.rs",
            "// use super::c::Gamma;\nuse super::Alpha;\npub struct Beta;",
        ),
        file(
            "m/c.rs",
            "use crate::m::{d::Delta, a::{self, Alpha}};\n#[cfg(test)]\nmod t { use super::super::d::Delta; }",
        ),
        file(
            "m/d.rs",
            "#[cfg(doc)]\nuse super::Gamma;\npub struct Delta;",
        ),
        file("m/tests.rs", "use super::c::Gamma;"),
    ];
    let uses = sibling_uses(&files);
    let pair = |a: &str, b: &str| (a.to_owned(), b.to_owned());
    assert_eq!(
        uses["m"],
        [
            pair("a", "b"),
            pair("b", "a"),
            pair("c", "a"),
            pair("c", "d")
        ]
    );
    assert_eq!(find_cycle(&uses["m"]).unwrap(), ["a", "b", "a"]);
    // Without the back-edge: a stack.
    let one_way: Vec<_> = uses["m"]
        .iter()
        .filter(|e| **e != pair("b", "a"))
        .cloned()
        .collect();
    assert_eq!(find_cycle(&one_way), None);
    // A longer cycle, and a file in a sub-folder reaching up with super::super.
    let three = [pair("x", "y"), pair("y", "z"), pair("z", "x")];
    assert_eq!(find_cycle(&three).unwrap(), ["x", "y", "z", "x"]);
    let nested = vec![
        file("m/mod.rs", "mod p;\nmod q;"),
        file("m/p/mod.rs", "mod inner;"),
        file("m/p/inner.rs", "fn f() { super::super::q::g() }"),
        file("m/q.rs", "use crate::m::p::inner;"),
    ];
    let uses = sibling_uses(&nested);
    assert_eq!(uses["m"], [pair("p", "q"), pair("q", "p")]);
}
