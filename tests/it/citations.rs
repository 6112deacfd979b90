//! Every file, folder, heading and anchor that the docs and the code's comments cite exists.
//!
//! Scanned: `README.md`, `ARCHITECTURE.md`, `BENCHMARKS.md`, `docs/**/*.md` and any
//! `crates/*/*.md` (whole text); the comments of `src/**/*.rs`, `tests/**/*.rs`,
//! `benches/**/*.rs` and of each `crates/*` crate's; `tools/*` and `.ci/*` (whole text).
//! Cited: repository paths (`src/...`, `tests/...`, `tools/<name>.py`, `BENCHMARKS.md`, ...; a
//! path whose first folder is a folder under a `src/`, such as `accel/bvh/query.rs`, is
//! looked up under every `src/`), Markdown links with their anchors (relative to the document's
//! folder; rustdoc's `Self::x` links are not files), and sections cited by name after a
//! Markdown file, as in `docs/decisions.md, "Shadow packets"` or `BENCHMARKS.md "Renders"`.
//! Paths under `../shared/` are outside the repository: checked when that folder exists.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Top-level folders and files of the repository whose paths are checked wherever cited.
const TOP: &[&str] = &["src", "tests", "benches", "tools", "docs", "examples", ".ci", "crates", "assets", "scenes"];
const TOP_FILES: &[&str] = &["README.md", "ARCHITECTURE.md", "BENCHMARKS.md", "Cargo.toml", "rustfmt.toml"];
/// Extensions that make a path with a slash a citation even when its first folder is not in `TOP`.
const SOURCE_EXT: &[&str] = &[".rs", ".md", ".py", ".sh"];

/// One citation: a path (as written) and, optionally, a heading or anchor in it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Cite {
    Path(String),
    /// A Markdown link's target: relative to the citing document's folder.
    Link(String),
    /// A path and a heading's text (`"Heading"`) or a link's anchor (`#anchor`).
    Section(String, String),
    Anchor(String, String),
}

/// The repository root: the first folder up from this crate's that holds `.git` or a
/// workspace `Cargo.toml`, so the test works at the root and in `crates/<name>/`.
fn repo_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    for dir in here.ancestors() {
        if dir.join(".git").exists() {
            return dir.to_path_buf();
        }
        let toml = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap_or_default();
        if toml.contains("[workspace]") && dir.join("README.md").exists() {
            return dir.to_path_buf();
        }
    }
    here.to_path_buf()
}

fn is_token_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || "_./#-".contains(c)
}

/// The text of a Rust file's comments (`//`, `///`, `//!`), a line each, code lines blank,
/// so that a citation wrapped over comment lines reads as one.
fn rust_comments(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        // A `//` inside a string literal (a URL) is not a comment: count the quotes before it.
        if let Some((i, _)) = line.match_indices("//").find(|(i, _)| line[..*i].matches('"').count() % 2 == 0) {
            out.push_str(line[i..].trim_start_matches('/').trim_start_matches('!'));
        }
        out.push('\n');
    }
    out
}

/// The quoted heading names after a Markdown path: `, "A"`, ` "A" and "B"`, `, \"A\"`.
fn quoted_after(rest: &str) -> Vec<String> {
    let mut names = Vec::new();
    // `"BENCHMARKS.md"), x` is a quoted path, not a path and a section.
    if !rest.starts_with([' ', ',', '\n']) {
        return names;
    }
    let mut r = rest;
    loop {
        let t = r.trim_start_matches(|c: char| c.is_whitespace() || c == ',' || c == '\\');
        let t = if names.is_empty() {
            t
        } else if let Some(x) = t.strip_prefix("and") {
            x.trim_start()
        } else {
            break;
        };
        let Some(body) = t.strip_prefix('"') else { break };
        let Some(end) = body.find('"') else { break };
        let name = body[..end].trim_end_matches('\\');
        if !name.starts_with(char::is_alphanumeric) || name.len() > 80 {
            break;
        }
        names.push(name.split_whitespace().collect::<Vec<_>>().join(" "));
        r = &body[end + 1..];
        if !names.is_empty() && !r.trim_start_matches([',', ' ', '\n']).starts_with("and") {
            break;
        }
    }
    names
}

