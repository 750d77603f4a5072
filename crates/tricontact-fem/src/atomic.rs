//! Atomic file replacement: write `name.tmp.ext` next to the target (the same extension, so
//! writers that choose a format by it work), sync it, then `rename` it over the target. On POSIX
//! file systems the rename is atomic, so readers (and a crash) see either the old or the new file,
//! never a half-written one; a failed write removes its temporary file.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{FemError, Result};

/// The temporary path next to `path`: `name.tmp.ext` (`name.tmp` without an extension).
fn temp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_stem()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// Replaces `path` atomically with the file `write` creates at the temporary path it is given.
///
/// # Errors
/// The error of `write`, or I/O errors with the path.
pub fn write_atomic_with(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    let done = write(&tmp).and_then(|()| {
        std::fs::File::open(&tmp)
            .and_then(|f| f.sync_all())
            .map_err(|e| FemError::io(&tmp, e))
    });
    if let Err(e) = done {
        let _ = std::fs::remove_file(&tmp);
        // The user named `path`, not its temporary twin: an I/O error names `path`.
        return Err(match e {
            FemError::Io { path: p, source } if p == tmp => FemError::io(path, source),
            other => other,
        });
    }
    std::fs::rename(&tmp, path).map_err(|e| FemError::io(path, e))
}

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// I/O errors, with the path.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |tmp| {
        let mut file = std::fs::File::create(tmp).map_err(|e| FemError::io(tmp, e))?;
        file.write_all(bytes).map_err(|e| FemError::io(tmp, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_content_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("tricontact-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("a.txt");
        write_atomic(&p, b"one").expect("write");
        write_atomic(&p, b"two").expect("write");
        assert_eq!(std::fs::read(&p).expect("read"), b"two");
        assert!(!dir.join("a.tmp.txt").exists());
        // A failing writer leaves neither its temporary file nor a changed target.
        let failed = write_atomic_with(&p, |tmp| {
            std::fs::write(tmp, b"half").map_err(|e| FemError::io(tmp, e))?;
            Err(FemError::Output("refused".into()))
        });
        assert!(failed.is_err());
        // An I/O error names the file asked for, not the temporary one.
        let missing = dir.join("no-such-folder").join("b.txt");
        let e = write_atomic(&missing, b"x")
            .expect_err("no folder")
            .to_string();
        assert!(
            e.contains("no-such-folder/b.txt") && !e.contains(".tmp"),
            "{e}"
        );
        assert_eq!(std::fs::read(&p).expect("read"), b"two");
        assert!(!dir.join("a.tmp.txt").exists());
        std::fs::remove_dir_all(&dir).ok();
    }
}
