//! Atomic file replacement: write `name.tmp` next to the target, flush and
//! sync it, then `rename` over the target. On POSIX file systems the rename
//! is atomic, so readers (and a crash) see either the old or the new file,
//! never a half-written one.

use std::io::Write;
use std::path::Path;

use crate::error::{FemError, Result};

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// I/O errors, with the path.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut tmp_name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let mut file = std::fs::File::create(&tmp).map_err(|e| FemError::io(&tmp, e))?;
    file.write_all(bytes).map_err(|e| FemError::io(&tmp, e))?;
    file.sync_all().map_err(|e| FemError::io(&tmp, e))?;
    drop(file);
    std::fs::rename(&tmp, path).map_err(|e| FemError::io(path, e))
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
        assert!(!dir.join("a.txt.tmp").exists());
        std::fs::remove_dir_all(&dir).ok();
    }
}
