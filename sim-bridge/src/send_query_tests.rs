use super::*;
use crate::codec::native::{decode_query, encode_reply};
use std::thread;

fn hot_reply(h: f64) -> TerrainReply {
    TerrainReply::HeightOfTerrain(Answer::Ready(Surface {
        height_m: h,
        normal_enu: [0.6, 0.0, 0.8],
    }))
}

#[test]
fn flags_parse_into_requests() {
    let p = parse_hot("--hot", "47.25, 11.35", false).unwrap();
    assert_eq!(p.altitude_m, None);
    assert_eq!(
        p.request,
        TerrainRequest::HeightOfTerrain {
            at: PosePosition::Geodetic {
                lat_deg: 47.25,
                lon_deg: 11.35,
                alt_m: 0.0
            }
        }
    );
    let p = parse_hot("--hot", "47.25,11.35,2500", false).unwrap();
    assert_eq!(p.altitude_m, Some(2500.0));
    let p = parse_hot("--hot-local", "100,-200,300", true).unwrap();
    assert!(matches!(
        p.request,
        TerrainRequest::HeightOfTerrain {
            at: PosePosition::LocalEnu { x, y, z }
        } if (x, y, z) == (100.0, -200.0, 300.0)
    ));
    let p = parse_los("--los", "47,11,3000,47.1,11.1,500", false).unwrap();
    assert!(matches!(
        p.request,
        TerrainRequest::LineOfSight {
            to: PosePosition::Geodetic { alt_m, .. },
            ..
        } if alt_m == 500.0
    ));
    let p = parse_los_vector("--los-vector", "47,11,3000,90,-10,0,20000", false).unwrap();
    assert_eq!(
        p.request,
        TerrainRequest::LineOfSightVector {
            from: PosePosition::Geodetic {
                lat_deg: 47.0,
                lon_deg: 11.0,
                alt_m: 3000.0
            },
            azimuth_deg: 90.0,
            elevation_deg: -10.0,
            min_range_m: 0.0,
            max_range_m: 20_000.0
        }
    );
}

#[test]
fn bad_flags_are_named() {
    for (r, want) in [
        (parse_hot("--hot", "47", false), "expected lat,lon[,alt]"),
        (parse_hot("--hot", "47,x", false), "--hot \"47,x\""),
        (parse_hot("--hot", "91,0", false), "`at.lat_deg`"),
        (
            parse_hot("--hot-local", "1,2,3,4", true),
            "expected x,y[,z]",
        ),
        (
            parse_los("--los", "1,2,3,4,5", false),
            "lat,lon,alt,lat,lon,alt",
        ),
        (parse_los("--los", "0,0,0,0,400,0", false), "`to.lon_deg`"),
        (
            parse_los_vector("--los-vector", "0,0,0,0,-95,0,10", false),
            "`elevation_deg`",
        ),
        (
            parse_los_vector("--los-vector", "0,0,0,0,0,10,5", false),
            "`max_range_m`",
        ),
        (
            parse_los_vector("--los-vector", "0,0,0,0,0,nan,5", false),
            "expected",
        ),
    ] {
        let e = r.unwrap_err();
        assert!(e.contains(want), "{want}: {e}");
    }
}

