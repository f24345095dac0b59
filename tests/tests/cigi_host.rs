//! A real CIGI host end to end (issue 12): the host program in `tests/cigi-host/`, written
//! with the CIGI Class Library's host API (`CigiHostSession`, `CigiOutgoingMsg`,
//! `CigiIncomingMsg` with event processors) and decoding aerie's answers with the CCL's own
//! packet classes, drives `aerie run --headless` on the embedded DEM. It checks:
//! - poses: every `--stats` row shows the camera at the pose the host sent (1 mm, 0.001°);
//! - HAT/HOT of every request type (HAT, HOT, extended; geodetic and ownship-relative;
//!   one-shot and periodic) against (a) `aerie_terrain::query` on the same dataset and (b) a
//!   bilinear read of the SRTM samples done here, within the quad's triangulation bound;
//! - line of sight (segments and vectors, basic and extended): hits where the oracle hits,
//!   misses where it is clear;
//! - IG modes: Reset → Standby → Operate in the Start of Frames, periodic requests dropped;
//! - a synchronous host: Start of Frames ≤ rendered frames, each answer in the next message;
//! - CIGI 3.0, 3.1, 3.2 and 3.3 hosts in both byte orders: little-endian natively, big-endian
//!   as a real s390x host under qemu-s390x (the CCL never byte-swaps what it sends).
//!
//! The CCL is built once per source hash into `target/cigi-ccl/` by `tests/cigi-host/build.sh`
//! (`make ccl`, which `make test` runs first; a plain `cargo test` builds it on demand).
//!
//! **Frames.** Geodetic points map to the dataset's local metres as `GeoMapping` does
//! (`x = Δlon/dlon · spacing_x`, `y = Δlat/dlat · spacing_y`, `z = alt`), restated here; a
//! LOS vector's azimuth and elevation are taken in that local frame (grid north is +y
//! everywhere, as for pose headings); ownship-relative points are the entity's body axes
//! (x forward, y right, z down) rotated by its heading, pitch and roll and placed with the
//! WGS84 tangent plane at the entity.

use std::collections::HashMap;
use std::sync::OnceLock;

use aerie::terrain::query::Ray;
use aerie_tests::cigi_host::{
    angle_diff, entity_relative, f, ig_run, normal_az_el, terrain, Arch, IgRun, Problems,
};
use glam::DVec3;
use serde_json::Value;

/// The demo DEM's reference points: the oracles agree with each other there, and the SRTM
/// quads under them have no voids (the test's own design, checked before any host runs).
#[test]
fn the_references_agree_where_the_tests_ask() {
    let t = terrain();
    for (lat, lon, _) in HOT_POINTS.iter().chain(&[VERSIONS_HOT]) {
        let b = t.srtm.bilinear(*lat, *lon).expect("a void-free SRTM quad");
        let (h, n) = t.hot(*lat, *lon).expect("terrain");
        assert!(
            (h - b.height_m).abs() <= b.twist_bound_m + 1e-9,
            "{lat},{lon}: {h} vs {b:?}"
        );
        assert!((n.length() - 1.0).abs() < 1e-12 && n.z > 0.0);
    }
    // At a sample itself the triangles, the bilinear patch and the raw sample coincide.
    let (lat, lon) = (47.25, 11.4);
    let raw = t.srtm.sample(480, 300).unwrap();
    assert!((t.srtm.bilinear(lat, lon).unwrap().height_m - raw).abs() < 1e-9);
    assert!((t.hot(lat, lon).unwrap().0 - raw).abs() < 1e-9);
    assert!(t.hot(OUTSIDE.0, OUTSIDE.1).is_none());
}

// ---------------------------------------------------------------- the scenario

