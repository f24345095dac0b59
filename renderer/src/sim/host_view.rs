//! The host's CIGI views applied to the channels (issues 6 and 7). The IG's channels are CIGI
//! views: channel ↔ view ID by the channel's `cigi_view` (default: its index in the config).
//! When the host has sent a View Control (packet 16) for a channel's view, its rotation (yaw,
//! pitch, roll relative to the ownship) replaces the channel's view offset and its X/Y/Z offset
//! (body frame: forward, right, down) the eye offset, each field only once the host enabled it;
//! a View Definition (21) replaces the frustum by its left/right/top/bottom half-angles (once
//! all four were given) and sets the near clip. The far clip is kept and reported, but aerie's
//! reversed-Z projection has an infinite far plane, so it clips nothing.
//!
//! A record that cannot be drawn (a half-angle of 90° or more, left ≥ right, near ≤ 0, a view
//! attached to another entity than the ownship...) is counted and ignored: the channel keeps
//! its configured values for that part, and nothing stops.
//!
//! Pure functions of the config channel and the latest [`ViewTable`] ([`apply_host_view`]), and
//! a per-session tracker ([`HostViews`]) that counts the records refused. Applied once per
//! frame before selection, in the window and the headless path alike.

use aerie_config::{Channel, ChannelFrustum, EyeOffset, ViewOffset};
use aerie_sim_bridge::codec::cigi::{ViewRecord, ViewTable, OWNSHIP};

use crate::sim::channel::{channel_camera, AircraftPose};
use aerie_terrain::camera::Camera;

/// A channel as drawn this frame: the configured one with the host's view applied.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveChannel {
    /// View offset, eye offset and frustum as drawn; everything else as configured.
    pub channel: Channel,
    /// Near clip from the host's View Definition, metres (`None`: the renderer's default).
    pub near_m: Option<f64>,
    /// Far clip from the host's View Definition, metres: reported only (infinite far plane).
    pub far_m: Option<f64>,
    /// Some View Control field of this channel's view was applied.
    pub host_view: bool,
    /// The View Definition's half-angles replaced the frustum.
    pub host_frustum: bool,
}

impl LiveChannel {
    /// The channel as configured, without a host view.
    pub fn configured(ch: &Channel) -> Self {
        Self {
            channel: ch.clone(),
            near_m: None,
            far_m: None,
            host_view: false,
            host_frustum: false,
        }
    }

    /// The channel's camera for `pose`, `aspect` = viewport width / height.
    pub fn camera(&self, pose: &AircraftPose, aspect: f64) -> Camera {
        let mut cam = channel_camera((pose.position, pose.attitude), &self.channel, aspect);
        if let Some(near) = self.near_m {
            cam.near = near;
        }
        cam
    }

    /// The summary's description of the channel as drawn.
    pub fn to_json(&self) -> serde_json::Value {
        let c = &self.channel;
        let frustum = match c.frustum {
            ChannelFrustum::Symmetric { hfov_deg, vfov_deg } => {
                serde_json::json!({"hfov": hfov_deg, "vfov": vfov_deg})
            }
            ChannelFrustum::Asymmetric {
                left_deg,
                right_deg,
                down_deg,
                up_deg,
            } => serde_json::json!({
                "left": left_deg, "right": right_deg, "down": down_deg, "up": up_deg
            }),
        };
        serde_json::json!({
            "name": c.name,
            "cigi_view": c.cigi_view,
            "host_view": self.host_view,
            "host_frustum": self.host_frustum,
            "view": {"heading": c.view.heading_deg, "pitch": c.view.pitch_deg, "roll": c.view.roll_deg},
            "eye": {"forward": c.eye.forward_m, "right": c.eye.right_m, "up": c.eye.up_m},
            "frustum": frustum,
            "near_m": self.near_m,
            "far_m": self.far_m,
        })
    }
}

/// Largest eye offset accepted from the host, metres (the config's limit too).
const MAX_EYE_OFFSET_M: f64 = 1000.0;

fn any(v: &[Option<f32>]) -> bool {
    v.iter().any(Option::is_some)
}

/// Why the View Control part of `r` cannot be drawn (`Ok` also when it has none).
pub fn check_control(r: &ViewRecord) -> Result<(), String> {
    if !any(&r.offset_m) && !any(&r.roll_pitch_yaw_deg) {
        return Ok(());
    }
    if r.entity_id != OWNSHIP {
        return Err(format!(
            "view {} follows entity {}: aerie draws views of the ownship (entity 0) only",
            r.view_id, r.entity_id
        ));
    }
    let [roll, pitch, yaw] = r.roll_pitch_yaw_deg;
    for (name, v, limit) in [
        ("roll", roll, 180.0),
        ("pitch", pitch, 90.0),
        ("yaw", yaw, 360.0),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && f64::from(v).abs() <= limit) {
                return Err(format!(
                    "view {} {name} {v}° is outside ±{limit}°",
                    r.view_id
                ));
            }
        }
    }
    for (name, v) in ["x", "y", "z"].iter().zip(r.offset_m) {
        if let Some(v) = v {
            if !(v.is_finite() && f64::from(v).abs() <= MAX_EYE_OFFSET_M) {
                return Err(format!(
                    "view {} {name} offset {v} m is outside ±{MAX_EYE_OFFSET_M} m",
                    r.view_id
                ));
            }
        }
    }
    Ok(())
}

