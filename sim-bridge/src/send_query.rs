//! `aerie-send --hot / --hot-local / --los / --los-vector`: one native terrain query
//! (`codec::native::encode_query`) sent to the IG, its answer awaited and printed. The parsing
//! and the printing are plain data in, text out; [`ask`] is the only part with a socket.
//!
//! Delivery: UDP may lose either datagram, so the query is sent again, with the same request
//! id, every [`RESEND_EVERY`] until an answer with that id arrives or the timeout passes; the
//! first answer wins (the IG answers each copy; later ones are ignored).

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use crate::codec::native::{decode_query, decode_reply, encode_query};
use crate::pose::PosePosition;
use crate::query::{Answer, LosHit, Surface, TerrainReply, TerrainRequest};

/// How often an unanswered query is sent again.
pub const RESEND_EVERY: Duration = Duration::from_millis(250);
/// `--timeout-ms` default.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_millis(1000);

/// A query from the command line: the request, and the altitude the user gave for a height
/// query (HAT is printed only then).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryPlan {
    /// What is asked.
    pub request: TerrainRequest,
    /// `--hot`'s optional third number: the altitude (or local z) to report HAT for.
    pub altitude_m: Option<f64>,
}

fn numbers(flag: &str, v: &str, form: &str, counts: &[usize]) -> Result<Vec<f64>, String> {
    let bad = || format!("{flag} {v:?}: expected {form}");
    let n: Vec<f64> = v
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    if counts.contains(&n.len()) {
        Ok(n)
    } else {
        Err(bad())
    }
}

fn point(local: bool, a: f64, b: f64, c: f64) -> PosePosition {
    if local {
        PosePosition::LocalEnu { x: a, y: b, z: c }
    } else {
        PosePosition::Geodetic {
            lat_deg: a,
            lon_deg: b,
            alt_m: c,
        }
    }
}

/// The request as the IG would read it: the packet decoder's checks (ranges, finite values)
/// applied before anything is sent, so a bad number is named here, not dropped by the IG.
fn checked(flag: &str, v: &str, plan: QueryPlan) -> Result<QueryPlan, String> {
    match decode_query(&encode_query(0, &plan.request)) {
        Ok(_) => Ok(plan),
        Err(crate::codec::DecodeError::Malformed { what, .. }) => {
            Err(format!("{flag} {v:?}: {what}"))
        }
        Err(e) => Err(format!("{flag} {v:?}: {e}")),
    }
}

/// `--hot lat,lon[,alt]` (`local`: `--hot-local x,y[,z]`): height of terrain there; with the
/// altitude, height above terrain too.
pub fn parse_hot(flag: &str, v: &str, local: bool) -> Result<QueryPlan, String> {
    let form = if local { "x,y[,z]" } else { "lat,lon[,alt]" };
    let n = numbers(flag, v, form, &[2, 3])?;
    let plan = QueryPlan {
        request: TerrainRequest::HeightOfTerrain {
            at: point(local, n[0], n[1], n.get(2).copied().unwrap_or(0.0)),
        },
        altitude_m: n.get(2).copied(),
    };
    checked(flag, v, plan)
}

/// `--los lat,lon,alt,lat,lon,alt` (`local`: x,y,z,x,y,z): first intersection along the
/// segment.
pub fn parse_los(flag: &str, v: &str, local: bool) -> Result<QueryPlan, String> {
    let form = if local {
        "x,y,z,x,y,z"
    } else {
        "lat,lon,alt,lat,lon,alt"
    };
    let n = numbers(flag, v, form, &[6])?;
    let plan = QueryPlan {
        request: TerrainRequest::LineOfSight {
            from: point(local, n[0], n[1], n[2]),
            to: point(local, n[3], n[4], n[5]),
        },
        altitude_m: None,
    };
    checked(flag, v, plan)
}

