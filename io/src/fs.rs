//! The file operations aerie's writers and page readers use, behind a trait so tests can put
//! [`crate::FaultyFs`] in their place.

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// A file open for writing.
pub trait OutFile: Write + Send {
    /// `fsync`: the data and metadata are on the disk when this returns `Ok`.
    fn sync_all(&mut self) -> io::Result<()>;
    /// Reserves `len` bytes of blocks (`posix_fallocate`); the file is at least `len` long.
    fn allocate(&mut self, len: u64) -> io::Result<()>;
    /// Cuts or extends the file to `len` bytes.
    fn set_len(&mut self, len: u64) -> io::Result<()>;
    /// The OS file, for memory-mapping a file whose blocks [`OutFile::allocate`] reserved.
    fn os_file(&self) -> &File;
}

/// A file open for reading at offsets (the tile store's pages, bake files).
pub trait InFile: Send + Sync {
    /// Reads up to `buf.len()` bytes at `offset`; may return fewer (a short read).
    fn read_at(&self, buf: &mut [u8], offset: u64) -> io::Result<usize>;
    /// The file's length now.
    fn len(&self) -> io::Result<u64>;
    /// Whether the file is empty now.
    fn is_empty(&self) -> io::Result<bool> {
        Ok(self.len()? == 0)
    }
    /// Fills `buf` from `offset`, retrying short reads; a file that ends first is
    /// `UnexpectedEof` with the offset reached.
    fn read_exact_at(&self, mut buf: &mut [u8], mut offset: u64) -> io::Result<()> {
        while !buf.is_empty() {
            match self.read_at(buf, offset) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        format!("the file ends at byte offset {offset}"),
                    ))
                }
                Ok(n) => {
                    buf = &mut buf[n..];
                    offset += n as u64;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// Creating, renaming, removing and syncing files.
pub trait FileSystem: Send + Sync + std::fmt::Debug {
    /// Creates `path`, failing if it exists (`O_EXCL`): temporaries never clobber anything.
    fn create_new(&self, path: &Path) -> io::Result<Box<dyn OutFile>>;
    /// Creates or truncates `path` (files appended to as they grow: recordings).
    fn create(&self, path: &Path) -> io::Result<Box<dyn OutFile>>;
    /// Opens `path` for reading.
    fn open(&self, path: &Path) -> io::Result<Box<dyn InFile>>;
    /// Renames `from` over `to` (same folder: atomic).
    fn rename(&self, from: &Path, to: &Path) -> io::Result<()>;
    /// Removes a file.
    fn remove_file(&self, path: &Path) -> io::Result<()>;
    /// `fsync` of a folder, so a rename in it survives a power cut.
    fn sync_dir(&self, dir: &Path) -> io::Result<()>;
}

/// The operating system's files.
#[derive(Debug, Default, Clone, Copy)]
pub struct RealFs;

/// The shared [`RealFs`].
pub fn real() -> Arc<dyn FileSystem> {
    static REAL: OnceLock<Arc<dyn FileSystem>> = OnceLock::new();
    REAL.get_or_init(|| Arc::new(RealFs)).clone()
}

struct RealOut(File);

impl Write for RealOut {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()
    }
}

impl OutFile for RealOut {
    fn sync_all(&mut self) -> io::Result<()> {
        self.0.sync_all()
    }

    fn allocate(&mut self, len: u64) -> io::Result<()> {
        allocate(&self.0, len)
    }

    fn set_len(&mut self, len: u64) -> io::Result<()> {
        self.0.set_len(len)
    }

    fn os_file(&self) -> &File {
        &self.0
    }
}

#[cfg(unix)]
fn allocate(f: &File, len: u64) -> io::Result<()> {
    use std::os::fd::AsRawFd;
    if len == 0 {
        return Ok(());
    }
    let len = libc::off_t::try_from(len)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "file too large"))?;
    loop {
        // The function reads no memory of ours.
        // SAFETY: a valid open descriptor owned by `f` for the duration of the call.
        let r = unsafe { libc::posix_fallocate(f.as_raw_fd(), 0, len) };
        match r {
            0 => return Ok(()),
            libc::EINTR => continue,
            e => return Err(io::Error::from_raw_os_error(e)),
        }
    }
}

#[cfg(not(unix))]
fn allocate(f: &File, len: u64) -> io::Result<()> {
    // No block reservation here: callers that map the file must write it instead.
    f.set_len(len)
}

struct RealIn(File);

impl InFile for RealIn {
    #[cfg(unix)]
    fn read_at(&self, buf: &mut [u8], offset: u64) -> io::Result<usize> {
        std::os::unix::fs::FileExt::read_at(&self.0, buf, offset)
    }

    #[cfg(windows)]
    fn read_at(&self, buf: &mut [u8], offset: u64) -> io::Result<usize> {
        std::os::windows::fs::FileExt::seek_read(&self.0, buf, offset)
    }

    fn len(&self) -> io::Result<u64> {
        Ok(self.0.metadata()?.len())
    }
}

impl FileSystem for RealFs {
    fn create_new(&self, path: &Path) -> io::Result<Box<dyn OutFile>> {
        let f = File::options()
            .read(true)
            .write(true)
            .create_new(true)
            .open(path)?;
        Ok(Box::new(RealOut(f)))
    }

    fn create(&self, path: &Path) -> io::Result<Box<dyn OutFile>> {
        let f = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)?;
        Ok(Box::new(RealOut(f)))
    }

    fn open(&self, path: &Path) -> io::Result<Box<dyn InFile>> {
        Ok(Box::new(RealIn(File::open(path)?)))
    }

    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        std::fs::rename(from, to)
    }

    fn remove_file(&self, path: &Path) -> io::Result<()> {
        std::fs::remove_file(path)
    }

    #[cfg(unix)]
    fn sync_dir(&self, dir: &Path) -> io::Result<()> {
        File::open(dir)?.sync_all()
    }

    #[cfg(not(unix))]
    fn sync_dir(&self, _dir: &Path) -> io::Result<()> {
        // Folders cannot be opened for syncing here; the rename is as durable as the OS makes it.
        Ok(())
    }
}