/// Why the View Definition part of `r` cannot be drawn (`Ok` also when it has none).
pub fn check_definition(r: &ViewRecord) -> Result<(), String> {
    if !any(&r.frustum) {
        return Ok(());
    }
    let id = r.view_id;
    if r.orthographic {
        return Err(format!(
            "view {id}: orthographic projection is not supported"
        ));
    }
    if let Some(n) = r.near_m() {
        if !(n.is_finite() && n > 0.0) {
            return Err(format!("view {id}: near {n} m must be greater than 0"));
        }
    }
    if let Some(f) = r.far_m() {
        let near = r.near_m().unwrap_or(0.0);
        if !(f.is_finite() && f > near) {
            return Err(format!(
                "view {id}: far {f} m must be greater than near ({near} m)"
            ));
        }
    }
    let names = ["left", "right", "top", "bottom"];
    for (name, v) in names.iter().zip(&r.frustum[2..]) {
        if let Some(v) = v {
            if !(v.is_finite() && v.abs() < 90.0) {
                return Err(format!(
                    "view {id}: {name} half-angle {v}° must be within (-90, 90)°"
                ));
            }
        }
    }
    if let Some([left, right, top, bottom]) = r.half_angles_deg() {
        if left >= right {
            return Err(format!(
                "view {id}: left half-angle {left}° must be less than right ({right}°)"
            ));
        }
        if bottom >= top {
            return Err(format!(
                "view {id}: bottom half-angle {bottom}° must be less than top ({top}°)"
            ));
        }
    }
    Ok(())
}

/// The channel `ch` as drawn with the host's record `rec` of its view (`None`: the host never
/// described it). A part of the record that fails [`check_control`] / [`check_definition`]
/// is ignored (the configured values stay).
pub fn apply_host_view(ch: &Channel, rec: Option<&ViewRecord>) -> LiveChannel {
    let mut live = LiveChannel::configured(ch);
    let Some(r) = rec else {
        return live;
    };
    if check_control(r).is_ok() {
        let [x, y, z] = r.offset_m.map(|v| v.map(f64::from));
        let [roll, pitch, yaw] = r.roll_pitch_yaw_deg.map(|v| v.map(f64::from));
        let (v, e) = (ch.view, ch.eye);
        live.channel.view = ViewOffset {
            heading_deg: yaw.unwrap_or(v.heading_deg),
            pitch_deg: pitch.unwrap_or(v.pitch_deg),
            roll_deg: roll.unwrap_or(v.roll_deg),
        };
        // CIGI's body frame is forward, right, down; the config's eye is forward, right, up.
        live.channel.eye = EyeOffset {
            forward_m: x.unwrap_or(e.forward_m),
            right_m: y.unwrap_or(e.right_m),
            up_m: z.map(|z| -z).unwrap_or(e.up_m),
        };
        live.host_view = any(&r.offset_m) || any(&r.roll_pitch_yaw_deg);
    }
    if check_definition(r).is_ok() {
        live.near_m = r.near_m().map(f64::from);
        live.far_m = r.far_m().map(f64::from);
        if let Some([left, right, top, bottom]) = r.half_angles_deg() {
            live.channel.frustum = ChannelFrustum::Asymmetric {
                left_deg: left.into(),
                right_deg: right.into(),
                down_deg: bottom.into(),
                up_deg: top.into(),
            };
            live.host_frustum = true;
        }
    }
    live
}

/// The host's views over a session: the channels as drawn, recomputed when the view table
/// changes, and how many view records were refused.
#[derive(Debug, Clone)]
pub struct HostViews {
    configured: Vec<Channel>,
    table: ViewTable,
    live: Vec<LiveChannel>,
    /// Changes of the host's view table seen.
    pub updates: u64,
    /// View records (of any view, with a channel or not) refused, counted once per change.
    pub rejected: u64,
    /// The last refusal, for the summary.
    pub last_rejection: Option<String>,
}

impl HostViews {
    pub fn new(configured: &[Channel]) -> Self {
        Self {
            configured: configured.to_vec(),
            table: ViewTable::default(),
            live: configured.iter().map(LiveChannel::configured).collect(),
            updates: 0,
            rejected: 0,
            last_rejection: None,
        }
    }

