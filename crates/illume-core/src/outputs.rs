//! Output folders that illume may clear or overwrite only where it can prove it wrote
//! the file (issue 38: a user's `preview.mp4`, `frames.csv` or `frame_00000.png` in an
//! output folder was deleted because its name looked like illume's).
//!
//! The proof is a manifest, [`MANIFEST`], in the folder. Before illume writes a file it
//! appends the file's name (an *intent*); once the file is in place it appends the
//! name with the file's size and modification time (a *stamp*). A file counts as
//! illume's only when its latest record is a stamp that matches it now; a temporary
//! file (`.NAME.PID.tmp`, `.NAME.partial`) counts as illume's when an intent for `NAME`
//! was recorded. Everything else in the folder — a file without a record, one changed
//! since illume wrote it, a folder, a link, a device — is the user's: illume refuses to
//! run and names it, touching nothing. Records are single appended lines (`O_APPEND`),
//! so shards writing into one folder at once share the manifest.

use std::collections::HashMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The manifest's file name in an output folder.
pub const MANIFEST: &str = ".illume-outputs";

/// The manifest's first line.
const HEADER: &str =
    "# illume output manifest v1: name<TAB>size<TAB>mtime_ns per file illume wrote";

/// What can go wrong with an output folder.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file system operation failed.
    #[error("{path}: {what}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The system's error.
        source: std::io::Error,
    },
    /// The folder holds files illume cannot prove it wrote.
    #[error(
        "{dir}: the output folder holds {} illume did not write or that changed since ({}{}); nothing was removed: choose an empty or new folder with --output, or move them away",
        if names.len() == 1 { "a file" } else { "files" },
        names.iter().take(3).cloned().collect::<Vec<_>>().join(", "),
        if names.len() > 3 { format!(" and {} more", names.len() - 3) } else { String::new() }
    )]
    Foreign {
        /// The folder.
        dir: PathBuf,
        /// The entries, sorted.
        names: Vec<String>,
    },
}

/// The latest record of a name in the manifest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Record {
    /// Illume was about to write it.
    Intent,
    /// Illume wrote it: its size and modification time \[ns since the epoch\].
    Stamp(u64, i128),
}

/// How an entry of an output folder relates to the manifest.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Entry {
    /// A file illume wrote and nobody changed since.
    Proven(String),
    /// A file illume meant to write (its intent is recorded) but whose stamp is missing
    /// or does not match: being written by another process now, or replaced since.
    Pending(String),
    /// Anything else: the user's.
    Foreign(String),
}

/// An output folder and its manifest.
#[derive(Clone, Debug)]
pub struct OutputDir {
    dir: PathBuf,
}

fn io<'a>(path: &'a Path, what: &'static str) -> impl FnOnce(std::io::Error) -> OutputError + 'a {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        what,
        source,
    }
}

/// A regular file's size and modification time, as stamped.
fn stamp_of(meta: &std::fs::Metadata) -> Option<(u64, i128)> {
    let mtime = meta.modified().ok()?;
    let ns = match mtime.duration_since(std::time::UNIX_EPOCH) {
        Ok(d) => d.as_nanos() as i128,
        Err(e) => -(e.duration().as_nanos() as i128),
    };
    Some((meta.len(), ns))
}

/// The name a temporary file stands for: `.NAME.PID.tmp` ([`crate::atomic`]) and
/// `.NAME.partial` give `NAME`.
pub fn temporary_target(name: &str) -> Option<&str> {
    let rest = name.strip_prefix('.')?;
    if let Some(target) = rest.strip_suffix(".partial") {
        return Some(target);
    }
    let rest = rest.strip_suffix(".tmp")?;
    let (target, pid) = rest.rsplit_once('.')?;
    (!pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit())).then_some(target)
}