/// The ownship of the answer runs: over the Inn valley north of Innsbruck, heading 30°, nose
/// up 5°, right wing down 10° (lat, lon, alt, heading, pitch, roll).
/// Off the grid lines: the point under it is inside one triangle (a normal is ambiguous on an
/// edge).
const OWNSHIP: [f64; 6] = [47.301_234_5, 11.402_345_6, 3000.0, 30.0, 5.0, -10.0];
/// Geodetic HAT/HOT points (lat, lon, alt): the valley floor, a slope, Patscherkofel.
const HOT_POINTS: [(f64, f64, f64); 3] = [
    (47.271_234_5, 11.392_345_6, 1000.0),
    (47.303_456_7, 11.381_234_5, 2500.0),
    (47.212_345_6, 11.461_234_5, 3000.0),
];
/// South of the tile: no terrain, an invalid answer.
const OUTSIDE: (f64, f64, f64) = (46.9, 11.4, 1000.0);
/// Ownship-relative points (x forward, y right, z down).
const ENTITY_OFFSETS: [[f64; 3]; 3] = [
    [0.0, 0.0, 0.0],
    [800.0, -300.0, 200.0],
    [-1500.0, 1200.0, -100.0],
];
/// LOS segments (lat, lon, alt → lat, lon, alt): into the slope west of the ownship (a hit),
/// and above every summit (clear).
const SEGMENTS: [[f64; 6]; 2] = [
    [47.3, 11.4, 2600.0, 47.303_456_7, 11.381_234_5, 1000.0],
    [47.3, 11.4, 3000.0, 47.28, 11.42, 3200.0],
];
/// LOS vectors (lat, lon, alt, azimuth, elevation, min, max range): 30° down towards the
/// south-south-west (a hit), 10° up (clear), and the first one cut short at 500 m (clear).
const VECTORS: [[f64; 7]; 3] = [
    [47.3, 11.4, 3000.0, -160.0, -30.0, 0.0, 8000.0],
    [47.3, 11.4, 3000.0, 45.0, 10.0, 0.0, 5000.0],
    [47.3, 11.4, 3000.0, -160.0, -30.0, 0.0, 500.0],
];
/// The point each version run asks about.
const VERSIONS_HOT: (f64, f64, f64) = (47.261_234_5, 11.352_345_6, 800.0);
/// Periodic requests in the answer run: every 3 IG frames, cancelled 30 IG frames later.
const PERIOD: u64 = 3;
/// Request IDs the host uses (tests/cigi-host/scripts.cpp).
const PERIODIC_IDS: std::ops::Range<u64> = 300..303;

/// HAT/HOT agree with the query service to f64 rounding for geodetic points; ownship-relative
/// points go through the tangent-plane rotation first (the IG's and this test's floating-point
/// order may differ: 0.1 mm).
const TOL_GEODETIC_M: f64 = 1e-6;
const TOL_ENTITY_M: f64 = 1e-4;
/// LOS ranges and points: both sides map the same f64 points into the same frame and
/// intersect the same triangles; 1 mm is the poses' tolerance.
const TOL_LOS_M: f64 = 1e-3;
/// Normals travel as f32 degrees.
const TOL_NORMAL_DEG: f64 = 1e-3;

fn point_args(p: (f64, f64, f64)) -> String {
    format!("{},{},{}", p.0, p.1, p.2)
}

fn list(v: &[f64]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The run every answer check shares: HAT/HOT of every kind, periodic requests, LOS.
fn answers_run() -> &'static IgRun {
    static RUN: OnceLock<IgRun> = OnceLock::new();
    RUN.get_or_init(|| {
        let mut a: Vec<String> = vec!["--start".into(), list(&OWNSHIP)];
        for p in HOT_POINTS.iter().chain(&[OUTSIDE]) {
            a.extend(["--at".into(), point_args(*p)]);
        }
        for o in ENTITY_OFFSETS {
            a.extend(["--entity-at".into(), list(&o)]);
        }
        for s in SEGMENTS {
            a.extend(["--segment".into(), list(&s)]);
        }
        for v in VECTORS {
            a.extend(["--vector".into(), list(&v)]);
        }
        a.extend(["--period", &PERIOD.to_string(), "--cancel-after", "30"].map(String::from));
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        ig_run(Arch::Native, 3, 60, 30, "hot", &a)
    })
}

// ---------------------------------------------------------------- checks

