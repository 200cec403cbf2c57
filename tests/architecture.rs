//! The module graph of the library has layers (docs/ARCHITECTURE.md): a module may use only
//! modules of lower layers, so the graph has no import circle and no arrow from a lower layer to
//! a higher one. This test reads every file under `src/` and checks each `crate::` path of its
//! production code (a file's `#[cfg(test)]` module, which closes a file, and `tests.rs` files may
//! use anything).

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// The layers, lowest first. A module of layer `i` may use modules of layers `< i`.
const LAYERS: &[&[&str]] = &[
    // the one error type
    &["error"],
    // vocabulary every part shares
    &["scalar", "linalg", "select", "sum", "prefetch", "simd"],
    &[
        "points", "parallel", "progress", "scatter", "names", "metric",
    ],
    // the caller's points, validated and packed
    &["packed"],
    // queries and their baselines (brute force, PCA sweep), then tables of their answers
    &["query"],
    &["table"],
    // the neighbour index: every query once, over what each flavour provides (Chapter 5)
    &["index"],
    // the k-d tree (Chapters 3, 5, 6)
    &["tree"],
    // normals, curvatures (Chapter 2); files; the dynamic forest of trees; point filters (outlier removal)
    &["geometry", "io", "dynamic", "filter"],
    // smoothing (Chapter 2); analytic test shapes and their metrics
    &["smooth", "shapes", "handle"],
    // the C ABI over all of it
    &["ffi"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file under `src/` belongs to (`None` for `lib.rs`).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).expect("under src/");
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    if first == "lib.rs" {
        return None;
    }
    Some(first.trim_end_matches(".rs").to_string())
}

/// The production part of a file: everything before its first `#[cfg(test)]`.
fn production(text: &str) -> &str {
    text.find("#[cfg(test)]").map_or(text, |i| &text[..i])
}

/// Names the crate root re-exports (`pub use module::...::Name;` and `pub use module::{A, B}`),
/// mapped to the module they come from, so that `crate::Name` counts as a use of that module.
fn root_reexports(lib: &str) -> BTreeMap<String, String> {
    let mut map = BTreeMap::new();
    for stmt in lib.split(';') {
        let stmt = stmt.trim();
        let Some(path) = stmt.strip_prefix("pub use ") else {
            continue;
        };
        let module = path.split("::").next().unwrap_or("").trim().to_string();
        let names = match (path.find('{'), path.rfind('}')) {
            (Some(a), Some(b)) => path[a + 1..b].split(',').map(str::trim).collect(),
            _ => vec![path.rsplit("::").next().unwrap_or("").trim()],
        };
        for name in names.into_iter().filter(|n| !n.is_empty()) {
            map.insert(name.to_string(), module.clone());
        }
    }
    map
}

/// Every module a text names through `crate::` (`crate::a::...`, `crate::{a, b::c}`, and the
/// root's re-exports).
fn crate_uses(text: &str, reexports: &BTreeMap<String, String>) -> Vec<String> {
    let mut used = Vec::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut add = |name: String| {
        let module = reexports.get(&name).cloned().unwrap_or(name);
        if !module.is_empty() {
            used.push(module);
        }
    };
    for (i, _) in text.match_indices("crate::") {
        // `pub(crate)` and `$crate::` are not paths into the crate root
        if text[..i].ends_with('$') {
            continue;
        }
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            // the items of the group at its top level: `a::x`, `b::{y, z}`, `Name`
            let mut depth = 1;
            let mut item_start = 0;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' | ',' if depth == 1 => {
                        add(ident(group[item_start..j].trim_start()));
                        item_start = j + 1;
                        if c == '}' {
                            break;
                        }
                    }
                    '}' => depth -= 1,
                    _ => {}
                }
            }
        } else {
            add(ident(rest));
        }
    }
    used
}

