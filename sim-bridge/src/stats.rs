//! Input counters: shared between the receiving thread (writes, relaxed atomics) and whoever
//! reports them (reads a [`StatsSnapshot`]). No locks.

use crate::codec::cigi::{packet_name, PacketCounts};

use std::sync::atomic::{
    AtomicU64,
    Ordering::{Acquire, Relaxed, Release},
};

/// Why a datagram (or shared-memory sample) was not used. Each is counted separately.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DropReason {
    /// Not any known protocol, or the wrong magic for the configured one.
    Unknown,
    /// Shorter or longer than the protocol's fixed size.
    BadSize,
    /// Known protocol, unsupported version.
    BadVersion,
    /// CRC-32 mismatch (aerie native).
    BadCrc,
    /// Structurally broken: bad packet size inside a CIGI message, reserved bits set, …
    Malformed,
    /// A pose value is NaN/infinite or outside its definition (latitude, pitch, …).
    Invalid,
    /// A finite pose value beyond the plausibility limits (position outside the world bound,
    /// altitude, speed, rate or angle no aircraft reaches): an outlier.
    Implausible,
    /// Well formed but asks for something aerie does not do (e.g. an attached ownship).
    Unsupported,
    /// The sender's address is not on the allow-list.
    NotAllowed,
    /// Older sequence number than the last accepted one.
    OutOfOrder,
    /// Same sequence number as the last accepted one.
    Duplicate,
}

impl DropReason {
    /// Every reason, in reporting order.
    pub const ALL: [DropReason; 11] = [
        DropReason::Unknown,
        DropReason::BadSize,
        DropReason::BadVersion,
        DropReason::BadCrc,
        DropReason::Malformed,
        DropReason::Invalid,
        DropReason::Implausible,
        DropReason::Unsupported,
        DropReason::NotAllowed,
        DropReason::OutOfOrder,
        DropReason::Duplicate,
    ];

