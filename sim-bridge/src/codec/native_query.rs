//! aerie native terrain queries: a host asks the IG for the height of terrain or a line of sight
//! (`AERQ`, 76 bytes) and the IG answers (`AERA`, 84 bytes). Both little-endian, fixed size,
//! protected by a CRC-32 like the native pose packet; specified in `sim-bridge/PROTOCOL.md`.
//!
//! Request (`AERQ`):
//!
//! | off | size | field |
//! |----:|-----:|-------|
//! | 0 | 4 | magic `"AERQ"` |
//! | 4 | 2 | version u16 = 1 |
//! | 6 | 1 | kind u8: 1 HOT at a point, 2 LOS segment, 3 LOS vector |
//! | 7 | 1 | flags u8: bit 0 the first point is local ENU, bit 1 the segment's end is local ENU |
//! | 8 | 4 | request id u32 (echoed in the answer) |
//! | 12 | 2 | size u16 = 76 |
//! | 14 | 2 | reserved, 0 |
//! | 16 | 24 | point f64×3 (HOT point, LOS source): lat°, lon°, alt m or x, y, z m |
//! | 40 | 32 | f64×4: segment end (3 values, then 0), or vector azimuth°, elevation°, min m, max m; HOT: 0 |
//! | 72 | 4 | CRC-32 of bytes 0..72 |
//!
//! Answer (`AERA`):
//!
//! | off | size | field |
//! |----:|-----:|-------|
//! | 0 | 4 | magic `"AERA"` |
//! | 4 | 2 | version u16 = 1 |
//! | 6 | 1 | kind u8: 1 HOT, 2 LOS (segment or vector) |
//! | 7 | 1 | status u8: 0 ready, 1 no terrain, 2 pending, timed out |
//! | 8 | 4 | request id u32 |
//! | 12 | 2 | size u16 = 84 |
//! | 14 | 1 | flags u8: bit 0 LOS hit, bit 1 hit point is local ENU |
//! | 15 | 1 | reserved, 0 |
//! | 16 | 8 | HOT height f64, m |
//! | 24 | 8 | LOS range f64, m |
//! | 32 | 24 | normal f64×3, unit, local ENU |
//! | 56 | 24 | LOS hit point f64×3 (as the request's source) |
//! | 80 | 4 | CRC-32 of bytes 0..80 |
//!
//! Fields that do not apply (the answer's values when not ready, a clear line's range) are 0,
//! and the decoders insist on it, so that every packet has one reading.

use super::protocol::{DecodeError, Protocol};
use super::wire::{ByteOrder, Rd, Wr};
use crate::pose::{PosePosition, MAX_ALT_M, MAX_ANGLE_DEG, MAX_WORLD_BOUND_M, MIN_ALT_M};
use crate::query::{Answer, LosHit, Surface, TerrainReply, TerrainRequest};

/// First four bytes of a native query.
pub const QUERY_MAGIC: [u8; 4] = *b"AERQ";
/// First four bytes of a native answer.
pub const REPLY_MAGIC: [u8; 4] = *b"AERA";
/// The query/answer version this module reads and writes.
pub const QUERY_VERSION: u16 = 1;
/// Query datagram size in bytes.
pub const QUERY_SIZE: usize = 76;
/// Answer datagram size in bytes.
pub const REPLY_SIZE: usize = 84;

/// Request kind: height of terrain at a point.
pub const KIND_HOT: u8 = 1;
/// Request kind: line of sight along a segment (answer kind for both LOS requests).
pub const KIND_LOS: u8 = 2;
/// Request kind: line of sight along a vector.
pub const KIND_LOS_VECTOR: u8 = 3;

/// Query flag: the first point is local ENU metres (else WGS84).
pub const QFLAG_FROM_LOCAL: u8 = 1 << 0;
/// Query flag: the segment's end point is local ENU metres (else WGS84).
pub const QFLAG_TO_LOCAL: u8 = 1 << 1;
/// Answer flag: the line of sight hit the terrain.
pub const AFLAG_HIT: u8 = 1 << 0;
/// Answer flag: the hit point is local ENU metres (else WGS84).
pub const AFLAG_POINT_LOCAL: u8 = 1 << 1;