/// Macros a module exports (`#[macro_export] macro_rules! name`), which live at the crate root:
/// `crate::name` is a use of that module.
fn exported_macros(module: &str, text: &str, out: &mut BTreeMap<String, String>) {
    for (i, _) in text.match_indices("#[macro_export]") {
        let rest = &text[i..];
        if let Some(at) = rest.find("macro_rules!") {
            let name: String = rest[at + "macro_rules!".len()..]
                .trim_start()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.insert(name, module.to_string());
        }
    }
}

#[test]
fn every_module_uses_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = fs::read_to_string(src.join("lib.rs")).expect("src/lib.rs");
    let mut reexports = root_reexports(&lib);
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    for file in &files {
        if let Some(module) = module_of(&src, file) {
            let text = fs::read_to_string(file).expect("a source file");
            exported_macros(&module, &text, &mut reexports);
        }
    }
    let mut violations = Vec::new();
    let mut unplaced = Vec::new();
    for file in &files {
        let Some(module) = module_of(&src, file) else {
            continue;
        };
        let Some(layer) = layer_of(&module) else {
            unplaced.push(module);
            continue;
        };
        // a `tests.rs` file is a test module (`#[cfg(test)] mod tests;`)
        if file.file_name().is_some_and(|f| f == "tests.rs") {
            continue;
        }
        let text = fs::read_to_string(file).expect("a source file");
        for used in crate_uses(production(&text), &reexports) {
            if used == module {
                continue;
            }
            match layer_of(&used) {
                Some(l) if l < layer => {}
                _ => violations.push(format!(
                    "{} ({module}, layer {layer}) uses crate::{used} (layer {:?})",
                    file.strip_prefix(&src).unwrap().display(),
                    layer_of(&used)
                )),
            }
        }
    }
    unplaced.sort();
    unplaced.dedup();
    assert!(
        unplaced.is_empty(),
        "modules without a layer (add them to LAYERS and docs/ARCHITECTURE.md): {unplaced:?}"
    );
    assert!(
        violations.is_empty(),
        "arrows to the same or a higher layer:\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_reader_finds_grouped_and_reexported_uses() {
    let reexports = root_reexports("pub use error::{NbhdError, Result};\npub use tree::KdTree;");
    let uses = crate_uses(
        "use crate::{query::Neighbor, table::{A, B}, KdTree};\nlet e: crate::Result<()>;\npub(crate) fn f() {}",
        &reexports,
    );
    assert_eq!(uses, ["query", "table", "tree", "error"]);
}

// ---- One neighbour index (docs/ARCHITECTURE.md, "One index") ----
//
// Every query is written once, in `src/index/`, over the few facts each flavour provides. The
// checks below fail when a second copy of the query family, of its result collectors, of the
// persistence envelope or of the runtime dispatch appears beside it.

/// The query family of `NeighborIndex`: a definition of one of these names outside
/// `src/index/` is a second implementation, unless it is listed in [`QUERY_NAMES_ELSEWHERE`].
const QUERY_NAMES: &[&str] = &[
    "knn",
    "radius",
    "knn_radius",
    "in_box",
    "in_boxes",
    "neighborhoods",
    "neighborhoods_at",
    "neighborhoods_of",
    "spacing",
    "pairs",
    "pairs_with",
    "count_pairs_with",
    "weigh_pairs_with",
];

