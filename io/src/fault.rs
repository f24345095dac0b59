//! Fault injection for tests: a [`FileSystem`] over real files that runs out of space, cuts
//! writes and reads short, fails with `EIO`, or sleeps, as its [`Faults`] say.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::fs::{real, FileSystem, InFile, OutFile};

/// What goes wrong. The default injects nothing.
#[derive(Debug, Clone, Default)]
pub struct Faults {
    /// A disk of this many bytes: writes and allocations past it fail with `ENOSPC` (the
    /// bytes that fit are written, as a real disk does). Removed files give their space back.
    pub capacity: Option<u64>,
    /// Each write takes at most this many bytes (short writes; callers must loop).
    pub max_write: Option<usize>,
    /// The write call with this index (0-based, over all files) fails with `EIO`.
    pub eio_on_write: Option<u64>,
    /// `fsync` of files fails with this OS error: `EIO` (a disk that lost the data on the
    /// way), or `ENOSPC` (delayed allocation: every `write` was taken into the page cache, the
    /// blocks could not be found at writeback — how a full ext4/XFS disk turns an unsynced
    /// file into a 0-byte one).
    pub sync_errno: Option<i32>,
    /// Renames fail with `EIO`.
    pub fail_rename: bool,
    /// Each read returns at most this many bytes (short reads).
    pub max_read: Option<usize>,
    /// A read that touches this byte offset fails with `EIO` (a bad sector).
    pub eio_at_read_offset: Option<u64>,
    /// Sleep this long in every write and read (a slow or remote disk).
    pub latency: Option<Duration>,
}

impl Faults {
    /// A disk that fills after `bytes`.
    pub fn full_after(bytes: u64) -> Self {
        Self {
            capacity: Some(bytes),
            ..Self::default()
        }
    }
}

#[derive(Debug, Default)]
struct State {
    /// Bytes held by each file created through this file system, by current path.
    sizes: HashMap<PathBuf, Arc<Mutex<u64>>>,
    writes: u64,
}

impl State {
    fn used(&self) -> u64 {
        self.sizes.values().map(|s| *s.lock().expect("size")).sum()
    }
}

/// Real files under fault injection. Clones share the disk's state.
#[derive(Debug, Clone)]
pub struct FaultyFs {
    inner: Arc<dyn FileSystem>,
    faults: Faults,
    state: Arc<Mutex<State>>,
}

fn enospc() -> io::Error {
    io::Error::from_raw_os_error(libc::ENOSPC)
}

fn eio() -> io::Error {
    io::Error::from_raw_os_error(libc::EIO)
}

impl FaultyFs {
    /// Real files with `faults`.
    pub fn new(faults: Faults) -> Self {
        Self {
            inner: real(),
            faults,
            state: Arc::default(),
        }
    }

    /// As an `Arc<dyn FileSystem>` for the writers.
    pub fn shared(&self) -> Arc<dyn FileSystem> {
        Arc::new(self.clone())
    }

    /// Write calls seen so far.
    pub fn writes(&self) -> u64 {
        self.state.lock().expect("state").writes
    }

    /// Bytes the files created through this file system hold now.
    pub fn used(&self) -> u64 {
        self.state.lock().expect("state").used()
    }

    fn track(&self, path: &Path) -> Arc<Mutex<u64>> {
        let size = Arc::new(Mutex::new(0));
        let mut s = self.state.lock().expect("state");
        s.sizes.insert(path.to_path_buf(), size.clone());
        size
    }
}

struct FaultyOut {
    file: Box<dyn OutFile>,
    size: Arc<Mutex<u64>>,
    fs: FaultyFs,
}

impl Write for FaultyOut {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let f = &self.fs.faults;
        if let Some(d) = f.latency {
            std::thread::sleep(d);
        }
        let (index, used) = {
            let mut s = self.fs.state.lock().expect("state");
            s.writes += 1;
            (s.writes - 1, s.used())
        };
        if f.eio_on_write == Some(index) {
            return Err(eio());
        }
        let mut n = buf.len();
        if let Some(m) = f.max_write {
            n = n.min(m.max(1));
        }
        if let Some(cap) = f.capacity {
            let free = cap.saturating_sub(used);
            if free == 0 && n > 0 {
                return Err(enospc());
            }
            n = n.min(usize::try_from(free).unwrap_or(usize::MAX));
        }
        let n = self.file.write(&buf[..n])?;
        *self.size.lock().expect("size") += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

impl OutFile for FaultyOut {
    fn sync_all(&mut self) -> io::Result<()> {
        if let Some(errno) = self.fs.faults.sync_errno {
            return Err(io::Error::from_raw_os_error(errno));
        }
        self.file.sync_all()
    }

    fn allocate(&mut self, len: u64) -> io::Result<()> {
        if let Some(cap) = self.fs.faults.capacity {
            let have = *self.size.lock().expect("size");
            let others = self.fs.used() - have;
            if others + len.max(have) > cap {
                return Err(enospc());
            }
        }
        self.file.allocate(len)?;
        let mut size = self.size.lock().expect("size");
        *size = (*size).max(len);
        Ok(())
    }

    fn set_len(&mut self, len: u64) -> io::Result<()> {
        self.file.set_len(len)?;
        let mut size = self.size.lock().expect("size");
        *size = (*size).min(len);
        Ok(())
    }

    fn os_file(&self) -> &File {
        self.file.os_file()
    }
}

struct FaultyIn {
    file: Box<dyn InFile>,
    faults: Faults,
}

impl InFile for FaultyIn {
    fn read_at(&self, buf: &mut [u8], offset: u64) -> io::Result<usize> {
        if let Some(d) = self.faults.latency {
            std::thread::sleep(d);
        }
        let mut n = buf.len();
        if let Some(m) = self.faults.max_read {
            n = n.min(m.max(1));
        }
        if let Some(bad) = self.faults.eio_at_read_offset {
            if (offset..offset + n as u64).contains(&bad) {
                return Err(eio());
            }
        }
        self.file.read_at(&mut buf[..n], offset)
    }

    fn len(&self) -> io::Result<u64> {
        self.file.len()
    }
}

impl FileSystem for FaultyFs {
    fn create_new(&self, path: &Path) -> io::Result<Box<dyn OutFile>> {
        let file = self.inner.create_new(path)?;
        let size = self.track(path);
        Ok(Box::new(FaultyOut {
            file,
            size,
            fs: self.clone(),
        }))
    }

    fn create(&self, path: &Path) -> io::Result<Box<dyn OutFile>> {
        let file = self.inner.create(path)?;
        let size = self.track(path);
        Ok(Box::new(FaultyOut {
            file,
            size,
            fs: self.clone(),
        }))
    }

    fn open(&self, path: &Path) -> io::Result<Box<dyn InFile>> {
        Ok(Box::new(FaultyIn {
            file: self.inner.open(path)?,
            faults: self.faults.clone(),
        }))
    }

    fn rename(&self, from: &Path, to: &Path) -> io::Result<()> {
        if self.faults.fail_rename {
            return Err(eio());
        }
        self.inner.rename(from, to)?;
        let mut s = self.state.lock().expect("state");
        if let Some(size) = s.sizes.remove(from) {
            s.sizes.insert(to.to_path_buf(), size);
        }
        Ok(())
    }

    fn remove_file(&self, path: &Path) -> io::Result<()> {
        self.inner.remove_file(path)?;
        self.state.lock().expect("state").sizes.remove(path);
        Ok(())
    }

    fn sync_dir(&self, dir: &Path) -> io::Result<()> {
        self.inner.sync_dir(dir)
    }
}
