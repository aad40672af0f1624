//! No source file under `src/` grows past [`MOST_LINES`] lines: a file that long holds several
//! concerns, and a newcomer reads a module a file at a time. The files that are longer today are
//! listed in [`LONGER_TODAY`] with their length, which they may not exceed; each leaves the list
//! when it is split (the list only shrinks).

use std::path::Path;

/// The most lines a source file under `src/` has.
const MOST_LINES: usize = 800;

/// Files longer than [`MOST_LINES`] today, with the most lines each may have until it is split.
const LONGER_TODAY: &[(&str, usize)] = &[];

#[test]
fn no_source_file_is_longer_than_its_limit() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut lengths = Vec::new();
    collect(&src, &src, &mut lengths);
    assert!(lengths.len() > 20, "found only {} files", lengths.len());
    let mut problems = Vec::new();
    for (rel, lines) in &lengths {
        let limit = LONGER_TODAY
            .iter()
            .find(|(name, _)| name == rel)
            .map_or(MOST_LINES, |&(_, most)| most);
        if *lines > limit {
            problems.push(format!("src/{rel}: {lines} lines, at most {limit}"));
        }
    }
    for (name, most) in LONGER_TODAY {
        match lengths.iter().find(|(rel, _)| rel == name) {
            None => problems.push(format!("src/{name} is listed in LONGER_TODAY but gone")),
            Some((_, lines)) if *lines <= MOST_LINES => problems.push(format!(
                "src/{name} has {lines} lines now: take it out of LONGER_TODAY"
            )),
            Some((_, lines)) if lines < most => problems.push(format!(
                "src/{name} shrank to {lines} lines: lower its LONGER_TODAY entry from {most}"
            )),
            Some(_) => {}
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every `.rs` file under `dir`, as (path relative to `root`, lines).
fn collect(root: &Path, dir: &Path, out: &mut Vec<(String, usize)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let lines = std::fs::read_to_string(&path).unwrap().lines().count();
            out.push((rel, lines));
        }
    }
}