#[test]
fn lines_say_what_came_back() {
    let hot = parse_hot("--hot", "47.25,11.35,2500", false).unwrap();
    let l = answer_line(&hot, &hot_reply(1234.5));
    assert!(l.starts_with("HOT 1234.500 m, HAT 1265.500 m"), "{l}");
    assert!(
        l.contains("normal (e, n, u) 0.60000 0.00000 0.80000"),
        "{l}"
    );
    let no_alt = parse_hot("--hot", "47.25,11.35", false).unwrap();
    assert!(!answer_line(&no_alt, &hot_reply(10.0)).contains("HAT"));
    let l = answer_line(&hot, &TerrainReply::HeightOfTerrain(Answer::NoTerrain));
    assert!(l.contains("no terrain there"), "{l}");
    let los = parse_los("--los", "47,11,3000,47.1,11.1,500", false).unwrap();
    let hit = TerrainReply::LineOfSight(Answer::Ready(Some(LosHit {
        range_m: 4321.25,
        point: PosePosition::Geodetic {
            lat_deg: 47.05,
            lon_deg: 11.05,
            alt_m: 1800.0,
        },
        normal_enu: [0.0, 0.0, 1.0],
    })));
    let l = answer_line(&los, &hit);
    assert!(
        l.starts_with(
            "LOS hit at range 4321.250 m: lat 47.0500000° lon 11.0500000° alt 1800.000 m"
        ),
        "{l}"
    );
    let clear = TerrainReply::LineOfSight(Answer::Ready(None));
    assert!(answer_line(&los, &clear).contains("clear"));
    let l = answer_line(&los, &TerrainReply::LineOfSight(Answer::Pending));
    assert!(l.contains("not resident in time"), "{l}");
    assert_eq!(exit_status(Some(&hit)), 0);
    assert_eq!(exit_status(Some(&clear)), 0);
    assert_eq!(
        exit_status(Some(&TerrainReply::LineOfSight(Answer::Pending))),
        1
    );
    assert_eq!(
        exit_status(Some(&TerrainReply::HeightOfTerrain(Answer::NoTerrain))),
        1
    );
    assert_eq!(exit_status(None), 1);
    // JSON: the fields a script reads.
    let to: SocketAddr = "127.0.0.1:47800".parse().unwrap();
    let asked = |reply| Asked {
        reply,
        sends: 2,
        ignored: 0,
        waited: Duration::from_micros(1500),
    };
    let j = answer_json(&hot, 7, to, &asked(Some(hot_reply(1234.5))));
    assert_eq!(
        j,
        "{\"kind\":\"hot\",\"id\":7,\"to\":\"127.0.0.1:47800\",\"status\":\"ready\",\"sends\":2,\
         \"waited_ms\":1.500,\"height_m\":1234.5,\"hat_m\":1265.5,\"normal_enu\":[0.6,0,0.8]}"
    );
    let j = answer_json(&los, 7, to, &asked(Some(hit)));
    assert!(j.contains("\"hit\":true,\"range_m\":4321.25,\"point\":{\"lat_deg\":47.05,\"lon_deg\":11.05,\"alt_m\":1800}"), "{j}");
    assert!(answer_json(&los, 7, to, &asked(Some(clear))).ends_with("\"hit\":false}"));
    assert!(answer_json(&los, 7, to, &asked(None)).contains("\"status\":\"timeout\""));
    let j = answer_json(
        &hot,
        7,
        to,
        &asked(Some(TerrainReply::HeightOfTerrain(Answer::NoTerrain))),
    );
    assert!(
        j.contains("\"status\":\"no_terrain\"") && !j.contains("height_m"),
        "{j}"
    );
}

/// A fake IG: answers the `skip`-th and later queries it receives (after sending junk and a
/// wrong-id answer first), each with a height of 100 + the request's point's latitude.
fn fake_ig(skip: usize) -> (SocketAddr, thread::JoinHandle<usize>) {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let addr = s.local_addr().unwrap();
    let h = thread::spawn(move || {
        let mut buf = [0u8; 512];
        let mut seen = 0;
        while let Ok((n, from)) = s.recv_from(&mut buf) {
            let (id, q) = decode_query(&buf[..n]).unwrap();
            seen += 1;
            if seen <= skip {
                continue;
            }
            let TerrainRequest::HeightOfTerrain {
                at: PosePosition::Geodetic { lat_deg, .. },
            } = q
            else {
                panic!("{q:?}")
            };
            s.send_to(b"junk", from).unwrap();
            s.send_to(&encode_reply(id ^ 1, &hot_reply(-1.0)), from)
                .unwrap();
            s.send_to(&encode_reply(id, &hot_reply(100.0 + lat_deg)), from)
                .unwrap();
            break;
        }
        seen
    });
    (addr, h)
}

#[test]
fn ask_gets_the_answer_with_its_id() {
    let (ig, h) = fake_ig(0);
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let q = parse_hot("--hot", "12.5,3", false).unwrap().request;
    let a = ask(&s, ig, 0xABCD, &q, Duration::from_secs(5), RESEND_EVERY).unwrap();
    assert_eq!(a.reply, Some(hot_reply(112.5)));
    assert_eq!(a.ignored, 2, "the junk and the other id");
    assert_eq!(a.sends, 1);
    assert_eq!(h.join().unwrap(), 1);
}

#[test]
fn a_lost_query_is_sent_again() {
    // The IG "loses" the first two copies; the third is answered.
    let (ig, h) = fake_ig(2);
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let q = parse_hot("--hot", "-3,3", false).unwrap().request;
    let a = ask(
        &s,
        ig,
        9,
        &q,
        Duration::from_secs(5),
        Duration::from_millis(20),
    )
    .unwrap();
    assert_eq!(a.reply, Some(hot_reply(97.0)));
    assert!(a.sends >= 3, "{a:?}");
    assert_eq!(h.join().unwrap(), 3);
}

#[test]
fn silence_is_a_timeout_not_an_error() {
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    let q = parse_hot("--hot", "0,0", false).unwrap().request;
    let a = ask(
        &s,
        silent.local_addr().unwrap(),
        1,
        &q,
        Duration::from_millis(120),
        Duration::from_millis(50),
    )
    .unwrap();
    assert_eq!(a.reply, None);
    assert!(a.sends >= 2, "{a:?}");
    let mut buf = [0u8; 128];
    silent
        .set_read_timeout(Some(Duration::from_secs(1)))
        .unwrap();
    let (n, _) = silent.recv_from(&mut buf).unwrap();
    assert_eq!(
        decode_query(&buf[..n]),
        Ok((1, q)),
        "what was sent is the query"
    );
}