impl OutputDir {
    /// The folder `dir`, created if missing. Its manifest is made by the first record
    /// (a run that fails before writing anything leaves no file behind).
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        std::fs::create_dir_all(dir).map_err(io(dir, "cannot create folder"))?;
        Ok(Self {
            dir: dir.to_path_buf(),
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The manifest's path.
    pub fn manifest(&self) -> PathBuf {
        self.dir.join(MANIFEST)
    }

    /// Appends `line` (with the header first when the manifest is new).
    fn append(&self, line: &str) -> Result<(), OutputError> {
        let path = self.manifest();
        let new = !path.exists();
        let mut text = String::new();
        if new {
            text.push_str(HEADER);
            text.push('\n');
        }
        if !line.is_empty() {
            text.push_str(line);
            text.push('\n');
        }
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(io(&path, "cannot open the output manifest"))?;
        // One write per record: appends of a line are not interleaved between processes.
        file.write_all(text.as_bytes())
            .map_err(io(&path, "cannot write the output manifest"))
    }

    /// Records that illume is about to write `name` (call before creating it or its
    /// temporary file). When `name` exists already it must be illume's (its latest
    /// record a stamp that matches it), or it is refused and left as it is.
    pub fn intend(&self, name: &str) -> Result<(), OutputError> {
        let path = self.dir.join(name);
        if let Ok(meta) = std::fs::symlink_metadata(&path) {
            let proven = meta.is_file()
                && matches!(self.records()?.get(name),
                    Some(Record::Stamp(size, mtime)) if stamp_of(&meta) == Some((*size, *mtime)));
            if !proven {
                return self.refuse_foreign(vec![name.to_owned()]);
            }
        }
        self.append(name)
    }

    /// Records that illume wrote `name` (call once it is in place).
    pub fn written(&self, name: &str) -> Result<(), OutputError> {
        let path = self.dir.join(name);
        let meta = std::fs::metadata(&path).map_err(io(&path, "cannot read back"))?;
        let (size, mtime) = stamp_of(&meta).unwrap_or((meta.len(), 0));
        self.append(&format!("{name}\t{size}\t{mtime}"))
    }

    /// Writes `bytes` as `name` through a temporary file, recording intent and stamp.
    pub fn write_file(&self, name: &str, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        let path = self.dir.join(name);
        self.intend(name)?;
        crate::atomic::write_file(&path, bytes).map_err(io(&path, "cannot write"))?;
        self.written(name)
    }

    /// The manifest's latest record per name (a missing manifest: none).
    fn records(&self) -> Result<HashMap<String, Record>, OutputError> {
        let path = self.manifest();
        let text = match std::fs::symlink_metadata(&path) {
            Ok(m) if m.is_file() => {
                crate::files::read_regular(&path, 1 << 30).map_err(io(&path, "cannot read"))?
            }
            _ => return Ok(HashMap::new()),
        };
        let mut records = HashMap::new();
        for line in String::from_utf8_lossy(&text).lines() {
            if line.starts_with('#') || line.is_empty() {
                continue;
            }
            let mut fields = line.split('\t');
            let name = fields.next().unwrap_or_default().to_owned();
            let record = match (fields.next(), fields.next()) {
                (Some(size), Some(mtime)) => match (size.parse(), mtime.parse()) {
                    (Ok(size), Ok(mtime)) => Record::Stamp(size, mtime),
                    // A torn or edited line proves nothing.
                    _ => Record::Intent,
                },
                _ => Record::Intent,
            };
            records.insert(name, record);
        }
        Ok(records)
    }

    /// Every entry of the folder but the manifest, classified (sorted by name).
    pub fn survey(&self) -> Result<Vec<Entry>, OutputError> {
        let records = self.records()?;
        let mut entries = Vec::new();
        let list = std::fs::read_dir(&self.dir).map_err(io(&self.dir, "cannot list"))?;
        for entry in list {
            let entry = entry.map_err(io(&self.dir, "cannot list"))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            if name == MANIFEST {
                continue;
            }
            // `DirEntry::metadata` does not follow links: a link is never proven.
            let meta = entry.metadata().ok().filter(|m| m.is_file());
            let record = records.get(&name);
            let kind = match (meta, record) {
                (Some(meta), Some(Record::Stamp(size, mtime)))
                    if stamp_of(&meta) == Some((*size, *mtime)) =>
                {
                    Entry::Proven(name)
                }
                (Some(_), Some(_)) => Entry::Pending(name),
                (Some(_), None) => match temporary_target(&name).and_then(|t| records.get(t)) {
                    Some(_) => Entry::Proven(name),
                    None => Entry::Foreign(name),
                },
                (None, _) => Entry::Foreign(name),
            };
            entries.push(kind);
        }
        entries.sort_by(|a, b| entry_name(a).cmp(entry_name(b)));
        Ok(entries)
    }

    /// Refuses when any of `names` is the user's.
    pub fn refuse_foreign(&self, names: Vec<String>) -> Result<(), OutputError> {
        if names.is_empty() {
            return Ok(());
        }
        Err(OutputError::Foreign {
            dir: self.dir.clone(),
            names,
        })
    }

    /// Removes `name` (a file [`OutputDir::survey`] proved illume's).
    pub fn remove(&self, name: &str) -> Result<(), OutputError> {
        let path = self.dir.join(name);
        std::fs::remove_file(&path).map_err(io(&path, "cannot remove an earlier run's file"))
    }

    /// Makes the folder ready for a whole new run: refuses, touching nothing, when
    /// anything in it is not proven illume's; otherwise removes every file and starts
    /// the manifest afresh.
    pub fn clear(dir: &Path) -> Result<Self, OutputError> {
        let out = Self::create(dir)?;
        let mut proven = Vec::new();
        let mut foreign = Vec::new();
        for entry in out.survey()? {
            match entry {
                Entry::Proven(n) => proven.push(n),
                Entry::Pending(n) | Entry::Foreign(n) => foreign.push(n),
            }
        }
        out.refuse_foreign(foreign)?;
        for name in proven {
            out.remove(&name)?;
        }
        // The folder holds nothing now: the manifest starts afresh with the next record.
        let manifest = out.manifest();
        if std::fs::symlink_metadata(&manifest).is_ok() {
            std::fs::remove_file(&manifest)
                .map_err(io(&manifest, "cannot remove the output manifest"))?;
        }
        Ok(out)
    }
}

/// An entry's name.
pub fn entry_name(e: &Entry) -> &str {
    match e {
        Entry::Proven(n) | Entry::Pending(n) | Entry::Foreign(n) => n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fresh(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("illume-outputs-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn only_files_with_a_matching_stamp_are_removed() {
        let dir = fresh("stamp");
        let out = OutputDir::clear(&dir).unwrap();
        out.write_file("frames.csv", "a,b\n").unwrap();
        out.write_file("frame_00000.png", "png").unwrap();
        // A run's files go.
        OutputDir::clear(&dir).unwrap();
        assert!(!dir.join("frames.csv").exists());
        // A user's file of the same name, and one rewritten after illume wrote it, stay.
        let out = OutputDir::clear(&dir).unwrap();
        out.write_file("frames.csv", "a,b\n").unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::write(dir.join("frames.csv"), "the user's table, longer").unwrap();
        std::fs::write(dir.join("preview.mp4"), "the user's film").unwrap();
        let e = OutputDir::clear(&dir).unwrap_err().to_string();
        assert!(e.contains("frames.csv") && e.contains("preview.mp4"), "{e}");
        assert_eq!(
            std::fs::read_to_string(dir.join("frames.csv")).unwrap(),
            "the user's table, longer"
        );
        // A folder without a manifest (an older illume's, or the user's) proves nothing.
        std::fs::remove_file(dir.join(MANIFEST)).unwrap();
        std::fs::remove_file(dir.join("frames.csv")).unwrap();
        assert!(OutputDir::clear(&dir).is_err());
        assert!(dir.join("preview.mp4").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_user_file_is_never_overwritten() {
        let dir = fresh("overwrite");
        let out = OutputDir::create(&dir).unwrap();
        out.write_file("report.md", "one").unwrap();
        out.write_file("report.md", "two").unwrap();
        std::fs::write(dir.join("results.csv"), "the user's").unwrap();
        let e = out
            .write_file("results.csv", "ours")
            .unwrap_err()
            .to_string();
        assert!(e.contains("results.csv"), "{e}");
        assert_eq!(
            std::fs::read_to_string(dir.join("results.csv")).unwrap(),
            "the user's"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporaries_of_intended_files_are_illumes() {
        assert_eq!(
            temporary_target(".frame_00001.png.42.tmp"),
            Some("frame_00001.png")
        );
        assert_eq!(
            temporary_target(".preview.gif.partial"),
            Some("preview.gif")
        );
        assert_eq!(temporary_target(".notes.txt"), None);
        let dir = fresh("tmp");
        let out = OutputDir::clear(&dir).unwrap();
        out.intend("frame_00001.png").unwrap();
        std::fs::write(dir.join(".frame_00001.png.42.tmp"), "half").unwrap();
        std::fs::write(dir.join(".frame_00002.png.42.tmp"), "not ours").unwrap();
        let e = OutputDir::clear(&dir).unwrap_err().to_string();
        assert!(
            e.contains(".frame_00002.png.42.tmp") && !e.contains("00001"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
