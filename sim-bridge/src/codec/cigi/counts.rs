//! Per-packet-ID counts of a message (and, merged, of a session), with the packets' names.

/// How many packets of each ID, as a compact list sorted by ID (a message holds a handful of
/// IDs; a session's summary merges its messages' counts).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PacketCounts {
    counts: Vec<(u8, u32)>,
}

impl PacketCounts {
    /// Counts one more packet of `id`.
    pub fn add(&mut self, id: u8) {
        self.add_n(id, 1);
    }

    /// Counts `n` more packets of `id` (saturating).
    pub fn add_n(&mut self, id: u8, n: u32) {
        match self.counts.binary_search_by_key(&id, |&(i, _)| i) {
            Ok(i) => self.counts[i].1 = self.counts[i].1.saturating_add(n),
            Err(i) => self.counts.insert(i, (id, n)),
        }
    }

    /// Adds every count of `other`.
    pub fn merge(&mut self, other: &PacketCounts) {
        for &(id, n) in &other.counts {
            self.add_n(id, n);
        }
    }

    /// The count of `id` (0 when none).
    pub fn get(&self, id: u8) -> u32 {
        self.counts
            .binary_search_by_key(&id, |&(i, _)| i)
            .map_or(0, |i| self.counts[i].1)
    }

    /// (ID, count) pairs by ascending ID, zero counts left out.
    pub fn as_slice(&self) -> &[(u8, u32)] {
        &self.counts
    }

    /// Every packet counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().map(|&(_, n)| u64::from(n)).sum()
    }

    /// Nothing counted.
    pub fn is_empty(&self) -> bool {
        self.counts.is_empty()
    }
}

impl std::fmt::Display for PacketCounts {
    /// `id name ×count` pairs, e.g. `1 IG Control ×1, 2 Entity Control ×3`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (k, &(id, n)) in self.counts.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{id} {} ×{n}", packet_name(id).unwrap_or("unknown"))?;
        }
        Ok(())
    }
}

/// The name of a CIGI 3.x packet ID (CCL `CIGI_*_PACKET_ID_V3*` defines), `None` for IDs the
/// ICD does not define (200+ are user-defined).
pub fn packet_name(id: u8) -> Option<&'static str> {
    const HOST: [&str; 35] = [
        "IG Control",
        "Entity Control",
        "Conformal Clamped Entity Control",
        "Component Control",
        "Short Component Control",
        "Articulated Part Control",
        "Short Articulated Part Control",
        "Rate Control",
        "Celestial Sphere Control",
        "Atmosphere Control",
        "Environmental Region Control",
        "Weather Control",
        "Maritime Surface Conditions Control",
        "Wave Control",
        "Terrestrial Surface Conditions Control",
        "View Control",
        "Sensor Control",
        "Motion Tracker Control",
        "Earth Reference Model Definition",
        "Trajectory Definition",
        "View Definition",
        "Collision Detection Segment Definition",
        "Collision Detection Volume Definition",
        "HAT/HOT Request",
        "Line of Sight Segment Request",
        "Line of Sight Vector Request",
        "Position Request",
        "Environmental Conditions Request",
        "Symbol Surface Definition",
        "Symbol Text Definition",
        "Symbol Circle Definition",
        "Symbol Line Definition",
        "Symbol Clone",
        "Symbol Control",
        "Short Symbol Control",
    ];
    const IG: [&str; 17] = [
        "Start of Frame",
        "HAT/HOT Response",
        "HAT/HOT Extended Response",
        "Line of Sight Response",
        "Line of Sight Extended Response",
        "Sensor Response",
        "Sensor Extended Response",
        "Position Response",
        "Weather Conditions Response",
        "Aerosol Concentration Response",
        "Maritime Surface Conditions Response",
        "Terrestrial Surface Conditions Response",
        "Collision Detection Segment Notification",
        "Collision Detection Volume Notification",
        "Animation Stop Notification",
        "Event Notification",
        "Image Generator Message",
    ];
    match id {
        1..=35 => Some(HOST[usize::from(id - 1)]),
        101..=117 => Some(IG[usize::from(id - 101)]),
        200..=255 => Some("user-defined"),
        _ => None,
    }
}