fn looks_like_path(tok: &str, src_dirs: &BTreeSet<String>) -> bool {
    if TOP_FILES.contains(&tok) || tok.starts_with("../shared/") {
        return true;
    }
    let segs: Vec<&str> = tok.split('/').collect();
    if segs.len() < 2 || segs[..segs.len() - 1].iter().any(|s| s.is_empty() || *s == ".") {
        return false;
    }
    if TOP.contains(&segs[0]) {
        return segs.len() >= 2 && !segs[1].is_empty();
    }
    SOURCE_EXT.iter().any(|e| tok.ends_with(e)) && src_dirs.contains(segs[0])
}

/// The citations in a text (a Markdown document's whole text, or a source file's comments).
fn extract(text: &str, src_dirs: &BTreeSet<String>) -> BTreeSet<Cite> {
    let mut out = BTreeSet::new();
    // Markdown links.
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let Some(end) = after.find(')') else { break };
        let target = after[..end].trim();
        let file_like = target.contains(['/', '.']) || target.starts_with('#');
        if file_like && !target.contains("://") && !target.contains("::") && !target.contains(['<', ' ', '\n']) {
            match target.split_once('#') {
                Some((p, a)) => {
                    out.insert(Cite::Anchor(p.to_string(), a.to_string()));
                }
                None if !target.is_empty() => {
                    out.insert(Cite::Link(target.to_string()));
                }
                None => {}
            }
        }
        rest = &after[end..];
    }
    // Path tokens, and the section names that follow a Markdown path.
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let mut k = 0;
    while k < chars.len() {
        if !is_token_char(chars[k].1) {
            k += 1;
            continue;
        }
        let start = chars[k].0;
        // Tokens start at a boundary: not inside a link target or a URL.
        let prev = text[..start].chars().next_back();
        while k < chars.len() && is_token_char(chars[k].1) {
            k += 1;
        }
        let end = if k < chars.len() { chars[k].0 } else { text.len() };
        if matches!(prev, Some('(') if text[..start].ends_with("](")) || text[..start].ends_with("://") {
            continue;
        }
        if text[..start].ends_with(':') && text[..start].trim_end_matches(':').ends_with(char::is_alphabetic) {
            // `https:` and the like.
            let word: String = text[..start].chars().rev().skip(1).take_while(|c| c.is_alphabetic()).collect();
            if word == "ptth" || word == "sptth" {
                continue;
            }
        }
        let mut tok = text[start..end].trim_end_matches(['.', ',', ':', '-']);
        if tok.starts_with("../") && !tok.starts_with("../shared/") {
            continue;
        }
        let anchor = tok.split_once('#').map(|(p, a)| (p.to_string(), a.to_string()));
        if let Some((p, _)) = &anchor {
            tok = &tok[..p.len()];
        }
        // `name.{obj,gltf}` is a pattern, not one file.
        if !looks_like_path(tok, src_dirs) || text[end..].starts_with('{') {
            continue;
        }
        match anchor {
            Some((p, a)) if !a.is_empty() => {
                out.insert(Cite::Section(p, format!("#{a}")));
            }
            _ => {
                out.insert(Cite::Path(tok.to_string()));
            }
        }
        if tok.ends_with(".md") {
            for name in quoted_after(&text[end..]) {
                out.insert(Cite::Section(tok.to_string(), name));
            }
        }
    }
    out
}

/// GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn headings(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap_or_default();
    let mut fenced = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            fenced = !fenced;
        }
        if !fenced && line.starts_with('#') {
            out.push(line.trim_start_matches('#').trim().to_string());
        }
    }
    out
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

struct Repo {
    root: PathBuf,
    /// The repository root and each `crates/*` folder.
    crate_roots: Vec<PathBuf>,
    /// The folders directly under each `src/` (`accel`, `integrator`, ...): module-style paths.
    src_dirs: BTreeSet<String>,
}