/// `--los-vector lat,lon,alt,azimuth,elevation,min,max` (`local`: x,y,z,…): first
/// intersection along the vector, degrees and metres.
pub fn parse_los_vector(flag: &str, v: &str, local: bool) -> Result<QueryPlan, String> {
    let form = if local {
        "x,y,z,azimuth,elevation,min_m,max_m"
    } else {
        "lat,lon,alt,azimuth,elevation,min_m,max_m"
    };
    let n = numbers(flag, v, form, &[7])?;
    let plan = QueryPlan {
        request: TerrainRequest::LineOfSightVector {
            from: point(local, n[0], n[1], n[2]),
            azimuth_deg: n[3],
            elevation_deg: n[4],
            min_range_m: n[5],
            max_range_m: n[6],
        },
        altitude_m: None,
    };
    checked(flag, v, plan)
}

/// What came back for one query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Asked {
    /// The answer with the query's id, or `None` when the timeout passed first.
    pub reply: Option<TerrainReply>,
    /// How many times the query was sent.
    pub sends: u32,
    /// Datagrams received that were not this query's answer (other ids, other packets).
    pub ignored: u32,
    /// Time from the first send to the answer (or to the timeout).
    pub waited: Duration,
}

/// Sends query `id` to `to` from `socket` and waits up to `timeout` for its answer, sending it
/// again every `resend_every`. Only socket errors are errors; a timeout is an [`Asked`] with
/// no reply.
pub fn ask(
    socket: &UdpSocket,
    to: SocketAddr,
    id: u32,
    request: &TerrainRequest,
    timeout: Duration,
    resend_every: Duration,
) -> std::io::Result<Asked> {
    let packet = encode_query(id, request);
    let start = Instant::now();
    let mut out = Asked {
        reply: None,
        sends: 0,
        ignored: 0,
        waited: Duration::ZERO,
    };
    let mut next_send = start;
    let mut buf = [0u8; 2048];
    loop {
        let now = Instant::now();
        let deadline = start + timeout;
        if now >= deadline {
            out.waited = now - start;
            return Ok(out);
        }
        if now >= next_send {
            socket.send_to(&packet, to)?;
            out.sends += 1;
            next_send = now + resend_every;
        }
        // A zero read timeout means "block forever" to std: wait at least 1 ms.
        let wait = next_send.min(deadline).saturating_duration_since(now);
        socket.set_read_timeout(Some(wait.max(Duration::from_millis(1))))?;
        match socket.recv_from(&mut buf) {
            Ok((n, _)) => match decode_reply(&buf[..n]) {
                Ok((got, reply)) if got == id => {
                    out.reply = Some(reply);
                    out.waited = start.elapsed();
                    return Ok(out);
                }
                _ => out.ignored += 1,
            },
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            // An ICMP "port unreachable" from an earlier send (nobody listening yet): keep
            // trying until the timeout, like a lost datagram.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {}
            Err(e) => return Err(e),
        }
    }
}

/// The exit status for an answer: 0 when ready (a hit, a clear line or a height), 1 for a
/// timeout, no terrain, or terrain that was not resident in time.
pub fn exit_status(reply: Option<&TerrainReply>) -> i32 {
    match reply {
        Some(TerrainReply::HeightOfTerrain(Answer::Ready(_)))
        | Some(TerrainReply::LineOfSight(Answer::Ready(_))) => 0,
        _ => 1,
    }
}

fn position_text(p: &PosePosition) -> String {
    match *p {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => format!("lat {lat_deg:.7}° lon {lon_deg:.7}° alt {alt_m:.3} m"),
        PosePosition::LocalEnu { x, y, z } => format!("x {x:.3} y {y:.3} z {z:.3} m"),
    }
}

fn normal_text(n: &[f64; 3]) -> String {
    format!("normal (e, n, u) {:.5} {:.5} {:.5}", n[0], n[1], n[2])
}

/// Why there is no answer, in words (for the line and the error message).
fn not_ready_text<T>(a: &Answer<T>) -> &'static str {
    match a {
        Answer::NoTerrain => "no terrain there (outside the loaded data, or none loaded)",
        _ => "the terrain there was not resident in time (pending, the IG gave up waiting)",
    }
}

