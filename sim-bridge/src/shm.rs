//! Shared-memory pose input for a simulator on the same host: a 136-byte file (by default
//! `/dev/shm/aerie-pose`) holding one [`ShmPose`], guarded by a seqlock.
//!
//! Writer protocol (one writer): `seq += 1` (odd: writing), release fence, write the fields,
//! `seq += 1` with release (even: stable). Reader: load `seq` (acquire); if odd, retry; copy the
//! fields; acquire fence; reload `seq`; if it changed, the copy may be torn: retry (bounded —
//! after [`DEFAULT_MAX_RETRIES`] the reader gives up for this poll and keeps the last pose).
//! The C header `sim-bridge/include/aerie_pose.h` and the Python example
//! `sim-bridge/examples/shm_writer.py` implement the writer side.
//!
//! Every field is accessed as an aligned 64-bit atomic word (the header word packs magic,
//! version and size; the flags word packs flags and a reserved u32), so concurrent access is
//! defined behaviour on the Rust side. Host byte order (little-endian on x86-64/AArch64).

use std::fs::OpenOptions;
use std::path::{Path, PathBuf};
use std::sync::atomic::{fence, AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use memmap2::{MmapOptions, MmapRaw};

use crate::ingest::{input_channel, Ingest, InputParams, PoseReader};
use crate::pose::{Pose, PoseLimits, PosePosition};
use crate::stats::{Counters, StatsSnapshot};
use crate::timing::{monotonic_s, ExtrapolationParams};

/// `magic` field: the bytes `"AEPS"` (0x53504541 read little-endian).
pub const SHM_MAGIC: u32 = u32::from_le_bytes(*b"AEPS");
/// Layout version.
pub const SHM_VERSION: u16 = 1;
/// Size of [`ShmPose`] and of the file.
pub const SHM_SIZE: usize = 136;
/// Default file name in `/dev/shm`.
pub const DEFAULT_SHM_NAME: &str = "aerie-pose";
/// Flag: the position is local ENU metres (else WGS84 lat/lon/alt).
pub const SHM_FLAG_LOCAL_ENU: u32 = 1 << 0;
/// Flag: the velocity field is valid.
pub const SHM_FLAG_VELOCITY: u32 = 1 << 1;
/// Flag: the rates field is valid.
pub const SHM_FLAG_RATES: u32 = 1 << 2;
/// Torn reads retried per poll before giving up until the next poll.
pub const DEFAULT_MAX_RETRIES: u32 = 64;

/// The shared-memory layout (documentation and size/offset checks; access goes through 64-bit
/// atomic words at these offsets). Mirrors `struct aerie_pose` in `aerie_pose.h`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShmPose {
    /// [`SHM_MAGIC`].
    pub magic: u32,
    /// [`SHM_VERSION`].
    pub version: u16,
    /// [`SHM_SIZE`].
    pub size: u16,
    /// Seqlock counter: odd while the writer is writing, even when stable; 0 = never written.
    pub seq: u64,
    /// `SHM_FLAG_*` bits.
    pub flags: u32,
    /// 0.
    pub reserved: u32,
    /// Simulator frame number.
    pub frame: u64,
    /// Simulation time, seconds.
    pub sim_time_s: f64,
    /// lat°, lon°, alt m (WGS84) or x, y, z m (local ENU).
    pub position: [f64; 3],
    /// Heading, pitch, roll, degrees.
    pub attitude_deg: [f64; 3],
    /// East, north, up velocity, m/s.
    pub velocity_enu: [f64; 3],
    /// Heading, pitch, roll rates, deg/s.
    pub rates_deg_s: [f64; 3],
}

const _: () = assert!(std::mem::size_of::<ShmPose>() == SHM_SIZE);
const WORDS: usize = SHM_SIZE / 8;
const W_HEADER: usize = 0;
const W_SEQ: usize = 1;
const W_FLAGS: usize = 2;
const W_FRAME: usize = 3;
const W_TIME: usize = 4;
const W_POS: usize = 5;
const W_ATT: usize = 8;
const W_VEL: usize = 11;
const W_RATES: usize = 14;

