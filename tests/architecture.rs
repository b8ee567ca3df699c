//! The architecture docs/ARCHITECTURE.md draws, held by the code: the layers (no import runs
//! back up, so no cycle), method names only in the registry and the methods' own folders, and
//! no source file over 800 lines.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nimbus::integrators::registry::METHODS;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, sorted.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A file's code without its unit tests (`#[cfg(test)]` to the end, where nimbus keeps them)
/// and without comment lines, as (line number, line) pairs.
fn code_lines(text: &str) -> Vec<(usize, &str)> {
    text.lines()
        .enumerate()
        .take_while(|(_, l)| !l.trim_start().starts_with("#[cfg(test)]"))
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l))
        .collect()
}

/// The folder (or single-file module) of `src/` a file belongs to.
fn module_of(path: &Path) -> String {
    let rel = path.strip_prefix(root().join("src")).unwrap();
    let first = rel.components().next().unwrap().as_os_str().to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// The layers of docs/ARCHITECTURE.md's diagram, top first: the code block after
/// "## Layers" whose lines list modules separated by `>`.
fn layers() -> Vec<Vec<String>> {
    let doc = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).unwrap();
    let start = doc.find("## Layers").expect("ARCHITECTURE.md has a Layers section");
    // The code blocks are the odd pieces between fences; the diagram is the first with `>`.
    let block = doc[start..]
        .split("```")
        .skip(1)
        .step_by(2)
        .find(|b| b.contains('>'))
        .expect("a diagram of layers separated by '>' in the Layers section");
    block
        .split('>')
        .map(|layer| {
            layer.split(|c: char| c == ',' || c.is_whitespace()).filter(|m| !m.is_empty()).map(String::from).collect()
        })
        .collect()
}

/// Each module of `src/` imports only modules on lower layers of the diagram: no import runs
/// back up, so the module graph has no cycle. `main.rs` and `cli/` (the binary) and `lib.rs`
/// stand above every layer.
#[test]
fn imports_only_run_down_the_layers() {
    let layers = layers();
    let rank: BTreeMap<&str, usize> =
        layers.iter().enumerate().flat_map(|(i, l)| l.iter().map(move |m| (m.as_str(), i))).collect();
    // Names lib.rs re-exports at the crate's root (`pub use error::{Error, Result}`) stand for
    // their module.
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    let mut reexports = BTreeMap::new();
    for line in lib.lines().filter_map(|l| l.trim().strip_prefix("pub use ")) {
        if let Some((module, names)) = line.trim_end_matches(';').split_once("::") {
            for name in names.trim_matches(|c| c == '{' || c == '}').split(',') {
                reexports.insert(name.trim().to_string(), module.to_string());
            }
        }
    }
    let mut problems = Vec::new();
    for path in sources(&root().join("src")) {
        let module = module_of(&path);
        if ["main", "lib", "cli"].contains(&module.as_str()) {
            continue;
        }
        let Some(&own) = rank.get(module.as_str()) else {
            problems.push(format!("src/{module} is on no layer of docs/ARCHITECTURE.md"));
            continue;
        };
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in code_lines(&text) {
            for (i, _) in line.match_indices("crate::") {
                let name: String = line[i + 7..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                let target = reexports.get(&name).cloned().unwrap_or(name);
                if target == module || target.is_empty() {
                    continue;
                }
                match rank.get(target.as_str()) {
                    Some(&r) if r > own => {}
                    _ => problems.push(format!(
                        "{}:{n}: {module} imports {target}, which is not on a layer below it",
                        path.strip_prefix(root()).unwrap().display()
                    )),
                }
            }
        }
    }
    assert!(problems.is_empty(), "imports against the layers:\n{}", problems.join("\n"));
}

/// A method's name or alias appears as a string only in the registry and the methods' own
/// folders: the rest of `src/` asks the registry. `cli/graph.rs` is the one exception, the
/// radiance graph's own toolchain (`nimbus graph build`, the thesis's `graph_maker`).
#[test]
fn method_names_live_in_the_registry_and_their_folders() {
    let names: Vec<&str> =
        METHODS.iter().flat_map(|m| std::iter::once(m.name).chain(m.aliases.iter().copied())).collect();
    let own_folders: Vec<PathBuf> = METHODS.iter().map(|m| root().join("src/integrators").join(m.name)).collect();
    let allowed = [root().join("src/integrators/registry.rs"), root().join("src/cli/graph.rs")];
    let mut problems = Vec::new();
    for path in sources(&root().join("src")) {
        if allowed.contains(&path) || own_folders.iter().any(|f| path.starts_with(f)) {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in code_lines(&text) {
            // The string literals of the line (escaped quotes are rare enough to ignore).
            for literal in line.split('"').skip(1).step_by(2) {
                let words = literal.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-'));
                if let Some(name) = words.into_iter().find(|w| names.contains(w)) {
                    problems.push(format!(
                        "{}:{n}: \"{literal}\" names the method \"{name}\"",
                        path.strip_prefix(root()).unwrap().display()
                    ));
                }
            }
        }
    }
    assert!(problems.is_empty(), "method names outside the registry:\n{}", problems.join("\n"));
}

/// No source file over 800 lines: a file that long holds more than one concept.
#[test]
fn no_source_file_over_800_lines() {
    let mut long = Vec::new();
    for dir in ["src", "parser/src", "tests"] {
        for path in sources(&root().join(dir)) {
            let n = std::fs::read_to_string(&path).unwrap().lines().count();
            if n > 800 {
                long.push(format!("{} ({n} lines)", path.strip_prefix(root()).unwrap().display()));
            }
        }
    }
    assert!(long.is_empty(), "files over 800 lines:\n{}", long.join("\n"));
}
