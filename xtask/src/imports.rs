//! The import graph between a crate's top-level modules (`crate::runner` → `crate::bus`), from
//! the `crate::` paths its non-test code names, and the cycles in it. A shared module that
//! reaches up into the modules built on it (a registry read by the loader, a bus folder importing
//! the CLI) makes every change ripple through all of them: the tests below keep the harness,
//! the simulator, the codecs and the fuzz targets free of such cycles.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module → the top-level modules its non-test code names, each with the files that
/// name it.
pub(crate) type Graph = BTreeMap<String, BTreeMap<String, BTreeSet<String>>>;

/// The graph of the crate whose sources are below `src`.
pub(crate) fn graph(src: &Path) -> std::io::Result<Graph> {
    let mut graph = Graph::new();
    let mut files = Vec::new();
    rust_files(src, &mut files)?;
    for file in files {
        let rel = file.strip_prefix(src).unwrap_or(&file);
        let Some(first) = rel.components().next() else {
            continue;
        };
        let first = first.as_os_str().to_string_lossy();
        let module = first.strip_suffix(".rs").unwrap_or(&first).to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        let text = without_tests(&without_comments(&std::fs::read_to_string(&file)?));
        let node = graph.entry(module.clone()).or_default();
        for named in crate_paths(&text) {
            if named != module && named != "self" {
                node.entry(named)
                    .or_default()
                    .insert(rel.display().to_string());
            }
        }
    }
    Ok(graph)
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            rust_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// The text without `//` comments: doc links (`[`crate::bus`]`) are no imports.
fn without_comments(text: &str) -> String {
    text.lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The text without the items marked `#[cfg(test)]` (a test module, a helper for tests): what
/// only the tests use is not part of the build's structure.
fn without_tests(text: &str) -> String {
    const MARK: &str = "#[cfg(test)]";
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find(MARK) {
        out.push_str(&rest[..at]);
        let item = &rest[at + MARK.len()..];
        // The item ends at its `;` (a `use`, a `mod x;`) or at the brace closing its body.
        let end = match (item.find(';'), item.find('{')) {
            (Some(semi), Some(open)) if semi < open => semi + 1,
            (Some(semi), None) => semi + 1,
            (_, Some(open)) => closing(item, open).map_or(item.len(), |c| c + 1),
            (None, None) => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The index of the brace closing the one at `open`. Braces inside string and character
/// literals do not count: a test's YAML text or format string may hold one alone.
fn closing(text: &str, open: usize) -> Option<usize> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut i = open;
    while i < b.len() {
        match b[i] {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(i);
                }
            }
            b'"' => i = string_end(b, i + 1, None)?,
            b'r' if !b[..i]
                .last()
                .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') =>
            {
                let hashes = b[i + 1..].iter().take_while(|c| **c == b'#').count();
                if b.get(i + 1 + hashes) == Some(&b'"') {
                    i = string_end(b, i + 2 + hashes, Some(hashes))?;
                }
            }
            // A character literal ('{', '\''); a lifetime ('a) has no closing quote.
            b'\'' => match (b.get(i + 1), b.get(i + 2), b.get(i + 3)) {
                (Some(b'\\'), _, _) => i = i + 2 + b[i + 2..].iter().position(|c| *c == b'\'')?,
                (Some(_), Some(b'\''), _) => i += 2,
                _ => {}
            },
            _ => {}
        }
        i += 1;
    }
    None
}

/// The index of the last character ending a string literal whose text starts at `from`: a raw
/// string's (`raw`: its number of `#`) takes no escapes and ends at a quote and as many `#`.
fn string_end(b: &[u8], from: usize, raw: Option<usize>) -> Option<usize> {
    let hashes = raw.unwrap_or(0);
    let mut i = from;
    while i < b.len() {
        match b[i] {
            b'\\' if raw.is_none() => i += 1,
            b'"' if b[i + 1..]
                .iter()
                .take(hashes)
                .filter(|c| **c == b'#')
                .count()
                == hashes =>
            {
                return Some(i + hashes);
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The top-level modules named by `crate::name` or `crate::{a, b::c}`.
fn crate_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (at, _) in text.match_indices("crate::") {
        if text[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == '$') {
            continue; // `$crate::`, `my_crate::`
        }
        let after = &text[at + "crate::".len()..];
        if after.starts_with('{') {
            let end = closing(after, 0).unwrap_or(after.len());
            let mut depth = 0;
            let mut items = vec![String::new()];
            for c in after[1..end].chars() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => items.push(String::new()),
                    _ => {}
                }
                if let Some(item) = items.last_mut() {
                    item.push(c);
                }
            }
            out.extend(
                items
                    .iter()
                    .map(|i| leading_name(i.trim_start_matches(',').trim())),
            );
        } else {
            out.push(leading_name(after));
        }
    }
    out.retain(|n| !n.is_empty());
    out
}

/// The identifier `text` starts with.
fn leading_name(text: &str) -> String {
    text.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The cycles of `graph`: its strongly connected components of more than one module.
pub(crate) fn cycles(graph: &Graph) -> Vec<BTreeSet<String>> {
    // Kosaraju: finishing order on the graph, then components on the reversed graph.
    let nodes: BTreeSet<&str> = graph
        .iter()
        .flat_map(|(a, to)| std::iter::once(a.as_str()).chain(to.keys().map(String::as_str)))
        .collect();
    let next = |n: &str| -> Vec<&str> {
        graph
            .get(n)
            .map(|to| to.keys().map(String::as_str).collect())
            .unwrap_or_default()
    };
    let mut seen = BTreeSet::new();
    let mut order = Vec::new();
    for &start in &nodes {
        if !seen.insert(start) {
            continue;
        }
        let mut stack = vec![(start, next(start), 0usize)];
        while let Some((node, to, i)) = stack.last_mut() {
            if let Some(&n) = to.get(*i) {
                *i += 1;
                if seen.insert(n) {
                    stack.push((n, next(n), 0));
                }
            } else {
                order.push(*node);
                stack.pop();
            }
        }
    }
    let mut reversed: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, to) in graph {
        for b in to.keys() {
            reversed.entry(b.as_str()).or_default().push(a.as_str());
        }
    }
    let mut placed = BTreeSet::new();
    let mut out = Vec::new();
    for &start in order.iter().rev() {
        if !placed.insert(start) {
            continue;
        }
        let mut component = BTreeSet::from([start.to_string()]);
        let mut todo = vec![start];
        while let Some(n) = todo.pop() {
            for &m in reversed.get(n).map(Vec::as_slice).unwrap_or_default() {
                if placed.insert(m) {
                    component.insert(m.to_string());
                    todo.push(m);
                }
            }
        }
        if component.len() > 1 {
            out.push(component);
        }
    }
    out
}

/// A cycle as a reader fixes it: each edge inside it, with the files that make it.
pub(crate) fn explain(graph: &Graph, cycle: &BTreeSet<String>) -> String {
    let mut s = String::new();
    for a in cycle {
        for (b, files) in graph.get(a).into_iter().flatten() {
            if cycle.contains(b) {
                let files: Vec<&str> = files.iter().map(String::as_str).collect();
                s.push_str(&format!("  {a} -> {b}: {}\n", files.join(", ")));
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_acyclic(krate: &str) {
        let src = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(krate)
            .join("src");
        let graph = graph(&src).unwrap();
        assert!(graph.len() > 5, "{krate}: {} modules", graph.len());
        let found: Vec<String> = cycles(&graph).iter().map(|c| explain(&graph, c)).collect();
        assert!(
            found.is_empty(),
            "{krate}'s top-level modules import each other in a cycle:\n{}",
            found.join("\n")
        );
    }

    #[test]
    fn the_harness_modules_import_without_cycles() {
        assert_acyclic("harness");
    }

    #[test]
    fn the_simulator_and_the_codecs_import_without_cycles() {
        assert_acyclic("sim");
        assert_acyclic("proto");
    }

    #[test]
    fn the_fuzz_targets_import_without_cycles() {
        assert_acyclic("fuzz");
    }

    #[test]
    fn paths_groups_and_test_items_are_read_as_the_compiler_reads_them() {
        let text = "use crate::a::X;\nuse crate::{b::{Y, Z}, c};\n// crate::commented\n\
                    #[cfg(test)]\nuse crate::only_tests;\n#[cfg(test)]\nmod tests { use crate::t; }\n\
                    fn f() { $crate::macro_path; crate::d::g() }";
        let text = without_tests(&without_comments(text));
        let mut found = crate_paths(&text);
        found.sort();
        assert_eq!(found, ["a", "b", "c", "d"]);
    }

    #[test]
    fn a_brace_in_a_literal_does_not_end_a_test_module() {
        let text = "#[cfg(test)]\nmod tests {\n  const Y: &str = r#\"x: [{ a\"#;\n  \
                    const Z: &str = \"{\\\"\";\n  const C: char = '{';\n  \
                    fn f<'a>(x: &'a str) { crate::t::g(x) }\n}\nfn h() { crate::e::k() }";
        assert_eq!(crate_paths(&without_tests(text)), ["e"]);
    }

    #[test]
    fn a_cycle_is_found_and_named_by_its_edges() {
        let mut graph = Graph::new();
        let mut edge = |a: &str, b: &str| {
            graph
                .entry(a.into())
                .or_default()
                .entry(b.into())
                .or_default()
                .insert(format!("{a}.rs"));
        };
        edge("runner", "bus");
        edge("bus", "enip");
        edge("enip", "runner");
        edge("cli", "runner");
        let found = cycles(&graph);
        assert_eq!(found.len(), 1);
        assert_eq!(
            found[0].iter().map(String::as_str).collect::<Vec<_>>(),
            ["bus", "enip", "runner"]
        );
        assert!(explain(&graph, &found[0]).contains("enip -> runner: enip.rs"));
    }
}
