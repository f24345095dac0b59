//! Absurd but finite values (±1.797e308 in f64 fields, ±f32::MAX in f32 ones) behind a valid
//! header and checksum: every codec refuses them, and the input counts them as implausible.

use aerie_sim_bridge::codec::cigi::{self, EntityControl, IgControl};
use aerie_sim_bridge::codec::{fgfs, native, xplane, ByteOrder};
use aerie_sim_bridge::pose::PoseLimits;
use aerie_sim_bridge::timing::SeqVerdict;
use aerie_sim_bridge::{
    decode, input_channel, DecodeError, DropReason, InputParams, Pose, PosePosition, Protocol,
    ProtocolChoice, Verdict,
};

const HUGE: f64 = 1.797e308;
const HUGE32: f32 = f32::MAX;

fn local(x: f64) -> Pose {
    Pose {
        position: PosePosition::LocalEnu {
            x,
            y: 10.0,
            z: 300.0,
        },
        attitude_deg: [92.0, 3.0, -8.0],
        sim_time_s: 10.0,
        frame: 600,
        velocity_enu: Some([120.0, -4.0, 1.0]),
        angular_rates_deg_s: Some([1.0, 0.0, -3.0]),
    }
}

/// Native packets with one absurd field each (valid CRC: `encode` computes it).
fn native_outliers() -> Vec<(&'static str, Vec<u8>)> {
    let mut out = Vec::new();
    for x in [HUGE, -HUGE] {
        out.push(("position.x", native::encode(&local(x), 1).to_vec()));
    }
    let mut p = local(0.0);
    p.attitude_deg[0] = f64::MAX;
    out.push(("attitude_deg.heading", native::encode(&p, 1).to_vec()));
    let mut p = local(0.0);
    p.velocity_enu = Some([HUGE, 0.0, 0.0]);
    out.push(("velocity_enu.east", native::encode(&p, 1).to_vec()));
    let mut p = local(0.0);
    p.angular_rates_deg_s = Some([0.0, -HUGE, 0.0]);
    out.push(("angular_rates_deg_s.pitch", native::encode(&p, 1).to_vec()));
    out
}

fn cigi_with(e: EntityControl) -> Vec<u8> {
    let ig = IgControl::default().encode(ByteOrder::Big);
    [&ig[..], &e.encode(ByteOrder::Big)[..]].concat()
}

fn cigi_outliers() -> Vec<(&'static str, Vec<u8>)> {
    let base = EntityControl {
        entity_state: 1,
        lat_deg: 45.0,
        lon_deg: 11.0,
        alt_m: 1500.0,
        ..EntityControl::default()
    };
    vec![
        (
            "position.alt_m",
            cigi_with(EntityControl {
                alt_m: HUGE,
                ..base
            }),
        ),
        (
            "attitude_deg.heading",
            cigi_with(EntityControl {
                yaw_deg: HUGE32,
                ..base
            }),
        ),
        (
            "attitude_deg.roll",
            cigi_with(EntityControl {
                roll_deg: -HUGE32,
                ..base
            }),
        ),
    ]
}

fn xplane_outliers() -> Vec<(&'static str, Vec<u8>)> {
    let base = xplane::Rpos::default();
    let with = |f: &dyn Fn(&mut xplane::Rpos)| {
        let mut r = base;
        f(&mut r);
        xplane::encode(&r).to_vec()
    };
    vec![
        ("position.alt_m", with(&|r| r.ele_m = -HUGE)),
        ("attitude_deg.heading", with(&|r| r.heading_deg = HUGE32)),
        ("velocity_enu.east", with(&|r| r.vx_east = HUGE32)),
        ("angular_rates_deg_s.roll", with(&|r| r.p_rad_s = HUGE32)),
    ]
}

fn fgfs_outliers() -> Vec<(&'static str, Vec<u8>)> {
    let base = fgfs::FdmPose::default();
    let with = |f: &dyn Fn(&mut fgfs::FdmPose)| {
        let mut r = base;
        f(&mut r);
        fgfs::encode(&r).to_vec()
    };
    vec![
        ("position.alt_m", with(&|r| r.altitude = HUGE)),
        ("attitude_deg.roll", with(&|r| r.phi = HUGE32)),
        ("velocity_enu.north", with(&|r| r.v_north = -HUGE32)),
        ("angular_rates_deg_s.heading", with(&|r| r.psidot = HUGE32)),
    ]
}

