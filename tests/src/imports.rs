//! A file-level import graph of one crate's `src/`, read from the code's own `use` lines and
//! inline `crate::`/`super::`/`self::` paths, for the architecture tests (ARCHITECTURE.md):
//! no cycles, layers importing only downwards.
//!
//! A node is a source file. Test modules (`#[cfg(test)] mod tests`, inline or in their own
//! file) are left out: tests may import anything. `mod x;` declarations are not imports. A path into a module resolves
//! through that module's `pub use` re-exports to the file that defines the item, so a facade
//! `mod.rs` whose children import each other's items through `super::` is not a cycle, while a
//! parent that uses a child's items and a child that uses the parent's own items is.
//! The reading is textual (no macro expansion, no type resolution): enough for our code, which
//! imports by path.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One crate's files and the arrows between them (importer → imported), paths relative to `src/`.
#[derive(Debug, Default)]
pub struct ImportGraph {
    pub files: BTreeSet<String>,
    pub arrows: BTreeMap<String, BTreeSet<String>>,
}

struct Module {
    /// File (relative to src/) whose node this module's code belongs to.
    node: String,
    /// Code of the file, comments removed.
    code: String,
    /// Child modules declared with `mod name;` (or inline `mod name {`).
    children: BTreeSet<String>,
    /// `pub use` re-exports: exported name → target path (absolute module path + item), or
    /// `None` when it points outside the crate.
    reexports: BTreeMap<String, Option<Vec<String>>>,
}

impl ImportGraph {
    /// Reads the library crate rooted at `src/lib.rs` (binaries `main.rs` and `bin/` are other
    /// crates and are left out).
    pub fn read(src: &Path) -> Result<Self, String> {
        let mut modules: BTreeMap<Vec<String>, Module> = BTreeMap::new();
        load_module(src, &src.join("lib.rs"), Vec::new(), None, &mut modules)?;
        let mut g = ImportGraph::default();
        for m in modules.values() {
            g.files.insert(m.node.clone());
        }
        for (path, m) in &modules {
            for target in uses(path, m) {
                if let Some(file) = resolve(&modules, &target, 0) {
                    if file != m.node {
                        g.arrows.entry(m.node.clone()).or_default().insert(file);
                    }
                }
            }
        }
        Ok(g)
    }

    /// Groups of files that import each other (strongly connected components of more than one
    /// file), each listed with the arrows inside it.
    pub fn cycles(&self) -> Vec<Vec<(String, String)>> {
        let sccs = tarjan(&self.files, &self.arrows);
        sccs.into_iter()
            .filter(|c| c.len() > 1)
            .map(|c| {
                let set: BTreeSet<&String> = c.iter().collect();
                let mut inside = Vec::new();
                for a in &c {
                    for b in self.arrows.get(a).into_iter().flatten() {
                        if set.contains(b) {
                            inside.push((a.clone(), b.clone()));
                        }
                    }
                }
                inside
            })
            .collect()
    }
}

fn rel(src: &Path, file: &Path) -> String {
    file.strip_prefix(src)
        .unwrap_or(file)
        .to_string_lossy()
        .replace('\\', "/")
}

