//! The crate's modules depend on each other without cycles.
//!
//! Lower layers never name upper ones. Today's layering, bottom up: `math`, `fixed`, `error`,
//! `limits`, `orca` → `geometry`, `rng` → `config` → `params` → `room` → `state` → `spec`,
//! `outputs` → `recording`, `scenario` → `sngnn` → `systems` → `pipeline` → `backend` → `document`
//! → `env` → `heatmap` → `render` → `viewer` (and the CLI, a crate of its own under `src/bin/`, left out). This test
//! does not pin that order, only what makes an order possible: it reads `src/` as text, builds the
//! graph of which module names which, and fails naming every cycle, with a line behind each
//! dependency.
//!
//! What counts as a dependency: every path of a `use` declaration and every `crate::…`,
//! `super::…`, `self::…` or `child_module::…` path in code, after comments (doc comments
//! included) and string and char literals are stripped and `#[cfg(test)]` items removed (`$crate`
//! paths in macro bodies are the caller's). A path is resolved to the deepest module file it
//! reaches (inline modules such as `state::role` belong to their file), through `pub use`
//! re-exports, so that naming an item through a facade (`crate::sngnn::Scorer`) is a dependency
//! on the module that defines it (`sngnn::scorer`). A module's uses of its own submodules
//! (declaring, re-exporting, calling them) are not dependencies; its submodules' uses of it are.
//!
//! Three graphs are checked: the top-level modules (`state` ↔ `systems` is a cycle even when only
//! `state::document` names `systems`), a finer one in which the submodules of [`SPLIT`] are nodes
//! of their own (`scenario` ↔ `systems::reset`, `systems::metrics` ↔ `systems::reward`; deeper
//! modules belong to their depth-2 ancestor, and each parent's own file is a node too), and the
//! files: every module file a node (`backend::gpu::device` ↔ `backend::gpu::kit` is a cycle).

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fmt::Write as _;
use std::path::Path;

/// Top-level modules whose submodules are nodes of the fine graph.
const SPLIT: &[&str] = &["backend", "config", "scenario", "sngnn", "state", "systems"];

#[test]
fn module_graph_is_acyclic() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    collect_files(&src, &src, &mut files);
    assert!(
        files.len() > 20,
        "found only {} source files under src/",
        files.len()
    );
    let graph = ModuleGraph::build(&files);
    // The parser sees the crate's dependencies at all.
    assert!(
        graph.edges.len() > 100,
        "only {} dependencies found",
        graph.edges.len()
    );
    assert!(graph.edges.contains_key(&("env".into(), "backend".into())));
    let report = graph.cycles(SPLIT);
    assert!(report.is_empty(), "module dependency cycles:\n{report}");
}

/// Every `.rs` file under `dir` but the CLI's, as (path relative to `root`, text), sorted.
fn collect_files(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let rel = path
            .strip_prefix(root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if path.is_dir() {
            if rel != "bin" {
                collect_files(root, &path, out);
            }
        } else if rel.ends_with(".rs") {
            out.push((rel, std::fs::read_to_string(&path).unwrap()));
        }
    }
}

/// The module path of a file relative to `src/` (`""` for the crate root).
fn module_of(rel: &str) -> String {
    let stem = rel.strip_suffix(".rs").unwrap();
    let stem = stem.strip_suffix("/mod").unwrap_or(stem);
    if stem == "lib" {
        String::new()
    } else {
        stem.replace('/', "::")
    }
}

/// Whether module `m` is `prefix` or one of its submodules.
fn within(m: &str, prefix: &str) -> bool {
    m == prefix || prefix.is_empty() || m.starts_with(&format!("{prefix}::"))
}

// ---------------------------------------------------------------------------------------------
// Text: comments and literals stripped, then tokens
// ---------------------------------------------------------------------------------------------