/// The one line printed for an answer: height (and HAT for the given altitude) and normal; or
/// the hit's range, point and normal, or "clear"; or why there is no answer.
pub fn answer_line(plan: &QueryPlan, reply: &TerrainReply) -> String {
    match reply {
        TerrainReply::HeightOfTerrain(Answer::Ready(Surface {
            height_m,
            normal_enu,
        })) => {
            let hat = plan
                .altitude_m
                .map(|a| format!(", HAT {:.3} m (altitude {a:.3} m)", a - height_m))
                .unwrap_or_default();
            format!("HOT {height_m:.3} m{hat}, {}", normal_text(normal_enu))
        }
        TerrainReply::LineOfSight(Answer::Ready(Some(LosHit {
            range_m,
            point,
            normal_enu,
        }))) => format!(
            "LOS hit at range {range_m:.3} m: {}, {}",
            position_text(point),
            normal_text(normal_enu)
        ),
        TerrainReply::LineOfSight(Answer::Ready(None)) => {
            "LOS clear: no terrain along the line".to_string()
        }
        TerrainReply::HeightOfTerrain(a) => format!("HOT: {}", not_ready_text(a)),
        TerrainReply::LineOfSight(a) => format!("LOS: {}", not_ready_text(a)),
    }
}

/// `s` as a JSON string literal (quotes, backslashes and control characters escaped).
pub fn json_string(s: &str) -> String {
    let mut o = String::from('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

fn json_position(p: &PosePosition) -> String {
    match *p {
        PosePosition::Geodetic {
            lat_deg,
            lon_deg,
            alt_m,
        } => format!("{{\"lat_deg\":{lat_deg},\"lon_deg\":{lon_deg},\"alt_m\":{alt_m}}}"),
        PosePosition::LocalEnu { x, y, z } => format!("{{\"x\":{x},\"y\":{y},\"z\":{z}}}"),
    }
}

fn json_normal(n: &[f64; 3]) -> String {
    format!("[{},{},{}]", n[0], n[1], n[2])
}

/// The answer as one JSON object (`--json`): `kind` (`hot`, `los`), `id`, `to`, `status`
/// (`ready`, `no_terrain`, `pending`, `timeout`), `sends`, `waited_ms`, then for a height
/// `height_m`, `hat_m` (null without an altitude), `normal_enu`; for a line of sight `hit`,
/// and on a hit `range_m`, `point`, `normal_enu`.
pub fn answer_json(plan: &QueryPlan, id: u32, to: SocketAddr, asked: &Asked) -> String {
    let kind = match plan.request {
        TerrainRequest::HeightOfTerrain { .. } => "hot",
        _ => "los",
    };
    let status = match asked.reply {
        None => "timeout",
        Some(TerrainReply::HeightOfTerrain(Answer::Ready(_)))
        | Some(TerrainReply::LineOfSight(Answer::Ready(_))) => "ready",
        Some(TerrainReply::HeightOfTerrain(Answer::NoTerrain))
        | Some(TerrainReply::LineOfSight(Answer::NoTerrain)) => "no_terrain",
        Some(_) => "pending",
    };
    let mut o = format!(
        "{{\"kind\":\"{kind}\",\"id\":{id},\"to\":{},\"status\":\"{status}\",\"sends\":{},\"waited_ms\":{:.3}",
        json_string(&to.to_string()),
        asked.sends,
        asked.waited.as_secs_f64() * 1e3
    );
    match asked.reply {
        Some(TerrainReply::HeightOfTerrain(Answer::Ready(s))) => {
            let hat = plan
                .altitude_m
                .map_or("null".to_string(), |a| (a - s.height_m).to_string());
            o.push_str(&format!(
                ",\"height_m\":{},\"hat_m\":{hat},\"normal_enu\":{}",
                s.height_m,
                json_normal(&s.normal_enu)
            ));
        }
        Some(TerrainReply::LineOfSight(Answer::Ready(Some(h)))) => o.push_str(&format!(
            ",\"hit\":true,\"range_m\":{},\"point\":{},\"normal_enu\":{}",
            h.range_m,
            json_position(&h.point),
            json_normal(&h.normal_enu)
        )),
        Some(TerrainReply::LineOfSight(Answer::Ready(None))) => o.push_str(",\"hit\":false"),
        _ => {}
    }
    o.push('}');
    o
}

#[cfg(test)]
#[path = "send_query_tests.rs"]
mod tests;
