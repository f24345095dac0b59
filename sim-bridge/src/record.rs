//! Recordings of raw datagrams with their arrival times, and their replay over UDP.
//!
//! File format (all little-endian; `sim-bridge/PROTOCOL.md`):
//!
//! | off | size | field |
//! |----:|-----:|-------|
//! | 0 | 8 | magic `"AERIEREC"` |
//! | 8 | 2 | version u16 = 1 |
//! | 10 | 2 | header size u16 = 16 |
//! | 12 | 4 | reserved, 0 |
//!
//! then one record per datagram, in arrival order:
//!
//! | off | size | field |
//! |----:|-----:|-------|
//! | 0 | 8 | arrival u64, nanoseconds since the recording started (non-decreasing) |
//! | 8 | 4 | length u32 (≤ 65 535) |
//! | 12 | length | the datagram's bytes, as received |

use std::io::{self, Write};
use std::net::{SocketAddr, UdpSocket};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use aerie_io::{FileSystem, OutFile};

/// First eight bytes of a recording.
pub const MAGIC: [u8; 8] = *b"AERIEREC";
/// The version written and read here.
pub const VERSION: u16 = 1;
/// File header size.
pub const HEADER_SIZE: usize = 16;
/// Per-record header size (arrival + length).
pub const RECORD_HEADER_SIZE: usize = 12;
/// Largest datagram a record may hold.
pub const MAX_PACKET: usize = 65_535;

/// Why a recording could not be written or read. Every variant names the file; format errors
/// name the byte offset.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be created, written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The recording.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// A write failed (a full disk): recording stopped, the file cut back to the last whole
    /// record so it still reads.
    #[error("{}: recording stopped at byte offset {offset} after {packets} datagrams: {source}; the file keeps those {packets} whole records", path.display())]
    Stopped {
        /// The recording.
        path: PathBuf,
        /// Datagrams in the file.
        packets: u64,
        /// Where the record that could not be written starts.
        offset: u64,
        /// The I/O error.
        source: io::Error,
    },
    /// The first eight bytes are not `AERIEREC`.
    #[error("{}: not an aerie recording (bytes 0..8 are {found:02x?}, expected \"AERIEREC\")", path.display())]
    BadMagic {
        /// The recording.
        path: PathBuf,
        /// What is there instead.
        found: Vec<u8>,
    },
    /// A version this build does not read.
    #[error("{}: recording version {found} at byte offset 8, this build reads version {VERSION}", path.display())]
    BadVersion {
        /// The recording.
        path: PathBuf,
        /// The version in the file.
        found: u16,
    },
    /// The file ends inside the header or a record.
    #[error("{}: truncated at byte offset {offset}: {what}", path.display())]
    Truncated {
        /// The recording.
        path: PathBuf,
        /// Where the incomplete part starts.
        offset: u64,
        /// What is incomplete.
        what: String,
    },
    /// A record is corrupt (oversized, or earlier than the one before).
    #[error("{}: bad record at byte offset {offset}: {what}", path.display())]
    BadRecord {
        /// The recording.
        path: PathBuf,
        /// Where the record starts.
        offset: u64,
        /// What is wrong.
        what: String,
    },
}

/// One recorded datagram.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedPacket {
    /// Arrival, nanoseconds since the recording started.
    pub t_ns: u64,
    /// The datagram as received.
    pub bytes: Vec<u8>,
}

fn header() -> [u8; HEADER_SIZE] {
    let mut h = [0u8; HEADER_SIZE];
    h[..8].copy_from_slice(&MAGIC);
    h[8..10].copy_from_slice(&VERSION.to_le_bytes());
    h[10..12].copy_from_slice(&(HEADER_SIZE as u16).to_le_bytes());
    h
}

