//! Reading input files without trusting them: only regular files (a named pipe would
//! block the reader forever, a device such as `/dev/zero` never ends), and no more
//! bytes than the caller's limit (checked against the size before reading, and again
//! while reading, for files that grow).

use std::io::Read;
use std::path::Path;

/// `Ok(size)` for a regular file (symbolic links followed) of at most `max_bytes`;
/// otherwise an error of kind [`std::io::ErrorKind::InvalidInput`] saying why (the
/// caller names the file).
pub fn check_regular(path: &Path, max_bytes: u64) -> std::io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a folder, pipe or device)",
        ));
    }
    if meta.len() > max_bytes {
        return Err(too_large(meta.len(), max_bytes));
    }
    Ok(meta.len())
}

/// The whole content of a regular file of at most `max_bytes` (see [`check_regular`]).
pub fn read_regular(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    let size = check_regular(path, max_bytes)?;
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(size as usize).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::OutOfMemory,
            format!("{size} bytes do not fit in memory"),
        )
    })?;
    std::fs::File::open(path)?
        .take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64, max_bytes));
    }
    Ok(bytes)
}

/// [`read_regular`] as UTF-8 text.
pub fn read_regular_text(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read_regular(path, max_bytes)?).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (byte {} is not valid UTF-8)",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// Largest settings file (configuration, scenario) illume reads \[bytes\].
pub const MAX_SETTINGS_BYTES: u64 = 16 << 20;

fn too_large(size: u64, max_bytes: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("{size} bytes is more than the {max_bytes} bytes illume reads from such a file"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_and_large_files_are_refused_before_reading() {
        let dir = std::env::temp_dir().join(format!("illume-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("a.txt");
        std::fs::write(&f, "hello").unwrap();
        assert_eq!(read_regular(&f, 5).unwrap(), b"hello");
        assert_eq!(read_regular_text(&f, 5).unwrap(), "hello");
        let e = read_regular(&f, 4).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert!(e.to_string().contains("5 bytes"), "{e}");
        let e = read_regular(&dir, 100).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        if Path::new("/dev/zero").exists() {
            let e = read_regular(Path::new("/dev/zero"), 100).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        std::fs::write(&f, [0xff, 0xfe]).unwrap();
        let e = read_regular_text(&f, 5).unwrap_err();
        assert!(e.to_string().contains("UTF-8"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
