//! The per-view records a host has set up, kept across messages.

use super::format::MAX_VIEWS;
use super::message::CigiMessage;
use super::view_packets::{ViewControl, ViewDefinition};

/// What the host has set for one view (fields it never enabled are `None`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewRecord {
    /// View ID.
    pub view_id: u16,
    /// Group ID (last seen).
    pub group_id: u8,
    /// Entity the view follows (View Control's entity; 0 = ownship).
    pub entity_id: u16,
    /// Eye offset X (forward), Y (right), Z (down), metres.
    pub offset_m: [Option<f32>; 3],
    /// Roll, pitch, yaw relative to the entity, degrees.
    pub roll_pitch_yaw_deg: [Option<f32>; 3],
    /// Near, far (metres), left, right, top, bottom (degrees).
    pub frustum: [Option<f32>; 6],
    /// Mirror mode from the last View Definition.
    pub mirror_mode: u8,
    /// Orthographic projection from the last View Definition.
    pub orthographic: bool,
    /// View type from the last View Definition.
    pub view_type: u8,
}

impl ViewRecord {
    /// Near clip distance, metres.
    pub fn near_m(&self) -> Option<f32> {
        self.frustum[0]
    }
    /// Far clip distance, metres.
    pub fn far_m(&self) -> Option<f32> {
        self.frustum[1]
    }
    /// Left, right, top, bottom half-angles in degrees when all four are set.
    pub fn half_angles_deg(&self) -> Option<[f32; 4]> {
        Some([
            self.frustum[2]?,
            self.frustum[3]?,
            self.frustum[4]?,
            self.frustum[5]?,
        ])
    }
}

/// The per-view state built from View Control and View Definition packets, sorted by view ID.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewTable {
    views: Vec<ViewRecord>,
}

impl ViewTable {
    /// All views the host has described, by ascending view ID.
    pub fn views(&self) -> &[ViewRecord] {
        &self.views
    }

    /// The record of `view_id`.
    pub fn get(&self, view_id: u16) -> Option<&ViewRecord> {
        self.views
            .binary_search_by_key(&view_id, |v| v.view_id)
            .ok()
            .map(|i| &self.views[i])
    }

    fn slot(&mut self, view_id: u16) -> Option<&mut ViewRecord> {
        match self.views.binary_search_by_key(&view_id, |v| v.view_id) {
            Ok(i) => Some(&mut self.views[i]),
            Err(i) if self.views.len() < MAX_VIEWS => {
                self.views.insert(
                    i,
                    ViewRecord {
                        view_id,
                        ..ViewRecord::default()
                    },
                );
                Some(&mut self.views[i])
            }
            Err(_) => None,
        }
    }

    /// Applies a View Control (enabled fields only). Returns whether anything changed.
    pub fn apply_control(&mut self, c: &ViewControl) -> bool {
        let Some(v) = self.slot(c.view_id) else {
            return false;
        };
        let before = *v;
        v.group_id = c.group_id;
        v.entity_id = c.entity_id;
        for i in 0..3 {
            if c.enable & (1 << i) != 0 {
                v.offset_m[i] = Some(c.offset_m[i]);
            }
            if c.enable & (1 << (i + 3)) != 0 {
                v.roll_pitch_yaw_deg[i] = Some(c.roll_pitch_yaw_deg[i]);
            }
        }
        *v != before
    }

    /// Applies a View Definition (enabled frustum fields only). Returns whether anything changed.
    pub fn apply_definition(&mut self, d: &ViewDefinition) -> bool {
        let Some(v) = self.slot(d.view_id) else {
            return false;
        };
        let before = *v;
        v.group_id = d.group_id;
        v.mirror_mode = d.mirror_mode;
        v.orthographic = d.orthographic;
        v.view_type = d.view_type;
        for (i, value) in d.values().into_iter().enumerate() {
            if d.enable & (1 << i) != 0 {
                v.frustum[i] = Some(value);
            }
        }
        *v != before
    }

    /// Applies every view packet of a message in order. Returns whether anything changed.
    pub fn apply(&mut self, m: &CigiMessage) -> bool {
        let mut changed = false;
        for c in &m.view_controls {
            changed |= self.apply_control(c);
        }
        for d in &m.view_definitions {
            changed |= self.apply_definition(d);
        }
        changed
    }
}