/// The session: one Start of Frame per rendered frame, in the host's version and byte order,
/// every host message accepted, nothing the CCL refused.
fn check_session(r: &IgRun, p: &mut Problems) {
    let Some(s) = r.host.summary() else {
        p.check(false, || "the host printed no summary".into());
        return;
    };
    let n = |k: &str| s[k].as_u64().unwrap_or(u64::MAX);
    let (igc, sof) = if r.minor >= 2 { (24, 24) } else { (16, 16) };
    p.check(s["byte_order"] == r.arch.byte_order(), || {
        format!(
            "host byte order {} (expected {})",
            s["byte_order"],
            r.arch.byte_order()
        )
    });
    p.check(n("sof") == r.frames, || {
        format!(
            "{} Start of Frames for {} rendered frames (one per frame)",
            n("sof"),
            r.frames
        )
    });
    p.check(
        s["ig_frame_steps"]
            .as_object()
            .is_some_and(|m| m.keys().all(|k| k == "1")),
        || {
            format!(
                "IG frame counter steps {} (each Start of Frame the next frame)",
                s["ig_frame_steps"]
            )
        },
    );
    p.check(n("exceptions") == 0, || {
        format!("{} messages the CCL refused", n("exceptions"))
    });
    p.check(n("sof_swapped") == 0, || {
        format!(
            "{} Start of Frames in the other byte order",
            n("sof_swapped")
        )
    });
    let only = |k: &str, want: u64| {
        s[k].as_object()
            .is_some_and(|m| m.len() == 1 && m.contains_key(&want.to_string()))
    };
    p.check(only("sof_sizes", sof), || {
        format!(
            "Start of Frame sizes {} (CIGI 3.{} has {sof} bytes)",
            s["sof_sizes"], r.minor
        )
    });
    p.check(only("sent_igc_sizes", igc), || {
        format!(
            "IG Control sizes sent {} (3.{}: {igc} bytes)",
            s["sent_igc_sizes"], r.minor
        )
    });
    if r.minor >= 2 {
        // The CCL moves its host to the newest version the IG answers in: an IG answering
        // 3.3 to a 3.2 host turns it into a 3.3 host.
        p.check(only("sof_minors", r.minor.into()), || {
            format!(
                "Start of Frame minor versions {} (host 3.{})",
                s["sof_minors"], r.minor
            )
        });
        p.check(only("sent_minors", r.minor.into()), || {
            format!(
                "the host sent minor versions {} (asked 3.{})",
                s["sent_minors"], r.minor
            )
        });
    }
    let input = &r.summary["input"];
    p.check(input["dropped_total"] == 0, || {
        format!("aerie dropped host messages: {input}")
    });
    p.check(input["accepted"].as_u64().unwrap_or(0) > 0, || {
        "aerie accepted nothing".into()
    });
    let v = &r.summary["validation"];
    p.check(v["errors"] == 0 && v["warnings"] == 0, || {
        format!("validation {v}")
    });
}

/// Every frame drew the pose the host sent in the message the row names.
fn check_poses(r: &IgRun, moving: bool, p: &mut Problems) {
    let t = terrain();
    let sent: HashMap<u64, &Value> = r
        .host
        .sent("msg")
        .map(|m| (m["host_frame"].as_u64().unwrap(), m))
        .collect();
    p.check(r.rows.len() as u64 == r.frames, || {
        format!("{} stats rows", r.rows.len())
    });
    let mut frames = Vec::new();
    for row in &r.rows {
        let num = |k: &str| row[k].parse::<f64>().unwrap_or(f64::NAN);
        let hf = num("host_frame") as u64;
        let Some(m) = sent.get(&hf) else {
            p.check(false, || {
                format!("frame {}: host frame {hf} was never sent", row["frame"])
            });
            continue;
        };
        frames.push(hf);
        p.check(row["extrapolated"] == "0", || {
            format!("row {row:?} extrapolated")
        });
        // The eye at exactly the sent point, the attitude taken there (issue 14).
        let (lat, lon) = (f(&m["lat"]), f(&m["lon"]));
        let want = t.world(lat, lon, f(&m["alt"]));
        for (k, w) in ["x_m", "y_m", "z_m"].into_iter().zip(want.to_array()) {
            p.check((num(k) - w).abs() <= 1e-3, || {
                format!("host frame {hf}: {k} {} vs sent {w}", num(k))
            });
        }
        let att = t.world_attitude(lat, lon, ["yaw", "pitch", "roll"].map(|s| f(&m[s])));
        for (k, w) in ["heading_deg", "pitch_deg", "roll_deg"]
            .into_iter()
            .zip(att)
        {
            p.check(angle_diff(num(k), w) <= 1e-3, || {
                format!("host frame {hf}: {k} {} vs sent (world) {w}", num(k))
            });
        }
        for (k, s) in [("lat_deg", "lat"), ("lon_deg", "lon")] {
            p.check((num(k) - f(&m[s])).abs() <= 1e-8, || {
                format!("host frame {hf}: {k} {} vs sent {}", num(k), m[s])
            });
        }
    }
    frames.dedup();
    if moving {
        p.check(frames.len() >= 5, || {
            format!("only host frames {frames:?} drawn")
        });
    }
}

