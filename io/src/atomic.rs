//! The atomic file writer: temporary sibling, checked writes, fsync, rename, cleanup.

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::fs::{real, FileSystem, OutFile};

const STEP_DIR_SYNC: &str = "fsync of the folder";

/// Why a file could not be written. Names the final path, the step and the OS reason.
#[derive(Debug)]
pub struct WriteError {
    /// The file that was to be written (not the temporary).
    pub path: PathBuf,
    /// What failed: "create", "write", "allocate", "map", "fsync", "rename".
    pub step: &'static str,
    /// The OS error.
    pub source: io::Error,
}

impl std::fmt::Display for WriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let reason = self.source.to_string().replace(['\n', '\r'], " ");
        write!(
            f,
            "{}: cannot write ({} failed): {reason}",
            self.path.display(),
            self.step
        )?;
        if self.step != STEP_DIR_SYNC {
            f.write_str("; nothing was written under that name")?;
        }
        Ok(())
    }
}

impl std::error::Error for WriteError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}

impl From<WriteError> for io::Error {
    fn from(e: WriteError) -> Self {
        io::Error::new(e.source.kind(), e.to_string())
    }
}

/// A file being written under a temporary name next to its final path. [`AtomicFile::commit`]
/// syncs and renames it into place; dropping it uncommitted (or any failed step) removes the
/// temporary, so the final path holds the old file or the complete new one.
///
/// The first failed write is remembered: later writes fail with it and `commit` returns it,
/// so a caller that ignores one error (a `BufWriter` dropped unflushed) still cannot commit a
/// cut file.
pub struct AtomicFile {
    fs: Arc<dyn FileSystem>,
    path: PathBuf,
    tmp: PathBuf,
    file: Option<Box<dyn OutFile>>,
    written: u64,
    failed: Option<(&'static str, io::Error)>,
    sync_dir: bool,
}

impl std::fmt::Debug for AtomicFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AtomicFile")
            .field("path", &self.path)
            .field("tmp", &self.tmp)
            .field("written", &self.written)
            .finish()
    }
}

/// `.<name>.aerie-tmp<pid>-<n>` next to `path`: hidden, unique within the process and across
/// processes, recognisable if a killed process leaves one behind.
fn temp_sibling(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.aerie-tmp{}-{n}", std::process::id()))
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

impl AtomicFile {
    /// Starts writing `path` on the real file system.
    pub fn create(path: &Path) -> Result<Self, WriteError> {
        Self::create_in(real(), path)
    }

    /// Starts writing `path` on `fs`.
    pub fn create_in(fs: Arc<dyn FileSystem>, path: &Path) -> Result<Self, WriteError> {
        let tmp = temp_sibling(path);
        let file = fs.create_new(&tmp).map_err(|source| WriteError {
            path: path.to_path_buf(),
            step: "create",
            source,
        })?;
        Ok(Self {
            fs,
            path: path.to_path_buf(),
            tmp,
            file: Some(file),
            written: 0,
            failed: None,
            sync_dir: true,
        })
    }

    /// Skips the folder `fsync` after the rename (the file itself is still synced before
    /// it): for many small files in one folder whose durability across a power cut matters
    /// less than their count.
    pub fn without_dir_sync(mut self) -> Self {
        self.sync_dir = false;
        self
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The temporary being written (tests check it is gone).
    pub fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// Bytes written so far.
    pub fn written(&self) -> u64 {
        self.written
    }

    fn error(&self, step: &'static str, source: io::Error) -> WriteError {
        WriteError {
            path: self.path.clone(),
            step,
            source,
        }
    }

    fn fail(&mut self, step: &'static str, e: &io::Error) {
        if self.failed.is_none() {
            self.failed = Some((step, io::Error::new(e.kind(), e.to_string())));
        }
    }

    fn check(&self) -> Result<(), WriteError> {
        match &self.failed {
            Some((step, e)) => Err(self.error(step, io::Error::new(e.kind(), e.to_string()))),
            None => Ok(()),
        }
    }

    /// Reserves `len` bytes on the disk and returns a writable map of them. The blocks are
    /// allocated before the map exists, so filling it cannot fault on a full disk; the bytes
    /// count as written. Call once, before any [`Write`] use.
    pub fn map_preallocated(&mut self, len: u64) -> Result<memmap2::MmapMut, WriteError> {
        self.check()?;
        let file = self.file.as_mut().expect("open until commit");
        if let Err(e) = file.allocate(len) {
            self.fail("allocate", &e);
            return Err(self.error("allocate", e));
        }
        // The temporary was created by this process with O_EXCL under a name no one else uses,
        // and it is not resized while the map lives (the map is dropped before `commit`).
        // SAFETY: its `len` bytes are allocated (posix_fallocate) and nobody else maps or resizes it.
        let map = unsafe {
            memmap2::MmapOptions::new()
                .len(len as usize)
                .map_mut(file.os_file())
        };
        match map {
            Ok(m) => {
                self.written = len;
                Ok(m)
            }
            Err(e) => {
                self.fail("map", &e);
                Err(self.error("map", e))
            }
        }
    }

    /// Flushes a map returned by [`AtomicFile::map_preallocated`], with the error named.
    pub fn flush_map(&mut self, map: &memmap2::MmapMut) -> Result<(), WriteError> {
        map.flush().map_err(|e| {
            self.fail("write", &e);
            self.error("write", e)
        })
    }

    /// Syncs the file, renames it over the final path and syncs the folder. On failure the
    /// temporary is removed and the final path is untouched.
    pub fn commit(mut self) -> Result<(), WriteError> {
        self.check()?;
        let mut file = self.file.take().expect("open until commit");
        if let Err(e) = file.flush().and_then(|_| file.sync_all()) {
            drop(file);
            return Err(self.error("fsync", e));
        }
        drop(file);
        if let Err(e) = self.fs.rename(&self.tmp, &self.path) {
            return Err(self.error("rename", e));
        }
        // Renamed: nothing to clean up any more.
        self.tmp = PathBuf::new();
        if self.sync_dir {
            self.fs
                .sync_dir(parent_dir(&self.path))
                .map_err(|e| self.error(STEP_DIR_SYNC, e))?;
        }
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if let Err(e) = self.check() {
            return Err(e.into());
        }
        let file = self.file.as_mut().expect("open until commit");
        match file.write(buf) {
            Ok(0) if !buf.is_empty() => {
                let e = io::Error::new(io::ErrorKind::WriteZero, "the disk took no bytes");
                self.fail("write", &e);
                Err(self.error("write", e).into())
            }
            Ok(n) => {
                self.written += n as u64;
                Ok(n)
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Err(e),
            Err(e) => {
                self.fail("write", &e);
                Err(self.error("write", e).into())
            }
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        if let Err(e) = self.check() {
            return Err(e.into());
        }
        let file = self.file.as_mut().expect("open until commit");
        file.flush().map_err(|e| {
            self.fail("write", &e);
            self.error("write", e).into()
        })
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        drop(self.file.take());
        if !self.tmp.as_os_str().is_empty() {
            let _ = self.fs.remove_file(&self.tmp);
        }
    }
}

/// Writes `bytes` to `path` atomically on the real file system.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_atomic_in(real(), path, bytes)
}

/// Writes `bytes` to `path` atomically on `fs`.
pub fn write_atomic_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    bytes: &[u8],
) -> Result<(), WriteError> {
    let mut f = AtomicFile::create_in(fs, path)?;
    if let Err(e) = f.write_all(bytes) {
        return Err(f.check().err().unwrap_or_else(|| f.error("write", e)));
    }
    f.commit()
}
