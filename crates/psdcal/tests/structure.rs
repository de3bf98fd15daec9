//! The facade is a thin application layer (ARCHITECTURE.md, "The facade"):
//! lib.rs only declares folders and re-exports; the code lives in workflow
//! folders, and a folder imports only from folders below it in [`LAYERS`]
//! (its own files aside). Every `crate::` path of a module names its folder
//! and module, never a re-export at the crate root.

use std::fs;
use std::path::{Path, PathBuf};

/// The folders, lowest first: each may import from those before it.
const LAYERS: [&str; 12] = [
    "base",
    "dataset",
    "psd_map",
    "calibration",
    "answer",
    "signals",
    "live",
    "simulation",
    "reports",
    "network",
    "study",
    "frontend",
];

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// A source file's code: its lines before a `#[cfg(test)]` module, line
/// comments removed (doc comments may name any path).
fn code(path: &Path) -> String {
    fs::read_to_string(path)
        .unwrap()
        .lines()
        .take_while(|l| !l.starts_with("#[cfg(test)]"))
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The first path segment after every `crate::` in `text`, with the
/// segments of `crate::{a::…, b::…}` groups.
fn crate_heads(text: &str) -> Vec<String> {
    let mut heads = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let head: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !head.is_empty() {
                    heads.push(head);
                }
            }
        } else {
            heads.push(
                rest.chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect(),
            );
        }
    }
    heads
}

#[test]
fn lib_rs_only_declares_and_reexports() {
    let lib = code(&src().join("lib.rs"));
    let mut rest = lib.as_str().trim_start();
    while !rest.is_empty() {
        let statement = ["pub use ", "mod ", "#![", "#[cfg("]
            .iter()
            .any(|start| rest.starts_with(start));
        assert!(statement, "lib.rs holds more than declarations: {rest:.60}");
        let end = rest.find([';', ']']).unwrap() + 1;
        assert!(!rest[..end].contains("fn "), "lib.rs holds a function");
        rest = rest[end..].trim_start();
    }
    for layer in LAYERS {
        assert!(
            lib.contains(&format!("mod {layer};")),
            "lib.rs does not declare the folder {layer}"
        );
    }
}

#[test]
fn every_module_lives_in_a_folder_and_imports_only_downwards() {
    let mut checked = 0;
    for entry in fs::read_dir(src()).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            assert_eq!(
                path.file_name().unwrap(),
                "lib.rs",
                "{} is outside the workflow folders",
                path.display()
            );
            continue;
        }
        let folder = path.file_name().unwrap().to_string_lossy().into_owned();
        let level = LAYERS
            .iter()
            .position(|l| *l == folder)
            .unwrap_or_else(|| panic!("the folder {folder} is not in LAYERS"));
        for file in fs::read_dir(&path).unwrap() {
            let file = file.unwrap().path();
            for head in crate_heads(&code(&file)) {
                let target = LAYERS.iter().position(|l| **l == head).unwrap_or_else(|| {
                    panic!(
                        "{}: `crate::{head}` is not a folder path (import from the module \
                         that defines it)",
                        file.display()
                    )
                });
                assert!(
                    target <= level,
                    "{}: the folder {folder} imports from {head}, which sits above it",
                    file.display()
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 40, "only {checked} modules found");
}

#[test]
fn the_crate_path_scanner_reads_groups() {
    assert_eq!(
        crate_heads("use crate::{base::error::Error, answer::sensor};\nx(crate::study::y)"),
        ["base", "answer", "study"]
    );
}