/// Start of Frame of each received message, by message number.
fn sofs_by_msg(r: &IgRun) -> HashMap<u64, &Value> {
    r.host
        .recv("sof")
        .map(|s| (s["msg"].as_u64().unwrap(), s))
        .collect()
}

/// The pose of the message numbered `n` (lat, lon, alt, yaw, pitch, roll).
fn pose_of(r: &IgRun, n: u64) -> Option<[f64; 6]> {
    let m = r.host.sent("msg").find(|m| m["n"] == n)?;
    Some(["lat", "lon", "alt", "yaw", "pitch", "roll"].map(|k| f(&m[k])))
}

/// One HAT/HOT response against both references. `req` is the host's request line.
fn check_hot_answer(r: &IgRun, req: &Value, resp: &Value, p: &mut Problems) {
    let t = terrain();
    let id = &req["id"];
    let entity = req["coord"] == "entity";
    let (lat, lon, alt) = if entity {
        let Some(pose) = pose_of(r, req["n"].as_u64().unwrap()) else {
            p.check(false, || format!("request {id}: no message {}", req["n"]));
            return;
        };
        let g = entity_relative(pose, ["x", "y", "z"].map(|k| f(&req[k])));
        (g.lat_deg, g.lon_deg, g.alt_m)
    } else {
        (f(&req["lat"]), f(&req["lon"]), f(&req["alt"]))
    };
    let tol = if entity { TOL_ENTITY_M } else { TOL_GEODETIC_M };
    let ext = req["type"] == "ext";
    p.check(resp["recv"] == if ext { "hotx" } else { "hot" }, || {
        format!(
            "request {id} ({}) answered by {}",
            req["type"], resp["recv"]
        )
    });
    if !ext {
        p.check(resp["type"] == req["type"], || {
            format!(
                "request {id}: {} answer to a {} request",
                resp["type"], req["type"]
            )
        });
    }
    let Some((hot, normal)) = t.hot(lat, lon) else {
        p.check(resp["valid"] == false, || {
            format!("request {id} off the terrain answered {resp}")
        });
        return;
    };
    p.check(resp["valid"] == true, || {
        format!("request {id} at {lat},{lon}: invalid {resp}")
    });
    let (hat_got, hot_got) = if ext {
        (f(&resp["hat"]), f(&resp["hot"]))
    } else if resp["type"] == "hat" {
        (f(&resp["height"]), alt - f(&resp["height"]))
    } else {
        (alt - f(&resp["height"]), f(&resp["height"]))
    };
    p.check((hot_got - hot).abs() <= tol, || {
        format!("request {id}: HOT {hot_got} vs query {hot} at {lat},{lon}")
    });
    p.check((hat_got - (alt - hot)).abs() <= tol, || {
        format!(
            "request {id}: HAT {hat_got} vs {} (alt {alt} − query {hot})",
            alt - hot
        )
    });
    if let Some(b) = t.srtm.bilinear(lat, lon) {
        p.check((hot_got - b.height_m).abs() <= b.twist_bound_m + tol, || {
            format!(
                "request {id}: HOT {hot_got} vs SRTM bilinear {} beyond the quad's triangulation bound {}",
                b.height_m, b.twist_bound_m
            )
        });
    } else {
        p.check(entity, || {
            format!("request {id}: SRTM void under a geodetic point")
        });
    }
    if ext && !t.on_triangle_edge(t.local(lat, lon, alt)) {
        let (az, el) = normal_az_el(normal);
        p.check((f(&resp["norm_el"]) - el).abs() <= TOL_NORMAL_DEG, || {
            format!("request {id}: normal elevation {} vs {el}", resp["norm_el"])
        });
        p.check(
            el > 89.9 || angle_diff(f(&resp["norm_az"]), az) <= TOL_NORMAL_DEG,
            || format!("request {id}: normal azimuth {} vs {az}", resp["norm_az"]),
        );
        p.check(resp["material"] == 0, || {
            format!("request {id}: material {}", resp["material"])
        });
    }
    if r.minor >= 2 {
        // The least significant nibble of the last host frame the IG had when it computed the
        // answer, i.e. that of the Start of Frame of the same message.
        let sof = sofs_by_msg(r)
            .get(&resp["msg"].as_u64().unwrap_or(0))
            .copied()
            .cloned();
        let lsn = sof.map(|s| s["last_host_frame"].as_u64().unwrap_or(99) & 0xF);
        p.check(resp["host_frame_lsn"].as_u64() == lsn, || {
            format!(
                "request {id}: host frame LSN {} vs Start of Frame's {lsn:?}",
                resp["host_frame_lsn"]
            )
        });
    }
}

