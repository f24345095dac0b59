//! CIGI 3.x minor versions and what differs between them on the wire.
//!
//! The minor version is read from the host's IG Control (CCL `CigiIncomingMsg.cpp`,
//! `ProcessIncomingMsg`: the major version at byte 2, the minor version in the upper nibble of
//! byte 4 — byte 5 in a Start of Frame). CIGI 3.0 and 3.1 have a 16-byte IG Control without a
//! minor-version field (CCL `CigiIGCtrlV3.cpp`: byte 4 bits 4–7 are reserved, written 0), so
//! the two cannot be told apart: the CCL reads such a message as 3.0 and so does aerie. Every
//! packet aerie reads or writes has the same bytes in 3.0 and 3.1, so the answer (a 16-byte
//! Start of Frame, CCL `CigiSOFV3.cpp`) is right for either.

/// A CIGI 3 minor version.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum CigiVersion {
    /// CIGI 3.0 — also what a 3.1 host's 16-byte IG Control decodes as (same bytes).
    V3_0,
    /// CIGI 3.1 (encodes exactly as 3.0).
    V3_1,
    /// CIGI 3.2: 24-byte IG Control and Start of Frame, update periods, host frame LSNs.
    V3_2,
    /// CIGI 3.3: adds the IG Control and Entity Control smoothing flags.
    #[default]
    V3_3,
}

impl CigiVersion {
    /// Every version, oldest first.
    pub const ALL: [CigiVersion; 4] = [
        CigiVersion::V3_0,
        CigiVersion::V3_1,
        CigiVersion::V3_2,
        CigiVersion::V3_3,
    ];

    /// The minor version number (0..=3).
    pub fn minor(self) -> u8 {
        match self {
            CigiVersion::V3_0 => 0,
            CigiVersion::V3_1 => 1,
            CigiVersion::V3_2 => 2,
            CigiVersion::V3_3 => 3,
        }
    }

    /// The version of minor number `minor`, if it is one of 0..=3.
    pub fn from_minor(minor: u8) -> Option<Self> {
        Self::ALL.get(usize::from(minor)).copied()
    }

    /// The version a host's IG Control declares, from its size byte and byte 4. A 16-byte IG
    /// Control is 3.0 (or 3.1: the same bytes). A 24-byte one is 3.2 or later: its minor
    /// nibble 2 is 3.2, 3 and above read as 3.3 (the newest layout known, as the CCL's
    /// `CigiVersionID::BestCigiVersion` does), and 0 or 1 — a host that did not fill the
    /// nibble in — read as 3.2, the layout the size says. Any other size is `None`.
    pub fn from_ig_control(size: u8, byte4: u8) -> Option<Self> {
        match (size, byte4 >> 4) {
            (16, _) => Some(CigiVersion::V3_0),
            (24, 0..=2) => Some(CigiVersion::V3_2),
            (24, _) => Some(CigiVersion::V3_3),
            _ => None,
        }
    }

    /// IG Control size in this version (CCL `CigiBaseIGCtrl.h`: 16 for 3.0/3.1, 24 after).
    pub fn ig_control_size(self) -> u8 {
        if self.is_3_2_or_later() {
            24
        } else {
            16
        }
    }

    /// Start of Frame size in this version (CCL `CigiBaseSOF.h`: 16 for 3.0/3.1, 24 after).
    pub fn start_of_frame_size(self) -> u8 {
        self.ig_control_size()
    }

    /// 3.2 or later: IG Control / Start of Frame carry the minor version and the last frame
    /// received, requests carry an update period, responses the host frame's 4 low bits.
    pub fn is_3_2_or_later(self) -> bool {
        self >= CigiVersion::V3_2
    }

    /// 3.3: IG Control and Entity Control carry a smoothing (extrapolation) enable.
    pub fn has_smoothing(self) -> bool {
        self >= CigiVersion::V3_3
    }
}

impl std::fmt::Display for CigiVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "3.{}", self.minor())
    }
}