/// Loads the module at `file` with module path `path`; `node` is the file its code counts for
/// (itself, or the declaring file for `#[path]` test modules).
fn load_module(
    src: &Path,
    file: &Path,
    path: Vec<String>,
    node: Option<String>,
    modules: &mut BTreeMap<Vec<String>, Module>,
) -> Result<(), String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let code = strip_comments(&text);
    let node = node.unwrap_or_else(|| rel(src, file));
    // Directory where `mod x;` children live: `a/` for `a/mod.rs` and `lib.rs`, `a/b/` for `a/b.rs`.
    let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let dir = if name == "mod.rs" || name == "lib.rs" {
        file.parent().unwrap().to_path_buf()
    } else {
        file.with_extension("")
    };
    let mut children = BTreeSet::new();
    let mut declared: Vec<(String, PathBuf, bool)> = Vec::new();
    let mut pending_path: Option<String> = None;
    let mut pending_test = false;
    // The original text: `#[path = "..."]` is a string literal, blanked in `code`.
    for line in text.lines() {
        let t = line.trim();
        if let Some(p) = t
            .strip_prefix("#[path = \"")
            .and_then(|r| r.split('"').next())
        {
            pending_path = Some(p.to_string());
            if !t.contains("mod ") {
                continue;
            }
        }
        if t.starts_with("#[cfg(test)]") {
            pending_test = true;
        }
        let decl = t
            .trim_start_matches("#[cfg(test)]")
            .trim()
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub ");
        if let Some(rest) = decl.strip_prefix("mod ") {
            let ident: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let after = rest[ident.len()..].trim_start();
            if after.starts_with(';') && pending_test {
                // Test modules may import anything: they are not part of the architecture.
                pending_path = None;
            } else if after.starts_with(';') {
                children.insert(ident.clone());
                match pending_path.take() {
                    // `#[path]` is relative to the declaring file's own directory.
                    Some(p) => declared.push((ident, file.parent().unwrap().join(p), true)),
                    None => {
                        let a = dir.join(format!("{ident}.rs"));
                        let b = dir.join(&ident).join("mod.rs");
                        declared.push((ident, if a.exists() { a } else { b }, false));
                    }
                }
            } else if after.starts_with('{') {
                children.insert(ident);
            }
        }
        if !t.starts_with("#[") {
            pending_path = None;
            pending_test = false;
        }
    }
    let mut m = Module {
        node: node.clone(),
        code,
        children,
        reexports: BTreeMap::new(),
    };
    for (alias, target) in reexports(&path, &m) {
        m.reexports.insert(alias, target);
    }
    modules.insert(path.clone(), m);
    for (ident, child, by_path) in declared {
        let mut p = path.clone();
        p.push(ident);
        let child_node = by_path.then(|| node.clone());
        load_module(src, &child, p, child_node, modules)?;
    }
    Ok(())
}

/// Removes `//` comments (doc comments included) and string literals' contents, so paths in
/// prose or strings are not read as imports.
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut in_str = false;
        let mut prev = ' ';
        let mut cut = line.len();
        for (i, c) in line.char_indices() {
            if c == '"' && prev != '\\' && prev != '\'' {
                in_str = !in_str;
            }
            if !in_str && c == '/' && line[i + 1..].starts_with('/') {
                cut = i;
                break;
            }
            prev = c;
        }
        let kept = &line[..cut];
        // Blank out string contents.
        let mut s = String::with_capacity(kept.len());
        let mut in_s = false;
        let mut p = ' ';
        for c in kept.chars() {
            if c == '"' && p != '\\' && p != '\'' {
                in_s = !in_s;
                s.push(c);
            } else {
                s.push(if in_s { ' ' } else { c });
            }
            p = c;
        }
        out.push_str(&s);
        out.push('\n');
    }
    out
}