/// Every one-shot HAT/HOT request: answered once, in the IG's next message (an asynchronous
/// host's request may land just after a frame began: then the one after), right.
fn check_hot(r: &IgRun, p: &mut Problems) {
    let mut asked = 0;
    for req in r.host.sent("hot_req").filter(|q| q["period"] == 0) {
        let id = req["id"].as_u64().unwrap();
        if PERIODIC_IDS.contains(&id) {
            continue;
        }
        asked += 1;
        let resp = r.host.responses(id);
        p.check(resp.len() == 1, || {
            format!("request {id}: {} answers {resp:?}", resp.len())
        });
        let Some(first) = resp.first() else { continue };
        p.check(
            first["latency_msgs"]
                .as_u64()
                .is_some_and(|l| (1..=2).contains(&l)),
            || {
                format!(
                    "request {id}: answered {} IG messages later",
                    first["latency_msgs"]
                )
            },
        );
        check_hot_answer(r, req, first, p);
    }
    p.check(asked > 0, || "no HAT/HOT request was sent".into());
}

/// Periodic requests: one answer every `PERIOD` IG frames until the host cancels them.
fn check_periodic(r: &IgRun, p: &mut Problems) {
    for id in PERIODIC_IDS {
        let reqs: Vec<&Value> = r.host.sent("hot_req").filter(|q| q["id"] == id).collect();
        let (Some(start), Some(cancel)) = (
            reqs.iter().find(|q| q["period"] != 0),
            reqs.iter().find(|q| q["period"] == 0),
        ) else {
            p.check(false, || {
                format!("periodic request {id}: not sent and cancelled: {reqs:?}")
            });
            continue;
        };
        let rx_cancel = cancel["rx"].as_u64().unwrap();
        let resp = r.host.responses(id);
        let before: Vec<&&Value> = resp
            .iter()
            .filter(|a| a["msg"].as_u64().unwrap() <= rx_cancel)
            .collect();
        p.check(before.len() >= 3, || {
            format!(
                "periodic request {id}: {} answers before the cancel",
                before.len()
            )
        });
        let frames: Vec<u64> = before
            .iter()
            .map(|a| a["ig_frame"].as_u64().unwrap())
            .collect();
        p.check(frames.windows(2).all(|w| w[1] - w[0] == PERIOD), || {
            format!(
                "periodic request {id} (every {PERIOD} frames) answered at IG frames {frames:?}"
            )
        });
        // The cancelling request itself may be answered once (it is a one-shot request).
        let late: Vec<u64> = resp
            .iter()
            .map(|a| a["msg"].as_u64().unwrap())
            .filter(|&m| m > rx_cancel + 2)
            .collect();
        p.check(late.is_empty(), || {
            format!(
                "periodic request {id} cancelled by message {} still answered in messages {late:?}",
                cancel["n"]
            )
        });
        for a in before {
            check_hot_answer(r, start, a, p);
        }
    }
}