fn header_word() -> u64 {
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&SHM_MAGIC.to_ne_bytes());
    b[4..6].copy_from_slice(&SHM_VERSION.to_ne_bytes());
    b[6..8].copy_from_slice(&(SHM_SIZE as u16).to_ne_bytes());
    u64::from_ne_bytes(b)
}

fn split_header(w: u64) -> (u32, u16, u16) {
    let b = w.to_ne_bytes();
    (
        u32::from_ne_bytes([b[0], b[1], b[2], b[3]]),
        u16::from_ne_bytes([b[4], b[5]]),
        u16::from_ne_bytes([b[6], b[7]]),
    )
}

fn flags_word(flags: u32) -> u64 {
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&flags.to_ne_bytes());
    u64::from_ne_bytes(b)
}

fn flags_of(w: u64) -> u32 {
    let b = w.to_ne_bytes();
    u32::from_ne_bytes([b[0], b[1], b[2], b[3]])
}

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

/// A 136-byte shared mapping viewed as 64-bit atomic words.
struct Words {
    map: MmapRaw,
    /// Kept open to check the file's size before touching the mapping (a file truncated
    /// under a mapping raises SIGBUS on access).
    file: std::fs::File,
}

impl Words {
    fn word(&self, i: usize) -> &AtomicU64 {
        assert!(i < WORDS && self.map.len() >= SHM_SIZE);
        // SAFETY: the mapping is at least SHM_SIZE bytes, page-aligned (so every 8-byte offset
        // is aligned for AtomicU64), lives as long as `self`, and is only ever accessed through
        // atomics on our side.
        unsafe { AtomicU64::from_ptr(self.map.as_mut_ptr().add(i * 8).cast::<u64>()) }
    }

    fn open(path: &Path, write: bool) -> Result<Words, ShmError> {
        let io = |source| ShmError::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = OpenOptions::new()
            .read(true)
            .write(write)
            .create(write)
            .truncate(false)
            .open(path)
            .map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if write && len < SHM_SIZE as u64 {
            file.set_len(SHM_SIZE as u64).map_err(io)?;
        } else if len < SHM_SIZE as u64 {
            return Err(ShmError::TooSmall {
                path: path.to_path_buf(),
                len,
            });
        }
        let opts = {
            let mut o = MmapOptions::new();
            o.len(SHM_SIZE);
            o
        };
        let map = if write {
            opts.map_raw(&file)
        } else {
            opts.map_raw_read_only(&file)
        }
        .map_err(io)?;
        Ok(Words { map, file })
    }

    /// Whether the file still covers the mapping.
    fn intact(&self) -> bool {
        self.file
            .metadata()
            .map(|m| m.len() >= SHM_SIZE as u64)
            .unwrap_or(false)
    }
}

/// Writes poses into a shared-memory file (the simulator side; used by tests and tools).
pub struct ShmWriter {
    words: Words,
    path: PathBuf,
}

