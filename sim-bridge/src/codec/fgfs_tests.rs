use super::*;
use crate::stats::DropReason;

/// The first 88 bytes of a golden FGNetFDM v24, written by hand from net_fdm.hxx, all
/// big-endian: version 24, padding 0, longitude 0.25 rad (0x3FD0000000000000), latitude
/// 0.75 rad (0x3FE8000000000000), altitude 1000.0 m (0x408F400000000000), agl 300.0
/// (0x43960000), phi 0.125 (0x3E000000), theta −0.0625 (0xBD800000), psi 1.5 (0x3FC00000),
/// alpha 0, beta 0, phidot 0.5 (0x3F000000), thetadot 0, psidot −0.25 (0xBE800000), vcas
/// 250.0 (0x437A0000), climb 10.0 (0x41200000), v_north 100.0 (0x42C80000), v_east −50.0
/// (0xC2480000), v_down −10.0 (0xC1200000).
const HEAD: [u8; 88] = [
    0x00, 0x00, 0x00, 0x18, // 0: version 24
    0x00, 0x00, 0x00, 0x00, // 4: padding
    0x3F, 0xD0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 8: longitude
    0x3F, 0xE8, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 16: latitude
    0x40, 0x8F, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00, // 24: altitude
    0x43, 0x96, 0x00, 0x00, // 32: agl
    0x3E, 0x00, 0x00, 0x00, // 36: phi
    0xBD, 0x80, 0x00, 0x00, // 40: theta
    0x3F, 0xC0, 0x00, 0x00, // 44: psi
    0x00, 0x00, 0x00, 0x00, // 48: alpha
    0x00, 0x00, 0x00, 0x00, // 52: beta
    0x3F, 0x00, 0x00, 0x00, // 56: phidot
    0x00, 0x00, 0x00, 0x00, // 60: thetadot
    0xBE, 0x80, 0x00, 0x00, // 64: psidot
    0x43, 0x7A, 0x00, 0x00, // 68: vcas
    0x41, 0x20, 0x00, 0x00, // 72: climb rate
    0x42, 0xC8, 0x00, 0x00, // 76: v_north
    0xC2, 0x48, 0x00, 0x00, // 80: v_east
    0xC1, 0x20, 0x00, 0x00, // 84: v_down
];

/// A field's C type in `net_fdm.hxx`.
#[derive(Clone, Copy, Debug)]
enum Ty {
    U32,
    I32,
    F32,
    F64,
}

impl Ty {
    /// Size and alignment (the same for these types on every platform FlightGear builds on).
    fn size(self) -> usize {
        match self {
            Ty::F64 => 8,
            _ => 4,
        }
    }
}