/// The oracle's line of sight for a host's LOS request line, and whether it is a segment.
fn los_oracle(req: &Value) -> (Option<(f64, DVec3, DVec3)>, bool) {
    let t = terrain();
    let from = t.local(f(&req["lat"]), f(&req["lon"]), f(&req["alt"]));
    if req["sent"] == "los_seg" {
        let to = t.local(f(&req["lat2"]), f(&req["lon2"]), f(&req["alt2"]));
        (t.los(&Ray::segment(from, to).unwrap()), true)
    } else {
        let (az, el) = (f(&req["az"]).to_radians(), f(&req["el"]).to_radians());
        let dir = DVec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin());
        let ray = Ray::new(from, dir, f(&req["min"]), f(&req["max"])).unwrap();
        (t.los(&ray), false)
    }
}

fn check_los(r: &IgRun, p: &mut Problems) {
    let t = terrain();
    let reqs: Vec<&Value> = r
        .host
        .sent("los_seg")
        .chain(r.host.sent("los_vect"))
        .collect();
    p.check(reqs.len() == 2 * (SEGMENTS.len() + VECTORS.len()), || {
        format!("{} LOS requests sent", reqs.len())
    });
    for req in reqs {
        let id = req["id"].as_u64().unwrap();
        let resp = r.host.responses(id);
        p.check(resp.len() == 1, || {
            format!("LOS {id}: {} answers {resp:?}", resp.len())
        });
        let Some(a) = resp.first() else { continue };
        let ext = req["extended"] == true;
        p.check(a["recv"] == if ext { "losx" } else { "los" }, || {
            format!("LOS {id} (extended {ext}) answered by {}", a["recv"])
        });
        p.check(
            a["latency_msgs"]
                .as_u64()
                .is_some_and(|l| (1..=2).contains(&l)),
            || format!("LOS {id}: answered {} IG messages later", a["latency_msgs"]),
        );
        p.check(a["entity_id_valid"] == false, || {
            format!("LOS {id}: entity hit {a}")
        });
        let (oracle, segment) = los_oracle(req);
        match oracle {
            Some((range, point, normal)) => {
                p.check(a["valid"] == true, || {
                    format!("LOS {id}: the oracle hits at {range} m, answer {a}")
                });
                if segment {
                    p.check(a["visible"] == false, || {
                        format!("LOS {id}: blocked segment visible {a}")
                    });
                }
                p.check((f(&a["range"]) - range).abs() <= TOL_LOS_M, || {
                    format!("LOS {id}: range {} vs oracle {range}", a["range"])
                });
                if ext {
                    p.check(a["range_valid"] == true, || {
                        format!("LOS {id}: range invalid {a}")
                    });
                    let got = t.local(f(&a["lat"]), f(&a["lon"]), f(&a["alt"]));
                    p.check((got - point).length() <= TOL_LOS_M, || {
                        format!("LOS {id}: intersection {got} vs oracle {point}")
                    });
                    let ground = t.hot(f(&a["lat"]), f(&a["lon"])).map(|g| g.0);
                    p.check(
                        ground.is_some_and(|g| (g - f(&a["alt"])).abs() <= TOL_LOS_M),
                        || {
                            format!(
                                "LOS {id}: intersection alt {} but the ground there is {ground:?}",
                                a["alt"]
                            )
                        },
                    );
                    let (az, el) = normal_az_el(normal);
                    p.check((f(&a["norm_el"]) - el).abs() <= TOL_NORMAL_DEG, || {
                        format!("LOS {id}: normal elevation {} vs {el}", a["norm_el"])
                    });
                    p.check(
                        el > 89.9 || angle_diff(f(&a["norm_az"]), az) <= TOL_NORMAL_DEG,
                        || format!("LOS {id}: normal azimuth {} vs {az}", a["norm_az"]),
                    );
                    p.check(a["material"] == 0, || {
                        format!("LOS {id}: material {}", a["material"])
                    });
                }
            }
            None => {
                p.check(a["valid"] == false, || {
                    format!("LOS {id}: clear per the oracle, answer {a}")
                });
                if segment {
                    p.check(a["visible"] == true, || {
                        format!("LOS {id}: clear segment not visible {a}")
                    });
                }
                if ext {
                    p.check(a["range_valid"] == false, || {
                        format!("LOS {id}: clear but range valid {a}")
                    });
                }
            }
        }
    }
}