impl ShmWriter {
    /// Opens or creates `path`, sizes it to [`SHM_SIZE`] and writes the header. An existing
    /// file keeps its sequence counter (rounded up to even), so readers see the new writes.
    pub fn create(path: &Path) -> Result<Self, ShmError> {
        let words = Words::open(path, true)?;
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

    /// Publishes `pose` (seqlock write; wait-free).
    pub fn write(&mut self, pose: &Pose) {
        let mut flags = 0;
        let position = match pose.position {
            PosePosition::Geodetic {
                lat_deg,
                lon_deg,
                alt_m,
            } => [lat_deg, lon_deg, alt_m],
            PosePosition::LocalEnu { x, y, z } => {
                flags |= SHM_FLAG_LOCAL_ENU;
                [x, y, z]
            }
        };
        if pose.velocity_enu.is_some() {
            flags |= SHM_FLAG_VELOCITY;
        }
        if pose.angular_rates_deg_s.is_some() {
            flags |= SHM_FLAG_RATES;
        }
        let w = |i: usize| self.words.word(i);
        let seq = w(W_SEQ).load(Ordering::Relaxed);
        w(W_SEQ).store(seq.wrapping_add(1), Ordering::Relaxed);
        fence(Ordering::Release);
        w(W_FLAGS).store(flags_word(flags), Ordering::Relaxed);
        w(W_FRAME).store(pose.frame, Ordering::Relaxed);
        w(W_TIME).store(pose.sim_time_s.to_bits(), Ordering::Relaxed);
        let vectors = [
            (W_POS, position),
            (W_ATT, pose.attitude_deg),
            (W_VEL, pose.velocity_enu.unwrap_or([0.0; 3])),
            (W_RATES, pose.angular_rates_deg_s.unwrap_or([0.0; 3])),
        ];
        for (base, v) in vectors {
            for (k, x) in v.iter().enumerate() {
                w(base + k).store(x.to_bits(), Ordering::Relaxed);
            }
        }
        w(W_SEQ).store(seq.wrapping_add(2), Ordering::Release);
    }
}

/// The result of one [`ShmReader::read`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShmRead {
    /// The writer has not written a pose yet (`seq` is 0).
    NotWritten,
    /// Same sequence as the last read: nothing new.
    Unchanged,
    /// A new, consistent pose (not yet validated: see [`Pose::validate`]).
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
    /// The file was truncated below the layout's size: the mapping is not read (it would
    /// fault); reopen the file.
    Truncated,
}

/// Reads poses from a shared-memory file. Never blocks: [`read`](Self::read) makes at most
/// `1 + max_retries` attempts.
pub struct ShmReader {
    words: Words,
    path: PathBuf,
    last_seq: u64,
    max_retries: u32,
}