/// Definitions of a query name outside `src/index/` that are not a second implementation:
/// (file under `src/`, name, why).
const QUERY_NAMES_ELSEWHERE: &[(&str, &str, &str)] = &[
    // the runtime handle: one line each, dispatching to the typed index's trait method
    ("handle.rs", "neighborhoods", "dispatch"),
    ("handle.rs", "neighborhoods_at", "dispatch"),
    ("handle.rs", "neighborhoods_of", "dispatch"),
    ("handle.rs", "in_boxes", "dispatch"),
    ("handle.rs", "spacing", "dispatch"),
    ("handle.rs", "pairs", "dispatch"),
    ("handle.rs", "pairs_with", "dispatch"),
    ("handle.rs", "count_pairs_with", "dispatch"),
    ("handle.rs", "weigh_pairs_with", "dispatch"),
    // constructors of the run-time neighbourhood description, not queries
    ("query/mod.rs", "knn", "NeighborhoodSpec"),
    ("query/mod.rs", "radius", "NeighborhoodSpec"),
    ("query/mod.rs", "knn_radius", "NeighborhoodSpec"),
    // the brute-force baseline every test compares the index with
    ("query/brute.rs", "in_box", "baseline"),
    // the C exports' shared bodies over the handle (`nbhd_tree_*` and `nbhd_dynamic_*`)
    ("ffi/table.rs", "neighborhoods", "C export"),
    ("ffi/table.rs", "neighborhoods_of", "C export"),
    ("ffi/pairs.rs", "pairs", "C export"),
    ("ffi/pairs.rs", "pairs_with", "C export"),
];

/// The types that implement `NeighborIndex`, by the file of their implementation (in the
/// files' order).
const INDEX_FLAVOURS: &[(&str, &str)] = &[
    ("dynamic/search.rs", "DynamicKdTree"),
    ("tree/mod.rs", "KdTree"),
];

/// Traits and types that exist once: the index, its result collectors, the persistence
/// envelope, the runtime handle, the option names.
const DEFINED_ONCE: &[&str] = &[
    "trait NeighborIndex",
    "trait NeighborSearch",
    "trait ResultSet",
    "trait RowSets",
    "trait Persist",
    "enum AnyIndex",
    "trait OptionName",
];

/// Every production file under `dir` as (path relative to `dir` with `/`, production text).
fn production_files(dir: &Path) -> Vec<(String, String)> {
    let mut files = Vec::new();
    rust_files(dir, &mut files);
    files.sort();
    files
        .iter()
        .filter(|f| f.file_name().is_some_and(|n| n != "tests.rs"))
        .map(|f| {
            let rel = f
                .strip_prefix(dir)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let text = fs::read_to_string(f).expect("a source file");
            (rel, production(&text).to_string())
        })
        .collect()
}

/// Whether `line` defines `what` (`trait Name` or `enum Name`, any visibility).
fn defines(line: &str, what: &str) -> bool {
    let l = line.trim_start();
    let l = ["pub ", "pub(crate) ", "pub(super) "]
        .iter()
        .find_map(|v| l.strip_prefix(v))
        .unwrap_or(l);
    l.strip_prefix(what)
        .is_some_and(|rest| rest.starts_with([' ', '<', ':', '{']))
}

/// The names of `names` that `text` defines as functions (`fn name(` or `fn name<`).
fn defined_fns<'a>(text: &str, names: &[&'a str]) -> Vec<&'a str> {
    names
        .iter()
        .copied()
        .filter(|n| text.contains(&format!("fn {n}(")) || text.contains(&format!("fn {n}<")))
        .collect()
}

/// The query names defined outside `src/index/` and not listed as allowed: (file, name).
fn second_queries(files: &[(String, String)]) -> Vec<(String, &'static str)> {
    let mut found = Vec::new();
    for (rel, text) in files {
        if rel.starts_with("index/") {
            continue;
        }
        for name in defined_fns(text, QUERY_NAMES) {
            if !QUERY_NAMES_ELSEWHERE
                .iter()
                .any(|&(f, n, _)| f == rel && n == name)
            {
                found.push((rel.clone(), name));
            }
        }
    }
    found
}

#[test]
fn every_query_is_written_once_in_the_index() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = production_files(&src);
    let second = second_queries(&files);
    assert!(
        second.is_empty(),
        "a query of the index defined outside src/index/ (write it once in NeighborIndex, \
         or list it in QUERY_NAMES_ELSEWHERE with the reason): {second:?}"
    );
    // every allowance is still needed (a stale one would hide a later copy)
    for &(file, name, why) in QUERY_NAMES_ELSEWHERE {
        let text = &files.iter().find(|(r, _)| r == file).expect(file).1;
        assert!(
            defined_fns(text, &[name]) == [name],
            "src/{file} no longer defines {name} ({why}): drop it from QUERY_NAMES_ELSEWHERE"
        );
    }
}