// ---------------------------------------------------------------- tests

/// The scenario is what it claims: the hit segment and vector hit, the others are clear.
#[test]
fn the_line_of_sight_scenario_hits_and_misses_as_designed() {
    let seg = |s: [f64; 6]| {
        los_oracle(
            &serde_json::json!({"sent": "los_seg", "lat": s[0], "lon": s[1], "alt": s[2],
            "lat2": s[3], "lon2": s[4], "alt2": s[5]}),
        )
        .0
    };
    let vect = |v: [f64; 7]| {
        los_oracle(
            &serde_json::json!({"sent": "los_vect", "lat": v[0], "lon": v[1], "alt": v[2],
            "az": v[3], "el": v[4], "min": v[5], "max": v[6]}),
        )
        .0
    };
    let hit = seg(SEGMENTS[0]).expect("segment 0 hits");
    assert!(hit.0 > 100.0, "{hit:?}");
    assert!(seg(SEGMENTS[1]).is_none());
    let v = vect(VECTORS[0]).expect("vector 0 hits");
    assert!(v.0 > 500.0 && v.0 < 8000.0, "{v:?}");
    assert!(vect(VECTORS[1]).is_none());
    assert!(vect(VECTORS[2]).is_none(), "cut short before the ground");
}

#[test]
fn hat_hot_answers_match_the_query_service_and_the_srtm_samples() {
    let r = answers_run();
    let mut p = Problems::new(&r.label);
    check_session(r, &mut p);
    check_poses(r, false, &mut p);
    check_hot(r, &mut p);
    check_periodic(r, &mut p);
    p.finish();
}

#[test]
fn line_of_sight_hits_where_the_query_service_hits() {
    let r = answers_run();
    let mut p = Problems::new(&r.label);
    check_los(r, &mut p);
    p.finish();
}

/// Operate → Reset (Standby) → Operate: each Start of Frame reports the mode of the newest
/// host message the IG had, and the Reset drops the host's periodic request for good.
#[test]
fn reset_reports_standby_until_operate_and_drops_requests() {
    let at = point_args(HOT_POINTS[0]);
    let start = list(&OWNSHIP);
    let args = [
        "--start",
        &start,
        "--at",
        &at,
        "--period",
        "1",
        "--cancel-after",
        "100000",
        "--operate-frames",
        "20",
        "--reset-frames",
        "20",
    ];
    let r = ig_run(Arch::Native, 3, 60, 30, "modes", &args);
    let mut p = Problems::new(&r.label);
    check_session(&r, &mut p);
    let msgs: Vec<&Value> = r.host.sent("msg").collect();
    let reset: Vec<u64> = msgs
        .iter()
        .filter(|m| m["mode"] == "standby")
        .map(|m| m["host_frame"].as_u64().unwrap())
        .collect();
    let (Some(&r0), Some(&r1)) = (reset.first(), reset.last()) else {
        panic!(
            "{}: the host sent no Reset in {} messages; its summary: {:?}",
            r.label,
            msgs.len(),
            r.host.summary()
        )
    };
    let again = r1 + 1;
    let sofs: Vec<&Value> = r.host.recv("sof").collect();
    for s in &sofs {
        let lh = s["last_host_frame"].as_u64().unwrap();
        if (r0..=r1).contains(&lh) {
            p.check(s["mode"] == "standby", || {
                format!(
                    "IG frame {} (host frame {lh}, a Reset) reports {}",
                    s["ig_frame"], s["mode"]
                )
            });
        }
        if lh >= again {
            p.check(s["mode"] == "operate", || {
                format!(
                    "IG frame {} (host frame {lh}, Operate again) reports {}",
                    s["ig_frame"], s["mode"]
                )
            });
        }
        p.check(s["database"].as_i64().is_some_and(|d| d >= 0), || {
            format!(
                "IG frame {}: database {} (loading) though none was asked",
                s["ig_frame"], s["database"]
            )
        });
    }
    p.check(
        sofs.iter()
            .any(|s| s["mode"] == "operate" && s["last_host_frame"].as_u64() < Some(r0)),
        || "no Start of Frame in Operate before the Reset".into(),
    );
    let first_standby = sofs
        .iter()
        .find(|s| s["mode"] == "standby")
        .map(|s| s["msg"].as_u64().unwrap());
    p.check(first_standby.is_some(), || {
        format!("no Start of Frame reported Standby (Reset in host frames {r0}..={r1})")
    });
    let answers: Vec<u64> = PERIODIC_IDS
        .flat_map(|id| r.host.responses(id))
        .map(|a| a["msg"].as_u64().unwrap())
        .collect();
    let cut = first_standby.unwrap_or(u64::MAX);
    p.check(answers.iter().any(|&m| m < cut), || {
        "the periodic request was never answered before the Reset".into()
    });
    let after: Vec<u64> = answers.iter().copied().filter(|&m| m >= cut).collect();
    p.check(after.is_empty(), || {
        format!("the periodic request survived the Reset: answers in messages {after:?}")
    });
    p.finish();
}

