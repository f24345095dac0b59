//! The bake file's constants and byte layout: where each level section starts.

/// First 8 bytes of every bake file.
pub const BAKE_MAGIC: [u8; 8] = *b"AERIEBAK";
/// The format version this build writes and reads.
pub const BAKE_VERSION: u32 = 3;
/// Header bytes before the first level section.
pub const HEADER_SIZE: usize = 96;
/// File name suffix of bake files.
pub const BAKE_EXTENSION: &str = "aerie-bake";

pub(super) struct Section {
    pub(super) offset: usize,
    pub(super) tiles_x: u32,
    pub(super) tiles_y: u32,
}

pub(super) struct Layout {
    pub(super) sections: Vec<Section>,
    pub(super) total: u64,
}

/// f32 values per tile in level `l`'s section: min + max at level 0, ε over each tile's four
/// quadrants at level 1, over each of its 16 blocks above.
pub(super) fn values_per_tile(l: u32) -> usize {
    match l {
        0 => 2,
        1 => 4,
        _ => 16,
    }
}

/// Byte size of level `l`'s section with n tiles.
pub(super) fn section_size(l: u32, n: usize) -> usize {
    16 + 4 * values_per_tile(l) * n
}

pub(super) fn file_layout(width: u32, height: u32, m: u32, levels: u32) -> Layout {
    let q = u64::from(m - 1);
    let mut offset = HEADER_SIZE;
    let mut sections = Vec::new();
    for l in 0..levels {
        let t = q << l;
        let tiles_x = ((u64::from(width) - 1) / t) as u32;
        let tiles_y = ((u64::from(height) - 1) / t) as u32;
        sections.push(Section {
            offset,
            tiles_x,
            tiles_y,
        });
        offset += section_size(l, tiles_x as usize * tiles_y as usize);
    }
    Layout {
        sections,
        total: offset as u64 + 4,
    }
}
