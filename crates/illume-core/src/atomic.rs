//! Writing files so that a failure loses nothing: the content goes to a temporary file
//! in the same folder, which is renamed over the target only once complete (a rename
//! within one file system replaces the target at once).

use std::path::{Path, PathBuf};

/// The temporary sibling `path` is written through: `.NAME.PID.tmp` in its folder.
pub fn temporary_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Runs `write` on a temporary sibling of `path`, then renames it over `path`. On any
/// failure the temporary file is removed and `path` is left as it was.
pub fn write_with<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), AtomicWriteError<E>> {
    let tmp = temporary_sibling(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(AtomicWriteError::Write(e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        AtomicWriteError::Rename(e)
    })
}

/// Writes `bytes` to `path` atomically (see [`write_with`]).
pub fn write_file(path: &Path, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    write_with(path, |tmp| std::fs::write(tmp, bytes.as_ref())).map_err(|e| match e {
        AtomicWriteError::Write(e) | AtomicWriteError::Rename(e) => e,
    })
}

/// Why an atomic write failed.
#[derive(Debug)]
pub enum AtomicWriteError<E> {
    /// Writing the temporary file failed.
    Write(E),
    /// Renaming it over the target failed.
    Rename(std::io::Error),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("illume-atomic-file-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.csv");
        write_file(&p, "old").unwrap();
        let failed: Result<(), AtomicWriteError<&str>> = write_with(&p, |tmp| {
            std::fs::write(tmp, "half").unwrap();
            Err("disk full")
        });
        assert!(matches!(failed, Err(AtomicWriteError::Write("disk full"))));
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        write_file(&p, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "no temporary left"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