/// Answer status: the answer is in the packet.
pub const STATUS_READY: u8 = 0;
/// Answer status: no terrain there (outside the data, or none loaded).
pub const STATUS_NO_TERRAIN: u8 = 1;
/// Answer status: the terrain was not resident in time (the IG gave up waiting).
pub const STATUS_PENDING: u8 = 2;

const P: Protocol = Protocol::Aerie;
/// How far a decoded normal's length may be from 1.
const UNIT_TOLERANCE: f64 = 1e-6;

/// True when `bytes` is a native terrain query (`AERQ`), not a pose: the ingest hands it to
/// [`decode_query`] and answers it; [`super::detect`] never takes it for a pose.
pub fn is_query(bytes: &[u8]) -> bool {
    bytes.starts_with(&QUERY_MAGIC)
}

/// Encodes `request` with request id `id`.
pub fn encode_query(id: u32, request: &TerrainRequest) -> Vec<u8> {
    let (kind, from, to_local, tail) = match *request {
        TerrainRequest::HeightOfTerrain { at } => (KIND_HOT, at, false, [0.0; 4]),
        TerrainRequest::LineOfSight { from, to } => {
            let ([a, b, c], local) = to.wire();
            (KIND_LOS, from, local, [a, b, c, 0.0])
        }
        TerrainRequest::LineOfSightVector {
            from,
            azimuth_deg,
            elevation_deg,
            min_range_m,
            max_range_m,
        } => (
            KIND_LOS_VECTOR,
            from,
            false,
            [azimuth_deg, elevation_deg, min_range_m, max_range_m],
        ),
    };
    let (point, from_local) = from.wire();
    let flags =
        if from_local { QFLAG_FROM_LOCAL } else { 0 } | if to_local { QFLAG_TO_LOCAL } else { 0 };
    let mut w = Wr::new(ByteOrder::Little, QUERY_SIZE);
    w.raw(&QUERY_MAGIC)
        .u16(QUERY_VERSION)
        .u8(kind)
        .u8(flags)
        .u32(id)
        .u16(QUERY_SIZE as u16)
        .u16(0);
    for v in point.iter().chain(tail.iter()) {
        w.f64(*v);
    }
    let crc = crc32fast::hash(&w.buf);
    w.u32(crc);
    w.buf
}

/// Encodes `reply` as the answer to request `id`.
pub fn encode_reply(id: u32, reply: &TerrainReply) -> Vec<u8> {
    let mut height = 0.0;
    let mut range = 0.0;
    let mut normal = [0.0; 3];
    let mut point = [0.0; 3];
    let mut flags = 0u8;
    let (kind, status) = match *reply {
        TerrainReply::HeightOfTerrain(a) => (KIND_HOT, status_of(&a)),
        TerrainReply::LineOfSight(a) => (KIND_LOS, status_of(&a)),
    };
    match *reply {
        TerrainReply::HeightOfTerrain(Answer::Ready(s)) => {
            height = s.height_m;
            normal = s.normal_enu;
        }
        TerrainReply::LineOfSight(Answer::Ready(Some(hit))) => {
            let (p, local) = hit.point.wire();
            flags = AFLAG_HIT | if local { AFLAG_POINT_LOCAL } else { 0 };
            range = hit.range_m;
            normal = hit.normal_enu;
            point = p;
        }
        _ => {}
    }
    let mut w = Wr::new(ByteOrder::Little, REPLY_SIZE);
    w.raw(&REPLY_MAGIC)
        .u16(QUERY_VERSION)
        .u8(kind)
        .u8(status)
        .u32(id)
        .u16(REPLY_SIZE as u16)
        .u8(flags)
        .u8(0)
        .f64(height)
        .f64(range);
    for v in normal.iter().chain(point.iter()) {
        w.f64(*v);
    }
    let crc = crc32fast::hash(&w.buf);
    w.u32(crc);
    w.buf
}