    /// Short snake_case name used in logs and JSON summaries.
    pub fn name(self) -> &'static str {
        match self {
            DropReason::Unknown => "unknown",
            DropReason::BadSize => "bad_size",
            DropReason::BadVersion => "bad_version",
            DropReason::BadCrc => "bad_crc",
            DropReason::Malformed => "malformed",
            DropReason::Invalid => "invalid",
            DropReason::Implausible => "implausible",
            DropReason::Unsupported => "unsupported",
            DropReason::NotAllowed => "not_allowed",
            DropReason::OutOfOrder => "out_of_order",
            DropReason::Duplicate => "duplicate",
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

impl std::fmt::Display for DropReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Live counters of one input (one UDP port or one shared-memory file).
#[derive(Debug)]
pub struct Counters {
    received: AtomicU64,
    accepted: AtomicU64,
    no_pose: AtomicU64,
    dropped: [AtomicU64; DropReason::ALL.len()],
    gaps: AtomicU64,
    missed: AtomicU64,
    resyncs: AtomicU64,
    replies: AtomicU64,
    retries: AtomicU64,
    busy: AtomicU64,
    shm_shrinks: AtomicU64,
    /// f64 bits of the first accepted pose's arrival (0 bits = none yet).
    first_accept_bits: AtomicU64,
    /// f64 bits of the latest accepted pose's arrival.
    last_accept_bits: AtomicU64,
    /// CIGI packets of every decoded host message, by packet ID.
    cigi_packets: [AtomicU64; 256],
}

impl Default for Counters {
    fn default() -> Self {
        Self {
            received: AtomicU64::new(0),
            accepted: AtomicU64::new(0),
            no_pose: AtomicU64::new(0),
            dropped: Default::default(),
            gaps: AtomicU64::new(0),
            missed: AtomicU64::new(0),
            resyncs: AtomicU64::new(0),
            replies: AtomicU64::new(0),
            retries: AtomicU64::new(0),
            busy: AtomicU64::new(0),
            shm_shrinks: AtomicU64::new(0),
            first_accept_bits: AtomicU64::new(0),
            last_accept_bits: AtomicU64::new(0),
            cigi_packets: std::array::from_fn(|_| AtomicU64::new(0)),
        }
    }
}

impl Counters {
    pub(crate) fn received(&self) {
        self.received.fetch_add(1, Relaxed);
    }
    /// One more pose accepted, arriving at `arrival_s` (seconds on the monotonic timeline).
    /// Called after the pose was published to the reader; the release pairs with the acquire
    /// in [`snapshot`](Self::snapshot), so whoever reads `accepted = n` and then polls the
    /// reader gets the n-th accepted pose or a newer one (the flood test relies on it).
    pub(crate) fn accepted(&self, arrival_s: f64) {
        if self.accepted.fetch_add(1, Release) == 0 {
            self.first_accept_bits.store(arrival_s.to_bits(), Relaxed);
        }
        self.last_accept_bits.store(arrival_s.to_bits(), Relaxed);
    }
    pub(crate) fn no_pose(&self) {
        self.no_pose.fetch_add(1, Relaxed);
    }
    pub(crate) fn dropped(&self, r: DropReason) {
        self.dropped[r.index()].fetch_add(1, Relaxed);
    }
    pub(crate) fn gap(&self, missed: u64) {
        self.gaps.fetch_add(1, Relaxed);
        self.missed.fetch_add(missed, Relaxed);
    }
    pub(crate) fn resync(&self) {
        self.resyncs.fetch_add(1, Relaxed);
    }
    pub(crate) fn reply(&self) {
        self.replies.fetch_add(1, Relaxed);
    }
    pub(crate) fn retries(&self, n: u64) {
        self.retries.fetch_add(n, Relaxed);
    }
    pub(crate) fn busy(&self) {
        self.busy.fetch_add(1, Relaxed);
    }
    pub(crate) fn shm_shrink(&self) {
        self.shm_shrinks.fetch_add(1, Relaxed);
    }
    /// Adds a decoded CIGI message's per-ID packet counts.
    pub(crate) fn cigi_packets(&self, counts: &PacketCounts) {
        for &(id, n) in counts.as_slice() {
            self.cigi_packets[usize::from(id)].fetch_add(n.into(), Relaxed);
        }
    }

    /// A consistent-enough copy for reporting (each counter read once; `accepted` with
    /// acquire, see [`accepted`](Self::accepted)).
    pub fn snapshot(&self) -> StatsSnapshot {
        let mut dropped = [0; DropReason::ALL.len()];
        for (d, a) in dropped.iter_mut().zip(&self.dropped) {
            *d = a.load(Relaxed);
        }
        StatsSnapshot {
            received: self.received.load(Relaxed),
            accepted: self.accepted.load(Acquire),
            no_pose: self.no_pose.load(Relaxed),
            dropped,
            gaps: self.gaps.load(Relaxed),
            missed: self.missed.load(Relaxed),
            resyncs: self.resyncs.load(Relaxed),
            replies: self.replies.load(Relaxed),
            retries: self.retries.load(Relaxed),
            busy: self.busy.load(Relaxed),
            shm_shrinks: self.shm_shrinks.load(Relaxed),
            first_accept_s: f64::from_bits(self.first_accept_bits.load(Relaxed)),
            last_accept_s: f64::from_bits(self.last_accept_bits.load(Relaxed)),
            cigi_packets: CigiPacketTally(std::array::from_fn(|i| {
                self.cigi_packets[i].load(Relaxed)
            })),
        }
    }
}

/// CIGI packets received, by packet ID (every decoded host message's, IG Control included).
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CigiPacketTally([u64; 256]);

impl Default for CigiPacketTally {
    fn default() -> Self {
        CigiPacketTally([0; 256])
    }
}

impl std::fmt::Debug for CigiPacketTally {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_map().entries(self.nonzero()).finish()
    }
}

impl CigiPacketTally {
    /// Packets of ID `id`.
    pub fn get(&self, id: u8) -> u64 {
        self.0[usize::from(id)]
    }

    /// `(id, count)` for every ID seen, ascending.
    pub fn nonzero(&self) -> Vec<(u8, u64)> {
        (0..=255u8)
            .map(|id| (id, self.get(id)))
            .filter(|&(_, n)| n > 0)
            .collect()
    }

    /// Every packet counted.
    pub fn total(&self) -> u64 {
        self.0.iter().sum()
    }