#[test]
fn the_index_has_two_flavours_and_each_concept_one_definition() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = production_files(&src);
    let flavours: Vec<(String, String)> = files
        .iter()
        .flat_map(|(rel, text)| {
            text.match_indices("> NeighborIndex<T> for ")
                .map(move |(at, m)| {
                    let ty: String = text[at + m.len()..]
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    (rel.clone(), ty)
                })
        })
        .collect();
    let expected: Vec<(String, String)> = INDEX_FLAVOURS
        .iter()
        .map(|&(f, t)| (f.to_string(), t.to_string()))
        .collect();
    assert_eq!(
        flavours, expected,
        "the implementations of NeighborIndex (a new flavour overrides only its fast paths; \
         add it to INDEX_FLAVOURS and docs/ARCHITECTURE.md)"
    );
    // the front doors bind the one handle: no typed tree held by an enum of their own
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src");
    files.extend(
        production_files(&python)
            .into_iter()
            .map(|(r, t)| (format!("python/{r}"), t)),
    );
    for what in DEFINED_ONCE {
        let homes: Vec<&str> = files
            .iter()
            .filter(|(_, t)| t.lines().any(|l| defines(l, what)))
            .map(|(r, _)| r.as_str())
            .collect();
        assert_eq!(homes.len(), 1, "{what} is defined in {homes:?}, not once");
    }
    for (rel, text) in &files {
        let front_door = rel.starts_with("ffi/") || rel.starts_with("python/");
        let holds_tree = text.lines().any(|l| {
            let l = l.trim_start();
            (l.starts_with("F32(") || l.starts_with("F64(") || l.contains("Static"))
                && (l.contains("KdTree<f32>") || l.contains("KdTree<f64>"))
        });
        assert!(
            !(front_door && holds_tree),
            "{rel} holds typed trees in an enum of its own: use nbhd::handle::AnyIndex"
        );
    }
}

/// The methods `KdTree` and `DynamicKdTree` share at the Python door: written once, in the
/// `index_pymethods!` block of `python/src/index.rs` that both classes' blocks are made of.
const PYTHON_SHARED_METHODS: &[&str] = &[
    "size",
    "m",
    "dtype_name",
    "knn",
    "radius",
    "knn_radius",
    "neighborhoods",
    "in_box",
    "spacing",
    "pairs",
    "pairs_with",
    "count_pairs",
    "remove_statistical_outliers",
    "remove_radius_outliers",
    "to_bytes",
    "from_bytes",
    "__reduce__",
];

#[test]
fn python_classes_share_one_definition_of_each_query() {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/src");
    let files = production_files(&python);
    for (rel, text) in &files {
        if rel == "index.rs" {
            assert!(
                text.contains("macro_rules! index_pymethods"),
                "python/src/index.rs lost the shared #[pymethods] block"
            );
            continue;
        }
        // the query methods of the tree classes; the robust mode's step API (robust_tiles.rs)
        // has its own bytes methods, written once in bytes_pymethods! for its three classes
        if rel == "robust_tiles.rs" {
            assert!(text.contains("macro_rules! bytes_pymethods"));
            for name in ["to_bytes", "from_bytes", "__reduce__"] {
                assert_eq!(
                    text.matches(&format!("fn {name}")).count(),
                    1,
                    "python/src/robust_tiles.rs: `{name}` is written once, in bytes_pymethods!"
                );
            }
        }
        if !text.contains("KdTree") {
            continue;
        }
        let twice = defined_fns(text, PYTHON_SHARED_METHODS);
        assert!(
            twice.is_empty(),
            "python/src/{rel} defines {twice:?} of its own: write a method both classes have \
             once, in index_pymethods! (python/src/index.rs)"
        );
    }
    for (file, class) in [("tree.rs", "PyKdTree"), ("dynamic.rs", "PyDynamicKdTree")] {
        let text = &files.iter().find(|(r, _)| r == file).expect(file).1;
        assert!(
            text.contains(&format!("index_pymethods!(\n    {class},"))
                && !text.contains(&format!("#[pymethods]\nimpl {class} {{")),
            "python/src/{file}: the methods of {class} are one index_pymethods! block"
        );
    }
}