fn status_of<T>(a: &Answer<T>) -> u8 {
    match a {
        Answer::Ready(_) => STATUS_READY,
        Answer::NoTerrain => STATUS_NO_TERRAIN,
        Answer::Pending => STATUS_PENDING,
    }
}

/// Decodes and validates a native query: its request id and the request.
pub fn decode_query(b: &[u8]) -> Result<(u32, TerrainRequest), DecodeError> {
    let r = header(b, &QUERY_MAGIC, QUERY_SIZE)?;
    let kind = r.u8(6).ok_or_else(truncated)?;
    let flags = r.u8(7).ok_or_else(truncated)?;
    let id = r.u32(8).ok_or_else(truncated)?;
    let known = match kind {
        KIND_HOT | KIND_LOS_VECTOR => QFLAG_FROM_LOCAL,
        KIND_LOS => QFLAG_FROM_LOCAL | QFLAG_TO_LOCAL,
        other => {
            return Err(bad(format!(
                "query kind {other} (offset 6) is not 1 (HOT), 2 (LOS segment) or 3 (LOS vector)"
            )))
        }
    };
    if flags & !known != 0 {
        return Err(bad(format!(
            "query flag bits {:#04x} (offset 7) are not defined for kind {kind}",
            flags & !known
        )));
    }
    let f = |off: usize| r.f64(off).ok_or_else(truncated);
    let from_names = if kind == KIND_HOT { AT } else { FROM };
    let from = position(&r, 16, flags & QFLAG_FROM_LOCAL != 0, from_names)?;
    let request = match kind {
        KIND_HOT => {
            for (off, name) in [
                (40, "unused[0]"),
                (48, "unused[1]"),
                (56, "unused[2]"),
                (64, "unused[3]"),
            ] {
                zero(name, off, f(off)?)?;
            }
            TerrainRequest::HeightOfTerrain { at: from }
        }
        KIND_LOS => {
            let to = position(&r, 40, flags & QFLAG_TO_LOCAL != 0, TO)?;
            zero("unused", 64, f(64)?)?;
            TerrainRequest::LineOfSight { from, to }
        }
        _ => {
            let azimuth_deg = f(40)?;
            let elevation_deg = f(48)?;
            let min_range_m = f(56)?;
            let max_range_m = f(64)?;
            check(
                "azimuth_deg",
                40,
                azimuth_deg,
                azimuth_deg.abs() <= MAX_ANGLE_DEG,
                "[-720, 720]",
            )?;
            check(
                "elevation_deg",
                48,
                elevation_deg,
                (-90.0..=90.0).contains(&elevation_deg),
                "[-90, 90]",
            )?;
            check(
                "min_range_m",
                56,
                min_range_m,
                (0.0..=MAX_WORLD_BOUND_M).contains(&min_range_m),
                "[0, 1e9]",
            )?;
            check(
                "max_range_m",
                64,
                max_range_m,
                (min_range_m..=MAX_WORLD_BOUND_M).contains(&max_range_m),
                "[min_range_m, 1e9]",
            )?;
            TerrainRequest::LineOfSightVector {
                from,
                azimuth_deg,
                elevation_deg,
                min_range_m,
                max_range_m,
            }
        }
    };
    Ok((id, request))
}

