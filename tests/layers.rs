//! The library's layers go one way: every `crate::` path in a module's code (tests left out)
//! names the module itself or one in a lower layer of the table in `docs/index.md`
//! ("Architecture: the layers"), and the imports between modules of one layer form no circle.
//! The table is the declaration; this test reads it, so the picture and the code cannot drift
//! apart.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library's modules by layer, highest layer first, as `docs/index.md` lists them (the
/// front ends' rows name other crates, written as folders, and are left out).
fn declared_layers(root: &Path) -> Vec<Vec<String>> {
    let index = std::fs::read_to_string(root.join("docs/index.md")).expect("docs/index.md");
    let table = index
        .split("## Architecture: the layers")
        .nth(1)
        .expect("docs/index.md has the section \"Architecture: the layers\"");
    let mut layers = Vec::new();
    for line in table.lines().skip_while(|l| !l.starts_with('|')) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let Some(modules) = cells.get(2) else {
            continue;
        };
        let names: Vec<String> = modules
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|m| !m.contains('/'))
            .map(str::to_string)
            .collect();
        if !names.is_empty() {
            layers.push(names);
        }
    }
    layers
}

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable source folder") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The file a `mod name;` declaration in `file` refers to (`name.rs` or `name/mod.rs`).
fn child_files(file: &Path, name: &str) -> [PathBuf; 2] {
    let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let dir = file.parent().expect("a file in a folder");
    let dir = if matches!(stem, "mod" | "lib") {
        dir.to_path_buf()
    } else {
        dir.join(stem)
    };
    [
        dir.join(format!("{name}.rs")),
        dir.join(name).join("mod.rs"),
    ]
}

/// `source` without comments and without the items under `#[cfg(test)]`; the files of test
/// modules it declares (`#[cfg(test)] mod name;`) go to `test_files`.
fn code_lines(file: &Path, source: &str, test_files: &mut BTreeSet<PathBuf>) -> Vec<String> {
    let mut out = Vec::new();
    let mut lines = source.lines().map(|l| match l.find("//") {
        Some(at) => &l[..at],
        None => l,
    });
    while let Some(line) = lines.next() {
        if line.trim() != "#[cfg(test)]" {
            out.push(line.to_string());
            continue;
        }
        // The item under the attribute: a declaration ending in `;`, or a block.
        let mut depth = 0i64;
        for item in lines.by_ref() {
            let t = item.trim();
            if depth == 0
                && let Some(name) = t
                    .strip_prefix("mod ")
                    .or_else(|| t.strip_prefix("pub(crate) mod "))
                    .and_then(|r| r.strip_suffix(';'))
            {
                test_files.extend(child_files(file, name));
                break;
            }
            depth += item.matches('{').count() as i64 - item.matches('}').count() as i64;
            if depth <= 0 && (t.ends_with('}') || t.ends_with(';')) {
                break;
            }
        }
    }
    out
}

/// The modules that follow `crate::` in `line` (each of a group `crate::{a, b::c}`).
fn crate_paths(line: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    for (at, _) in line.match_indices("crate::") {
        // `crate::` itself, not the tail of `my_crate::` or a macro's `$crate::`.
        if line[..at]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$')
        {
            continue;
        }
        let rest = &line[at + "crate::".len()..];
        match rest.strip_prefix('{') {
            Some(group) => {
                let group = group.split('}').next().unwrap_or("");
                out.extend(group.split(',').map(ident).filter(|m| !m.is_empty()));
            }
            None => out.push(ident(rest)),
        }
    }
    out
}

#[test]
fn every_arrow_between_modules_points_down() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let layers = declared_layers(root);
    assert!(layers.len() >= 5, "no layer table found: {layers:?}");
    let rank: BTreeMap<&str, usize> = layers
        .iter()
        .enumerate()
        .flat_map(|(i, l)| l.iter().map(move |m| (m.as_str(), i)))
        .collect();
    let src = root.join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut test_files = BTreeSet::new();
    let mut code = BTreeMap::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("readable source");
        code.insert(file.clone(), code_lines(file, &text, &mut test_files));
    }
    let mut wrong = Vec::new();
    let mut arrows: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, lines) in &code {
        let relative = file.strip_prefix(&src).expect("under src");
        if relative == Path::new("lib.rs") || test_files.contains(file) {
            continue;
        }
        let first = relative.components().next().expect("a path");
        let module = Path::new(first.as_os_str())
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("a module name")
            .to_string();
        let Some(&from) = rank.get(module.as_str()) else {
            let why = format!("module `{module}` is in no layer of docs/index.md's table");
            if !wrong.contains(&why) {
                wrong.push(why);
            }
            continue;
        };
        for (n, line) in lines.iter().enumerate() {
            for target in crate_paths(line) {
                if target == module {
                    continue;
                }
                let at = format!("src/{}:{}", relative.display(), n + 1);
                match rank.get(target.as_str()) {
                    Some(&to) if to >= from => {
                        arrows.entry(module.clone()).or_default().insert(target);
                    }
                    Some(_) => wrong.push(format!("{at}: `{module}` uses the higher `{target}`")),
                    None => wrong.push(format!(
                        "{at}: `crate::{target}` is not a module of the table (name the module, \
                         not the crate root's re-export)"
                    )),
                }
            }
        }
    }
    // Within a layer arrows may go either way, but not around a circle.
    for start in arrows.keys() {
        let mut seen = BTreeSet::new();
        let mut todo: Vec<&String> = arrows[start].iter().collect();
        while let Some(m) = todo.pop() {
            if m == start {
                wrong.push(format!(
                    "`{start}` reaches itself through the modules it uses"
                ));
                break;
            }
            if seen.insert(m.clone()) {
                todo.extend(arrows.get(m).into_iter().flatten());
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_checker_sees_code_and_not_comments_or_tests() {
    let mut test_files = BTreeSet::new();
    let file = Path::new("src/a/b.rs");
    let source = "use crate::x::Y; // crate::comment\n\
                  fn f() { crate::z::g() }\n\
                  #[cfg(test)]\n\
                  mod tests {\n    use crate::t::T;\n    fn h() {}\n}\n\
                  #[cfg(test)]\n\
                  mod util;\n\
                  use my_crate::w;\n\
                  use crate::{p::P, q};\n";
    let lines = code_lines(file, source, &mut test_files);
    let paths: Vec<String> = lines.iter().flat_map(|l| crate_paths(l)).collect();
    assert_eq!(paths, ["x", "z", "p", "q"]);
    assert!(test_files.contains(Path::new("src/a/b/util.rs")));
}