    /// The channels as drawn with the host's latest `table`.
    pub fn update(&mut self, table: &ViewTable) -> &[LiveChannel] {
        if *table == self.table {
            return &self.live;
        }
        self.updates += 1;
        for r in table.views() {
            if self.table.get(r.view_id) == Some(r) {
                continue;
            }
            // Refusals are counted per changed record and told once each: a host repeating
            // a bad packet every frame does not flood the log.
            for why in [check_control(r), check_definition(r)]
                .into_iter()
                .filter_map(Result::err)
            {
                eprintln!("CIGI {why}; ignored (the channel keeps its configured values)");
                self.rejected += 1;
                self.last_rejection = Some(why);
            }
        }
        self.table = table.clone();
        self.live = self
            .configured
            .iter()
            .map(|c| apply_host_view(c, table.get(c.cigi_view)))
            .collect();
        &self.live
    }

    /// The channels as drawn with the last table.
    pub fn live(&self) -> &[LiveChannel] {
        &self.live
    }

    /// The summary's `views` object.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "host_views": self.table.views().len(),
            "updates": self.updates,
            "rejected": self.rejected,
            "last_rejection": self.last_rejection,
            "channels": self.live.iter().map(LiveChannel::to_json).collect::<Vec<_>>(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_sim_bridge::codec::cigi::{ViewControl, ViewDefinition};
    use glam::DVec3;

    use aerie_terrain::camera::Attitude;

    fn channel() -> Channel {
        Channel {
            view: ViewOffset {
                heading_deg: -60.0,
                pitch_deg: 1.0,
                roll_deg: 2.0,
            },
            eye: EyeOffset {
                forward_m: 3.0,
                right_m: 0.5,
                up_m: 1.0,
            },
            cigi_view: 4,
            ..Channel::window("left", 160, 90, 60.0, 1.0)
        }
    }

    fn control(enable: u8, offset: [f32; 3], rpy: [f32; 3]) -> ViewControl {
        ViewControl {
            view_id: 4,
            enable,
            offset_m: offset,
            roll_pitch_yaw_deg: rpy,
            ..ViewControl::default()
        }
    }

    fn definition(enable: u8, v: [f32; 6]) -> ViewDefinition {
        ViewDefinition {
            view_id: 4,
            enable,
            near_m: v[0],
            far_m: v[1],
            left_deg: v[2],
            right_deg: v[3],
            top_deg: v[4],
            bottom_deg: v[5],
            ..ViewDefinition::default()
        }
    }

    #[test]
    fn no_record_keeps_the_configured_channel() {
        let ch = channel();
        assert_eq!(apply_host_view(&ch, None), LiveChannel::configured(&ch));
    }

    #[test]
    fn view_control_replaces_only_the_enabled_fields() {
        let ch = channel();
        let mut t = ViewTable::default();
        // Yaw and pitch and the z offset only: roll, x, y stay as configured.
        t.apply_control(&control(0b11_0100, [9.0, 9.0, -1.5], [9.0, -4.5, 33.25]));
        let live = apply_host_view(&ch, t.get(4));
        assert!(live.host_view && !live.host_frustum);
        let v = live.channel.view;
        assert_eq!((v.heading_deg, v.pitch_deg, v.roll_deg), (33.25, -4.5, 2.0));
        let e = live.channel.eye;
        // CIGI z is down: −1.5 m down is 1.5 m up.
        assert_eq!((e.forward_m, e.right_m, e.up_m), (3.0, 0.5, 1.5));
        assert_eq!(live.channel.frustum, ch.frustum);
        // The camera follows: a level aircraft heading north looks 33.25° right of north.
        let pose = AircraftPose {
            position: DVec3::new(100.0, 200.0, 300.0),
            attitude: Attitude::from_degrees(0.0, 0.0, 0.0),
        };
        let cam = live.camera(&pose, 16.0 / 9.0);
        assert!((cam.attitude.heading.to_degrees() - 33.25).abs() < 1e-9);
        assert!((cam.attitude.pitch.to_degrees() + 4.5).abs() < 1e-9);
        assert!((cam.position - DVec3::new(100.5, 203.0, 301.5)).length() < 1e-9);
    }

    #[test]
    fn view_definition_replaces_the_frustum_and_near() {
        let ch = channel();
        let mut t = ViewTable::default();
        t.apply_definition(&definition(0x3F, [2.0, 9e4, -20.0, 25.0, 15.0, -10.0]));
        let live = apply_host_view(&ch, t.get(4));
        assert!(live.host_frustum && !live.host_view);
        assert_eq!(
            live.channel.frustum,
            ChannelFrustum::Asymmetric {
                left_deg: -20.0,
                right_deg: 25.0,
                down_deg: -10.0,
                up_deg: 15.0
            }
        );
        assert_eq!((live.near_m, live.far_m), (Some(2.0), Some(9e4)));
        let cam = live.camera(
            &AircraftPose {
                position: DVec3::ZERO,
                attitude: Attitude::from_degrees(0.0, 0.0, 0.0),
            },
            1.0,
        );
        assert_eq!(cam.near, 2.0);
        assert!((cam.frustum.tan_left - (-20f64).to_radians().tan()).abs() < 1e-7);
        assert!((cam.frustum.tan_up - 15f64.to_radians().tan()).abs() < 1e-7);
        // Only some half-angles: the frustum waits for the rest, near applies.
        let mut t = ViewTable::default();
        t.apply_definition(&definition(0b0101, [0.5, 0.0, -20.0, 0.0, 0.0, 0.0]));
        let live = apply_host_view(&ch, t.get(4));
        assert!(!live.host_frustum);
        assert_eq!(live.channel.frustum, ch.frustum);
        assert_eq!(live.near_m, Some(0.5));
    }

    #[test]
    fn bad_records_are_refused_and_the_configured_values_stay() {
        let ch = channel();
        let cases: [(ViewTable, &str); 7] = [
            (
                def([1.0, 9e4, 30.0, 20.0, 10.0, -10.0]),
                "left half-angle 30° must be less than right",
            ),
            (
                def([1.0, 9e4, -30.0, 20.0, -10.0, 10.0]),
                "bottom half-angle 10° must be less than top",
            ),
            (
                def([1.0, 9e4, -90.0, 20.0, 10.0, -10.0]),
                "left half-angle -90° must be within",
            ),
            (
                def([0.0, 9e4, -30.0, 20.0, 10.0, -10.0]),
                "near 0 m must be greater than 0",
            ),
            (
                def([10.0, 5.0, -30.0, 20.0, 10.0, -10.0]),
                "far 5 m must be greater than near",
            ),
            (
                ctl(0x3F, [0.0; 3], [0.0, 95.0, 0.0], 0),
                "pitch 95° is outside ±90°",
            ),
            (ctl(0x3F, [0.0; 3], [0.0, 5.0, 0.0], 3), "follows entity 3"),
        ];
        fn def(v: [f32; 6]) -> ViewTable {
            let mut t = ViewTable::default();
            t.apply_definition(&definition(0x3F, v));
            t
        }
        fn ctl(enable: u8, o: [f32; 3], rpy: [f32; 3], entity: u16) -> ViewTable {
            let mut t = ViewTable::default();
            t.apply_control(&ViewControl {
                entity_id: entity,
                ..control(enable, o, rpy)
            });
            t
        }
        for (t, says) in cases {
            let r = t.get(4).unwrap();
            let why = check_control(r).and(check_definition(r)).unwrap_err();
            assert!(why.contains(says), "{why}");
            let live = apply_host_view(&ch, Some(r));
            assert_eq!(live.channel, ch, "{says}");
            assert_eq!(live.near_m, None);
        }
        // The tracker counts each refused record once, however often the host repeats it.
        let mut hv = HostViews::new(std::slice::from_ref(&ch));
        let bad = def([1.0, 9e4, 30.0, 20.0, 10.0, -10.0]);
        for _ in 0..3 {
            assert_eq!(hv.update(&bad)[0].channel, ch);
        }
        assert_eq!((hv.updates, hv.rejected), (1, 1));
        let mut good = bad.clone();
        good.apply_definition(&definition(0x3F, [1.0, 9e4, -30.0, 20.0, 10.0, -10.0]));
        assert!(hv.update(&good)[0].host_frustum);
        assert_eq!((hv.updates, hv.rejected), (2, 1));
    }

    #[test]
    fn channels_map_to_their_own_view_ids() {
        let a = Channel {
            cigi_view: 0,
            ..Channel::window("a", 160, 90, 60.0, 1.0)
        };
        let b = Channel {
            cigi_view: 7,
            ..Channel::window("b", 160, 90, 60.0, 1.0)
        };
        let mut t = ViewTable::default();
        t.apply_control(&ViewControl {
            view_id: 7,
            enable: 0x20,
            roll_pitch_yaw_deg: [0.0, 0.0, 45.0],
            ..ViewControl::default()
        });
        let mut hv = HostViews::new(&[a.clone(), b]);
        let live = hv.update(&t);
        assert_eq!(live[0].channel, a);
        assert!(!live[0].host_view);
        assert_eq!(live[1].channel.view.heading_deg, 45.0);
        assert!(live[1].host_view);
        let j = hv.to_json();
        assert_eq!(j["channels"][1]["view"]["heading"], 45.0);
        assert_eq!(j["channels"][1]["cigi_view"], 7);
    }
}