/// `(name, type, count)`, in declaration order.
type Field = (&'static str, Ty, usize);

/// The members of `class FGNetFDM` up to and including `fuel_quantity[FG_MAX_TANKS]`, the same
/// in versions 24 and 25 (FG_MAX_ENGINES = 4, FG_MAX_TANKS = 4), copied from `net_fdm.hxx`.
const COMMON: &[Field] = &[
    ("version", Ty::U32, 1),
    ("padding", Ty::U32, 1),
    ("longitude", Ty::F64, 1),
    ("latitude", Ty::F64, 1),
    ("altitude", Ty::F64, 1),
    ("agl", Ty::F32, 1),
    ("phi", Ty::F32, 1),
    ("theta", Ty::F32, 1),
    ("psi", Ty::F32, 1),
    ("alpha", Ty::F32, 1),
    ("beta", Ty::F32, 1),
    ("phidot", Ty::F32, 1),
    ("thetadot", Ty::F32, 1),
    ("psidot", Ty::F32, 1),
    ("vcas", Ty::F32, 1),
    ("climb_rate", Ty::F32, 1),
    ("v_north", Ty::F32, 1),
    ("v_east", Ty::F32, 1),
    ("v_down", Ty::F32, 1),
    // v24: v_wind_body_north/east/down; v25: v_body_u/v/w.
    ("v_body_u", Ty::F32, 1),
    ("v_body_v", Ty::F32, 1),
    ("v_body_w", Ty::F32, 1),
    ("A_X_pilot", Ty::F32, 1),
    ("A_Y_pilot", Ty::F32, 1),
    ("A_Z_pilot", Ty::F32, 1),
    ("stall_warning", Ty::F32, 1),
    ("slip_deg", Ty::F32, 1),
    ("num_engines", Ty::U32, 1),
    ("eng_state", Ty::U32, 4),
    ("rpm", Ty::F32, 4),
    ("fuel_flow", Ty::F32, 4),
    ("fuel_px", Ty::F32, 4),
    ("egt", Ty::F32, 4),
    ("cht", Ty::F32, 4),
    ("mp_osi", Ty::F32, 4),
    ("tit", Ty::F32, 4),
    ("oil_temp", Ty::F32, 4),
    ("oil_px", Ty::F32, 4),
    ("num_tanks", Ty::U32, 1),
    ("fuel_quantity", Ty::F32, 4),
];

/// Version 25's additions after `fuel_quantity`.
const V25_TANKS: &[Field] = &[
    ("tank_selected", Ty::U32, 4),
    ("capacity_m3", Ty::F64, 4),
    ("unusable_m3", Ty::F64, 4),
    ("density_kgpm3", Ty::F64, 4),
    ("level_m3", Ty::F64, 4),
];

/// The members after the tanks, both versions (FG_MAX_WHEELS = 3).
const TAIL: &[Field] = &[
    ("num_wheels", Ty::U32, 1),
    ("wow", Ty::U32, 3),
    ("gear_pos", Ty::F32, 3),
    ("gear_steer", Ty::F32, 3),
    ("gear_compression", Ty::F32, 3),
    ("cur_time", Ty::U32, 1),
    ("warp", Ty::I32, 1),
    ("visibility", Ty::F32, 1),
    ("elevator", Ty::F32, 1),
    ("elevator_trim_tab", Ty::F32, 1),
    ("left_flap", Ty::F32, 1),
    ("right_flap", Ty::F32, 1),
    ("left_aileron", Ty::F32, 1),
    ("right_aileron", Ty::F32, 1),
    ("rudder", Ty::F32, 1),
    ("nose_wheel", Ty::F32, 1),
    ("speedbrake", Ty::F32, 1),
    ("spoilers", Ty::F32, 1),
];

fn fields(version: u32) -> Vec<Field> {
    let mut f = COMMON.to_vec();
    if version == VERSION_25 {
        f.extend_from_slice(V25_TANKS);
    }
    f.extend_from_slice(TAIL);
    f
}

/// The C layout of a field list: each member at the next multiple of its alignment, the
/// struct's size a multiple of its largest alignment. `(name, type, count, offset)`, size.
fn c_layout(fields: &[Field]) -> (Vec<(&'static str, Ty, usize, usize)>, usize) {
    let mut off = 0usize;
    let mut out = Vec::new();
    for &(name, ty, count) in fields {
        off = off.next_multiple_of(ty.size());
        out.push((name, ty, count, off));
        off += ty.size() * count;
    }
    let align = fields.iter().map(|f| f.1.size()).max().unwrap_or(1);
    (out, off.next_multiple_of(align))
}

fn offset_of(version: u32, name: &str) -> usize {
    let (layout, _) = c_layout(&fields(version));
    layout.iter().find(|f| f.0 == name).expect(name).3
}

/// The value the golden packets carry in every field: the head as in [`HEAD`], every other
/// member a distinct non-zero number (so that a decoder reading the wrong offset would see it).
fn golden_value(name: &str, index: usize, k: usize) -> f64 {
    match name {
        "longitude" => 0.25,
        "latitude" => 0.75,
        "altitude" => 1000.0,
        "agl" => 300.0,
        "phi" => 0.125,
        "theta" => -0.0625,
        "psi" => 1.5,
        "alpha" | "beta" | "thetadot" | "padding" => 0.0,
        "phidot" => 0.5,
        "psidot" => -0.25,
        "vcas" => 250.0,
        "climb_rate" => 10.0,
        "v_north" => 100.0,
        "v_east" => -50.0,
        "v_down" => -10.0,
        _ => 1000.0 + (k * 10 + index) as f64,
    }
}

/// A whole `FGNetFDM` of `version`, written member by member at the offsets the header's
/// field list gives (big-endian, as `htonl`/`htonf`/`htond` leave them).
fn golden_struct(version: u32) -> Vec<u8> {
    let (layout, size) = c_layout(&fields(version));
    let mut b = vec![0u8; size];
    for (k, &(name, ty, count, off)) in layout.iter().enumerate() {
        for i in 0..count {
            let at = off + i * ty.size();
            let v = golden_value(name, i, k);
            let bytes: Vec<u8> = match (name, ty) {
                ("version", _) => version.to_be_bytes().to_vec(),
                (_, Ty::U32) => (v as u32).to_be_bytes().to_vec(),
                (_, Ty::I32) => (-(v as i32)).to_be_bytes().to_vec(),
                (_, Ty::F32) => (v as f32).to_be_bytes().to_vec(),
                (_, Ty::F64) => v.to_be_bytes().to_vec(),
            };
            b[at..at + bytes.len()].copy_from_slice(&bytes);
        }
    }
    b
}

fn golden() -> Vec<u8> {
    let mut b = HEAD.to_vec();
    b.resize(SIZE, 0);
    b
}

fn head_pose() -> FdmPose {
    FdmPose {
        longitude: 0.25,
        latitude: 0.75,
        altitude: 1000.0,
        agl: 300.0,
        phi: 0.125,
        theta: -0.0625,
        psi: 1.5,
        phidot: 0.5,
        psidot: -0.25,
        vcas: 250.0,
        climb_rate: 10.0,
        v_north: 100.0,
        v_east: -50.0,
        v_down: -10.0,
        ..FdmPose::default()
    }
}

#[test]
fn struct_sizes_follow_the_header() {
    for (version, size) in VERSIONS {
        let (layout, computed) = c_layout(&fields(version));
        assert_eq!(computed, size, "version {version}");
        assert_eq!(size_of_version(version), Some(size));
        // The head aerie reads sits at the same offsets in both versions.
        for (name, off) in [
            ("longitude", 8),
            ("psi", 44),
            ("v_down", 84),
            ("v_body_u", 88),
        ] {
            assert_eq!(offset_of(version, name), off, "v{version} {name}");
        }
        assert_eq!(layout.last().unwrap().0, "spoilers");
    }
    // Version 25: tank_selected after fuel_quantity; the doubles fall on a multiple of 8 (no
    // padding anywhere in either version).
    assert_eq!(offset_of(VERSION_25, "fuel_quantity"), 288);
    assert_eq!(offset_of(VERSION_25, "tank_selected"), 304);
    assert_eq!(offset_of(VERSION_25, "capacity_m3"), 320);
    assert_eq!(offset_of(VERSION_25, "level_m3"), 416);
    assert_eq!(offset_of(VERSION_25, "num_wheels"), 448);
    assert_eq!(offset_of(VERSION_25, "spoilers"), 548);
    assert_eq!(offset_of(VERSION, "num_wheels"), 304);
    assert_eq!(offset_of(VERSION, "spoilers"), 404);
    assert_eq!(size_of_version(23), None);
}

#[test]
fn golden_structs_decode_per_version() {
    for (version, size) in VERSIONS {
        let b = golden_struct(version);
        assert_eq!(b.len(), size);
        // The hand-written head and the one built from the field list agree byte for byte.
        assert_eq!(&b[4..HEAD_SIZE], &HEAD[4..], "v{version}");
        assert_eq!(&b[..4], &version.to_be_bytes());
        assert!(looks_like(&b), "v{version}");
        assert_eq!(decode_fields(&b).unwrap(), head_pose(), "v{version}");
        let p = decode(&b).unwrap();
        assert_eq!(p.velocity_enu, Some([-15.24, 30.48, 3.048]));
    }
    // The tail is really there: v25's capacity_m3[0] and visibility as built.
    let b = golden_struct(VERSION_25);
    let cap = offset_of(VERSION_25, "capacity_m3");
    assert_ne!(&b[cap..cap + 8], &[0u8; 8]);
    let vis = offset_of(VERSION_25, "visibility");
    assert_ne!(&b[vis..vis + 4], &[0u8; 4]);
}

#[test]
fn round_trip_per_version() {
    let f = head_pose();
    let v24 = encode(&f);
    let v25 = encode_v25(&f);
    assert_eq!(v24.len(), SIZE);
    assert_eq!(v25.len(), SIZE_25);
    assert_eq!(&v24[..4], &24u32.to_be_bytes());
    assert_eq!(&v25[..4], &25u32.to_be_bytes());
    assert_eq!(&v24[4..HEAD_SIZE], &v25[4..HEAD_SIZE]);
    assert_eq!(decode_fields(&v24).unwrap(), f);
    assert_eq!(decode_fields(&v25).unwrap(), f);
    assert_eq!(decode(&v24).unwrap(), decode(&v25).unwrap());
}

#[test]
fn golden_bytes() {
    let f = FdmPose {
        longitude: 0.25,
        latitude: 0.75,
        altitude: 1000.0,
        agl: 300.0,
        phi: 0.125,
        theta: -0.0625,
        psi: 1.5,
        phidot: 0.5,
        psidot: -0.25,
        vcas: 250.0,
        climb_rate: 10.0,
        v_north: 100.0,
        v_east: -50.0,
        v_down: -10.0,
        ..FdmPose::default()
    };
    assert_eq!(encode(&f).to_vec(), golden());
    assert_eq!(decode_fields(&golden()).unwrap(), f);
    let p = decode(&golden()).unwrap();
    let PosePosition::Geodetic {
        lat_deg,
        lon_deg,
        alt_m,
    } = p.position
    else {
        panic!("geodetic expected")
    };
    assert!((lat_deg - 42.971_834_634_8).abs() < 1e-9, "{lat_deg}");
    assert!((lon_deg - 14.323_944_878_3).abs() < 1e-9, "{lon_deg}");
    assert_eq!(alt_m, 1000.0);
    let want_att = [85.943_669_269_9, -3.580_986_219_6, 7.161_972_439_1];
    for (got, want) in p.attitude_deg.iter().zip(want_att) {
        assert!((got - want).abs() < 1e-9, "{:?}", p.attitude_deg);
    }
    // Heading, pitch, roll rates from psidot, thetadot, phidot.
    let rates = p.angular_rates_deg_s.unwrap();
    assert!((rates[0] + 14.323_944_878_3).abs() < 1e-9);
    assert_eq!(rates[1], 0.0);
    assert!((rates[2] - 28.647_889_756_5).abs() < 1e-9);
    // ft/s → m/s, down → up.
    assert_eq!(p.velocity_enu, Some([-15.24, 30.48, 3.048]));
}

#[test]
fn wrong_versions_and_sizes_are_named() {
    let r = |b: &[u8]| decode(b).unwrap_err().reason();
    for (found, expected) in [(23u32, 24u32), (26, 25), (0, 24), (u32::MAX, 25)] {
        for size in [SIZE, SIZE_25] {
            let mut b = golden_struct(VERSION);
            b.resize(size, 0);
            b[..4].copy_from_slice(&found.to_be_bytes());
            assert!(looks_like(&b), "detected by its size");
            let e = decode(&b).unwrap_err();
            assert_eq!(
                e,
                DecodeError::BadVersion {
                    protocol: Protocol::Fgfs,
                    found,
                    expected
                }
            );
            assert!(e.to_string().contains(&format!("version {found}")), "{e}");
        }
    }
    // A version's header with the other version's size.
    let mut b = golden_struct(VERSION_25);
    b.truncate(SIZE);
    assert_eq!(
        decode(&b).unwrap_err(),
        DecodeError::BadSize {
            protocol: Protocol::Fgfs,
            len: SIZE,
            expected: SIZE_25
        }
    );
    let mut b = golden_struct(VERSION);
    b.resize(SIZE_25, 0);
    assert_eq!(r(&b), DropReason::BadSize);
    let mut b = golden();
    b[24..32].copy_from_slice(&(-50_000.0f64).to_be_bytes());
    assert_eq!(r(&b), DropReason::Implausible);
    let mut b = encode_v25(&head_pose()).to_vec();
    b[44..48].copy_from_slice(&f32::NAN.to_be_bytes());
    assert_eq!(r(&b), DropReason::Invalid);
    assert!(!looks_like(b"hello"));
}

#[test]
fn truncated_and_extended_never_panic() {
    for version in [VERSION, VERSION_25] {
        let full = golden_struct(version);
        for len in 0..full.len() + 8 {
            let mut b = full.clone();
            b.resize(len, 0xA5);
            let got = decode(&b);
            if len == full.len() {
                assert!(got.is_ok(), "v{version} {len}");
            } else {
                assert_eq!(
                    got.unwrap_err().reason(),
                    DropReason::BadSize,
                    "v{version} {len}"
                );
            }
        }
    }
}

#[test]
fn pose_round_trip_within_f32() {
    let p = decode(&golden()).unwrap();
    for b in [
        encode(&FdmPose::from_pose(&p)).to_vec(),
        encode_v25(&FdmPose::from_pose(&p)).to_vec(),
    ] {
        let q = decode(&b).unwrap();
        assert_eq!(q.position, p.position);
        for i in 0..3 {
            assert!((q.attitude_deg[i] - p.attitude_deg[i]).abs() < 1e-4);
            assert!((q.velocity_enu.unwrap()[i] - p.velocity_enu.unwrap()[i]).abs() < 1e-4);
        }
    }
}
