//! Round trips of every packet in every version and both byte orders, over random values:
//! what a version carries comes back unchanged, what it lacks comes back as its default.

use proptest::prelude::*;

use super::super::*;
use super::any::Any;
use crate::codec::wire::ByteOrder;

fn f32s() -> impl Strategy<Value = f32> {
    -1.0e6f32..1.0e6
}
fn f64s() -> impl Strategy<Value = f64> {
    -1.0e9f64..1.0e9
}
fn cs() -> impl Strategy<Value = CoordinateSystem> {
    prop_oneof![
        Just(CoordinateSystem::Geodetic),
        Just(CoordinateSystem::Entity)
    ]
}
fn los_type() -> impl Strategy<Value = LosRequestType> {
    prop_oneof![Just(LosRequestType::Basic), Just(LosRequestType::Extended)]
}
fn version() -> impl Strategy<Value = CigiVersion> {
    prop::sample::select(CigiVersion::ALL.to_vec())
}
fn order() -> impl Strategy<Value = ByteOrder> {
    prop_oneof![Just(ByteOrder::Little), Just(ByteOrder::Big)]
}

fn ig_control() -> impl Strategy<Value = Any> {
    (any::<(i8, u8, bool, bool, u32, u32, u32)>()).prop_map(|(db, m, t, s, f, ts, l)| {
        Any::Ig(IgControl {
            database: db,
            ig_mode: m & 3,
            timestamp_valid: t,
            smoothing: s,
            minor_version: 3,
            host_frame: f,
            timestamp: ts,
            last_ig_frame: l,
        })
    })
}

fn start_of_frame() -> impl Strategy<Value = Any> {
    (any::<(i8, u8, u8, bool, bool, u32, u32, u32)>()).prop_map(|(db, st, m, t, e, f, ts, l)| {
        Any::Sof(StartOfFrame {
            database: db,
            ig_status: st,
            ig_mode: m & 3,
            timestamp_valid: t,
            earth_reference_model: u8::from(e),
            ig_frame: f,
            timestamp: ts,
            last_host_frame: l,
        })
    })
}

fn entity() -> impl Strategy<Value = Any> {
    (
        any::<(u16, u8, u8, u8, u16, u16)>(),
        any::<[bool; 7]>(),
        (f32s(), f32s(), f32s()),
        (f64s(), f64s(), f64s()),
    )
        .prop_map(|((id, st, gc, an, ty, par), b, (r, p, y), (la, lo, al))| {
            Any::Entity(EntityControl {
                entity_id: id,
                entity_state: st & 3,
                attached: b[0],
                collision_detection: b[1],
                inherit_alpha: b[2],
                ground_clamp: gc & 3,
                animation_backward: b[3],
                animation_loop: b[4],
                animation_state: an & 3,
                smoothing: b[5],
                alpha: if b[6] { 255 } else { st },
                entity_type: ty,
                parent_id: par,
                roll_deg: r,
                pitch_deg: p,
                yaw_deg: y,
                lat_deg: la,
                lon_deg: lo,
                alt_m: al,
            })
        })
}

fn environment() -> impl Strategy<Value = Any> {
    prop_oneof![
        (any::<u16>(), f32s(), f64s(), f64s()).prop_map(|(id, y, la, lo)| Any::Clamp(
            ConformalClampedEntityControl {
                entity_id: id,
                yaw_deg: y,
                lat_deg: la,
                lon_deg: lo,
            }
        )),
        (
            any::<(u16, u8, bool, bool)>(),
            [f32s(), f32s(), f32s()],
            [f32s(), f32s(), f32s()]
        )
            .prop_map(
                |((id, part, apply, local), lin, ang)| Any::Rate(RateControl {
                    entity_id: id,
                    articulated_part_id: part,
                    apply_to_articulated_part: apply,
                    frame: if local {
                        RateFrame::Local
                    } else {
                        RateFrame::WorldOrParent
                    },
                    linear_m_s: lin,
                    angular_deg_s: ang,
                })
            ),
        (
            any::<(u8, u8, [bool; 5])>(),
            0u8..=42,
            0u8..100,
            0u16..10_000,
            f32s()
        )
            .prop_map(
                |((h, m, b), mo, d, y, s)| Any::Celestial(CelestialSphereControl {
                    hour: h,
                    minute: m,
                    ephemeris_enabled: b[0],
                    sun_enabled: b[1],
                    moon_enabled: b[2],
                    star_field_enabled: b[3],
                    date_valid: b[4],
                    month: mo,
                    day: d,
                    year: y,
                    star_field_intensity_pct: s,
                })
            ),
        (
            any::<(bool, u8)>(),
            [f32s(), f32s(), f32s(), f32s(), f32s(), f32s()]
        )
            .prop_map(|((e, h), f)| Any::Atmosphere(AtmosphereControl {
                atmospheric_model_enabled: e,
                humidity_pct: h,
                air_temperature_c: f[0],
                visibility_m: f[1],
                horizontal_wind_m_s: f[2],
                vertical_wind_m_s: f[3],
                wind_direction_deg: f[4],
                barometric_pressure_mbar: f[5],
            })),
    ]
}

