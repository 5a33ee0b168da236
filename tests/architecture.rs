//! The shape of the house, checked: the crates' arrows point one way, no two modules of a crate
//! import each other (directly or around a circle), and no source file outside the tests is longer
//! than a reader can hold (900 lines).
//!
//! Run it alone with `cargo test --release --test architecture`; on failure it prints the circle
//! (`runtime: control/controller.rs -> safety.rs -> control/controller.rs`) or the long files.
//!
//! How the module graph is read, without a compiler: every `.rs` file under a crate's `src/` is a
//! module (`foo/mod.rs` and `foo.rs` name module `foo`). Comments, string literals and
//! `#[cfg(test)]` modules are dropped (test code is not the architecture). An edge goes from a
//! module to each module named by a path in a `use` item, or by a `crate::`, `super::` or `self::`
//! path in code: to the longest prefix of the path that is a module, following the re-exports
//! (`pub use`) of that module for the next name. The `mod` and `pub use` items of a module are
//! declarations, not imports, and make no edge.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_LINES: usize = 900;

/// The workspace's crates, their `src/` folder and their root file.
const CRATES: [(&str, &str, &str); 5] = [
    ("model", "model/src", "lib.rs"),
    ("planner", "planner/src", "lib.rs"),
    ("drivers", "drivers/src", "lib.rs"),
    ("runtime", "runtime/src", "lib.rs"),
    ("adam", "src", "main.rs"),
];

