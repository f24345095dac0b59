//! `aerie-send --hot / --los / --los-vector` end to end: the binary sends a native query to a
//! fake IG (a socket that answers with `encode_reply`), prints the answer in one line or as
//! JSON, and exits 1 naming why when there is no answer, no terrain, or a pending one.

use std::net::{SocketAddr, UdpSocket};
use std::process::{Command, Output};
use std::thread;
use std::time::Duration;

use aerie_sim_bridge::codec::native::{decode_query, encode_reply};
use aerie_sim_bridge::query::{Answer, LosHit, Surface, TerrainReply, TerrainRequest};
use aerie_sim_bridge::PosePosition;

fn send(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_aerie-send"))
        .args(args)
        .output()
        .expect("run aerie-send")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fake IG answering one query with `answer(request)`; returns its address and the request
/// it received.
fn fake_ig(
    answer: impl Fn(&TerrainRequest) -> TerrainReply + Send + 'static,
) -> (SocketAddr, thread::JoinHandle<TerrainRequest>) {
    let s = UdpSocket::bind("127.0.0.1:0").unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let addr = s.local_addr().unwrap();
    let h = thread::spawn(move || {
        let mut buf = [0u8; 512];
        let (n, from) = s.recv_from(&mut buf).expect("a query arrives");
        let (id, q) = decode_query(&buf[..n]).expect("a valid query");
        s.send_to(&encode_reply(id, &answer(&q)), from).unwrap();
        q
    });
    (addr, h)
}

#[test]
fn hot_prints_height_hat_and_normal() {
    let (ig, h) = fake_ig(|q| {
        let TerrainRequest::HeightOfTerrain { at } = q else {
            panic!("{q:?}")
        };
        let PosePosition::Geodetic { lat_deg, .. } = at else {
            panic!("{at:?}")
        };
        // The height depends on the request, so the line proves the point travelled.
        TerrainReply::HeightOfTerrain(Answer::Ready(Surface {
            height_m: lat_deg * 10.0,
            normal_enu: [0.0, 0.6, 0.8],
        }))
    });
    let o = send(&["--hot", "47.5,11.25,1000", "--to", &ig.to_string()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert_eq!(out.lines().count(), 1, "{out}");
    assert!(
        out.starts_with("HOT 475.000 m, HAT 525.000 m (altitude 1000.000 m), normal (e, n, u) 0.00000 0.60000 0.80000"),
        "{out}"
    );
    assert_eq!(
        h.join().unwrap(),
        TerrainRequest::HeightOfTerrain {
            at: PosePosition::Geodetic {
                lat_deg: 47.5,
                lon_deg: 11.25,
                alt_m: 1000.0
            }
        }
    );
}

#[test]
fn los_vector_prints_the_hit_as_json() {
    let (ig, h) = fake_ig(|q| {
        let TerrainRequest::LineOfSightVector {
            from, max_range_m, ..
        } = *q
        else {
            panic!("{q:?}")
        };
        TerrainReply::LineOfSight(Answer::Ready(Some(LosHit {
            range_m: max_range_m / 2.0,
            point: from,
            normal_enu: [0.0, 0.0, 1.0],
        })))
    });
    let o = send(&[
        "--los-vector",
        "100,200,3000,45,-10,0,8000",
        "--local",
        "--json",
        "-",
        "--to",
        &ig.to_string(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.trim_end().starts_with("{\"kind\":\"los\""), "{out}");
    assert!(out.contains("\"status\":\"ready\""), "{out}");
    assert!(
        out.contains("\"hit\":true,\"range_m\":4000,\"point\":{\"x\":100,\"y\":200,\"z\":3000}"),
        "{out}"
    );
    assert!(matches!(
        h.join().unwrap(),
        TerrainRequest::LineOfSightVector {
            from: PosePosition::LocalEnu { .. },
            azimuth_deg,
            elevation_deg,
            ..
        } if (azimuth_deg, elevation_deg) == (45.0, -10.0)
    ));
}

#[test]
fn clear_line_and_json_file() {
    let (ig, h) = fake_ig(|_| TerrainReply::LineOfSight(Answer::Ready(None)));
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("answer.json");
    let o = send(&[
        "--los",
        "47,11,3000,47.01,11.01,2900",
        "--to",
        &ig.to_string(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).starts_with("LOS clear"), "{}", stdout(&o));
    let j = std::fs::read_to_string(&json).unwrap();
    assert!(
        j.contains("\"status\":\"ready\"") && j.contains("\"hit\":false"),
        "{j}"
    );
    assert!(matches!(
        h.join().unwrap(),
        TerrainRequest::LineOfSight { .. }
    ));
}

#[test]
fn no_terrain_and_pending_exit_1_naming_why() {
    for (answer, why) in [
        (Answer::NoTerrain, "no terrain there"),
        (Answer::Pending, "not resident in time"),
    ] {
        let (ig, h) = fake_ig(move |_| TerrainReply::HeightOfTerrain(answer));
        let o = send(&["--hot-local", "10,20", "--to", &ig.to_string()]);
        assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
        assert!(stderr(&o).contains(why), "{}", stderr(&o));
        assert!(matches!(
            h.join().unwrap(),
            TerrainRequest::HeightOfTerrain {
                at: PosePosition::LocalEnu { .. }
            }
        ));
    }
}

#[test]
fn silence_exits_1_after_the_timeout() {
    let silent = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = silent.local_addr().unwrap().to_string();
    let o = send(&[
        "--hot",
        "0,0",
        "--to",
        &to,
        "--timeout-ms",
        "300",
        "--json",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stdout(&o).contains("\"status\":\"timeout\""),
        "{}",
        stdout(&o)
    );
    assert!(stderr(&o).contains("no answer from"), "{}", stderr(&o));
    // It was resent with the same id (250 ms apart within 300 ms: two copies).
    silent
        .set_read_timeout(Some(Duration::from_secs(1)))
        .unwrap();
    let mut buf = [0u8; 128];
    let mut ids = Vec::new();
    while let Ok((n, _)) = silent.recv_from(&mut buf) {
        silent
            .set_read_timeout(Some(Duration::from_millis(50)))
            .unwrap();
        ids.push(decode_query(&buf[..n]).unwrap().0);
    }
    assert!(
        ids.len() >= 2 && ids.iter().all(|&i| i == ids[0]),
        "{ids:?}"
    );
}

#[test]
fn bad_query_arguments_exit_2() {
    for (args, want) in [
        (vec!["--hot", "95,0"], "`at.lat_deg`"),
        (
            vec!["--hot", "1,2", "--los", "1,2,3,4,5,6"],
            "one query per call",
        ),
        (vec!["--hot", "1,2", "--protocol", "cigi"], "native"),
        (
            vec!["--hot", "1,2", "--path", "x.csv"],
            "--path with a terrain query",
        ),
        (vec!["--los", "1,2,3"], "lat,lon,alt,lat,lon,alt"),
        (vec!["--hot", "1,2", "--timeout-ms", "0"], "--timeout-ms"),
    ] {
        let o = send(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
    }
}
