//! The shared-memory record (layout version 2): offsets, the header and checksum checks, and
//! the conversion between a [`Pose`] and the record's 64-bit words. Pure: no file, no mapping;
//! [`crate::shm`] reads and writes the file.

use crate::pose::{Pose, PosePosition};
use crate::stats::DropReason;

/// `magic` field: the bytes `"AEPS"` (0x53504541 read little-endian).
pub const SHM_MAGIC: u32 = u32::from_le_bytes(*b"AEPS");
/// Layout version: 2 added the checksum at offset 136 (version 1 was 136 bytes without one).
pub const SHM_VERSION: u16 = 2;
/// Size of [`ShmPose`] and of the file.
pub const SHM_SIZE: usize = 144;
/// The checksum covers the bytes `CRC_START..CRC_END` (flags through rates).
pub const SHM_CRC_START: usize = 16;
/// End (exclusive) of the checksummed bytes, and the checksum's offset.
pub const SHM_CRC_END: usize = 136;
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
/// words at these offsets). Mirrors `struct aerie_pose` in `aerie_pose.h`.
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
    /// CRC-32 (IEEE, as the native packet) of bytes 16..136 as stored.
    pub crc: u32,
    /// 0.
    pub reserved2: u32,
}

const _: () = assert!(std::mem::size_of::<ShmPose>() == SHM_SIZE);
pub(crate) const WORDS: usize = SHM_SIZE / 8;
pub(crate) const W_HEADER: usize = 0;
pub(crate) const W_SEQ: usize = 1;
pub(crate) const W_FLAGS: usize = 2;
pub(crate) const W_FRAME: usize = 3;
pub(crate) const W_TIME: usize = 4;
pub(crate) const W_POS: usize = 5;
pub(crate) const W_ATT: usize = 8;
pub(crate) const W_VEL: usize = 11;
pub(crate) const W_RATES: usize = 14;
pub(crate) const W_CRC: usize = 17;
const _: () = assert!(W_CRC * 8 == SHM_CRC_END && W_FLAGS * 8 == SHM_CRC_START);

pub(crate) fn header_word() -> u64 {
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&SHM_MAGIC.to_ne_bytes());
    b[4..6].copy_from_slice(&SHM_VERSION.to_ne_bytes());
    b[6..8].copy_from_slice(&(SHM_SIZE as u16).to_ne_bytes());
    u64::from_ne_bytes(b)
}

pub(crate) fn split_header(w: u64) -> (u32, u16, u16) {
    let b = w.to_ne_bytes();
    (
        u32::from_ne_bytes([b[0], b[1], b[2], b[3]]),
        u16::from_ne_bytes([b[4], b[5]]),
        u16::from_ne_bytes([b[6], b[7]]),
    )
}

/// The low u32 of a word as stored (flags, checksum).
pub(crate) fn low_u32(w: u64) -> u32 {
    let b = w.to_ne_bytes();
    u32::from_ne_bytes([b[0], b[1], b[2], b[3]])
}

fn low_u32_word(x: u32) -> u64 {
    let mut b = [0u8; 8];
    b[..4].copy_from_slice(&x.to_ne_bytes());
    u64::from_ne_bytes(b)
}

/// CRC-32 of the checksummed words (`W_FLAGS..W_CRC`) as their bytes lie in the file.
pub(crate) fn body_crc(v: &[u64; WORDS]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for w in &v[W_FLAGS..W_CRC] {
        h.update(&w.to_ne_bytes());
    }
    h.finalize()
}

pub(crate) fn words_of(b: &[u8; SHM_SIZE]) -> [u64; WORDS] {
    let mut v = [0u64; WORDS];
    for (w, c) in v.iter_mut().zip(b.chunks_exact(8)) {
        let mut word = [0u8; 8];
        word.copy_from_slice(c);
        *w = u64::from_ne_bytes(word);
    }
    v
}

/// Why a record was refused: the reason it is counted under, and the offending byte offset
/// with what was found there.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordError {
    /// The counter it goes to: `unknown` (magic), `bad_version`, `bad_size`, `bad_crc`.
    pub reason: DropReason,
    /// What is wrong, naming the byte offset.
    pub detail: String,
}

impl std::fmt::Display for RecordError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.detail)
    }
}

