//! Shared-memory pose input for a simulator on the same host: a 144-byte file (by default
//! `/dev/shm/aerie-pose`) holding one [`ShmPose`], guarded by a seqlock and a CRC-32.
//!
//! Writer protocol (one writer): `seq += 1` (odd: writing), release fence, write the fields
//! and the checksum, `seq += 1` with release (even: stable). Reader: read the record; if `seq`
//! is odd, retry; re-read `seq`; if it changed, the copy may be torn: retry (bounded — after
//! [`DEFAULT_MAX_RETRIES`] the reader gives up for this poll and keeps the last pose). Every
//! read re-checks the header (magic, version, size) and the checksum: a record that fails
//! either is dropped and counted by reason, never decoded into a pose.
//!
//! The reader never maps the file: it copies the record with `pread` on the descriptor. A
//! file that shrinks under a mapping raises SIGBUS on the next access, and a size check before
//! the access cannot close that race; `pread` on a short file simply returns fewer bytes,
//! which is counted as a shrink, and reading resumes when the file has regrown.
//!
//! The C header `sim-bridge/include/aerie_pose.h` and the Python example
//! `sim-bridge/examples/shm_writer.py` implement the writer side. The Rust [`ShmWriter`] (tests
//! and `aerie-send`) maps the file and stores every field as an aligned 64-bit atomic word, as
//! the C header does. Host byte order (little-endian on x86-64/AArch64).

use std::fs::{File, OpenOptions};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{fence, AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use memmap2::{MmapOptions, MmapRaw};

use crate::ingest::{input_channel, Ingest, InputParams, PoseReader};
use crate::pose::{Pose, PoseLimits};
use crate::stats::{Counters, StatsSnapshot};
use crate::timing::{monotonic_s, ExtrapolationParams};

use crate::shm_layout::{
    check_record, header_word, pose_from_words, pose_to_words, split_header, words_of, WORDS,
    W_FLAGS, W_HEADER, W_SEQ,
};
pub use crate::shm_layout::{
    decode_snapshot, RecordError, ShmPose, ShmSnapshot, DEFAULT_MAX_RETRIES, DEFAULT_SHM_NAME,
    SHM_CRC_END, SHM_CRC_START, SHM_FLAG_LOCAL_ENU, SHM_FLAG_RATES, SHM_FLAG_VELOCITY, SHM_MAGIC,
    SHM_SIZE, SHM_VERSION,
};
use crate::stats::DropReason;

/// `/dev/shm/<name>` for a bare name; a name containing `/` is taken as a path.
pub fn shm_path(name: &str) -> PathBuf {
    if name.contains('/') {
        PathBuf::from(name)
    } else {
        Path::new("/dev/shm").join(name)
    }
}

/// Why a shared-memory file cannot be used. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ShmError {
    /// Opening, sizing or mapping failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is smaller than the layout.
    #[error("{}: {len} bytes, the pose layout needs {SHM_SIZE}", path.display())]
    TooSmall {
        /// The file.
        path: PathBuf,
        /// Its size.
        len: u64,
    },
    /// Wrong magic, version or size in the header.
    #[error("{}: header is magic {magic:#010x} version {version} size {size}; expected {SHM_MAGIC:#010x} ({:?}) version {SHM_VERSION} size {SHM_SIZE}", path.display(), "AEPS")]
    BadHeader {
        /// The file.
        path: PathBuf,
        /// Magic found.
        magic: u32,
        /// Version found.
        version: u16,
        /// Size found.
        size: u16,
    },
}

/// The writer's shared mapping viewed as 64-bit atomic words.
struct Words {
    map: MmapRaw,
}

impl Words {
    fn word(&self, i: usize) -> &AtomicU64 {
        assert!(i < WORDS && self.map.len() >= SHM_SIZE);
        // The mapping is at least SHM_SIZE bytes and page-aligned (every 8-byte offset is aligned
        // for AtomicU64), lives as long as `self` and is only accessed through atomics here.
        // SAFETY: the pointer is valid, aligned and atomically accessed for the reference's life.
        unsafe { AtomicU64::from_ptr(self.map.as_mut_ptr().add(i * 8).cast::<u64>()) }
    }

    fn open(path: &Path) -> Result<Words, ShmError> {
        let io = |source| ShmError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(io)?;
        if file.metadata().map_err(io)?.len() < SHM_SIZE as u64 {
            file.set_len(SHM_SIZE as u64).map_err(io)?;
        }
        let map = MmapOptions::new()
            .len(SHM_SIZE)
            .map_raw(&file)
            .map_err(io)?;
        Ok(Words { map })
    }
}