/// A synchronous host (each message only after a Start of Frame, as the CCL's MiniHost) is
/// paced by the IG: no more Start of Frames than rendered frames, one host message per Start
/// of Frame, and the height asked in each message answered in the very next IG message.
#[test]
fn a_synchronous_host_is_paced_by_the_rendered_frames() {
    let start = list(&OWNSHIP);
    let r = ig_run(
        Arch::Native,
        3,
        40,
        20,
        "sync",
        &["--start", &start, "--quiet"],
    );
    let mut p = Problems::new(&r.label);
    check_session(&r, &mut p);
    let s = r.host.summary().expect("summary");
    let n = |k: &str| s[k].as_u64().unwrap_or(u64::MAX);
    let rendered = r.summary["frames"].as_u64().unwrap();
    p.check(n("sof") <= rendered, || {
        format!(
            "{} Start of Frames for {rendered} rendered frames: the host ran ahead of the IG",
            n("sof")
        )
    });
    p.check(n("sent") <= n("sof") + n("timeouts") + 1, || {
        format!(
            "{} messages sent for {} Start of Frames and {} timeouts",
            n("sent"),
            n("sof"),
            n("timeouts")
        )
    });
    let lat = s["latency_msgs"].as_object().cloned().unwrap_or_default();
    p.check(lat.keys().all(|k| k == "1"), || {
        format!("answer latencies (IG messages) {lat:?}")
    });
    p.check(n("hot") + 2 >= n("sof"), || {
        format!("{} answers for {} Start of Frames", n("hot"), n("sof"))
    });
    p.finish();
}

/// A host of one CIGI version and byte order: its poses drawn exactly, every HAT/HOT type
/// answered right, in its own version and byte order.
fn version_run(arch: Arch, minor: u8) {
    let at = point_args(VERSIONS_HOT);
    let args = [
        "--start",
        "47.25,11.35,2500,10,-3,2",
        "--move",
        "0.00001,0.000012,0.5,0.25",
        "--at",
        &at,
    ];
    let r = ig_run(arch, minor, 20, 20, "poses", &args);
    let mut p = Problems::new(&r.label);
    check_session(&r, &mut p);
    check_poses(&r, true, &mut p);
    check_hot(&r, &mut p);
    p.check(r.host.sent("hot_req").count() == 3, || {
        "three HAT/HOT requests".into()
    });
    p.finish();
}

#[test]
fn cigi_3_0_little_endian_host() {
    version_run(Arch::Native, 0);
}

#[test]
fn cigi_3_1_little_endian_host() {
    version_run(Arch::Native, 1);
}

#[test]
fn cigi_3_2_little_endian_host() {
    version_run(Arch::Native, 2);
}

#[test]
fn cigi_3_3_little_endian_host() {
    version_run(Arch::Native, 3);
}

#[test]
fn cigi_3_0_big_endian_host() {
    version_run(Arch::S390x, 0);
}

#[test]
fn cigi_3_1_big_endian_host() {
    version_run(Arch::S390x, 1);
}

#[test]
fn cigi_3_2_big_endian_host() {
    version_run(Arch::S390x, 2);
}

#[test]
fn cigi_3_3_big_endian_host() {
    version_run(Arch::S390x, 3);
}