impl Repo {
    fn open() -> Repo {
        let root = repo_root();
        let mut crate_roots = vec![root.clone()];
        if let Ok(entries) = std::fs::read_dir(root.join("crates")) {
            crate_roots.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()));
        }
        let mut src_dirs = BTreeSet::new();
        for c in &crate_roots {
            let Ok(entries) = std::fs::read_dir(c.join("src")) else { continue };
            src_dirs.extend(
                entries.flatten().filter(|e| e.path().is_dir()).filter_map(|e| e.file_name().into_string().ok()),
            );
        }
        Repo { root, crate_roots, src_dirs }
    }

    /// Where a cited path may be: the repository root, each crate, each `src/` (module
    /// paths), and the citing file's folder.
    fn resolve(&self, path: &str, from: &Path) -> Option<PathBuf> {
        let path = path.trim_end_matches('/');
        if let Some(rest) = path.strip_prefix("../shared").filter(|r| r.is_empty() || r.starts_with('/')) {
            // Beside the repository, or where the scenes folder the tests use lives (CI's
            // WAVEPATH_SCENES, `<shared>/scenes`, in a clone elsewhere).
            let beside = self.root.join("../shared");
            let from_scenes =
                std::env::var_os("WAVEPATH_SCENES").and_then(|s| PathBuf::from(s).parent().map(Path::to_path_buf));
            let shared = if beside.is_dir() { beside } else { from_scenes.unwrap_or(beside) };
            return Some(shared.join(rest.trim_start_matches('/')));
        }
        let mut bases: Vec<PathBuf> = vec![from.to_path_buf()];
        for c in &self.crate_roots {
            bases.push(c.clone());
            bases.push(c.join("src"));
        }
        bases.iter().map(|b| b.join(path)).find(|p| p.exists())
    }

    /// The broken citations of one file's text, as sentences.
    fn check(&self, file: &Path, text: &str) -> Vec<String> {
        let from = file.parent().unwrap_or(&self.root);
        let shown = file.strip_prefix(&self.root).unwrap_or(file).display().to_string();
        let mut broken = Vec::new();
        for cite in extract(text, &self.src_dirs) {
            let (path, section) = match &cite {
                Cite::Path(p) | Cite::Link(p) => (p.clone(), None),
                Cite::Section(p, s) | Cite::Anchor(p, s) => (p.clone(), Some(s.clone())),
            };
            let target = if path.is_empty() {
                Some(file.to_path_buf())
            } else if matches!(cite, Cite::Link(_) | Cite::Anchor(..)) {
                Some(from.join(&path)).filter(|p| p.exists()).or_else(|| self.resolve(&path, from))
            } else {
                self.resolve(&path, from)
            };
            let Some(target) = target else {
                broken.push(format!("{shown}: cites {path}, which does not exist"));
                continue;
            };
            if !target.exists() {
                // `../shared` absent: outside the repository, not checked.
                continue;
            }
            let Some(section) = section else { continue };
            if target.extension().is_none_or(|e| e != "md") {
                continue;
            }
            let hs = headings(&target);
            let ok = match section.strip_prefix('#') {
                Some(anchor) => hs.iter().any(|h| slug(h) == anchor),
                None => hs.iter().any(|h| h.eq_ignore_ascii_case(&section)),
            };
            if !ok {
                broken.push(format!("{shown}: cites {path} section {section:?}, which it does not have"));
            }
        }
        broken
    }

    /// Every scanned file with the text its citations are taken from.
    fn scanned(&self) -> Vec<(PathBuf, String)> {
        let mut files = Vec::new();
        for f in ["README.md", "ARCHITECTURE.md", "BENCHMARKS.md"] {
            files.push(self.root.join(f));
        }
        walk(&self.root.join("docs"), &mut files);
        for c in &self.crate_roots {
            for d in ["src", "tests", "benches"] {
                walk(&c.join(d), &mut files);
            }
            if c != &self.root
                && let Ok(entries) = std::fs::read_dir(c)
            {
                files.extend(entries.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "md")));
            }
        }
        for d in ["tools", ".ci"] {
            if let Ok(entries) = std::fs::read_dir(self.root.join(d)) {
                files.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_file()));
            }
        }
        let mut out = Vec::new();
        for f in files {
            let Ok(text) = std::fs::read_to_string(&f) else { continue };
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            let in_docs = f.starts_with(self.root.join("docs"));
            match ext {
                "rs" => out.push((f, rust_comments(&text))),
                "md" => out.push((f, text)),
                _ if in_docs => {}
                _ => out.push((f, text)),
            }
        }
        out
    }
}

