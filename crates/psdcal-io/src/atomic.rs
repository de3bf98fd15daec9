//! Atomic file output: every file psdcal writes (CSV or JSON) appears whole
//! or not at all.
//!
//! The content goes to a new temporary file in the destination's directory
//! (so that the final rename stays on one file system), which is flushed,
//! then renamed over the destination. If anything fails the temporary file is
//! removed and the destination is left as it was.
//!
//! A reader (or psdcal killed mid-write) therefore never sees a partial file.
//! The file is not forced to disk (no `fsync`): on this class of machine an
//! `fsync` costs several milliseconds, more than a whole calibration, and the
//! operating system writes the file back within seconds (file systems such
//! as ext4 flush a file renamed over another before committing the rename).
//! Run `sync` if the power may fail right after a run.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::IoError;

/// Writes a file atomically: `write` fills a buffered temporary file next to
/// `path`, which then replaces `path`.
pub fn write_atomic<F>(path: impl AsRef<Path>, write: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let path = path.as_ref();
    let error = |source| IoError::Write {
        file: path.display().to_string(),
        source,
    };
    let (temp_path, file) = create_temp(path).map_err(error)?;
    let result = fill(file, write).and_then(|()| fs::rename(&temp_path, path));
    if let Err(source) = result {
        // Best effort: the temporary file may already be gone.
        let _ = fs::remove_file(&temp_path);
        return Err(error(source));
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// A new, exclusively created temporary file in the destination's directory.
fn create_temp(path: &Path) -> io::Result<(PathBuf, File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            "the destination is not a file name",
        )
    })?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(name);
        temp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        let temp_path = dir.join(temp_name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp_path)
        {
            Ok(file) => return Ok((temp_path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

fn fill<F>(file: File, write: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        write_atomic_bytes(&path, b"first\n").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "first\n");
        write_atomic(&path, |w| writeln!(w, "second {}", 2)).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "second 2\n");
        assert_eq!(entries(dir.path()), ["out.csv"]);
    }

    #[test]
    fn failure_leaves_destination_untouched_and_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        fs::write(&path, "old").unwrap();
        let e = write_atomic(&path, |w| {
            w.write_all(b"partial new content")?;
            Err(io::Error::other("disk full"))
        })
        .unwrap_err();
        assert_eq!(fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(entries(dir.path()), ["out.json"]);
        assert!(matches!(e, IoError::Write { .. }));
        assert_eq!(
            e.to_string(),
            format!("{}: cannot write the file: disk full", path.display())
        );
    }

    #[test]
    fn missing_directory_is_a_write_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/out.csv");
        let e = write_atomic_bytes(&path, b"x").unwrap_err();
        assert!(matches!(e, IoError::Write { .. }));
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }

    #[test]
    fn destination_that_is_a_directory_fails_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sub");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep"), "k").unwrap();
        assert!(write_atomic_bytes(&target, b"x").is_err());
        assert_eq!(entries(dir.path()), ["sub"]);
        assert_eq!(entries(&target), ["keep"]);
    }
}