/// Which workspace crates each crate may depend on: `model <- planner`, `model <- drivers <-
/// runtime`, and the CLI on top of all.
const ALLOWED: [(&str, &[&str]); 5] = [
    ("model", &[]),
    ("planner", &["model"]),
    ("drivers", &["model"]),
    ("runtime", &["model", "drivers"]),
    ("adam", &["model", "planner", "drivers", "runtime"]),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|x| x == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a file relative to its crate's `src/` (`a/b.rs` and `a/b/mod.rs` → `a::b`;
/// the root file → empty).
fn module_of(relative: &Path, root_file: &str) -> Vec<String> {
    let mut parts: Vec<String> = relative
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    if parts.is_empty() && last == root_file {
        return parts;
    }
    if last != "mod.rs" {
        parts.push(last.trim_end_matches(".rs").to_owned());
    }
    parts
}

/// The source without comments and string/char literals (replaced by spaces, lines kept).
fn strip(source: &str) -> String {
    let b: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if b[i] == '\n' {
                        out.push('\n');
                    }
                    i += 1;
                }
            }
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !ident_char_before(&b, i)
        {
            // raw string r"..." / r#"..."#
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                if b[j] == '\n' {
                    out.push('\n');
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    i += 1;
                }
                if b.get(i) == Some(&'\n') {
                    out.push('\n');
                }
                i += 1;
            }
            out.push_str("\"\"");
            i += 1;
        } else if c == '\'' {
            // a char literal ('x', '\n', '\u{..}') or a lifetime ('a)
            if next == Some('\\') {
                let mut j = i + 2;
                while j < b.len() && b[j] != '\'' {
                    j += 1;
                }
                out.push_str("' '");
                i = j + 1;
            } else if b.get(i + 2) == Some(&'\'') {
                out.push_str("' '");
                i += 3;
            } else {
                out.push(c);
                i += 1;
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident_char_before(b: &[char], i: usize) -> bool {
    i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_')
}

/// Drops every `#[cfg(test)]` item that is a module with a body.
fn drop_test_modules(source: &str) -> String {
    let mut out = String::with_capacity(source.len());
    let mut rest = source;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at + "#[cfg(test)]".len()..];
        let trimmed = after.trim_start();
        let is_mod = trimmed.starts_with("mod ") || trimmed.starts_with("pub mod ");
        let brace = after.find('{');
        let semicolon = after.find(';');
        match (is_mod, brace) {
            (true, Some(open)) if semicolon.is_none_or(|s| s > open) => {
                let mut depth = 0usize;
                let mut end = after.len();
                for (k, ch) in after[open..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                rest = &after[end..];
            }
            _ => {
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// One `use` tree expanded into its full paths (`a::{b, c::d as e}` → `a::b`, `a::c::d`); `*`
/// and `self` end a path at their parent.
fn expand_use(tree: &str) -> Vec<Vec<String>> {
    fn parse(prefix: &[String], s: &str, out: &mut Vec<Vec<String>>) {
        let s = s.trim();
        if s.is_empty() {
            return;
        }
        if let Some(open) = s.find('{') {
            let head = s[..open].trim().trim_end_matches("::");
            let mut base = prefix.to_vec();
            base.extend(segments(head));
            let inner = &s[open + 1..s.rfind('}').unwrap_or(s.len())];
            for part in split_top(inner) {
                parse(&base, part, out);
            }
        } else {
            let path = s.split(" as ").next().unwrap_or(s);
            let mut full = prefix.to_vec();
            full.extend(segments(path));
            if full.last().is_some_and(|l| l == "self" || l == "*") {
                full.pop();
            }
            out.push(full);
        }
    }
    let mut out = Vec::new();
    parse(&[], tree, &mut out);
    out
}

fn segments(path: &str) -> Vec<String> {
    path.split("::")
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .collect()
}

fn split_top(s: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let mut depth = 0;
    let mut start = 0;
    for (i, ch) in s.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&s[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&s[start..]);
    parts
}

/// What one module says: the paths it uses, and its re-exports (`pub use`) by exported name.
#[derive(Default)]
struct ModuleText {
    uses: Vec<Vec<String>>,
    reexports: BTreeMap<String, Vec<String>>,
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

fn read_module(source: &str) -> ModuleText {
    let text = drop_test_modules(&strip(source));
    let mut module = ModuleText::default();
    // `use` items (also `pub use`, `pub(crate) use`)
    let mut in_use_spans = Vec::new();
    let bytes = text.as_bytes();
    let mut search = 0;
    while let Some(found) = text[search..].find("use ") {
        let at = search + found;
        search = at + 4;
        if at > 0 && is_ident_char(bytes[at - 1] as char) {
            continue;
        }
        let line_start = text[..at].rfind(['\n', ';', '{', '}']).map_or(0, |p| p + 1);
        let lead = text[line_start..at].trim();
        let public = lead.starts_with("pub");
        if !(lead.is_empty() || lead.starts_with("pub") || lead.starts_with("#[")) {
            continue;
        }
        let Some(end) = text[at..].find(';') else {
            break;
        };
        let tree = &text[at + 4..at + end];
        in_use_spans.push((at, at + end));
        for path in expand_use(tree) {
            if public {
                let name = tree_export_name(tree, &path);
                module.reexports.insert(name, path);
            } else {
                module.uses.push(path);
            }
        }
    }
    // `crate::`, `super::` and `self::` paths in code
    for anchor in ["crate::", "super::", "self::"] {
        let mut search = 0;
        while let Some(found) = text[search..].find(anchor) {
            let at = search + found;
            search = at + anchor.len();
            if at > 0 && (is_ident_char(bytes[at - 1] as char) || bytes[at - 1] == b':') {
                continue;
            }
            if in_use_spans.iter().any(|&(a, b)| at >= a && at < b) {
                continue;
            }
            let tail: String = text[at..]
                .chars()
                .take_while(|&c| is_ident_char(c) || c == ':')
                .collect();
            module.uses.push(segments(&tail));
        }
    }
    module
}

/// The name under which `pub use` exports `path` (its last segment, or its `as` alias).
fn tree_export_name(tree: &str, path: &[String]) -> String {
    let last = path.last().cloned().unwrap_or_default();
    let alias = format!("{last} as ");
    if let Some(at) = tree.find(&alias) {
        let rest = &tree[at + alias.len()..];
        return rest.chars().take_while(|&c| is_ident_char(c)).collect();
    }
    last
}

struct Crate {
    name: &'static str,
    /// module path → file (relative to the crate's `src/`)
    files: BTreeMap<Vec<String>, PathBuf>,
    texts: BTreeMap<Vec<String>, ModuleText>,
}

impl Crate {
    fn load(name: &'static str, src: &str, root_file: &str) -> Self {
        let dir = root().join(src);
        let mut paths = Vec::new();
        rust_files(&dir, &mut paths);
        let mut files = BTreeMap::new();
        let mut texts = BTreeMap::new();
        for path in paths {
            let relative = path.strip_prefix(&dir).expect("under src").to_path_buf();
            let module = module_of(&relative, root_file);
            let source = std::fs::read_to_string(&path).expect("readable source");
            texts.insert(module.clone(), read_module(&source));
            files.insert(module, relative);
        }
        Crate { name, files, texts }
    }

    /// The module a path used in `from` names, following re-exports.
    fn resolve(&self, from: &[String], path: &[String]) -> Option<Vec<String>> {
        let mut absolute = match path.first().map(String::as_str) {
            Some("crate" | "self" | "super") => self.absolute(from, path)?,
            Some(first) => {
                // 2018 paths: a child module of `from` by its bare name
                let mut child = from.to_vec();
                child.push(first.to_owned());
                if !self.files.contains_key(&child) {
                    return None;
                }
                from.iter().chain(path).cloned().collect()
            }
            None => return None,
        };
        for _ in 0..16 {
            let depth = (0..=absolute.len())
                .rev()
                .find(|&k| self.files.contains_key(&absolute[..k]))?;
            let module = absolute[..depth].to_vec();
            let Some(next) = absolute.get(depth) else {
                return Some(module);
            };
            match self.texts[&module].reexports.get(next) {
                Some(target) => {
                    let target = self.absolute(&module, target)?;
                    let mut new = target;
                    new.extend(absolute[depth + 1..].iter().cloned());
                    if new == absolute {
                        return Some(module);
                    }
                    absolute = new;
                }
                None => return Some(module),
            }
        }
        None
    }

    /// `path` as written in `from` (`crate::`, `self::`, `super::` or relative) made absolute.
    fn absolute(&self, from: &[String], path: &[String]) -> Option<Vec<String>> {
        match path.first().map(String::as_str) {
            Some("crate") => Some(path[1..].to_vec()),
            Some("self") => Some(from.iter().chain(&path[1..]).cloned().collect()),
            Some("super") => {
                let mut base = from.to_vec();
                let mut rest = path;
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop()?;
                    rest = &rest[1..];
                }
                base.extend(rest.iter().cloned());
                Some(base)
            }
            Some(_) => Some(from.iter().chain(path).cloned().collect()),
            None => None,
        }
    }

    fn edges(&self) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
        let mut edges: BTreeMap<_, BTreeSet<_>> = BTreeMap::new();
        for (module, text) in &self.texts {
            let out = edges.entry(module.clone()).or_default();
            for path in &text.uses {
                if let Some(target) = self.resolve(module, path) {
                    if &target != module && !target.starts_with(module) {
                        out.insert(target);
                    }
                }
            }
        }
        edges
    }

    fn file(&self, module: &[String]) -> String {
        self.files[module].display().to_string()
    }

    /// Every elementary circle's witness: for each strongly connected component with more than
    /// one module, one circle through it.
    fn circles(&self) -> Vec<String> {
        let edges = self.edges();
        let nodes: Vec<_> = edges.keys().cloned().collect();
        let index: BTreeMap<_, _> = nodes.iter().enumerate().map(|(i, n)| (n, i)).collect();
        let adjacency: Vec<Vec<usize>> = nodes
            .iter()
            .map(|n| {
                edges[n]
                    .iter()
                    .filter_map(|t| index.get(t).copied())
                    .collect()
            })
            .collect();
        let mut circles = Vec::new();
        for component in strongly_connected(&adjacency) {
            if component.len() < 2 {
                continue;
            }
            let members: BTreeSet<usize> = component.iter().copied().collect();
            let start = component[0];
            // a shortest path back to start within the component (BFS)
            let mut previous = vec![usize::MAX; nodes.len()];
            let mut queue = std::collections::VecDeque::from([start]);
            let mut closing = None;
            while let Some(n) = queue.pop_front() {
                for &m in &adjacency[n] {
                    if m == start {
                        closing = Some(n);
                        queue.clear();
                        break;
                    }
                    if members.contains(&m) && previous[m] == usize::MAX {
                        previous[m] = n;
                        queue.push_back(m);
                    }
                }
            }
            let mut walk = vec![start];
            let mut n = closing.expect("a strongly connected component has a circle");
            while n != start {
                walk.push(n);
                n = previous[n];
            }
            walk.push(start);
            let last = walk.len() - 1;
            walk[1..last].reverse();
            let names: Vec<String> = walk.iter().map(|&n| self.file(&nodes[n])).collect();
            let all: Vec<String> = component.iter().map(|&n| self.file(&nodes[n])).collect();
            circles.push(format!(
                "{}: {} (modules tied together: {})",
                self.name,
                names.join(" -> "),
                all.join(", ")
            ));
        }
        circles
    }
}

/// Tarjan's strongly connected components.
fn strongly_connected(adjacency: &[Vec<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        adjacency: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State<'_>, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for k in 0..s.adjacency[v].len() {
            let w = s.adjacency[v][k];
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(i) if s.on_stack[w] => s.low[v] = s.low[v].min(i),
                Some(_) => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            loop {
                let w = s.stack.pop().expect("v is on the stack");
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            component.sort_unstable();
            s.out.push(component);
        }
    }
    let n = adjacency.len();
    let mut s = State {
        adjacency,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

#[test]
fn no_circle_of_imports_within_a_crate() {
    let circles: Vec<String> = CRATES
        .iter()
        .flat_map(|&(name, src, root_file)| Crate::load(name, src, root_file).circles())
        .collect();
    assert!(
        circles.is_empty(),
        "modules that import each other:\n{}",
        circles.join("\n")
    );
}

#[test]
fn no_source_file_over_900_lines_outside_the_tests() {
    let mut long = Vec::new();
    for (_, src, _) in CRATES {
        let mut files = Vec::new();
        rust_files(&root().join(src), &mut files);
        for file in files {
            let lines = std::fs::read_to_string(&file)
                .expect("readable source")
                .lines()
                .count();
            if lines > MAX_LINES {
                long.push(format!("{} ({lines} lines)", file.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn crates_depend_one_way() {
    for (name, allowed) in ALLOWED {
        let manifest = if name == "adam" {
            root().join("Cargo.toml")
        } else {
            root().join(name).join("Cargo.toml")
        };
        let text = std::fs::read_to_string(&manifest).expect("readable manifest");
        let mut section = String::new();
        for line in text.lines() {
            let line = line.trim();
            if line.starts_with('[') {
                section = line.to_owned();
                continue;
            }
            if section != "[dependencies]" {
                continue;
            }
            let dependency = line.split(['=', '.', ' ']).next().unwrap_or("");
            let workspace_crate = CRATES.iter().any(|&(c, _, _)| c == dependency);
            assert!(
                !workspace_crate || allowed.contains(&dependency),
                "{}: {name} depends on {dependency}; allowed: {allowed:?}",
                manifest.display()
            );
        }
    }
}

#[test]
fn the_reader_finds_a_known_circle() {
    // The check itself must be able to fail: two modules that import each other.
    let a = read_module("use crate::b::Thing;\n/// [`crate::c`]\nfn f() { let s = \"crate::c\"; }\n#[cfg(test)]\nmod tests { use crate::c::X; }\n");
    assert_eq!(
        a.uses,
        vec![vec!["crate".to_owned(), "b".into(), "Thing".into()]]
    );
    let b =
        read_module("pub use self::inner::Thing;\nmod inner;\nfn g() -> crate::a::Y { todo() }\n");
    let inner = read_module("pub struct Thing;\n");
    let key = |s: &str| segments(s);
    let krate = Crate {
        name: "toy",
        files: [
            (vec![], PathBuf::from("lib.rs")),
            (key("a"), PathBuf::from("a.rs")),
            (key("b"), PathBuf::from("b/mod.rs")),
            (key("b::inner"), PathBuf::from("b/inner.rs")),
        ]
        .into_iter()
        .collect(),
        texts: [
            (vec![], ModuleText::default()),
            (key("a"), a),
            (key("b"), b),
            (key("b::inner"), inner),
        ]
        .into_iter()
        .collect(),
    };
    // `crate::b::Thing` is re-exported from b::inner: a depends on b/inner.rs, not on b
    let edges = krate.edges();
    assert!(edges[&key("a")].contains(&key("b::inner")), "{:?}", edges);
    assert!(edges[&key("b")].contains(&key("a")), "{:?}", edges);
    assert!(krate.circles().is_empty());
    let mut krate = krate;
    krate
        .texts
        .insert(key("b::inner"), read_module("use super::super::a::Y;\n"));
    let circles = krate.circles();
    assert_eq!(circles.len(), 1, "{circles:?}");
    assert!(
        circles[0].contains("a.rs -> b/inner.rs -> a.rs"),
        "{circles:?}"
    );
}

#[test]
fn use_trees_expand_to_full_paths() {
    let paths = expand_use("crate::{a::{B, c::D as E}, f, g::*, h::{self, I}}");
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(
        joined,
        [
            "crate::a::B",
            "crate::a::c::D",
            "crate::f",
            "crate::g",
            "crate::h",
            "crate::h::I"
        ]
    );
}