fn request() -> impl Strategy<Value = Any> {
    let ty = prop_oneof![
        Just(HatHotRequestType::Hat),
        Just(HatHotRequestType::Hot),
        Just(HatHotRequestType::Extended)
    ];
    prop_oneof![
        (any::<(u16, u8, u16)>(), ty, cs(), [f64s(), f64s(), f64s()]).prop_map(
            |((id, up, e), t, c, p)| Any::HatHotReq(HatHotRequest {
                request_id: id,
                request_type: t,
                coordinate_system: c,
                update_period: up,
                entity_id: e,
                point: p,
            })
        ),
        (
            any::<(u16, bool, u8, u16, u32, u8, u16)>(),
            los_type(),
            (cs(), cs(), cs()),
            [f64s(), f64s(), f64s()],
            [f64s(), f64s(), f64s()],
        )
            .prop_map(|((id, dv, a, e, mask, up, de), t, (s, d, r), src, dst)| {
                Any::LosSegReq(LosSegmentRequest {
                    request_id: id,
                    request_type: t,
                    source_coordinate_system: s,
                    destination_coordinate_system: d,
                    response_coordinate_system: r,
                    destination_entity_id_valid: dv,
                    alpha_threshold: a,
                    entity_id: e,
                    source: src,
                    destination: dst,
                    material_mask: mask,
                    update_period: up,
                    destination_entity_id: de,
                })
            }),
        (
            any::<(u16, u8, u16, u32, u8)>(),
            los_type(),
            (cs(), cs()),
            [f32s(), f32s(), f32s(), f32s()],
            [f64s(), f64s(), f64s()],
        )
            .prop_map(|((id, a, e, mask, up), t, (s, r), f, src)| {
                Any::LosVecReq(LosVectorRequest {
                    request_id: id,
                    request_type: t,
                    source_coordinate_system: s,
                    response_coordinate_system: r,
                    alpha_threshold: a,
                    entity_id: e,
                    azimuth_deg: f[0],
                    elevation_deg: f[1],
                    min_range_m: f[2],
                    max_range_m: f[3],
                    source: src,
                    material_mask: mask,
                    update_period: up,
                })
            }),
    ]
}

fn response() -> impl Strategy<Value = Any> {
    prop_oneof![
        (any::<(u16, bool, bool, u8)>(), f64s()).prop_map(|((id, v, hot, lsn), h)| {
            Any::Resp(CigiResponse::HatHot(HatHotResponse {
                request_id: id,
                valid: v,
                response_type: if hot {
                    HatHotResponseType::Hot
                } else {
                    HatHotResponseType::Hat
                },
                host_frame_lsn: lsn,
                height_m: h,
            }))
        }),
        (
            any::<(u16, bool, u8, u32)>(),
            f64s(),
            f64s(),
            f32s(),
            f32s()
        )
            .prop_map(|((id, v, lsn, mat), hat, hot, az, el)| {
                Any::Resp(CigiResponse::HatHotExtended(HatHotExtendedResponse {
                    request_id: id,
                    valid: v,
                    host_frame_lsn: lsn,
                    hat_m: hat,
                    hot_m: hot,
                    material_code: mat,
                    normal_azimuth_deg: az,
                    normal_elevation_deg: el,
                }))
            }),
        (any::<(u16, [bool; 3], u8, u8, u16)>(), f64s()).prop_map(|((id, b, lsn, n, e), r)| {
            Any::Resp(CigiResponse::Los(LosResponse {
                request_id: id,
                valid: b[0],
                entity_id_valid: b[1],
                visible: b[2],
                host_frame_lsn: lsn,
                response_count: n,
                entity_id: e,
                range_m: r,
            }))
        }),
        (
            any::<(u16, [bool; 4], u8, u8, u16, [u8; 4], u32)>(),
            cs(),
            (f64s(), [f64s(), f64s(), f64s()], f32s(), f32s()),
        )
            .prop_map(|((id, b, lsn, n, e, rgba, mat), c, (r, p, az, el))| {
                Any::Resp(CigiResponse::LosExtended(LosExtendedResponse {
                    request_id: id,
                    valid: b[0],
                    entity_id_valid: b[1],
                    range_valid: b[2],
                    visible: b[3],
                    point_coordinate_system: c,
                    host_frame_lsn: lsn,
                    response_count: n,
                    entity_id: e,
                    range_m: r,
                    point: p,
                    rgba,
                    material_code: mat,
                    normal_azimuth_deg: az,
                    normal_elevation_deg: el,
                }))
            }),
    ]
}

