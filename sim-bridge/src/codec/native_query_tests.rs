use super::*;
use crate::stats::DropReason;

fn geo(lat_deg: f64, lon_deg: f64, alt_m: f64) -> PosePosition {
    PosePosition::Geodetic {
        lat_deg,
        lon_deg,
        alt_m,
    }
}

#[test]
fn queries_round_trip() {
    for q in [
        TerrainRequest::HeightOfTerrain {
            at: geo(47.25, 11.35, 2000.0),
        },
        TerrainRequest::LineOfSight {
            from: geo(47.25, 11.35, 2000.0),
            to: PosePosition::LocalEnu {
                x: 1.0,
                y: -2.0,
                z: 3.0,
            },
        },
        TerrainRequest::LineOfSightVector {
            from: geo(47.25, 11.35, 2000.0),
            azimuth_deg: 45.0,
            elevation_deg: -5.0,
            min_range_m: 10.0,
            max_range_m: 10_000.0,
        },
    ] {
        let b = encode_query(0xDEAD_BEEF, &q);
        assert_eq!(b.len(), QUERY_SIZE);
        assert!(is_query(&b));
        assert_eq!(decode_query(&b), Ok((0xDEAD_BEEF, q)));
    }
}

#[test]
fn wrong_magic_is_unknown() {
    let b = encode_query(
        1,
        &TerrainRequest::HeightOfTerrain {
            at: geo(0.0, 0.0, 0.0),
        },
    );
    assert_eq!(decode_reply(&b).unwrap_err().reason(), DropReason::Unknown);
}