/// Writes datagrams to a recording as they arrive. Each record goes to the file in one checked
/// write, so a recording cut short by a kill ends at a record boundary (or reports where it is
/// cut); a failed write (a full disk) cuts the file back to the last whole record and stops
/// the recording with the file named.
pub struct Recorder {
    file: Option<Box<dyn OutFile>>,
    path: PathBuf,
    start_s: f64,
    last_ns: u64,
    packets: u64,
    /// Bytes of the header and the whole records written.
    len: u64,
    buf: Vec<u8>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("path", &self.path)
            .field("packets", &self.packets)
            .field("len", &self.len)
            .finish()
    }
}

impl Recorder {
    /// Creates (or truncates) `path` and writes the header; arrival times are stored relative
    /// to `start_s` (seconds on the monotonic timeline).
    pub fn create(path: &Path, start_s: f64) -> Result<Self, RecordingError> {
        Self::create_in(aerie_io::real(), path, start_s)
    }

    /// [`Recorder::create`] on the given file system (tests inject faults through it).
    pub fn create_in(
        fs: Arc<dyn FileSystem>,
        path: &Path,
        start_s: f64,
    ) -> Result<Self, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut file = fs.create(path).map_err(io)?;
        if let Err(e) = file.write_all(&header()) {
            drop(file);
            // Not even the header fits: leave no cut file.
            let _ = fs.remove_file(path);
            return Err(io(e));
        }
        Ok(Self {
            file: Some(file),
            path: path.to_path_buf(),
            start_s,
            last_ns: 0,
            packets: 0,
            len: HEADER_SIZE as u64,
            buf: Vec::with_capacity(2048),
        })
    }

    /// Appends one datagram that arrived at `arrival_s`. Datagrams longer than
    /// [`MAX_PACKET`] are cut to that length. After a failed write every call fails.
    pub fn record(&mut self, arrival_s: f64, bytes: &[u8]) -> Result<(), RecordingError> {
        let stopped = |r: &Self, source| RecordingError::Stopped {
            path: r.path.clone(),
            packets: r.packets,
            offset: r.len,
            source,
        };
        let Some(file) = self.file.as_mut() else {
            let e = io::Error::other("an earlier write failed");
            return Err(stopped(self, e));
        };
        let t = ((arrival_s - self.start_s).max(0.0) * 1e9) as u64;
        let t = t.max(self.last_ns);
        let bytes = &bytes[..bytes.len().min(MAX_PACKET)];
        self.buf.clear();
        self.buf.extend_from_slice(&t.to_le_bytes());
        self.buf
            .extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        self.buf.extend_from_slice(bytes);
        if let Err(e) = file.write_all(&self.buf) {
            // Cut the part of this record that reached the disk, then stop.
            let _ = file.set_len(self.len).and_then(|_| file.sync_all());
            self.file = None;
            return Err(stopped(self, e));
        }
        self.last_ns = t;
        self.len += self.buf.len() as u64;
        self.packets += 1;
        Ok(())
    }

    /// Datagrams recorded so far.
    pub fn packets(&self) -> u64 {
        self.packets
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Syncs the file to the disk; the recording goes on.
    pub fn sync(&mut self) -> Result<(), RecordingError> {
        match self.file.as_mut() {
            Some(f) => f.sync_all().map_err(|source| RecordingError::Io {
                path: self.path.clone(),
                source,
            }),
            None => Ok(()),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if let Err(e) = self.sync() {
            tracing::error!("{e}");
        }
    }
}

/// Writes a whole recording at once, atomically (complete file or none).
pub fn write_recording(path: &Path, packets: &[RecordedPacket]) -> Result<(), RecordingError> {
    write_recording_in(aerie_io::real(), path, packets)
}

/// [`write_recording`] on the given file system.
pub fn write_recording_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    packets: &[RecordedPacket],
) -> Result<(), RecordingError> {
    let mut out = header().to_vec();
    for p in packets {
        out.extend_from_slice(&p.t_ns.to_le_bytes());
        out.extend_from_slice(&(p.bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(&p.bytes);
    }
    aerie_io::write_atomic_in(fs, path, &out).map_err(|e| RecordingError::Io {
        path: path.to_path_buf(),
        source: io::Error::new(e.source.kind(), format!("{} failed: {}", e.step, e.source)),
    })
}

/// Parses a recording held in memory; `path` is only used in error messages.
pub fn parse_recording(b: &[u8], path: &Path) -> Result<Vec<RecordedPacket>, RecordingError> {
    let path_buf = || path.to_path_buf();
    if b.len() < 8 || b[..8] != MAGIC {
        if b.len() < 8 && MAGIC.starts_with(b) {
            return Err(RecordingError::Truncated {
                path: path_buf(),
                offset: 0,
                what: format!(
                    "file header needs {HEADER_SIZE} bytes, the file has {}",
                    b.len()
                ),
            });
        }
        return Err(RecordingError::BadMagic {
            path: path_buf(),
            found: b[..b.len().min(8)].to_vec(),
        });
    }
    if b.len() < HEADER_SIZE {
        return Err(RecordingError::Truncated {
            path: path_buf(),
            offset: 0,
            what: format!(
                "file header needs {HEADER_SIZE} bytes, the file has {}",
                b.len()
            ),
        });
    }
    let version = u16::from_le_bytes([b[8], b[9]]);
    if version != VERSION {
        return Err(RecordingError::BadVersion {
            path: path_buf(),
            found: version,
        });
    }
    let header_size = usize::from(u16::from_le_bytes([b[10], b[11]]));
    if header_size < HEADER_SIZE || header_size > b.len() {
        return Err(RecordingError::BadRecord {
            path: path_buf(),
            offset: 10,
            what: format!("header size {header_size} (expected 16 up to the file size)"),
        });
    }
    let mut packets = Vec::new();
    let mut off = header_size;
    let mut last = 0u64;
    while off < b.len() {
        let Some(h) = b.get(off..off + RECORD_HEADER_SIZE) else {
            return Err(RecordingError::Truncated {
                path: path_buf(),
                offset: off as u64,
                what: format!(
                    "record header needs {RECORD_HEADER_SIZE} bytes, {} left",
                    b.len() - off
                ),
            });
        };
        let mut t8 = [0u8; 8];
        t8.copy_from_slice(&h[..8]);
        let t_ns = u64::from_le_bytes(t8);
        let len = u32::from_le_bytes([h[8], h[9], h[10], h[11]]) as usize;
        if len > MAX_PACKET {
            return Err(RecordingError::BadRecord {
                path: path_buf(),
                offset: off as u64,
                what: format!("length {len} exceeds {MAX_PACKET}"),
            });
        }
        if t_ns < last {
            return Err(RecordingError::BadRecord {
                path: path_buf(),
                offset: off as u64,
                what: format!("arrival {t_ns} ns is before the previous record's {last} ns"),
            });
        }
        let start = off + RECORD_HEADER_SIZE;
        let Some(bytes) = b.get(start..start + len) else {
            return Err(RecordingError::Truncated {
                path: path_buf(),
                offset: off as u64,
                what: format!(
                    "record of {len} bytes, only {} left after its header",
                    b.len() - start
                ),
            });
        };
        packets.push(RecordedPacket {
            t_ns,
            bytes: bytes.to_vec(),
        });
        last = t_ns;
        off = start + len;
    }
    Ok(packets)
}

/// Reads a whole recording.
pub fn read_recording(path: &Path) -> Result<Vec<RecordedPacket>, RecordingError> {
    let b = std::fs::read(path).map_err(|source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_recording(&b, path)
}

/// How [`replay`] paces the datagrams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReplayTiming {
    /// With the recorded spacing (the first datagram goes out at once).
    Original,
    /// Back to back, as fast as the socket takes them.
    Fast,
}

/// What [`replay`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplayReport {
    /// Datagrams sent.
    pub packets: usize,
    /// Bytes sent.
    pub bytes: u64,
    /// Last minus first recorded arrival, seconds.
    pub recorded_span_s: f64,
    /// Wall time the replay took, seconds.
    pub elapsed_s: f64,
    /// Largest lateness of a send against its recorded time (original timing), seconds.
    pub max_late_s: f64,
}

/// Sends `packets` from `socket` to `to`, paced by `timing`; `progress` is called after every
/// datagram with the number sent so far.
pub fn replay(
    packets: &[RecordedPacket],
    socket: &UdpSocket,
    to: SocketAddr,
    timing: ReplayTiming,
    mut progress: impl FnMut(usize),
) -> io::Result<ReplayReport> {
    let start = Instant::now();
    let t0 = packets.first().map_or(0, |p| p.t_ns);
    let mut report = ReplayReport {
        packets: 0,
        bytes: 0,
        recorded_span_s: packets.last().map_or(0, |p| p.t_ns - t0) as f64 * 1e-9,
        elapsed_s: 0.0,
        max_late_s: 0.0,
    };
    for p in packets {
        if timing == ReplayTiming::Original {
            let due = start + Duration::from_nanos(p.t_ns - t0);
            // Sleep most of the way, then yield until due (sub-millisecond accuracy).
            loop {
                let now = Instant::now();
                if now >= due {
                    break;
                }
                let left = due - now;
                if left > Duration::from_micros(1500) {
                    std::thread::sleep(left - Duration::from_millis(1));
                } else {
                    std::thread::yield_now();
                }
            }
            let late = Instant::now().duration_since(due).as_secs_f64();
            report.max_late_s = report.max_late_s.max(late);
        }
        socket.send_to(&p.bytes, to)?;
        report.packets += 1;
        report.bytes += p.bytes.len() as u64;
        progress(report.packets);
    }
    report.elapsed_s = start.elapsed().as_secs_f64();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Arbitrary bytes after a valid header never panic the parser.
        #[test]
        fn random_recordings_never_panic(body in prop::collection::vec(any::<u8>(), 0..400)) {
            let mut b = header().to_vec();
            b.extend_from_slice(&body);
            let _ = parse_recording(&b, Path::new("r"));
            let _ = parse_recording(&body, Path::new("r"));
        }
    }

    fn sample() -> Vec<RecordedPacket> {
        vec![
            RecordedPacket {
                t_ns: 0,
                bytes: b"first".to_vec(),
            },
            RecordedPacket {
                t_ns: 16_666_667,
                bytes: vec![],
            },
            RecordedPacket {
                t_ns: 33_333_333,
                bytes: (0..=255u8).collect(),
            },
        ]
    }

    #[test]
    fn write_read_round_trip_and_layout() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.aerie-rec");
        write_recording(&path, &sample()).unwrap();
        let raw = std::fs::read(&path).unwrap();
        assert_eq!(&raw[..8], b"AERIEREC");
        assert_eq!(&raw[8..12], &[1, 0, 16, 0]);
        assert_eq!(&raw[16..24], &0u64.to_le_bytes());
        assert_eq!(&raw[24..28], &5u32.to_le_bytes());
        assert_eq!(&raw[28..33], b"first");
        assert_eq!(raw.len(), 16 + 3 * 12 + 5 + 256);
        assert_eq!(read_recording(&path).unwrap(), sample());
    }

    #[test]
    fn recorder_appends_and_is_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("live.aerie-rec");
        let mut r = Recorder::create(&path, 100.0).unwrap();
        r.record(100.5, b"a").unwrap();
        r.record(100.25, b"bb").unwrap(); // clock can't go back in the file
        r.record(101.0, b"ccc").unwrap();
        assert_eq!(r.packets(), 3);
        let got = read_recording(&path).unwrap();
        assert_eq!(
            got.iter().map(|p| p.t_ns).collect::<Vec<_>>(),
            vec![500_000_000, 500_000_000, 1_000_000_000]
        );
        assert_eq!(got[2].bytes, b"ccc");
    }

    #[test]
    fn a_full_disk_stops_the_recording_at_a_record_boundary_and_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("live.aerie-rec");
        // Room for the header, two 100-byte records and part of a third.
        let fs = aerie_io::FaultyFs::new(aerie_io::Faults::full_after(16 + 2 * 112 + 50));
        let mut r = Recorder::create_in(fs.shared(), &path, 0.0).unwrap();
        r.record(0.1, &[1u8; 100]).unwrap();
        r.record(0.2, &[2u8; 100]).unwrap();
        let err = r.record(0.3, &[3u8; 100]).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("live.aerie-rec"), "{msg}");
        assert!(msg.contains("No space left on device"), "{msg}");
        assert!(msg.contains("byte offset 240 after 2 datagrams"), "{msg}");
        // Stopped: later datagrams are refused, not silently lost.
        assert!(matches!(
            r.record(0.4, b"x"),
            Err(RecordingError::Stopped { .. })
        ));
        drop(r);
        let got = read_recording(&path).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(got[1].bytes, vec![2u8; 100]);
        // A whole recording written at once on a full disk: nothing under the name.
        let whole = dir.path().join("whole.aerie-rec");
        let fs = aerie_io::FaultyFs::new(aerie_io::Faults::full_after(100));
        let err = write_recording_in(fs.shared(), &whole, &sample()).unwrap_err();
        assert!(err.to_string().contains("whole.aerie-rec"), "{err}");
        assert!(!whole.exists());
    }

    #[test]
    fn truncation_names_the_byte_offset() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.aerie-rec");
        write_recording(&path, &sample()).unwrap();
        let full = std::fs::read(&path).unwrap();
        // Cut inside the third record's payload: the record starts at 16 + 12 + 5 + 12 = 45.
        let e = parse_recording(&full[..full.len() - 10], &path).unwrap_err();
        assert!(
            matches!(e, RecordingError::Truncated { offset: 45, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("byte offset 45"), "{e}");
        assert!(e.to_string().contains("t.aerie-rec"), "{e}");
        // Cut inside a record header.
        let e = parse_recording(&full[..50], &path).unwrap_err();
        assert!(
            matches!(e, RecordingError::Truncated { offset: 45, .. }),
            "{e}"
        );
        // Cut inside the file header.
        let e = parse_recording(&full[..12], &path).unwrap_err();
        assert!(
            matches!(e, RecordingError::Truncated { offset: 0, .. }),
            "{e}"
        );
        // Every prefix is either a valid recording or an error; never a panic.
        for n in 0..full.len() {
            let _ = parse_recording(&full[..n], &path);
        }
    }

    #[test]
    fn bad_files_are_refused() {
        let p = Path::new("x.rec");
        assert!(matches!(
            parse_recording(b"PNG\x89 not a recording", p),
            Err(RecordingError::BadMagic { .. })
        ));
        let mut b = header().to_vec();
        b[8] = 2;
        assert!(matches!(
            parse_recording(&b, p),
            Err(RecordingError::BadVersion { found: 2, .. })
        ));
        let mut b = header().to_vec();
        b.extend_from_slice(&5u64.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.push(0);
        b.extend_from_slice(&4u64.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        let e = parse_recording(&b, p).unwrap_err();
        assert!(
            matches!(e, RecordingError::BadRecord { offset: 29, .. }),
            "{e}"
        );
        let mut b = header().to_vec();
        b.extend_from_slice(&0u64.to_le_bytes());
        b.extend_from_slice(&70_000u32.to_le_bytes());
        assert!(matches!(
            parse_recording(&b, p),
            Err(RecordingError::BadRecord { offset: 16, .. })
        ));
        // Header only: an empty recording.
        assert_eq!(parse_recording(&header(), p).unwrap(), vec![]);
    }
}