fn all_outliers() -> Vec<(Protocol, &'static str, Vec<u8>)> {
    let mut out = Vec::new();
    for (p, list) in [
        (Protocol::Aerie, native_outliers()),
        (Protocol::Cigi, cigi_outliers()),
        (Protocol::XPlane, xplane_outliers()),
        (Protocol::Fgfs, fgfs_outliers()),
    ] {
        out.extend(list.into_iter().map(|(f, b)| (p, f, b)));
    }
    out
}

#[test]
fn the_baselines_decode() {
    // Each outlier differs from a valid packet in its one field only.
    native::decode(&native::encode(&local(0.0), 1)).unwrap();
    cigi::decode(&cigi_with(EntityControl {
        entity_state: 1,
        lat_deg: 45.0,
        lon_deg: 11.0,
        alt_m: 1500.0,
        ..EntityControl::default()
    }))
    .unwrap()
    .ownship_pose()
    .expect("an ownship pose");
    xplane::decode(&xplane::encode(&xplane::Rpos::default())).unwrap();
    fgfs::decode(&fgfs::encode(&fgfs::FdmPose::default())).unwrap();
}

#[test]
fn absurd_values_are_refused_by_every_codec() {
    for (protocol, field, bytes) in all_outliers() {
        let e = decode(ProtocolChoice::Auto, &bytes).expect_err(field);
        assert!(
            matches!(e.reason(), DropReason::Implausible | DropReason::Invalid),
            "{protocol} {field}: {e}"
        );
        if let DecodeError::Invalid { error, .. } = &e {
            assert_eq!(error.field(), field, "{protocol}: {e}");
        } else {
            panic!("{protocol} {field}: not a pose error: {e}");
        }
        assert!(e.to_string().contains(field), "{e}");
    }
}

#[test]
fn outliers_are_counted_as_implausible() {
    let (mut ingest, mut reader) = input_channel(InputParams::default());
    let outliers = all_outliers();
    let mut implausible = 0;
    for (protocol, field, bytes) in &outliers {
        let out = ingest.datagram(bytes, 1.0);
        match out.verdict {
            Verdict::Dropped(DropReason::Implausible) => implausible += 1,
            // An f32 field at f32::MAX times a unit conversion overflows to inf: not finite.
            Verdict::Dropped(DropReason::Invalid) => {}
            v => panic!("{protocol} {field}: {v:?}"),
        }
    }
    assert!(reader.latest().is_none(), "an outlier was published");
    let s = reader.stats();
    assert_eq!(s.dropped(DropReason::Implausible), implausible);
    assert_eq!(s.dropped_total(), outliers.len() as u64);
    // The ±1.797e308 native positions, headings, velocities and rates are all outliers.
    assert!(implausible >= native_outliers().len() as u64, "{s:?}");
}

#[test]
fn the_input_applies_its_configured_world_bound() {
    let far = native::encode(&local(5.0e7), 1);
    // Within what any configuration may allow: the codec passes it.
    native::decode(&far).unwrap();
    let (mut ingest, reader) = input_channel(InputParams::default());
    assert_eq!(
        ingest.datagram(&far, 1.0).verdict,
        Verdict::Dropped(DropReason::Implausible)
    );
    assert_eq!(
        ingest.pose(local(-5.0e7), 1.0),
        Verdict::Dropped(DropReason::Implausible)
    );
    assert_eq!(reader.stats().dropped(DropReason::Implausible), 2);
    let (mut wide, _r) = input_channel(InputParams {
        limits: PoseLimits::with_world_bound(1.0e8).unwrap(),
        ..InputParams::default()
    });
    assert_eq!(
        wide.datagram(&far, 1.0).verdict,
        Verdict::Accepted(Some(SeqVerdict::First))
    );
}