/// Writes poses into a shared-memory file (the simulator side; used by tests and tools). It
/// maps the file: whoever shrinks the file must not write until it has regrown (and should
/// [`create`](Self::create) the writer again, which rewrites the header).
pub struct ShmWriter {
    words: Words,
    path: PathBuf,
}

impl ShmWriter {
    /// Opens or creates `path`, grows it to [`SHM_SIZE`] if shorter and writes the header. An
    /// existing file keeps its sequence counter (rounded up to even), so readers see the new
    /// writes.
    pub fn create(path: &Path) -> Result<Self, ShmError> {
        let words = Words::open(path)?;
        let seq = words.word(W_SEQ).load(Ordering::Relaxed);
        if split_header(words.word(W_HEADER).load(Ordering::Relaxed))
            != (SHM_MAGIC, SHM_VERSION, SHM_SIZE as u16)
        {
            words.word(W_SEQ).store(0, Ordering::Relaxed);
        } else if seq & 1 == 1 {
            words.word(W_SEQ).store(seq + 1, Ordering::Release);
        }
        words.word(W_HEADER).store(header_word(), Ordering::Release);
        Ok(Self {
            words,
            path: path.to_path_buf(),
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Publishes `pose` (seqlock write with its checksum; wait-free).
    pub fn write(&mut self, pose: &Pose) {
        self.write_words(&pose_to_words(pose));
    }

    /// Publishes the checksummed words `W_FLAGS..=W_CRC` of `v` (the rest is ignored).
    fn write_words(&mut self, v: &[u64; WORDS]) {
        let w = |i: usize| self.words.word(i);
        let seq = w(W_SEQ).load(Ordering::Relaxed);
        w(W_SEQ).store(seq.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        for (i, x) in v.iter().enumerate().skip(W_FLAGS) {
            w(i).store(*x, Ordering::Relaxed);
        }
        w(W_SEQ).store(seq.wrapping_add(2), Ordering::Release);
    }

    /// Publishes `pose` with its checksum flipped (a reader must drop it).
    #[cfg(test)]
    pub(crate) fn write_with_bad_checksum(&mut self, pose: &Pose) {
        let mut v = pose_to_words(pose);
        v[crate::shm_layout::W_CRC] ^= 1;
        self.write_words(&v);
    }
}

/// The result of one [`ShmReader::read`].
#[derive(Clone, Debug, PartialEq)]
pub enum ShmRead {
    /// The writer has not written a pose yet (`seq` is 0).
    NotWritten,
    /// The same record as the last read (a pose already returned, or one already dropped).
    Unchanged,
    /// A new, consistent pose with a good header and checksum (not yet validated: see
    /// [`Pose::validate`]).
    New {
        /// The pose.
        pose: Pose,
        /// Its seqlock sequence (even).
        seq: u64,
        /// Torn reads retried before this one succeeded.
        retries: u32,
    },
    /// Every attempt was torn or found the writer mid-write; try again next poll.
    Busy {
        /// Attempts made.
        retries: u32,
    },
    /// A stable record failed the header or checksum check: dropped. Reported once per
    /// record; reading it again gives [`Unchanged`](Self::Unchanged).
    Dropped(RecordError),
    /// The file is shorter than the layout (it shrank under the reader): nothing decoded.
    /// Reading resumes by itself once the file has regrown.
    Shrunk {
        /// The bytes there were.
        len: u64,
        /// Whether this read found the shrink (the previous read saw a whole file).
        first: bool,
    },
    /// `pread` failed (not a shrink): reopen the file.
    Failed(std::io::ErrorKind),
}

/// Reads poses from a shared-memory file through `pread` (never a mapping, so a file that
/// shrinks cannot fault the reader). Never blocks: [`read`](Self::read) makes at most
/// `1 + max_retries` attempts.
pub struct ShmReader {
    file: File,
    path: PathBuf,
    last_seq: u64,
    /// The last dropped record (its words), so a record is counted once, not once per poll.
    last_dropped: Option<[u64; WORDS]>,
    shrunk: bool,
    max_retries: u32,
}

impl ShmReader {
    /// Opens `path` read-only and checks its size and header.
    pub fn open(path: &Path) -> Result<Self, ShmError> {
        let io = |source| ShmError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = File::open(path).map_err(io)?;
        let mut b = [0u8; SHM_SIZE];
        let n = read_record(&file, &mut b).map_err(io)?;
        if n < SHM_SIZE {
            return Err(ShmError::TooSmall {
                path: path.to_path_buf(),
                len: n as u64,
            });
        }
        let (magic, version, size) = split_header(words_of(&b)[W_HEADER]);
        if (magic, version, usize::from(size)) != (SHM_MAGIC, SHM_VERSION, SHM_SIZE) {
            return Err(ShmError::BadHeader {
                path: path.to_path_buf(),
                magic,
                version,
                size,
            });
        }
        Ok(Self {
            file,
            path: path.to_path_buf(),
            last_seq: 0,
            last_dropped: None,
            shrunk: false,
            max_retries: DEFAULT_MAX_RETRIES,
        })
    }

    /// Sets the bound on torn-read retries per call.
    pub fn with_max_retries(mut self, n: u32) -> Self {
        self.max_retries = n;
        self
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// One seqlock read attempt series; see [`ShmRead`].
    pub fn read(&mut self) -> ShmRead {
        let mut b = [0u8; SHM_SIZE];
        let mut crc_misses = 0;
        for attempt in 0..=self.max_retries {
            let n = match read_record(&self.file, &mut b) {
                Ok(n) => n,
                Err(e) => return ShmRead::Failed(e.kind()),
            };
            if n < SHM_SIZE {
                let first = !self.shrunk;
                self.shrunk = true;
                // A regrown file starts over (its writer re-creates the header and the
                // sequence): its first record is new whatever its seq.
                self.last_seq = 0;
                self.last_dropped = None;
                return ShmRead::Shrunk {
                    len: n as u64,
                    first,
                };
            }
            self.shrunk = false;
            let v = words_of(&b);
            let s1 = v[W_SEQ];
            if s1 & 1 == 1 {
                std::hint::spin_loop();
                continue;
            }
            let checked = check_record(&v);
            if s1 != 0 && s1 == self.last_seq && checked.is_ok() {
                return ShmRead::Unchanged;
            }
            // The copy is consistent only if no write began while it was taken.
            fence(Ordering::Acquire);
            match self.seq_now() {
                Ok(Some(s2)) if s2 == s1 => {}
                Ok(_) => {
                    std::hint::spin_loop();
                    continue;
                }
                Err(e) => return ShmRead::Failed(e.kind()),
            }
            if let Err(e) = checked {
                // A checksum mismatch on a stable record may still be a copy torn on a weakly
                // ordered CPU: look once more before calling it garbage.
                if e.reason == DropReason::BadCrc && crc_misses == 0 {
                    crc_misses += 1;
                    continue;
                }
                if self.last_dropped == Some(v) {
                    return ShmRead::Unchanged;
                }
                self.last_dropped = Some(v);
                return ShmRead::Dropped(e);
            }
            if s1 == 0 {
                return ShmRead::NotWritten;
            }
            self.last_seq = s1;
            self.last_dropped = None;
            return ShmRead::New {
                pose: pose_from_words(&v),
                seq: s1,
                retries: attempt,
            };
        }
        ShmRead::Busy {
            retries: self.max_retries + 1,
        }
    }

    /// `seq` as the file holds it now (`None`: the file no longer covers it).
    fn seq_now(&self) -> std::io::Result<Option<u64>> {
        let mut s = [0u8; 8];
        let mut n = 0;
        while n < 8 {
            match self.file.read_at(&mut s[n..], 8 + n as u64) {
                Ok(0) => return Ok(None),
                Ok(k) => n += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(Some(u64::from_ne_bytes(s)))
    }
}

/// `pread`s the record from offset 0; returns the bytes read (fewer than [`SHM_SIZE`]: the
/// file is shorter).
fn read_record(file: &File, b: &mut [u8; SHM_SIZE]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < SHM_SIZE {
        match file.read_at(&mut b[n..], n as u64) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// A shared-memory input.
#[derive(Clone, Debug)]
pub struct ShmConfig {
    /// The file (see [`shm_path`]).
    pub path: PathBuf,
    /// How often the polling thread looks for a new pose (its arrival-time resolution).
    pub poll_interval: Duration,
    /// Torn-read retries per poll.
    pub max_retries: u32,
    /// Extrapolation limits for the reader.
    pub extrapolation: ExtrapolationParams,
    /// Plausibility limits: poses beyond them are dropped as implausible.
    pub limits: PoseLimits,
}

impl Default for ShmConfig {
    fn default() -> Self {
        Self {
            path: shm_path(DEFAULT_SHM_NAME),
            poll_interval: Duration::from_micros(500),
            max_retries: DEFAULT_MAX_RETRIES,
            extrapolation: ExtrapolationParams::default(),
            limits: PoseLimits::default(),
        }
    }
}

/// A thread polling a shared-memory file and feeding a [`PoseReader`]. It waits for the file to
/// appear (checking every 100 ms), and reopens it when nothing changed for a second (a
/// restarted writer may have replaced the file). Records that fail the header or checksum
/// check are counted under their [`DropReason`], a file that shrank under the reader under
/// `shm_shrinks` ([`StatsSnapshot::shm_shrinks`]). Dropping it stops the thread.
pub struct ShmSource {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    counters: Arc<Counters>,
}

impl ShmSource {
    /// Starts polling `cfg.path`.
    pub fn spawn(cfg: ShmConfig) -> std::io::Result<(ShmSource, PoseReader)> {
        let (ingest, reader) = input_channel(InputParams {
            name: format!("shm {}", cfg.path.display()),
            extrapolation: cfg.extrapolation,
            limits: cfg.limits,
            ..InputParams::default()
        });
        let counters = ingest.counters().clone();
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name("aerie-shm".into())
                .spawn(move || poll_loop(cfg, ingest, stop))?
        };
        Ok((
            ShmSource {
                stop,
                thread: Some(thread),
                counters,
            },
            reader,
        ))
    }

    /// Counters now.
    pub fn stats(&self) -> StatsSnapshot {
        self.counters.snapshot()
    }

    /// Stops the thread and waits for it.
    pub fn stop(mut self) {
        self.stop_and_join();
    }

    fn stop_and_join(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for ShmSource {
    fn drop(&mut self) {
        self.stop_and_join();
    }
}

fn poll_loop(cfg: ShmConfig, mut ingest: Ingest, stop: Arc<AtomicBool>) {
    let name = cfg.path.display().to_string();
    let mut reader: Option<ShmReader> = None;
    let mut last_error = String::new();
    let mut next_open = Instant::now();
    let mut last_change = Instant::now();
    let mut shrunk = false;
    let counters = ingest.counters().clone();
    while !stop.load(Ordering::Relaxed) {
        if reader.is_none() && Instant::now() >= next_open {
            match ShmReader::open(&cfg.path) {
                Ok(r) => {
                    tracing::info!("shm {name}: opened");
                    reader = Some(r.with_max_retries(cfg.max_retries));
                    last_error.clear();
                    last_change = Instant::now();
                }
                Err(e) => {
                    let msg = e.to_string();
                    if msg != last_error {
                        tracing::warn!("shared memory not usable yet: {msg}");
                        last_error = msg;
                    }
                    next_open = Instant::now() + Duration::from_millis(100);
                }
            }
        }
        if let Some(r) = reader.as_mut() {
            let read = r.read();
            if shrunk && !matches!(read, ShmRead::Shrunk { .. } | ShmRead::Failed(_)) {
                shrunk = false;
                tracing::info!("shm {name}: the file is whole again");
            }
            match read {
                ShmRead::New { pose, retries, .. } => {
                    let arrival = monotonic_s();
                    counters.retries(retries.into());
                    ingest.pose(pose, arrival);
                    last_change = Instant::now();
                }
                ShmRead::Busy { retries } => {
                    counters.retries(retries.into());
                    counters.busy();
                }
                ShmRead::Dropped(e) => {
                    ingest.count_drop(e.reason, &e);
                    last_change = Instant::now();
                }
                ShmRead::Shrunk { len, .. } => {
                    // Counted once per shrink, also across a reopen while it stays short.
                    if !shrunk {
                        counters.shm_shrink();
                        shrunk = true;
                        tracing::warn!(
                            "shm {name}: the file shrank to {len} bytes (the layout needs \
                             {SHM_SIZE}); nothing read until it regrows"
                        );
                    }
                    reopen_if_idle(&mut reader, &mut next_open, last_change);
                }
                ShmRead::Failed(kind) => {
                    tracing::warn!("shm {name}: read failed ({kind}); reopening");
                    reader = None;
                    next_open = Instant::now() + Duration::from_millis(100);
                }
                ShmRead::Unchanged | ShmRead::NotWritten => {
                    reopen_if_idle(&mut reader, &mut next_open, last_change);
                }
            }
        }
        std::thread::sleep(cfg.poll_interval);
    }
}

/// After a second without a new record, look again: the writer may have been restarted on a
/// new file (the old one, unlinked, would stay short or unchanged forever).
fn reopen_if_idle(reader: &mut Option<ShmReader>, next_open: &mut Instant, last_change: Instant) {
    if last_change.elapsed() > Duration::from_secs(1) {
        *reader = None;
        *next_open = Instant::now();
    }
}

#[cfg(test)]
#[path = "shm_tests.rs"]
mod tests;