fn any_packet() -> impl Strategy<Value = Any> {
    prop_oneof![
        ig_control(),
        start_of_frame(),
        entity(),
        environment(),
        request(),
        response()
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// Every packet survives encode → decode in every version and byte order, except the
    /// fields its version does not carry; its size is the version's, and the big-endian and
    /// little-endian encodings are each other's mirror field by field (same size, same ID).
    #[test]
    fn every_packet_round_trips(p in any_packet(), v in version(), o in order()) {
        let bytes = p.encode(v, o);
        prop_assert_eq!(usize::from(bytes[1]), bytes.len());
        let back = p.decode_like(&bytes, v, o).unwrap();
        prop_assert_eq!(back, p.as_in(v));
        if let Any::Sof(_) = p {
            // 3.1 encodes as 3.0 and reads back as 3.0.
            let want = if v == CigiVersion::V3_1 { CigiVersion::V3_0 } else { v };
            let (_, got_v, got_o) = StartOfFrame::decode_with_version(&bytes).unwrap();
            prop_assert_eq!((got_v, got_o), (want, o));
        }
        let other = if o == ByteOrder::Big { ByteOrder::Little } else { ByteOrder::Big };
        let mirrored = p.encode(v, other);
        prop_assert_eq!(mirrored.len(), bytes.len());
        prop_assert_eq!(&mirrored[..2], &bytes[..2]);
        // Decoding in the wrong byte order never panics (it may well decode to garbage).
        let _ = p.decode_like(&bytes, v, other);
    }

    /// A host message of random packets in any version and order decodes in that version and
    /// order, counting each packet once by ID.
    #[test]
    fn host_messages_round_trip(
        ig in ig_control(),
        body in prop::collection::vec(prop_oneof![entity(), environment(), request()], 0..8),
        v in version(),
        o in order(),
    ) {
        let mut bytes = ig.encode(v, o);
        for p in &body {
            bytes.extend(p.encode(v, o));
        }
        let m = decode(&bytes);
        // An ownship (entity 0) with out-of-range values drops the whole message by design.
        let ownship_bad = body.iter().any(|p| matches!(p, Any::Entity(e) if e.entity_id == 0));
        prop_assume!(!ownship_bad);
        let m = m.unwrap();
        let want_v = if v == CigiVersion::V3_1 { CigiVersion::V3_0 } else { v };
        prop_assert_eq!((m.version, m.byte_order), (want_v, o));
        prop_assert_eq!(m.packet_counts.total(), body.len() as u64 + 1);
        let filed = m.entities.len() + m.conformal_clamped.len() + m.rate_controls.len()
            + m.requests.len() + usize::from(m.celestial.is_some())
            + usize::from(m.atmosphere.is_some());
        // Kept or rejected: nothing is lost (celestial/atmosphere keep only the last one).
        let env_repeats = body.iter().filter(|p| matches!(p, Any::Celestial(_))).count().saturating_sub(1)
            + body.iter().filter(|p| matches!(p, Any::Atmosphere(_))).count().saturating_sub(1);
        prop_assert!(filed + m.rejected.len() + env_repeats >= body.len());
        prop_assert_eq!(m.skipped, 0);
        for r in &m.rejected {
            prop_assert!(r.offset >= usize::from(v.ig_control_size()) && r.offset < bytes.len());
            prop_assert!(!r.error.to_string().is_empty());
        }
        for r in &m.requests {
            match r {
                CigiRequest::HatHot(x) => prop_assert!(x.check().is_ok()),
                CigiRequest::LosSegment(x) => prop_assert!(x.check().is_ok()),
                CigiRequest::LosVector(x) => prop_assert!(x.check().is_ok()),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// Valid messages of every version, then cut, extended, or with bytes overwritten: the
    /// fuzz body's invariants hold (no panic, kept packets valid, answer in the host's version
    /// and order), and so does the IG-side decoder.
    #[test]
    fn mutated_messages_keep_the_fuzz_invariants(
        ig in ig_control(),
        body in prop::collection::vec(prop_oneof![entity(), environment(), request()], 0..6),
        v in version(),
        o in order(),
        cut in any::<prop::sample::Index>(),
        tail in prop::collection::vec(any::<u8>(), 0..40),
        pokes in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..6),
    ) {
        let mut bytes = ig.encode(v, o);
        for p in &body {
            bytes.extend(p.encode(v, o));
        }
        crate::fuzzing::decode_cigi(&bytes);
        let mut poked = bytes.clone();
        for (i, b) in &pokes {
            let i = i.index(poked.len());
            poked[i] = *b;
        }
        crate::fuzzing::decode_cigi(&poked);
        let n = cut.index(bytes.len() + 1);
        crate::fuzzing::decode_cigi(&bytes[..n]);
        bytes.extend(&tail);
        crate::fuzzing::decode_cigi(&bytes);
    }
}
