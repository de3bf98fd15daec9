//! No input is ever overwritten: before a run, every output path is
//! compared with every input (the same file, also through symbolic or hard
//! links) and with the other outputs, and a clash is refused before any
//! work is done.

use std::path::{Path, PathBuf};

use crate::error::IoError;

/// The identity of an existing file: device and inode on Unix, the
/// canonical path elsewhere.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    #[cfg(not(unix))]
    Canonical(PathBuf),
}

fn identity(path: &Path) -> Option<Identity> {
    let metadata = std::fs::metadata(path).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some(Identity::Inode(metadata.dev(), metadata.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = metadata;
        path.canonicalize().ok().map(Identity::Canonical)
    }
}

/// Where a file that may not exist yet would be: its folder made
/// canonical, then its name.
fn destination(path: &Path) -> PathBuf {
    if let Ok(canonical) = path.canonicalize() {
        return canonical;
    }
    let parent = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    match (parent.canonicalize(), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// Refuses outputs that are one of the inputs or one another. `inputs` and
/// `outputs` pair each path with the option that names it (`--points`,
/// `--out`) for the message.
pub fn refuse_overwrite(
    inputs: &[(&str, &Path)],
    outputs: &[(&str, &Path)],
) -> Result<(), IoError> {
    for (k, (out_option, out)) in outputs.iter().enumerate() {
        let out_identity = identity(out);
        for (in_option, input) in inputs {
            let same = match (&out_identity, identity(input)) {
                (Some(a), Some(b)) => *a == b,
                _ => destination(out) == destination(input),
            };
            if same {
                return Err(IoError::OutputIsInput {
                    file: out.display().to_string(),
                    message: format!(
                        "{out_option} would overwrite the input given with {in_option} ({}); \
                         nothing was done: write the output to another file",
                        input.display()
                    ),
                });
            }
        }
        for (other_option, other) in &outputs[..k] {
            if destination(out) == destination(other) {
                return Err(IoError::OutputIsInput {
                    file: out.display().to_string(),
                    message: format!(
                        "{out_option} and {other_option} name the same file; nothing was done: \
                         give them different files"
                    ),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_files_through_links_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("obs.csv");
        std::fs::write(&input, "x").unwrap();
        let other = dir.path().join("out.json");
        let ok = refuse_overwrite(&[("-o", &input)], &[("--out", &other)]);
        assert!(ok.is_ok());
        let e = refuse_overwrite(&[("-o", &input)], &[("--out", &input)]).unwrap_err();
        assert!(
            e.to_string()
                .contains("--out would overwrite the input given with -o"),
            "{e}"
        );
        // Through a relative spelling, a hard link and a symbolic link.
        let dotted = dir.path().join(".").join("obs.csv");
        assert!(refuse_overwrite(&[("-o", &input)], &[("--out", &dotted)]).is_err());
        let hard = dir.path().join("hard.csv");
        std::fs::hard_link(&input, &hard).unwrap();
        assert!(refuse_overwrite(&[("-o", &input)], &[("--out", &hard)]).is_err());
        #[cfg(unix)]
        {
            let soft = dir.path().join("soft.csv");
            std::os::unix::fs::symlink(&input, &soft).unwrap();
            assert!(refuse_overwrite(&[("-o", &input)], &[("--out", &soft)]).is_err());
        }
        // Two outputs that are one file, existing or not.
        let e = refuse_overwrite(&[], &[("--out", &other), ("--residuals", &other)]).unwrap_err();
        assert!(e.to_string().contains("name the same file"), "{e}");
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "x");
    }
}