/// Checks the header (magic, version, size) and, for a stable written record (`seq` even and
/// not 0), the checksum.
pub(crate) fn check_record(v: &[u64; WORDS]) -> Result<(), RecordError> {
    let err = |reason, detail| Err(RecordError { reason, detail });
    let (magic, version, size) = split_header(v[W_HEADER]);
    if magic != SHM_MAGIC {
        return err(
            DropReason::Unknown,
            format!("offset 0: magic {magic:#010x}, expected {SHM_MAGIC:#010x} (\"AEPS\")"),
        );
    }
    if version != SHM_VERSION {
        return err(
            DropReason::BadVersion,
            format!("offset 4: version {version}, expected {SHM_VERSION}"),
        );
    }
    if usize::from(size) != SHM_SIZE {
        return err(
            DropReason::BadSize,
            format!("offset 6: size {size}, expected {SHM_SIZE}"),
        );
    }
    let seq = v[W_SEQ];
    let (stored, computed) = (low_u32(v[W_CRC]), body_crc(v));
    if seq != 0 && seq & 1 == 0 && stored != computed {
        return err(
            DropReason::BadCrc,
            format!(
                "offset {SHM_CRC_END}: checksum {stored:#010x}, bytes \
                 {SHM_CRC_START}..{SHM_CRC_END} give {computed:#010x}"
            ),
        );
    }
    Ok(())
}

/// The record words of `pose`, checksum included (header and seq left 0).
pub(crate) fn pose_to_words(pose: &Pose) -> [u64; WORDS] {
    let mut flags = 0;
    let (position, local) = pose.position.wire();
    if local {
        flags |= SHM_FLAG_LOCAL_ENU;
    }
    if pose.velocity_enu.is_some() {
        flags |= SHM_FLAG_VELOCITY;
    }
    if pose.angular_rates_deg_s.is_some() {
        flags |= SHM_FLAG_RATES;
    }
    let mut v = [0u64; WORDS];
    v[W_FLAGS] = low_u32_word(flags);
    v[W_FRAME] = pose.frame;
    v[W_TIME] = pose.sim_time_s.to_bits();
    let vectors = [
        (W_POS, position),
        (W_ATT, pose.attitude_deg),
        (W_VEL, pose.velocity_enu.unwrap_or([0.0; 3])),
        (W_RATES, pose.angular_rates_deg_s.unwrap_or([0.0; 3])),
    ];
    for (base, xs) in vectors {
        for (k, x) in xs.iter().enumerate() {
            v[base + k] = x.to_bits();
        }
    }
    v[W_CRC] = low_u32_word(body_crc(&v));
    v
}

pub(crate) fn pose_from_words(v: &[u64; WORDS]) -> Pose {
    let f = |i: usize| f64::from_bits(v[i]);
    let v3 = |i: usize| [f(i), f(i + 1), f(i + 2)];
    let flags = low_u32(v[W_FLAGS]);
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

/// A byte copy of the shared-memory file, decoded (tools, tests and the fuzz target).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShmSnapshot {
    /// The seqlock counter (odd: the copy was taken mid-write and may be torn; its checksum
    /// is not checked).
    pub seq: u64,
    /// The pose, `None` when `seq` is 0 (never written). Not validated: see [`Pose::validate`].
    pub pose: Option<Pose>,
}

/// Decodes a byte copy of the file (host byte order, at least [`SHM_SIZE`] bytes; the file
/// may be longer): the header and, for an even `seq`, the checksum are checked as by the live
/// reader. Errors name the byte offset.
pub fn decode_snapshot(b: &[u8]) -> Result<ShmSnapshot, String> {
    let Some(rec) = b.get(..SHM_SIZE) else {
        return Err(format!("{} bytes, the layout needs {SHM_SIZE}", b.len()));
    };
    let mut a = [0u8; SHM_SIZE];
    a.copy_from_slice(rec);
    let v = words_of(&a);
    check_record(&v).map_err(|e| e.detail)?;
    // Unknown flag bits are ignored, as by the live reader.
    let seq = v[W_SEQ];
    Ok(ShmSnapshot {
        seq,
        pose: (seq != 0).then(|| pose_from_words(&v)),
    })
}