/// The source with comments (doc comments included), string literals (raw and byte ones too) and
/// char literals blanked out; newlines are kept so that line numbers still match.
fn strip(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let blank = |out: &mut String, s: &[char]| {
        out.extend(s.iter().filter(|&&ch| ch == '\n'));
    };
    let mut i = 0;
    while i < c.len() {
        let prev_ident = i > 0 && ident(c[i - 1]);
        if c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && c.get(i + 1) == Some(&'*') {
            let (start, mut depth) = (i, 0);
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            blank(&mut out, &c[start..i.min(c.len())]);
        } else if c[i] == 'r'
            && (!prev_ident || (c[i - 1] == 'b' && (i < 2 || !ident(c[i - 2]))))
            && matches!(c.get(i + 1), Some('"' | '#'))
        {
            // Raw string r"…", r#"…"#, br#"…"# (the `b` stays behind as a harmless identifier).
            let start = i;
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]); // `r#ident`
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            blank(&mut out, &c[start..j.min(c.len())]);
            i = j;
        } else if c[i] == '"' {
            let start = i;
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
            blank(&mut out, &c[start..i.min(c.len())]);
        } else if c[i] == '\'' && c.get(i + 1) == Some(&'\\') {
            // Escaped char literal: '\n', '\'', '\u{…}' (the escaped character is skipped).
            i += 3;
            while i < c.len() && c[i] != '\'' {
                i += 1;
            }
            i += 1;
            out.push_str("' '");
        } else if c[i] == '\'' && c.get(i + 2) == Some(&'\'') {
            i += 3;
            out.push_str("' '");
        } else {
            out.push(c[i]); // includes the quote of a lifetime
            i += 1;
        }
    }
    out
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Punct(char),
}

fn tokens(stripped: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = stripped.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(c[start..i].iter().collect()), line));
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push((Tok::Sep, line));
            i += 2;
        } else {
            out.push((Tok::Punct(ch), line));
            i += 1;
        }
    }
    out
}

fn is_ident(t: Option<&(Tok, usize)>, name: &str) -> bool {
    matches!(t, Some((Tok::Ident(s), _)) if s == name)
}

fn is_punct(t: Option<&(Tok, usize)>, p: char) -> bool {
    matches!(t, Some((Tok::Punct(q), _)) if *q == p)
}

