//! The architecture holds (ARCHITECTURE.md): no file imports a file that imports it back, the
//! renderer's layers import only downwards, no source file over 800 lines, and the terrain
//! decisions build without any Vulkan or windowing crate; the frame plan names no Vulkan type.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use aerie_tests::imports::ImportGraph;
use aerie_tests::repo_root;

/// The library crates of the workspace (their `src/` folders).
const CRATES: [&str; 5] = [
    "renderer/src",
    "terrain/src",
    "sim-bridge/src",
    "config/src",
    "io/src",
];

/// The renderer's layers, bottom first: a file may import its own layer or a lower one.
const LAYERS: [&str; 5] = ["vk", "render", "sim", "tools", "app"];

fn graph(src: &str) -> ImportGraph {
    ImportGraph::read(&repo_root().join(src)).unwrap_or_else(|e| panic!("{src}: {e}"))
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let mut report = String::new();
    for src in CRATES {
        let g = graph(src);
        assert!(g.files.len() > 3, "{src}: read only {:?}", g.files);
        for cycle in g.cycles() {
            report.push_str(&format!("{src}: a cycle of {} arrows:\n", cycle.len()));
            for (a, b) in cycle {
                report.push_str(&format!("  {a} -> {b}\n"));
            }
        }
    }
    assert!(report.is_empty(), "import cycles:\n{report}");
}

fn layer_of(file: &str) -> Option<usize> {
    let top = file.split('/').next()?;
    LAYERS.iter().position(|l| *l == top)
}

#[test]
fn renderer_layers_import_only_downwards() {
    let g = graph("renderer/src");
    let mut seen = BTreeSet::new();
    let mut upward = Vec::new();
    for (from, tos) in &g.arrows {
        let Some(lf) = layer_of(from) else { continue };
        for to in tos {
            let Some(lt) = layer_of(to) else { continue };
            seen.insert((LAYERS[lf], LAYERS[lt]));
            if lt > lf {
                upward.push(format!("{from} ({}) -> {to} ({})", LAYERS[lf], LAYERS[lt]));
            }
        }
    }
    // The graph is really read: the render layer uses vk, the app uses render.
    assert!(seen.contains(&("render", "vk")), "{seen:?}");
    assert!(seen.contains(&("app", "render")), "{seen:?}");
    assert!(
        upward.is_empty(),
        "imports that run up the layers:\n{}",
        upward.join("\n")
    );
}

fn is_test_file(rel: &str) -> bool {
    let name = rel.rsplit('/').next().unwrap_or(rel);
    name == "tests.rs" || name.ends_with("_tests.rs") || rel.contains("/tests/")
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_source_file_over_800_lines() {
    let root = repo_root();
    let mut long = Vec::new();
    let mut counted = 0;
    for src in CRATES {
        let mut files = Vec::new();
        rust_files(&root.join(src), &mut files);
        for f in files {
            let rel = f.strip_prefix(&root).unwrap().to_string_lossy().to_string();
            if is_test_file(&rel) {
                continue;
            }
            counted += 1;
            let lines = std::fs::read_to_string(&f).unwrap().lines().count();
            if lines > 800 {
                long.push(format!("{rel}: {lines} lines"));
            }
        }
    }
    assert!(counted > 50, "only {counted} source files found");
    assert!(
        long.is_empty(),
        "files over 800 lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn terrain_crate_has_no_vulkan_or_window_dependency() {
    let lock = std::fs::read_to_string(repo_root().join("Cargo.lock")).unwrap();
    let lock: toml::Value = toml::from_str(&lock).unwrap();
    let packages = lock["package"].as_array().unwrap();
    let deps: BTreeMap<&str, Vec<&str>> = packages
        .iter()
        .map(|p| {
            let name = p["name"].as_str().unwrap();
            let d = p
                .get("dependencies")
                .and_then(|d| d.as_array())
                .map(|a| {
                    // "name" or "name version" when several versions are locked.
                    a.iter()
                        .filter_map(|v| v.as_str()?.split(' ').next())
                        .collect()
                })
                .unwrap_or_default();
            (name, d)
        })
        .collect();
    let mut reach = BTreeSet::new();
    let mut todo = vec!["aerie-terrain"];
    while let Some(n) = todo.pop() {
        if reach.insert(n) {
            todo.extend(deps.get(n).into_iter().flatten().copied());
        }
    }
    // Read for real: the renderer reaches ash through its own entry.
    assert!(deps["aerie"].contains(&"ash"));
    assert!(reach.contains("glam"), "{reach:?}");
    for banned in [
        "ash",
        "ash-window",
        "gpu-allocator",
        "winit",
        "raw-window-handle",
    ] {
        assert!(
            !reach.contains(banned),
            "aerie-terrain depends on {banned} (through {reach:?})"
        );
    }
}

#[test]
fn commands_do_not_import_the_command_enum() {
    // cli.rs dispatches to the commands; a command importing it back was the old 9-file cycle.
    let g = graph("renderer/src");
    assert!(g.arrows["app/cli.rs"]
        .iter()
        .any(|f| f.starts_with("app/commands/")));
    let importers: Vec<&String> = g
        .arrows
        .iter()
        .filter(|(_, to)| to.contains("app/cli.rs"))
        .map(|(from, _)| from)
        .collect();
    assert!(importers.is_empty(), "import app/cli.rs: {importers:?}");
}

#[test]
fn the_frame_plan_names_no_vulkan_type() {
    // The decisions of a frame are plain data (ARCHITECTURE.md "What is pure"): no `ash` import
    // and no `vk::` type in their code (doc comments may mention what the recording makes).
    let root = repo_root().join("renderer/src/render");
    for file in ["plan.rs", "jobs.rs", "stats.rs", "uniforms.rs"] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(text.lines().count() > 20, "{file} is not the plan I know");
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            assert!(
                !code.contains("ash::") && !code.contains("vk::") && !code.contains("use ash"),
                "render/{file}:{}: {line}",
                i + 1
            );
        }
    }
}