#[test]
fn the_structural_checks_see_a_second_copy() {
    let files = vec![
        ("index/mod.rs".to_string(), "fn knn(&self) {}".to_string()),
        (
            "dynamic/search.rs".to_string(),
            "pub fn radius<Q>(&self) {}".to_string(),
        ),
        (
            "handle.rs".to_string(),
            "pub fn spacing(&self) {}".to_string(),
        ),
    ];
    assert_eq!(
        second_queries(&files),
        [("dynamic/search.rs".to_string(), "radius")]
    );
    assert_eq!(
        defined_fns("fn in_boxes(x) fn in_box<T>()", &["in_box", "in_boxes"]),
        ["in_box", "in_boxes"]
    );
    assert!(defines(
        "    pub(super) trait RowSets<T: Scalar> {",
        "trait RowSets"
    ));
    assert!(!defines("impl<T> RowSets<T> for Rows {", "trait RowSets"));
    assert!(!defines("pub trait RowSetsMore {", "trait RowSets"));
}

/// The longest a production function may be, in lines from its `fn` line to its closing brace
/// (docs/ARCHITECTURE.md: functions under ~100 lines with names that explain themselves).
const MAX_FN_LINES: usize = 100;

/// The functions with a body in `text` (formatted by rustfmt) as (name, first line, lines):
/// each runs from its `fn` line to the first line after it that is its indentation and `}`.
fn fn_lengths(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (at, line) in lines.iter().enumerate() {
        let body = line.trim_start();
        let indent = &line[..line.len() - body.len()];
        let Some(name_at) = body.find("fn ").filter(|&i| {
            let head = &body[..i];
            head.split_whitespace().all(|w| {
                ["pub", "const", "unsafe", "async", "extern", "\"C\""].contains(&w)
                    || w.starts_with("pub(")
            })
        }) else {
            continue;
        };
        let name: String = body[name_at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        // the signature ends at the first line ending in `{` (a body), `;` (a declaration) or
        // `}` (a body on that line)
        let Some(open) = lines[at..]
            .iter()
            .position(|l| l.trim_end().ends_with(['{', ';', '}']))
        else {
            continue;
        };
        if !lines[at + open].trim_end().ends_with('{') {
            continue;
        }
        let close = format!("{indent}}}");
        if let Some(end) = lines[at + open..].iter().position(|l| *l == close) {
            found.push((name, at + 1, open + end + 1));
        }
    }
    found
}

#[test]
fn no_production_function_is_longer_than_the_limit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut long = Vec::new();
    for dir in ["src", "cli/src", "python/src"] {
        for (rel, text) in production_files(&root.join(dir)) {
            for (name, line, len) in fn_lengths(&text) {
                if len > MAX_FN_LINES {
                    long.push(format!("{dir}/{rel}:{line} {name} ({len} lines)"));
                }
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines (split them into steps with names that explain \
         themselves): {long:#?}"
    );
}

#[test]
fn the_length_check_measures_bodies_and_skips_declarations() {
    let text = "pub(crate) fn a<T>(\n    x: T,\n) -> T {\n    x\n}\n\
                trait S {\n    fn decl(&self);\n    fn one(&self) {}\n    fn two(&self) {\n        \
                let _ = 1;\n    }\n}\n\
                pub unsafe extern \"C\" fn c() {\n    if true {\n    }\n}\n";
    assert_eq!(
        fn_lengths(text),
        [
            ("a".to_string(), 1, 5),
            ("two".to_string(), 9, 3),
            ("c".to_string(), 13, 4)
        ]
    );
}