    /// `id name ×count` pairs (`1 IG Control ×60, 2 Entity Control ×60`), or `none`.
    pub fn summary(&self) -> String {
        let parts: Vec<String> = self
            .nonzero()
            .into_iter()
            .map(|(id, n)| match packet_name(id) {
                Some(name) => format!("{id} {name} ×{n}"),
                None => format!("{id} ×{n}"),
            })
            .collect();
        if parts.is_empty() {
            "none".into()
        } else {
            parts.join(", ")
        }
    }
}

/// Counter values at one moment. `received = accepted + no_pose + dropped_total()` once the
/// receiving thread is idle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StatsSnapshot {
    /// Datagrams received (UDP) or new samples seen (shared memory).
    pub received: u64,
    /// Poses accepted and handed to the frame loop.
    pub accepted: u64,
    /// Valid messages that carried no ownship pose (e.g. a CIGI message with views only).
    pub no_pose: u64,
    /// Dropped, indexed like [`DropReason::ALL`]; see [`StatsSnapshot::dropped`].
    pub dropped: [u64; DropReason::ALL.len()],
    /// Sequence gaps (a jump forward by more than one).
    pub gaps: u64,
    /// Sequence numbers skipped over by those gaps (packets lost or reordered away).
    pub missed: u64,
    /// Times the sequence tracker restarted (sender restarted, or silent for a long time).
    pub resyncs: u64,
    /// CIGI Start of Frame answers sent.
    pub replies: u64,
    /// Shared memory: torn reads retried.
    pub retries: u64,
    /// Shared memory: polls that gave up after the bounded retries (writer busy).
    pub busy: u64,
    /// Shared memory: times the file was found shorter than the layout (nothing read from it
    /// until it regrew).
    pub shm_shrinks: u64,
    /// Arrival of the first accepted pose, seconds on the monotonic timeline (0 if none).
    pub first_accept_s: f64,
    /// Arrival of the latest accepted pose (0 if none).
    pub last_accept_s: f64,
    /// CIGI packets received by packet ID.
    pub cigi_packets: CigiPacketTally,
}

impl StatsSnapshot {
    /// How many were dropped for `reason`.
    pub fn dropped(&self, reason: DropReason) -> u64 {
        self.dropped[reason.index()]
    }

    /// Dropped for any reason.
    pub fn dropped_total(&self) -> u64 {
        self.dropped.iter().sum()
    }

    /// Accepted poses per second between the first and the latest accepted arrival (`None`
    /// with fewer than two poses or no time between them).
    pub fn pose_rate_hz(&self) -> Option<f64> {
        let span = self.last_accept_s - self.first_accept_s;
        (self.accepted >= 2 && span > 0.0).then(|| (self.accepted - 1) as f64 / span)
    }

    /// `(reason, count)` for every reason with a non-zero count.
    pub fn dropped_by_reason(&self) -> Vec<(DropReason, u64)> {
        DropReason::ALL
            .iter()
            .map(|&r| (r, self.dropped(r)))
            .filter(|&(_, n)| n > 0)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reasons_index_in_order() {
        for (i, r) in DropReason::ALL.iter().enumerate() {
            assert_eq!(r.index(), i);
        }
        let c = Counters::default();
        c.received();
        c.dropped(DropReason::BadCrc);
        c.dropped(DropReason::BadCrc);
        c.gap(3);
        let s = c.snapshot();
        assert_eq!(s.dropped(DropReason::BadCrc), 2);
        assert_eq!(s.dropped_total(), 2);
        assert_eq!((s.gaps, s.missed), (1, 3));
        assert_eq!(s.dropped_by_reason(), vec![(DropReason::BadCrc, 2)]);
        assert_eq!(s.pose_rate_hz(), None);
        c.accepted(10.0);
        c.accepted(10.5);
        c.accepted(11.0);
        assert_eq!(c.snapshot().pose_rate_hz(), Some(2.0));
    }

    #[test]
    fn cigi_packets_are_tallied_by_id() {
        let c = Counters::default();
        assert_eq!(c.snapshot().cigi_packets.summary(), "none");
        let mut m = PacketCounts::default();
        m.add(1);
        m.add_n(2, 3);
        m.add(60);
        c.cigi_packets(&m);
        c.cigi_packets(&m);
        let t = c.snapshot().cigi_packets;
        assert_eq!(t.get(2), 6);
        assert_eq!(t.nonzero(), vec![(1, 2), (2, 6), (60, 2)]);
        assert_eq!(t.total(), 10);
        let s = t.summary();
        assert!(s.starts_with("1 IG Control ×2, 2 Entity Control ×6"), "{s}");
        // An ID CIGI does not define: the number alone.
        assert!(s.ends_with(", 60 ×2"), "{s}");
    }
}
