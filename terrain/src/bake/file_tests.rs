//! The bake file's format 3 (quadrants at level 1, blocks above): its sizes, a round trip,
//! values that are not ε refused by place, and an older format replaced on first use.

use super::format::HEADER_SIZE;
use super::tests::ds;
use super::*;
use crate::dataset::Dataset;

/// A grid padded on both sides (60 × 100 real samples in 65 × 129) with 5 levels of 5-vertex
/// tiles: levels 2..=4 carry blocks.
fn grid() -> (Dataset, ErrorBake) {
    let d = ds(60, 100, |c, r| {
        (((c * 37 + r * 11) % 23) as f32) * 1.5 + ((c as f32) * 0.3).sin() * 40.0
    });
    let params = BakeParams {
        tile_size: 5,
        levels: 0,
    };
    let b = bake(&d, params, &|_, _| {});
    assert_eq!(b.levels.len(), 5);
    (d, b)
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Byte offset of each level's section, from the section headers.
fn section_offsets(bytes: &[u8], levels: usize) -> Vec<usize> {
    let mut at = HEADER_SIZE;
    let mut v = Vec::new();
    for l in 0..levels {
        v.push(at);
        let n = u32_at(bytes, at + 4) as usize * u32_at(bytes, at + 8) as usize;
        at += 16 + 4 * n * [2, 4, 16][l.min(2)];
    }
    assert_eq!(at + 4, bytes.len());
    v
}

/// The file CRC recomputed after an edit.
fn reseal(bytes: &mut [u8]) {
    let end = bytes.len() - 4;
    let c = crc32fast::hash(&bytes[..end]);
    bytes[end..].copy_from_slice(&c.to_le_bytes());
}

#[test]
fn format_3_keeps_quadrants_at_level_1_and_blocks_above_and_reads_back() {
    let (d, b) = grid();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.aerie-bake");
    write_bake(&p, &b).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(u32_at(&bytes, 8), 3);
    assert_eq!(BAKE_VERSION, 3);
    assert_eq!(bytes.len() as u64, b.file_size());
    let at = section_offsets(&bytes, b.levels.len());
    let f32s =
        |at: usize, n: usize| -> Vec<u32> { (0..n).map(|k| u32_at(&bytes, at + 4 * k)).collect() };
    let bits = |v: &[f32]| -> Vec<u32> { v.iter().map(|x| x.to_bits()).collect() };
    // Level 1: 4 values a tile, row-major over level 0's tiles: level 0's coarse ε.
    let n1 = b.levels[1].len();
    assert_eq!(f32s(at[1] + 16, 4 * n1), bits(&b.levels[0].coarse_eps));
    // Levels ≥ 2: 16 a tile, row-major over level L−2's tiles: level L−2's fine ε.
    for (l, &at) in at.iter().enumerate().skip(2) {
        let n = b.levels[l].len();
        assert_eq!(b.levels[l - 2].len(), 16 * n);
        assert_eq!(
            f32s(at + 16, 16 * n),
            bits(&b.levels[l - 2].fine_eps),
            "level {l}"
        );
    }
    let back = read_bake(&p, &d).unwrap();
    assert_eq!(back, b);
    // Measured blocks, not their parents' bound: tighter somewhere.
    assert!((0..b.levels.len() - 2).any(|l| {
        let (child, parent) = (&b.levels[l], &b.levels[l + 1]);
        child.fine_eps.iter().enumerate().any(|(i, &f)| {
            let (cx, cy) = (i as u32 % child.tiles_x, i as u32 / child.tiles_x);
            f < parent.coarse_eps[((cy / 2) * parent.tiles_x + cx / 2) as usize]
        })
    }));
}

#[test]
fn a_value_that_is_not_an_eps_is_refused_naming_level_tile_and_byte() {
    let (_, b) = grid();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.aerie-bake");
    write_bake(&p, &b).unwrap();
    let good = std::fs::read(&p).unwrap();
    let at = section_offsets(&good, b.levels.len());
    let tiles0 = b.levels[0].tiles_x as usize;
    let tiles1 = b.levels[1].tiles_x as usize;
    for (level, k, v, field, of, tx) in [
        (1, 5, f32::NAN, "quadrant ε", 0, tiles0),
        (3, 7, -1.0, "block ε", 1, tiles1),
        (2, 0, f32::INFINITY, "block ε", 0, tiles0),
    ] {
        let mut bytes = good.clone();
        let off = at[level] + 16 + 4 * k;
        bytes[off..off + 4].copy_from_slice(&v.to_le_bytes());
        reseal(&mut bytes);
        std::fs::write(&p, &bytes).unwrap();
        let e = read_bake_file(&p).unwrap_err();
        assert!(
            matches!(&e, BakeError::Corrupt { field: f, offset, .. } if f == field && *offset == off as u64),
            "{e:?}"
        );
        let msg = e.to_string();
        for part in [
            format!("byte offset {off}"),
            format!(
                "level {level} over level {of}'s tile ({}, {})",
                k % tx,
                k / tx
            ),
            format!("index {k}"),
        ] {
            assert!(msg.contains(&part), "`{msg}` lacks `{part}`");
        }
    }
}

/// Format 2's bytes of `b`: each level ≥ 1 keeps 4 values a tile, the quadrants (row-major
/// over level L−1's tiles), as the format-2 encoder wrote them.
fn format_2_bytes(b: &ErrorBake, format_3: &[u8]) -> Vec<u8> {
    let mut out = format_3[..HEADER_SIZE].to_vec();
    out[8..12].copy_from_slice(&2u32.to_le_bytes());
    for t in &b.levels {
        for v in [t.level, t.tiles_x, t.tiles_y, 0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let arrays: Vec<&[f32]> = match t.level {
            0 => vec![&t.min, &t.max],
            l => vec![&b.levels[l as usize - 1].coarse_eps],
        };
        for v in arrays.into_iter().flatten() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    let total = out.len() as u64 + 4;
    out[64..72].copy_from_slice(&total.to_le_bytes());
    let hcrc = crc32fast::hash(&out[..92]);
    out[92..96].copy_from_slice(&hcrc.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    reseal(&mut out);
    out
}

#[test]
fn a_format_2_bake_is_replaced_on_first_use_saying_why() {
    let (d, b) = grid();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.aerie-bake");
    write_bake(&p, &b).unwrap();
    let old = format_2_bytes(&b, &std::fs::read(&p).unwrap());
    assert!(old.len() < b.file_size() as usize);
    std::fs::write(&p, &old).unwrap();
    let e = read_bake(&p, &d).unwrap_err();
    assert!(matches!(e, BakeError::Version { found: 2, .. }), "{e:?}");
    let params = BakeParams {
        tile_size: 5,
        levels: 0,
    };
    let (got, outcome) = load_or_bake(&d, &p, params, false, &|_, _| {}).unwrap();
    let BakeOutcome::Replaced(why) = outcome else {
        panic!("{outcome:?}")
    };
    for part in [
        "format version 2",
        "byte offset 8",
        "16 blocks",
        "version 3",
    ] {
        assert!(why.contains(part), "`{why}` lacks `{part}`");
    }
    assert_eq!(got, b);
    assert_eq!(read_bake(&p, &d).unwrap(), b);
    assert_eq!(u32_at(&std::fs::read(&p).unwrap(), 8), 3);
    // The next use finds it up to date.
    let (_, outcome) = load_or_bake(&d, &p, params, false, &|_, _| {}).unwrap();
    assert_eq!(outcome, BakeOutcome::UpToDate);
}
