//! The README's Rust example is `examples/readme.rs` verbatim (that file
//! is compiled by `cargo test`, so the README's example compiles), and the
//! dependencies it shows are the ones the example needs: the facade by
//! path and the workspace's nalgebra version.

use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The text of the first ```` ```LANG ```` block of `text`.
fn block<'a>(text: &'a str, lang: &str) -> &'a str {
    let open = format!("```{lang}\n");
    let start = text.find(&open).expect("the block") + open.len();
    let end = start + text[start..].find("```").expect("its end");
    &text[start..end]
}

#[test]
fn the_readme_rust_example_is_the_compiled_example() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let example = std::fs::read_to_string(root().join("crates/psdcal/examples/readme.rs")).unwrap();
    assert_eq!(block(&readme, "rust"), example);
    assert!(
        !readme.contains("cargo add psdcal"),
        "the crate is not published"
    );
}

#[test]
fn the_readme_dependencies_name_the_workspace_versions() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let toml = block(&readme, "toml");
    assert!(
        toml.contains("psdcal = { path = \"../psdcal/crates/psdcal\" }"),
        "{toml}"
    );
    let workspace = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let nalgebra = workspace
        .lines()
        .find(|l| l.starts_with("nalgebra = "))
        .unwrap();
    let version = nalgebra.split('"').nth(1).unwrap();
    assert!(
        toml.contains(&format!("nalgebra = \"{version}\"")),
        "{toml}"
    );
}