/// The index just past the bracketed group that opens at `i` (`(`, `[` or `{`).
fn skip_group(toks: &[(Tok, usize)], mut i: usize) -> usize {
    let mut depth = 0i32;
    while i < toks.len() {
        match toks[i].0 {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => {
                depth -= 1;
                if depth == 0 {
                    return i + 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    i
}

/// The tokens with every `#[cfg(test)]` item removed, and the names of the `#[cfg(test)] mod x;`
/// declarations among them; `None` when the file itself is `#![cfg(test)]`.
#[allow(clippy::type_complexity, reason = "a private helper of one test")]
fn without_test_items(toks: Vec<(Tok, usize)>) -> Option<(Vec<(Tok, usize)>, Vec<String>)> {
    let is_cfg_test = |toks: &[(Tok, usize)], at: usize| -> bool {
        let want = [
            Tok::Punct('['),
            Tok::Ident("cfg".into()),
            Tok::Punct('('),
            Tok::Ident("test".into()),
            Tok::Punct(')'),
            Tok::Punct(']'),
        ];
        toks.len() >= at + want.len() && toks[at..at + want.len()].iter().map(|t| &t.0).eq(&want)
    };
    let mut out = Vec::with_capacity(toks.len());
    let mut test_mods = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        if is_punct(toks.get(i), '#') && is_punct(toks.get(i + 1), '!') && is_cfg_test(&toks, i + 2)
        {
            return None;
        }
        if !(is_punct(toks.get(i), '#') && is_cfg_test(&toks, i + 1)) {
            out.push(toks[i].clone());
            i += 1;
            continue;
        }
        // Skip the attribute, any further attributes, then the item: up to its `;` or through its
        // `{…}` body, whichever comes first outside brackets.
        i += 7;
        while is_punct(toks.get(i), '#') && is_punct(toks.get(i + 1), '[') {
            i = skip_group(&toks, i + 1);
        }
        let item_start = i;
        while i < toks.len() {
            match toks[i].0 {
                Tok::Punct(';') => {
                    i += 1;
                    break;
                }
                Tok::Punct('{') => {
                    i = skip_group(&toks, i);
                    break;
                }
                Tok::Punct('(' | '[') => i = skip_group(&toks, i),
                _ => i += 1,
            }
        }
        let item = &toks[item_start..i];
        let m = item.iter().position(|t| t.0 == Tok::Ident("mod".into()));
        if let (Some(m), Some((Tok::Punct(';'), _))) = (m, item.last()) {
            if let Some((Tok::Ident(name), _)) = item.get(m + 1) {
                test_mods.push(name.clone());
            }
        }
    }
    Some((out, test_mods))
}

// ---------------------------------------------------------------------------------------------
// Paths
// ---------------------------------------------------------------------------------------------

/// A path named in a file: the module whose scope it is written in, its segments as written and
/// its line; `reexport` holds the exported name of a `pub use` leaf.
#[derive(Debug)]
struct Named {
    scope: Vec<String>,
    segs: Vec<String>,
    line: usize,
    reexport: Option<String>,
}

/// Parses a use tree starting at `i` into its leaves (path, alias or `*`).
#[allow(clippy::type_complexity, reason = "a private helper of one test")]
fn use_tree(
    toks: &[(Tok, usize)],
    i: &mut usize,
    mut prefix: Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>, usize)>,
) {
    let line = toks.get(*i).map_or(0, |t| t.1);
    if toks.get(*i).map(|t| &t.0) == Some(&Tok::Sep) {
        *i += 1; // `use ::std::…`
    }
    loop {
        match toks.get(*i).map(|t| &t.0) {
            Some(Tok::Ident(s)) if s != "as" => {
                prefix.push(s.clone());
                *i += 1;
                if toks.get(*i).map(|t| &t.0) == Some(&Tok::Sep) {
                    *i += 1;
                } else {
                    break;
                }
            }
            Some(Tok::Punct('{')) => {
                *i += 1;
                while *i < toks.len() && !is_punct(toks.get(*i), '}') {
                    let before = *i;
                    use_tree(toks, i, prefix.clone(), out);
                    if is_punct(toks.get(*i), ',') {
                        *i += 1;
                    } else if *i == before {
                        *i += 1; // unexpected token: move on
                    }
                }
                *i += 1;
                return;
            }
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push((prefix, Some("*".into()), line));
                return;
            }
            _ => break,
        }
    }
    let mut alias = None;
    if is_ident(toks.get(*i), "as") {
        if let Some((Tok::Ident(a), _)) = toks.get(*i + 1) {
            alias = Some(a.clone());
        }
        *i += 2;
    }
    // `use a::b::{self, …}`: `self` names the module itself.
    if prefix.len() > 1 && prefix.last().is_some_and(|s| s == "self") {
        prefix.pop();
    }
    out.push((prefix, alias, line));
}

/// Every path a file names: use declarations and module-rooted paths in code. `children` are the
/// file modules directly below `module`.
fn named_paths(
    module: &[String],
    toks: &[(Tok, usize)],
    children: &BTreeSet<String>,
) -> Vec<Named> {
    let mut out = Vec::new();
    // Inline modules open at the file's top: (name, brace depth inside it).
    let mut inline: Vec<(String, i32)> = Vec::new();
    let mut depth = 0i32;
    let scope = |inline: &[(String, i32)]| -> Vec<String> {
        module
            .iter()
            .cloned()
            .chain(inline.iter().map(|(n, _)| n.clone()))
            .collect()
    };
    let mut i = 0;
    while i < toks.len() {
        let prev = if i > 0 { Some(&toks[i - 1].0) } else { None };
        match &toks[i].0 {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                if inline.last().is_some_and(|&(_, d)| d == depth) {
                    inline.pop();
                }
                depth -= 1;
            }
            Tok::Ident(kw)
                if kw == "mod"
                    && matches!(toks.get(i + 1), Some((Tok::Ident(_), _)))
                    && is_punct(toks.get(i + 2), '{') =>
            {
                if let Some((Tok::Ident(name), _)) = toks.get(i + 1) {
                    inline.push((name.clone(), depth + 1));
                }
            }
            Tok::Ident(kw) if kw == "use" && !is_punct(toks.get(i + 1), '<') => {
                // `pub use` or `pub(…) use`.
                let public = is_ident(toks.get(i.wrapping_sub(1)), "pub")
                    || (is_punct(toks.get(i.wrapping_sub(1)), ')')
                        && (2..6).any(|k| {
                            i >= k
                                && is_ident(toks.get(i - k), "pub")
                                && is_punct(toks.get(i - k + 1), '(')
                        }));
                let line = toks[i].1;
                i += 1;
                let mut leaves = Vec::new();
                use_tree(toks, &mut i, Vec::new(), &mut leaves);
                let scope = scope(&inline);
                for (segs, alias, _) in leaves {
                    let reexport = match (&alias, public) {
                        (Some(a), true) if a == "*" => None,
                        (Some(a), true) if a == "_" => None,
                        (Some(a), true) => Some(a.clone()),
                        (None, true) => segs.last().cloned(),
                        _ => None,
                    };
                    out.push(Named {
                        scope: scope.clone(),
                        segs,
                        line,
                        reexport,
                    });
                }
                while i < toks.len() && !is_punct(toks.get(i), ';') {
                    i += 1;
                }
                continue;
            }
            Tok::Ident(first)
                if toks.get(i + 1).map(|t| &t.0) == Some(&Tok::Sep)
                    && !matches!(prev, Some(Tok::Sep | Tok::Punct('$' | '.')))
                    && (matches!(first.as_str(), "crate" | "super" | "self")
                        || (inline.is_empty() && children.contains(first))) =>
            {
                let line = toks[i].1;
                let mut segs = vec![first.clone()];
                let mut j = i + 1;
                while toks.get(j).map(|t| &t.0) == Some(&Tok::Sep) {
                    match toks.get(j + 1) {
                        Some((Tok::Ident(s), _)) => {
                            segs.push(s.clone());
                            j += 2;
                        }
                        _ => break,
                    }
                }
                out.push(Named {
                    scope: scope(&inline),
                    segs,
                    line,
                    reexport: None,
                });
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// A path written in `scope`, made absolute (segments below the crate root), or `None` when it
/// leaves the crate.
fn absolute(scope: &[String], segs: &[String], modules: &BTreeSet<String>) -> Option<Vec<String>> {
    let first = segs.first()?;
    match first.as_str() {
        "crate" => Some(segs[1..].to_vec()),
        "self" => Some(scope.iter().chain(&segs[1..]).cloned().collect()),
        "super" => {
            let ups = segs.iter().take_while(|s| *s == "super").count();
            let base = scope.len().checked_sub(ups)?;
            Some(scope[..base].iter().chain(&segs[ups..]).cloned().collect())
        }
        _ => {
            let child: Vec<String> = scope
                .iter()
                .chain(std::iter::once(first))
                .cloned()
                .collect();
            modules
                .contains(&child.join("::"))
                .then(|| scope.iter().chain(segs).cloned().collect())
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The graph
// ---------------------------------------------------------------------------------------------

struct ModuleGraph {
    /// (from, to) file modules → the first place that makes the dependency: `file:line path`.
    edges: BTreeMap<(String, String), String>,
}

impl ModuleGraph {
    /// `files`: (path relative to `src/`, text).
    fn build(files: &[(String, String)]) -> Self {
        struct File {
            rel: String,
            module: String,
            named: Vec<Named>,
        }
        let mut modules: BTreeSet<String> = files.iter().map(|(rel, _)| module_of(rel)).collect();
        let mut parsed = Vec::new();
        let mut test_only = BTreeSet::new();
        for (rel, text) in files {
            let module = module_of(rel);
            let Some((toks, test_mods)) = without_test_items(tokens(&strip(text))) else {
                test_only.insert(module);
                continue;
            };
            for m in test_mods {
                test_only.insert(if module.is_empty() {
                    m
                } else {
                    format!("{module}::{m}")
                });
            }
            parsed.push((rel.clone(), module, toks));
        }
        modules.retain(|m| !test_only.iter().any(|t| within(m, t)));
        let mut files = Vec::new();
        for (rel, module, toks) in parsed {
            if !modules.contains(&module) {
                continue;
            }
            let segs: Vec<String> = if module.is_empty() {
                vec![]
            } else {
                module.split("::").map(String::from).collect()
            };
            let children = modules
                .iter()
                .filter_map(|m| {
                    let rest = if module.is_empty() {
                        Some(m.as_str())
                    } else {
                        m.strip_prefix(&format!("{module}::"))
                    }?;
                    (!rest.is_empty() && !rest.contains("::")).then(|| rest.to_string())
                })
                .collect();
            let named = named_paths(&segs, &toks, &children);
            files.push(File { rel, module, named });
        }

        // Re-exports: module → exported name → absolute path of what it names.
        let mut reexports: BTreeMap<String, BTreeMap<String, Vec<String>>> = BTreeMap::new();
        for f in &files {
            for n in &f.named {
                if let (Some(name), Some(abs)) =
                    (&n.reexport, absolute(&n.scope, &n.segs, &modules))
                {
                    reexports
                        .entry(f.module.clone())
                        .or_default()
                        .insert(name.clone(), abs);
                }
            }
        }
        // The deepest file module a path reaches, through re-exports.
        let resolve = |mut abs: Vec<String>| -> String {
            for _ in 0..16 {
                let len = (0..=abs.len())
                    .rev()
                    .find(|&k| modules.contains(&abs[..k].join("::")))
                    .unwrap_or(0);
                let module = abs[..len].join("::");
                match abs
                    .get(len)
                    .and_then(|name| reexports.get(&module)?.get(name))
                {
                    Some(target) if *target != abs[..=len] => {
                        abs = target.iter().chain(&abs[len + 1..]).cloned().collect();
                    }
                    _ => return module,
                }
            }
            panic!("re-export loop at {}", abs.join("::"));
        };

        let mut edges = BTreeMap::new();
        for f in &files {
            for n in &f.named {
                let Some(abs) = absolute(&n.scope, &n.segs, &modules) else {
                    continue;
                };
                let to = resolve(abs);
                if to == f.module || to.is_empty() || f.module.is_empty() {
                    continue;
                }
                // A module owns its submodules: declaring, re-exporting or calling them is no
                // dependency (the submodules' uses of it are).
                if within(&to, &f.module) {
                    continue;
                }
                edges
                    .entry((f.module.clone(), to))
                    .or_insert_with(|| format!("src/{}:{} {}", f.rel, n.line, n.segs.join("::")));
            }
        }
        ModuleGraph { edges }
    }

    /// The cycles of the top-level graph, of the fine one and of the files': for each strongly connected
    /// component its modules and a shortest cycle through each of them, every dependency with the
    /// place that makes it. Empty when there are none.
    fn cycles(&self, split: &[&str]) -> String {
        let top = |m: &str| m.split("::").next().unwrap().to_string();
        let fine = |m: &str| {
            let segs: Vec<&str> = m.split("::").collect();
            let depth = if split.contains(&segs[0]) { 2 } else { 1 };
            segs[..depth.min(segs.len())].join("::")
        };
        let mut report = String::new();
        for (name, node) in [
            ("top-level modules", &top as &dyn Fn(&str) -> String),
            ("submodules", &fine),
            ("files", &|m: &str| m.to_string()),
        ] {
            let mut graph: BTreeMap<String, BTreeMap<String, &str>> = BTreeMap::new();
            for ((from, to), place) in &self.edges {
                let (a, b) = (node(from), node(to));
                if a != b {
                    graph.entry(a).or_default().entry(b).or_insert(place);
                }
            }
            for component in strongly_connected(&graph) {
                let all: Vec<&str> = component.iter().map(String::as_str).collect();
                let _ = writeln!(report, "[{name}] modules on a cycle: {}", all.join(", "));
                // A shortest cycle through each of them, each written once.
                let mut seen = BTreeSet::new();
                for start in &component {
                    let mut cycle = shortest_cycle(&graph, &component, start);
                    let first = (0..cycle.len()).min_by_key(|&k| &cycle[k]).unwrap();
                    cycle.rotate_left(first);
                    if !seen.insert(cycle.clone()) {
                        continue;
                    }
                    let _ = writeln!(report, "  {} -> {}", cycle.join(" -> "), cycle[0]);
                    for (k, a) in cycle.iter().enumerate() {
                        let b = &cycle[(k + 1) % cycle.len()];
                        let _ = writeln!(report, "    {a} -> {b}: {}", graph[a][b]);
                    }
                }
            }
        }
        report
    }
}

/// The strongly connected components of more than one node (Tarjan), in a stable order.
fn strongly_connected<V>(graph: &BTreeMap<String, BTreeMap<String, V>>) -> Vec<BTreeSet<String>> {
    struct Tarjan<'g, V> {
        graph: &'g BTreeMap<String, BTreeMap<String, V>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        on_stack: BTreeSet<&'g str>,
        out: Vec<BTreeSet<String>>,
    }
    impl<'g, V> Tarjan<'g, V> {
        fn visit(&mut self, v: &'g str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.graph.get(v).into_iter().flat_map(|m| m.keys()) {
                if !self.index.contains_key(w.as_str()) {
                    self.visit(w);
                    let lw = self.low[w.as_str()];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.on_stack.contains(w.as_str()) {
                    let iw = self.index[w.as_str()];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = BTreeSet::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on_stack.remove(w);
                    component.insert(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    self.out.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.out.sort();
    t.out
}

/// A shortest cycle through `start`, inside its strongly connected `component`.
fn shortest_cycle<V>(
    graph: &BTreeMap<String, BTreeMap<String, V>>,
    component: &BTreeSet<String>,
    start: &String,
) -> Vec<String> {
    let mut parent: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = VecDeque::from([start.as_str()]);
    while let Some(v) = queue.pop_front() {
        for w in graph[v].keys().filter(|w| component.contains(*w)) {
            if w == start {
                let mut cycle = vec![v.to_string()];
                let mut at = v;
                while at != start {
                    at = parent[at];
                    cycle.push(at.to_string());
                }
                cycle.reverse();
                return cycle;
            }
            if !parent.contains_key(w.as_str()) {
                parent.insert(w, v);
                queue.push_back(w);
            }
        }
    }
    unreachable!("{start} lies on no cycle of its component");
}

// ---------------------------------------------------------------------------------------------
// The checker itself
// ---------------------------------------------------------------------------------------------

fn graph_of(files: &[(&str, &str)]) -> ModuleGraph {
    let files: Vec<(String, String)> = files
        .iter()
        .map(|(r, t)| (r.to_string(), t.to_string()))
        .collect();
    ModuleGraph::build(&files)
}

#[test]
fn strip_blanks_comments_and_literals_only() {
    let text = r##"a // crate::x::y
"crate::s" /* crate::b /* nested */ */ r#"crate::r"# '"' '\'' "crate::t" '\u{1F600}'
fn f<'a>(x: &'a str) {} b'c' br"crate::q" "two
lines crate::m \" crate::e"
crate::kept::item"##;
    let stripped = strip(text);
    assert_eq!(stripped.matches("crate").count(), 1, "{stripped}");
    assert!(stripped.contains("fn f<'a>(x: &'a str)"), "{stripped}");
    assert_eq!(stripped.lines().count(), 5, "{stripped}");
    assert!(
        stripped.lines().last().unwrap().starts_with("crate::kept"),
        "{stripped}"
    );
}

#[test]
fn finds_a_cycle_through_super_and_a_facade() {
    let g = graph_of(&[
        ("lib.rs", "pub mod a; pub mod systems;"),
        ("a.rs", "use crate::systems::run;\nfn f() { run() }"),
        (
            "systems/mod.rs",
            "pub mod reset; mod other;\npub use reset::run;",
        ),
        ("systems/reset.rs", "pub fn run() { super::super::a::g(); }"),
        ("systems/other.rs", "use super::reset::run;"),
    ]);
    assert!(
        g.edges.contains_key(&("a".into(), "systems::reset".into())),
        "{:?}",
        g.edges
    );
    assert!(
        !g.edges
            .contains_key(&("systems".into(), "systems::reset".into())),
        "{:?}",
        g.edges
    );
    let report = g.cycles(&["systems"]);
    let top = "[top-level modules] modules on a cycle: a, systems\n  a -> systems -> a\n";
    assert!(report.contains(top), "{report}");
    let fine = "[submodules] modules on a cycle: a, systems::reset\n  a -> systems::reset -> a\n";
    assert!(report.contains(fine), "{report}");
    assert!(
        report.contains("src/systems/reset.rs:1 super::super::a::g"),
        "{report}"
    );
}

#[test]
fn ignores_test_modules_doc_comments_and_strings() {
    let g = graph_of(&[
        ("lib.rs", "pub mod a; pub mod b;"),
        ("a.rs", "use crate::b::X;"),
        (
            "b.rs",
            "/// Calls [`crate::a::f`].\npub struct X;\nconst S: &str = \"crate::a::f\";\n\
             #[cfg(test)]\nmod tests { use crate::a::f; fn t() { crate::a::f() } }\n\
             macro_rules! m { () => { $crate::a::f() } }",
        ),
    ]);
    assert_eq!(g.edges.len(), 1, "{:?}", g.edges);
    assert!(g.cycles(&[]).is_empty());
}

#[test]
fn resolves_groups_self_and_inline_modules() {
    let g = graph_of(&[
        ("lib.rs", "pub mod a; pub mod b; pub mod c;"),
        (
            "a.rs",
            "use crate::{b::{self, Y}, c as cc};\npub mod inner { use super::super::c::Z; }",
        ),
        ("b.rs", "pub struct Y;"),
        ("c.rs", "pub struct Z;"),
    ]);
    let edges: Vec<_> = g.edges.keys().cloned().collect();
    assert_eq!(edges, [("a".into(), "b".into()), ("a".into(), "c".into())]);
}

#[test]
fn finds_a_cycle_between_files_below_depth_two() {
    // `backend::gpu::device` and `backend::gpu::kit` fold into `backend::gpu` in the fine graph,
    // so only the graph of files sees them name each other; the parent's uses of its children
    // (declaring, re-exporting) are no dependency, so `gpu` ↔ `gpu::kit` is no cycle.
    let g = graph_of(&[
        ("lib.rs", "pub mod backend;"),
        ("backend/mod.rs", "pub mod gpu;"),
        (
            "backend/gpu/mod.rs",
            "pub mod device; pub mod kit;\npub use device::GpuDevice;",
        ),
        (
            "backend/gpu/device.rs",
            "pub struct GpuDevice { cache: super::kit::Cache }",
        ),
        (
            "backend/gpu/kit.rs",
            "use super::GpuDevice;\npub struct Cache;",
        ),
    ]);
    let report = g.cycles(&["backend"]);
    let files = "[files] modules on a cycle: backend::gpu::device, backend::gpu::kit\n";
    assert!(report.contains(files), "{report}");
    assert!(
        report.contains(
            "backend::gpu::kit -> backend::gpu::device: src/backend/gpu/kit.rs:1 super::GpuDevice"
        ),
        "{report}"
    );
    assert!(!report.contains("[submodules]"), "{report}");
    assert!(!report.contains("[top-level modules]"), "{report}");
}