/// Expands a path text such as `a::b::{c, d::{e, f}}` into its leaf paths.
fn expand(text: &str) -> Vec<Vec<String>> {
    // `x as y` keeps its alias as `x@y` in the leaf (see `expand_with_alias`).
    let text: String = text
        .replace(" as ", "@")
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    fn go(prefix: &[String], s: &str, out: &mut Vec<Vec<String>>) {
        if let Some(i) = s.find('{') {
            let head: Vec<String> = s[..i]
                .split("::")
                .filter(|x| !x.is_empty())
                .map(str::to_string)
                .collect();
            let mut p = prefix.to_vec();
            p.extend(head);
            let inner = &s[i + 1..s.rfind('}').unwrap_or(s.len())];
            let mut depth = 0;
            let mut start = 0;
            for (k, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        go(&p, &inner[start..k], out);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            go(&p, &inner[start..], out);
        } else {
            let mut p = prefix.to_vec();
            for seg in s.split("::").filter(|x| !x.is_empty()) {
                if seg != "self" {
                    p.push(seg.to_string());
                }
            }
            if !p.is_empty() {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    go(&[], &text, &mut out);
    out
}

/// Makes `segments`, written in module `at` (inside an inline child `inline` when given),
/// absolute; `None` when it names something outside the crate.
fn absolute(
    at: &[String],
    inline: Option<&str>,
    children: &BTreeSet<String>,
    segs: &[String],
) -> Option<Vec<String>> {
    let mut here: Vec<String> = at.to_vec();
    if let Some(i) = inline {
        here.push(i.to_string());
    }
    let (first, rest) = segs.split_first()?;
    match first.as_str() {
        "crate" => Some(rest.to_vec()),
        "self" => Some([here.as_slice(), rest].concat()),
        "super" => {
            let mut base = here;
            base.pop()?;
            let mut rest = rest;
            while rest.first().map(String::as_str) == Some("super") {
                base.pop()?;
                rest = &rest[1..];
            }
            Some([base.as_slice(), rest].concat())
        }
        // Uniform paths: a child module of this one (only meaningful outside inline children).
        name if inline.is_none() && children.contains(name) => Some([at, segs].concat()),
        _ => None,
    }
}

/// Every in-crate path module `path` uses, absolute.
fn uses(path: &[String], m: &Module) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut inline: Option<String> = None;
    let mut statement = String::new();
    let mut in_use = false;
    let mut after_cfg_test = false;
    for line in m.code.lines() {
        let t = line.trim_start();
        // An inline `mod name {` at the top level starts code one module deeper (it runs to
        // the end of the file in our sources); an inline test module ends what is read: tests
        // may import anything, they are not part of the architecture.
        if !line.starts_with(' ') {
            if let Some(rest) = t
                .trim_start_matches("pub(crate) ")
                .trim_start_matches("pub(super) ")
                .trim_start_matches("pub ")
                .strip_prefix("mod ")
                .filter(|r| r.trim_end().ends_with('{'))
            {
                if after_cfg_test {
                    break;
                }
                inline = Some(rest.trim_end_matches('{').trim().to_string());
            }
            after_cfg_test = t.starts_with("#[cfg(test)]");
        }
        let stmt_start = t
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub(super) ")
            .trim_start_matches("pub ");
        if !in_use && stmt_start.starts_with("use ") {
            in_use = true;
            statement.clear();
            statement.push_str(&stmt_start[4..]);
        } else if in_use {
            statement.push_str(t);
        }
        if in_use {
            if let Some(end) = statement.find(';') {
                let body = statement[..end].to_string();
                for mut segs in expand(&body) {
                    if let Some(last) = segs.last_mut() {
                        if let Some((name, _alias)) = last.split_once('@') {
                            *last = name.to_string();
                        }
                    }
                    if let Some(a) = absolute(path, inline.as_deref(), &m.children, &segs) {
                        out.push(a);
                    }
                }
                in_use = false;
            }
            continue;
        }
        // Inline paths in code: crate::a::b, super::x, self::y, child::z.
        let child_keys: Vec<String> = m
            .children
            .iter()
            .filter(|c| inline.is_none() && c.as_str() != "tests")
            .map(|c| format!("{c}::"))
            .collect();
        let keys = ["crate::", "super::", "self::"]
            .into_iter()
            .map(str::to_string)
            .chain(child_keys);
        for key in keys {
            let key = key.as_str();
            let mut from = 0;
            while let Some(i) = line[from..].find(key) {
                let at = from + i;
                let before = line[..at].chars().last();
                from = at + key.len();
                if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                    continue;
                }
                let tail: String = line[at..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                let segs: Vec<String> = tail
                    .split("::")
                    .filter(|s| !s.is_empty())
                    .map(str::to_string)
                    .collect();
                if let Some(a) = absolute(path, inline.as_deref(), &m.children, &segs) {
                    out.push(a);
                }
            }
        }
    }
    out
}

/// `pub use` re-exports of module `path`: exported name → absolute target (None: external).
fn reexports(path: &[String], m: &Module) -> Vec<(String, Option<Vec<String>>)> {
    let mut out = Vec::new();
    for stmt in m.code.split(';') {
        let t = stmt.trim();
        let Some(body) = t.strip_prefix("pub use ") else {
            continue;
        };
        let body: String = body.chars().filter(|c| *c != '\n').collect();
        for leaf in expand_with_alias(&body) {
            let (segs, alias) = leaf;
            let target = absolute(path, None, &m.children, &segs);
            out.push((alias, target));
        }
    }
    out
}

/// Like [`expand`], keeping the name each leaf is exported as (`x as y` → y).
fn expand_with_alias(body: &str) -> Vec<(Vec<String>, String)> {
    let mut out = Vec::new();
    // Split aliases out first: replace " as " leaves by marking them.
    for leaf in expand(&body.replace(" as ", "@")) {
        let mut segs = leaf;
        let last = segs.pop().unwrap_or_default();
        let (name, alias) = match last.split_once('@') {
            Some((n, a)) => (n.to_string(), a.to_string()),
            None => (last.clone(), last),
        };
        segs.push(name);
        if alias != "*" {
            out.push((segs, alias));
        }
    }
    out
}

/// The file an absolute path lands in: the deepest module it names, followed through that
/// module's re-exports of the next segment.
fn resolve(
    modules: &BTreeMap<Vec<String>, Module>,
    target: &[String],
    depth: usize,
) -> Option<String> {
    if depth > 16 {
        return None;
    }
    let mut k = target.len();
    while k > 0 && !modules.contains_key(&target[..k]) {
        k -= 1;
    }
    let module = modules.get(&target[..k])?;
    if let Some(next) = target.get(k) {
        if let Some(re) = module.reexports.get(next) {
            return match re {
                Some(t) => {
                    let full = [t.as_slice(), &target[k + 1..]].concat();
                    resolve(modules, &full, depth + 1).or_else(|| Some(module.node.clone()))
                }
                None => None, // an external crate's item
            };
        }
    }
    Some(module.node.clone())
}

/// Tarjan's strongly connected components.
fn tarjan(
    nodes: &BTreeSet<String>,
    arrows: &BTreeMap<String, BTreeSet<String>>,
) -> Vec<Vec<String>> {
    struct St<'a> {
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        on: BTreeSet<&'a str>,
        stack: Vec<&'a str>,
        next: usize,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(v: &'a str, arrows: &'a BTreeMap<String, BTreeSet<String>>, s: &mut St<'a>) {
        s.index.insert(v, s.next);
        s.low.insert(v, s.next);
        s.next += 1;
        s.stack.push(v);
        s.on.insert(v);
        for w in arrows.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(w, arrows, s);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut c = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on.remove(w);
                c.push(w.to_string());
                if w == v {
                    break;
                }
            }
            s.out.push(c);
        }
    }
    let mut s = St {
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        on: BTreeSet::new(),
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in nodes {
        if !s.index.contains_key(v.as_str()) {
            visit(v, arrows, &mut s);
        }
    }
    s.out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, files: &[(&str, &str)]) {
        for (p, text) in files {
            let f = dir.join(p);
            std::fs::create_dir_all(f.parent().unwrap()).unwrap();
            std::fs::write(f, text).unwrap();
        }
    }

    #[test]
    fn finds_a_cycle_between_two_files_and_none_through_a_facade() {
        let d = tempfile::tempdir().unwrap();
        write(
            d.path(),
            &[
                ("lib.rs", "pub mod a;\npub mod b;\npub mod v;\n"),
                ("a.rs", "use crate::b::Thing;\npub struct A;\n"),
                (
                    "b.rs",
                    "pub struct Thing;\nfn f() { let _ = crate::a::A; }\n",
                ),
                // A facade: v/mod.rs re-exports x's item; y uses it through super.
                ("v/mod.rs", "pub mod x;\npub mod y;\npub use x::X;\n"),
                ("v/x.rs", "pub struct X;\n"),
                ("v/y.rs", "use super::X;\n// use crate::a::A; (a comment)\n"),
            ],
        );
        let g = ImportGraph::read(d.path()).unwrap();
        let cycles = g.cycles();
        assert_eq!(cycles.len(), 1, "{cycles:?}");
        let files: BTreeSet<&str> = cycles[0].iter().map(|(a, _)| a.as_str()).collect();
        assert_eq!(files, BTreeSet::from(["a.rs", "b.rs"]));
        assert!(g.arrows["v/y.rs"].contains("v/x.rs"), "{:?}", g.arrows);
        assert!(
            !g.arrows["v/y.rs"].contains("a.rs"),
            "comments are not imports"
        );
    }

    #[test]
    fn a_parent_using_its_child_that_uses_the_parent_is_a_cycle() {
        let d = tempfile::tempdir().unwrap();
        write(
            d.path(),
            &[
                ("lib.rs", "pub mod p;\n"),
                (
                    "p/mod.rs",
                    "pub mod c;\npub struct Own;\npub fn go() { c::run(); }\n",
                ),
                ("p/c.rs", "use super::{Own};\npub fn run() {}\n"),
            ],
        );
        let g = ImportGraph::read(d.path()).unwrap();
        assert_eq!(g.cycles().len(), 1, "{:?}", g.arrows);
    }

    #[test]
    fn test_modules_are_left_out() {
        let d = tempfile::tempdir().unwrap();
        write(
            d.path(),
            &[
                ("lib.rs", "pub mod a;\npub mod b;\n"),
                (
                    "a.rs",
                    "pub struct A;\n#[cfg(test)]\n#[path = \"a_tests.rs\"]\nmod tests;\n",
                ),
                ("a_tests.rs", "use super::*;\nuse crate::b::B;\n"),
                (
                    "b.rs",
                    "pub struct B;\n#[cfg(test)]\npub(crate) mod tests {\n    use crate::a::A;\n}\n",
                ),
            ],
        );
        let g = ImportGraph::read(d.path()).unwrap();
        assert!(!g.files.contains("a_tests.rs"), "{:?}", g.files);
        assert!(g.arrows.is_empty(), "{:?}", g.arrows);
    }
}
