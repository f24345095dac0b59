//! The IG session's counters: what the host sent (per packet ID), what the IG answered and how
//! late, and what answering cost.

use crate::codec::cigi::PacketCounts;

/// Answer latencies are counted per number of IG frames up to this many (the last bucket holds
/// this many or more).
pub const LATENCY_BUCKETS: usize = 10;

/// Counters of one IG session.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IgStats {
    /// CIGI messages taken.
    pub messages: u64,
    /// Host → IG packets by ID (every taken message's, IG Control included).
    pub packets: PacketCounts,
    /// Packets left out of their message because a value failed its check.
    pub rejected_packets: u64,
    /// Packets other than IG Control ignored because the host had the IG in Reset/Standby.
    pub ignored_in_standby: u64,
    /// Start of Frames sent (one per IG frame once the host is known).
    pub start_of_frames: u64,
    /// HAT/HOT and LOS responses sent.
    pub responses_sent: u64,
    /// Responses dropped because there was nowhere to send them (replies off, no host).
    pub responses_unsent: u64,
    /// Responses that did not fit a message and went in the next one.
    pub deferred: u64,
    /// HAT/HOT and LOS requests received (valid ones).
    pub requests_received: u64,
    /// Request packets rejected by their checks (answered invalid).
    pub requests_rejected: u64,
    /// Requests refused because the table was full (answered invalid).
    pub requests_refused: u64,
    /// Periodic requests ended (by the host's period 0, or their entity destroyed).
    pub requests_cancelled: u64,
    /// Requests dropped by a host's Reset.
    pub requests_dropped: u64,
    /// Answers with data (HAT/HOT valid, LOS hit or clear).
    pub answered: u64,
    /// Answers marked invalid (no terrain, not known entity, timed out, rejected).
    pub answered_invalid: u64,
    /// Of those, answered invalid after the terrain stayed pending for the bound.
    pub timed_out: u64,
    /// Frames a request was asked again because its terrain was pending.
    pub retries: u64,
    /// Outcomes dropped because the host replaced the request while it was asked.
    pub stale: u64,
    /// First answers by latency in IG frames (index = frames; the last bucket is
    /// [`LATENCY_BUCKETS`] − 1 or more).
    pub latency_frames: [u64; LATENCY_BUCKETS],
    /// The largest latency seen, frames.
    pub latency_max_frames: u64,
    /// Native queries received, answered, answered "timed out", refused for a full queue.
    pub native_received: u64,
    /// Native answers sent.
    pub native_answered: u64,
    /// Native answers that said "pending, timed out".
    pub native_timed_out: u64,
    /// Native queries refused because too many were waiting.
    pub native_refused: u64,
    /// Entities created, destroyed, refused (table full).
    pub entities_created: u64,
    /// Entities destroyed.
    pub entities_destroyed: u64,
    /// Entity Controls refused because the table was full.
    pub entities_refused: u64,
    /// Rate Controls for articulated parts (not kept).
    pub part_rates_ignored: u64,
    /// Frames whose answering time was recorded, the total and the largest, µs.
    pub cpu_frames: u64,
    /// Total CPU µs answering.
    pub cpu_us_total: f64,
    /// Largest CPU µs of one frame.
    pub cpu_us_max: f64,
    /// Datagrams the transport failed to send.
    pub send_errors: u64,
    /// Live requests now (filled in by the session).
    pub requests_live: u64,
    /// Live periodic requests now.
    pub periodic_live: u64,
    /// Native queries waiting now.
    pub native_waiting: u64,
    /// Entities known now.
    pub entities: u64,
}

impl IgStats {
    pub(crate) fn note_latency(&mut self, frames: u64) {
        let i = (frames as usize).min(LATENCY_BUCKETS - 1);
        self.latency_frames[i] += 1;
        self.latency_max_frames = self.latency_max_frames.max(frames);
    }

    pub(crate) fn note_cpu_us(&mut self, us: f64) {
        if us.is_finite() && us >= 0.0 {
            self.cpu_frames += 1;
            self.cpu_us_total += us;
            self.cpu_us_max = self.cpu_us_max.max(us);
        }
    }

    /// First answers counted in [`latency_frames`](Self::latency_frames).
    pub fn latency_count(&self) -> u64 {
        self.latency_frames.iter().sum()
    }

    /// Mean latency of first answers, frames.
    pub fn latency_mean_frames(&self) -> Option<f64> {
        let n = self.latency_count();
        (n > 0).then(|| {
            self.latency_frames
                .iter()
                .enumerate()
                .map(|(i, &c)| i as f64 * c as f64)
                .sum::<f64>()
                / n as f64
        })
    }

    /// Mean CPU µs spent answering per frame.
    pub fn cpu_us_mean(&self) -> Option<f64> {
        (self.cpu_frames > 0).then(|| self.cpu_us_total / self.cpu_frames as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_buckets_and_means() {
        let mut s = IgStats::default();
        assert_eq!(s.latency_mean_frames(), None);
        s.note_latency(1);
        s.note_latency(1);
        s.note_latency(4);
        s.note_latency(40);
        assert_eq!(s.latency_frames[1], 2);
        assert_eq!(s.latency_frames[4], 1);
        assert_eq!(s.latency_frames[LATENCY_BUCKETS - 1], 1);
        assert_eq!(s.latency_max_frames, 40);
        assert_eq!(s.latency_count(), 4);
        assert_eq!(s.latency_mean_frames(), Some((1.0 + 1.0 + 4.0 + 9.0) / 4.0));
        s.note_cpu_us(10.0);
        s.note_cpu_us(30.0);
        s.note_cpu_us(f64::NAN);
        assert_eq!((s.cpu_frames, s.cpu_us_max), (2, 30.0));
        assert_eq!(s.cpu_us_mean(), Some(20.0));
    }
}