#[test]
fn every_cited_path_and_section_exists() {
    let repo = Repo::open();
    assert!(repo.root.join("README.md").exists(), "repository root not found from {}", env!("CARGO_MANIFEST_DIR"));
    let scanned = repo.scanned();
    assert!(scanned.len() > 50, "only {} files scanned from {}", scanned.len(), repo.root.display());
    let broken: Vec<String> = scanned.iter().flat_map(|(f, text)| repo.check(f, text)).collect();
    assert!(broken.is_empty(), "{} broken citations:\n{}", broken.len(), broken.join("\n"));
}

#[test]
fn the_extractor_finds_paths_links_and_sections() {
    // One literal per line, so that no line of this file has a `//` outside a string.
    let text = concat!(
        "See `src/accel/bvh/build.rs` and tests/it/main.rs, the [notes](docs/decisions.md#tree)\n",
        "and (docs/decisions.md, \"Fast\n build\" and \"Leaf layouts\"), BENCHMARKS.md \"Renders\";\n",
        "module accel/bvh/traverse.rs, ../shared/peers/run.sh, [page](https://x.org/a.md), ",
        "target/release/wavepath, cs184/sky/CBbunny.dae, crates/<x>/src, [same](#tests), ",
        "[`f`](Self::f), e2e/run.sh, scenes/m.{obj,dae}, join(REPO, \"BENCHMARKS.md\"), x",
    );
    let src_dirs: BTreeSet<String> = ["accel".to_string()].into();
    let got: Vec<Cite> = extract(text, &src_dirs).into_iter().collect();
    let p = |s: &str| Cite::Path(s.to_string());
    let s = |a: &str, b: &str| Cite::Section(a.to_string(), b.to_string());
    let mut want = vec![
        p("src/accel/bvh/build.rs"),
        p("tests/it/main.rs"),
        Cite::Anchor("docs/decisions.md".into(), "tree".into()),
        Cite::Anchor(String::new(), "tests".into()),
        p("docs/decisions.md"),
        s("docs/decisions.md", "Fast build"),
        s("docs/decisions.md", "Leaf layouts"),
        p("BENCHMARKS.md"),
        s("BENCHMARKS.md", "Renders"),
        p("accel/bvh/traverse.rs"),
        p("../shared/peers/run.sh"),
    ];
    want.sort();
    assert_eq!(got, want);
    let comments =
        rust_comments(&format!("let u = \"http:{0}a/b.rs\"; {0} see tools/x.py\n{0}/ and\n{0}/ docs/y.md", "//"));
    let got: Vec<Cite> = extract(&comments, &src_dirs).into_iter().collect();
    assert_eq!(got, vec![p("docs/y.md"), p("tools/x.py")]);
}

#[test]
fn a_broken_citation_is_reported() {
    let repo = Repo::open();
    let readme = repo.root.join("README.md");
    let text = "src/no/such/file.rs, [x](docs/nothing.md), docs/decisions.md \"No such entry\", \
                [y](ARCHITECTURE.md#no-such-anchor), ARCHITECTURE.md \"Layers\", src/lib.rs";
    let broken = repo.check(&readme, text);
    assert_eq!(broken.len(), 4, "{broken:#?}");
    assert!(broken.iter().any(|b| b.contains("src/no/such/file.rs")));
    assert!(broken.iter().any(|b| b.contains("docs/nothing.md")));
    assert!(broken.iter().any(|b| b.contains("No such entry")));
    assert!(broken.iter().any(|b| b.contains("no-such-anchor")));
    assert_eq!(slug("Ray throughput against the peers"), "ray-throughput-against-the-peers");
    assert_eq!(slug("A Cornell box around the 25.6M-triangle Lucy"), "a-cornell-box-around-the-256m-triangle-lucy");
}
