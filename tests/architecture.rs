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
    // vocabulary every part shares
    &["scalar", "error", "linalg", "select", "prefetch", "simd"],
    &["points", "parallel", "progress", "scatter", "names"],
    // the caller's points, validated and packed
    &["cloud"],
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