/// Decodes and validates a native answer: the request id it answers and the answer.
pub fn decode_reply(b: &[u8]) -> Result<(u32, TerrainReply), DecodeError> {
    let r = header(b, &REPLY_MAGIC, REPLY_SIZE)?;
    let kind = r.u8(6).ok_or_else(truncated)?;
    let status = r.u8(7).ok_or_else(truncated)?;
    let id = r.u32(8).ok_or_else(truncated)?;
    let flags = r.u8(14).ok_or_else(truncated)?;
    if kind != KIND_HOT && kind != KIND_LOS {
        return Err(bad(format!(
            "answer kind {kind} (offset 6) is not 1 (HOT) or 2 (LOS)"
        )));
    }
    if status > STATUS_PENDING {
        return Err(bad(format!(
            "answer status {status} (offset 7) is not 0 (ready), 1 (no terrain) or 2 (pending)"
        )));
    }
    let hit = kind == KIND_LOS && status == STATUS_READY && flags & AFLAG_HIT != 0;
    let known = if hit {
        AFLAG_HIT | AFLAG_POINT_LOCAL
    } else if kind == KIND_LOS && status == STATUS_READY {
        AFLAG_HIT
    } else {
        0
    };
    if flags & !known != 0 {
        return Err(bad(format!(
            "answer flag bits {:#04x} (offset 14) are not defined for kind {kind}, status {status}{}",
            flags & !known,
            if kind == KIND_LOS && status == STATUS_READY { ", no hit" } else { "" }
        )));
    }
    if r.u8(15).ok_or_else(truncated)? != 0 {
        return Err(bad("reserved byte (offset 15) is not 0"));
    }
    let f = |off: usize| r.f64(off).ok_or_else(truncated);
    let height = f(16)?;
    let range = f(24)?;
    let hot_ready = kind == KIND_HOT && status == STATUS_READY;
    if hot_ready {
        check(
            "height_m",
            16,
            height,
            (MIN_ALT_M..=MAX_ALT_M).contains(&height),
            "[-12000, 1e6]",
        )?;
    } else {
        zero("height_m", 16, height)?;
    }
    if hit {
        check(
            "range_m",
            24,
            range,
            (0.0..=MAX_WORLD_BOUND_M).contains(&range),
            "[0, 1e9]",
        )?;
    } else {
        zero("range_m", 24, range)?;
    }
    let normal = [f(32)?, f(40)?, f(48)?];
    if hot_ready || hit {
        unit_normal(normal)?;
    } else {
        for (i, v) in normal.iter().enumerate() {
            zero(NORMAL[i], 32 + 8 * i, *v)?;
        }
    }
    let point = if hit {
        Some(position(&r, 56, flags & AFLAG_POINT_LOCAL != 0, POINT)?)
    } else {
        for i in 0..3 {
            zero(
                ["point[0]", "point[1]", "point[2]"][i],
                56 + 8 * i,
                f(56 + 8 * i)?,
            )?;
        }
        None
    };
    let reply = match (kind, status) {
        (KIND_HOT, STATUS_READY) => TerrainReply::HeightOfTerrain(Answer::Ready(Surface {
            height_m: height,
            normal_enu: normal,
        })),
        (KIND_HOT, s) => TerrainReply::HeightOfTerrain(not_ready(s)),
        (_, STATUS_READY) => TerrainReply::LineOfSight(Answer::Ready(point.map(|point| LosHit {
            range_m: range,
            point,
            normal_enu: normal,
        }))),
        (_, s) => TerrainReply::LineOfSight(not_ready(s)),
    };
    Ok((id, reply))
}

fn not_ready<T>(status: u8) -> Answer<T> {
    if status == STATUS_NO_TERRAIN {
        Answer::NoTerrain
    } else {
        Answer::Pending
    }
}

/// Magic, version, length, CRC, size field and the request's reserved u16: the checks both
/// packets share, in the native pose packet's order.
fn header<'a>(b: &'a [u8], magic: &[u8; 4], size: usize) -> Result<Rd<'a>, DecodeError> {
    if !b.starts_with(magic) {
        return Err(DecodeError::BadMagic { protocol: P });
    }
    let r = Rd::new(b, ByteOrder::Little);
    let version = r.u16(4).ok_or_else(truncated)?;
    if version != QUERY_VERSION {
        return Err(DecodeError::BadVersion {
            protocol: P,
            found: version.into(),
            expected: QUERY_VERSION.into(),
        });
    }
    if b.len() != size {
        return Err(DecodeError::BadSize {
            protocol: P,
            len: b.len(),
            expected: size,
        });
    }
    let crc_at = size - 4;
    let found = r.u32(crc_at).ok_or_else(truncated)?;
    let computed = crc32fast::hash(&b[..crc_at]);
    if found != computed {
        return Err(DecodeError::BadCrc {
            protocol: P,
            found,
            computed,
        });
    }
    let field = r.u16(12).ok_or_else(truncated)?;
    if usize::from(field) != size {
        return Err(bad(format!(
            "size field (offset 12) is {field}, expected {size}"
        )));
    }
    if size == QUERY_SIZE && r.u16(14).ok_or_else(truncated)? != 0 {
        return Err(bad("reserved field (offset 14) is not 0"));
    }
    Ok(r)
}