impl ShmReader {
    /// Opens `path` read-only and checks its header.
    pub fn open(path: &Path) -> Result<Self, ShmError> {
        let words = Words::open(path, false)?;
        let (magic, version, size) = split_header(words.word(W_HEADER).load(Ordering::Acquire));
        if (magic, version, usize::from(size)) != (SHM_MAGIC, SHM_VERSION, SHM_SIZE) {
            return Err(ShmError::BadHeader {
                path: path.to_path_buf(),
                magic,
                version,
                size,
            });
        }
        Ok(Self {
            words,
            path: path.to_path_buf(),
            last_seq: 0,
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

    /// One seqlock read attempt series; see [`ShmRead`]. Checks first that the file was not
    /// truncated (writers must never shrink the file while readers run; the check narrows the
    /// window in which one that does could fault the reader to microseconds).
    pub fn read(&mut self) -> ShmRead {
        if !self.words.intact() {
            return ShmRead::Truncated;
        }
        let w = |i: usize| self.words.word(i);
        let mut v = [0u64; WORDS];
        for attempt in 0..=self.max_retries {
            let s1 = w(W_SEQ).load(Ordering::Acquire);
            if s1 == 0 {
                return ShmRead::NotWritten;
            }
            if s1 == self.last_seq {
                return ShmRead::Unchanged;
            }
            if s1 & 1 == 1 {
                std::hint::spin_loop();
                continue;
            }
            for (i, slot) in v.iter_mut().enumerate().skip(W_FLAGS) {
                *slot = w(i).load(Ordering::Relaxed);
            }
            fence(Ordering::Acquire);
            if w(W_SEQ).load(Ordering::Relaxed) != s1 {
                std::hint::spin_loop();
                continue;
            }
            self.last_seq = s1;
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
}

fn pose_from_words(v: &[u64; WORDS]) -> Pose {
    let f = |i: usize| f64::from_bits(v[i]);
    let v3 = |i: usize| [f(i), f(i + 1), f(i + 2)];
    let flags = flags_of(v[W_FLAGS]);
    let [a, b, c] = v3(W_POS);
    Pose {
        position: if flags & SHM_FLAG_LOCAL_ENU != 0 {
            PosePosition::LocalEnu { x: a, y: b, z: c }
        } else {
            PosePosition::Geodetic {
                lat_deg: a,
                lon_deg: b,
                alt_m: c,
            }
        },
        attitude_deg: v3(W_ATT),
        sim_time_s: f(W_TIME),
        frame: v[W_FRAME],
        velocity_enu: (flags & SHM_FLAG_VELOCITY != 0).then(|| v3(W_VEL)),
        angular_rates_deg_s: (flags & SHM_FLAG_RATES != 0).then(|| v3(W_RATES)),
    }
}

/// A byte copy of the shared-memory file, decoded (tools, tests and the fuzz target; the live
/// reader goes through atomics and the seqlock instead).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShmSnapshot {
    /// The seqlock counter (odd: the copy was taken mid-write and may be torn).
    pub seq: u64,
    /// The pose, `None` when `seq` is 0 (never written). Not validated: see [`Pose::validate`].
    pub pose: Option<Pose>,
}

/// Decodes a byte copy of the file (host byte order, at least [`SHM_SIZE`] bytes; the file
/// may be longer). Errors name the byte offset.
pub fn decode_snapshot(b: &[u8]) -> Result<ShmSnapshot, String> {
    if b.len() < SHM_SIZE {
        return Err(format!("{} bytes, the layout needs {SHM_SIZE}", b.len()));
    }
    let mut v = [0u64; WORDS];
    for (i, w) in v.iter_mut().enumerate() {
        let mut word = [0u8; 8];
        word.copy_from_slice(&b[i * 8..i * 8 + 8]);
        *w = u64::from_ne_bytes(word);
    }
    let (magic, version, size) = split_header(v[W_HEADER]);
    if magic != SHM_MAGIC {
        return Err(format!(
            "offset 0: magic {magic:#010x}, expected {SHM_MAGIC:#010x}"
        ));
    }
    if version != SHM_VERSION {
        return Err(format!(
            "offset 4: version {version}, expected {SHM_VERSION}"
        ));
    }
    if usize::from(size) != SHM_SIZE {
        return Err(format!("offset 6: size {size}, expected {SHM_SIZE}"));
    }
    // Unknown flag bits are ignored, as by the live reader.
    let seq = v[W_SEQ];
    Ok(ShmSnapshot {
        seq,
        pose: (seq != 0).then(|| pose_from_words(&v)),
    })
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
/// restarted writer may have replaced the file). Dropping it stops the thread.
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
    let mut reader: Option<ShmReader> = None;
    let mut last_error = String::new();
    let mut next_open = Instant::now();
    let mut last_change = Instant::now();
    let counters = ingest.counters().clone();
    while !stop.load(Ordering::Relaxed) {
        if reader.is_none() && Instant::now() >= next_open {
            match ShmReader::open(&cfg.path) {
                Ok(r) => {
                    tracing::info!("shm {}: opened", cfg.path.display());
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
            match r.read() {
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
                ShmRead::Truncated => {
                    tracing::warn!("shm {}: file truncated; reopening", cfg.path.display());
                    reader = None;
                    next_open = Instant::now() + Duration::from_millis(100);
                }
                ShmRead::Unchanged | ShmRead::NotWritten => {
                    if last_change.elapsed() > Duration::from_secs(1) {
                        // Look again: the writer may have been restarted on a new file.
                        reader = None;
                        next_open = Instant::now();
                    }
                }
            }
        }
        std::thread::sleep(cfg.poll_interval);
    }
}

#[cfg(test)]
#[path = "shm_tests.rs"]
mod tests;
