//! The engine's layers (ARCHITECTURE.md): a top-level module of the engine uses only modules
//! of lower layers, and inside every folder the modules' uses of one another form no cycle.
//! Read from the source text: every `crate::` and `super::` path outside comments and unit
//! tests, resolved to the module it names.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Lowest first. A module may use the modules of the layers before its own, none of its own.
const LAYERS: &[&[&str]] = &[
    &["choice"],
    &["cpu", "geometry"],
    &["sampling"],
    &["cs184"],
    &["scene"],
    &["settings"],
    &["accel", "bsdf", "effects", "film", "lights", "load", "request"],
    // `denoise` uses `film`, so it sits above it.
    &["denoise", "stats"],
    &["integrator"],
    &["raysets", "render"],
];

/// Module path (`["accel", "bvh", "traverse"]`) -> its source without comments and unit tests.
fn modules(src: &Path) -> BTreeMap<Vec<String>, String> {
    let mut out = BTreeMap::new();
    for path in crate::tests::common::files_with_ext(src, &["rs"]) {
        let rel = path.strip_prefix(src).unwrap().with_extension("");
        let mut name: Vec<String> = rel.iter().map(|c| c.to_string_lossy().into_owned()).collect();
        if name.last().is_some_and(|n| n == "mod") {
            name.pop();
        }
        if name == ["lib"] || name.first().is_some_and(|n| n == "tests") {
            continue; // the crate root (the face) and these tests
        }
        out.insert(name, code_of(&std::fs::read_to_string(&path).unwrap()));
    }
    out
}

/// The text without `//` comments and without the unit-test module at the end of a file.
fn code_of(text: &str) -> String {
    let mut code = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("#[cfg(test)]") || t.starts_with("#[cfg(all(test") {
            break;
        }
        code.push_str(line.split("//").next().unwrap_or(""));
        code.push('\n');
    }
    code
}

/// The modules `code` (of module `from`) names: for each `crate::a::b` or `super::b` path,
/// its longest prefix that is a module of `known`.
fn uses(from: &[String], code: &str, known: &BTreeSet<Vec<String>>) -> BTreeSet<Vec<String>> {
    let mut found = BTreeSet::new();
    let bytes = code.as_bytes();
    for start in [&b"crate::"[..], &b"super::"[..]] {
        let mut at = 0;
        while let Some(i) = code[at..].find(std::str::from_utf8(start).unwrap()) {
            let i = at + i;
            at = i + start.len();
            if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':') {
                continue;
            }
            // The path: identifiers joined by `::`, up to the first other character; a brace
            // group is expanded one level (`use crate::a::{b, c::d}`).
            let rest = &code[i..];
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(rest.len());
            let head: Vec<&str> = rest[..end].split("::").filter(|s| !s.is_empty()).collect();
            let mut paths = vec![head.clone()];
            if rest[end..].starts_with('{') {
                let close = rest[end..].find('}').map_or(rest.len(), |k| end + k);
                for part in rest[end + 1..close].split(',') {
                    let part: Vec<&str> = part.trim().split("::").map(str::trim).filter(|s| !s.is_empty()).collect();
                    if !part.is_empty() {
                        paths.push(head.iter().copied().chain(part).collect());
                    }
                }
            }
            for p in paths {
                let mut base: Vec<String> = Vec::new();
                let mut rest = &p[..];
                if rest.first() == Some(&"crate") {
                    rest = &rest[1..];
                } else {
                    // `super` in `a/b.rs` and in `a/b/mod.rs` is `a`.
                    base = from.to_vec();
                    while rest.first() == Some(&"super") {
                        base.pop();
                        rest = &rest[1..];
                    }
                }
                let mut target = base.clone();
                let mut best = None;
                for seg in rest {
                    target.push(seg.to_string());
                    if known.contains(&target) {
                        best = Some(target.clone());
                    } else {
                        break;
                    }
                }
                if let Some(t) = best {
                    found.insert(t);
                }
            }
        }
    }
    found
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every use between two different modules, as (user, used).
fn edges() -> Vec<(Vec<String>, Vec<String>)> {
    let src = src_dir();
    let mods = modules(&src);
    let known: BTreeSet<Vec<String>> = mods.keys().cloned().collect();
    let mut out = Vec::new();
    for (name, code) in &mods {
        for used in uses(name, code, &known) {
            if &used != name {
                out.push((name.clone(), used));
            }
        }
    }
    out
}

#[test]
fn top_level_modules_use_only_lower_layers() {
    let layer_of = |m: &str| LAYERS.iter().position(|l| l.contains(&m));
    let mut bad = Vec::new();
    let tops: BTreeSet<String> = modules(&src_dir()).keys().map(|k| k[0].clone()).collect();
    for t in &tops {
        assert!(layer_of(t).is_some(), "module `{t}` is in no layer: add it to LAYERS and ARCHITECTURE.md");
    }
    let mut seen = 0;
    for (from, to) in edges() {
        if from[0] == to[0] {
            continue;
        }
        seen += 1;
        let (a, b) = (layer_of(&from[0]).unwrap(), layer_of(&to[0]).unwrap());
        if b >= a {
            bad.push(format!("{} uses {}", from.join("::"), to.join("::")));
        }
    }
    // The reader finds the uses at all (a parser that saw nothing would pass).
    assert!(seen > 50, "only {seen} uses between top-level modules found");
    assert!(bad.is_empty(), "uses against the layer order:\n{}", bad.join("\n"));
}

#[test]
fn modules_of_a_folder_use_one_another_without_cycles() {
    // Per folder: the graph of its child modules (a use anywhere below a child counts for it).
    let mut graphs: BTreeMap<Vec<String>, BTreeSet<(String, String)>> = BTreeMap::new();
    for (from, to) in edges() {
        let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
        if common < from.len() && common < to.len() {
            graphs.entry(from[..common].to_vec()).or_default().insert((from[common].clone(), to[common].clone()));
        }
    }
    assert!(graphs.get(&vec!["accel".to_string(), "bvh".to_string()]).is_some_and(|g| g.len() > 5));
    for (folder, g) in &graphs {
        // A cycle exists iff repeatedly removing nodes without incoming edges leaves some.
        let mut nodes: BTreeSet<&String> = g.iter().flat_map(|(a, b)| [a, b]).collect();
        loop {
            let free: Vec<&String> =
                nodes.iter().copied().filter(|n| !g.iter().any(|(a, b)| b == *n && nodes.contains(a))).collect();
            if free.is_empty() {
                break;
            }
            for n in free {
                nodes.remove(n);
            }
        }
        assert!(nodes.is_empty(), "modules of `{}` use one another in a cycle among {:?}", folder.join("::"), nodes);
    }
}