/// Field names of a point: geodetic, then local.
type Names = ([&'static str; 3], [&'static str; 3]);
const AT: Names = (
    ["at.lat_deg", "at.lon_deg", "at.alt_m"],
    ["at.x", "at.y", "at.z"],
);
const FROM: Names = (
    ["from.lat_deg", "from.lon_deg", "from.alt_m"],
    ["from.x", "from.y", "from.z"],
);
const TO: Names = (
    ["to.lat_deg", "to.lon_deg", "to.alt_m"],
    ["to.x", "to.y", "to.z"],
);
const POINT: Names = (
    ["point.lat_deg", "point.lon_deg", "point.alt_m"],
    ["point.x", "point.y", "point.z"],
);
const NORMAL: [&str; 3] = ["normal.east", "normal.north", "normal.up"];

/// Reads and checks a point at `off`: latitude, longitude and altitude in a pose's ranges, or
/// local metres within the widest world bound.
fn position(r: &Rd, off: usize, local: bool, names: Names) -> Result<PosePosition, DecodeError> {
    let v = [0, 1, 2].map(|i| r.f64(off + 8 * i));
    let [Some(a), Some(b), Some(c)] = v else {
        return Err(truncated());
    };
    if local {
        for (i, x) in [a, b, c].into_iter().enumerate() {
            check(
                names.1[i],
                off + 8 * i,
                x,
                x.abs() <= MAX_WORLD_BOUND_M,
                "[-1e9, 1e9]",
            )?;
        }
        Ok(PosePosition::LocalEnu { x: a, y: b, z: c })
    } else {
        check(names.0[0], off, a, (-90.0..=90.0).contains(&a), "[-90, 90]")?;
        check(
            names.0[1],
            off + 8,
            b,
            (-180.0..360.0).contains(&b),
            "[-180, 360)",
        )?;
        check(
            names.0[2],
            off + 16,
            c,
            (MIN_ALT_M..=MAX_ALT_M).contains(&c),
            "[-12000, 1e6]",
        )?;
        Ok(PosePosition::Geodetic {
            lat_deg: a,
            lon_deg: b,
            alt_m: c,
        })
    }
}

fn unit_normal(n: [f64; 3]) -> Result<(), DecodeError> {
    for (i, v) in n.iter().enumerate() {
        check(
            NORMAL[i],
            32 + 8 * i,
            *v,
            v.abs() <= 1.0 + UNIT_TOLERANCE,
            "[-1, 1]",
        )?;
    }
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if (len - 1.0).abs() > UNIT_TOLERANCE {
        return Err(bad(format!(
            "normal (offset 32) has length {len}, expected a unit vector"
        )));
    }
    Ok(())
}

/// A value that must be finite and `ok`; the error names the field, its offset and the range.
fn check(name: &str, off: usize, v: f64, ok: bool, range: &str) -> Result<(), DecodeError> {
    if !v.is_finite() {
        Err(bad(format!(
            "field `{name}` (offset {off}) is not finite ({v})"
        )))
    } else if !ok {
        Err(bad(format!(
            "field `{name}` (offset {off}) = {v} is outside {range}"
        )))
    } else {
        Ok(())
    }
}

/// A field that does not apply must be 0 (bit for bit: −0 and NaN are refused too).
fn zero(name: &str, off: usize, v: f64) -> Result<(), DecodeError> {
    if v.to_bits() == 0 {
        Ok(())
    } else {
        Err(bad(format!(
            "field `{name}` (offset {off}) = {v} does not apply here and must be 0"
        )))
    }
}

fn bad(what: impl Into<String>) -> DecodeError {
    DecodeError::malformed(P, what)
}

fn truncated() -> DecodeError {
    DecodeError::truncated(P)
}

#[cfg(test)]
#[path = "native_query_tests.rs"]
mod tests;
