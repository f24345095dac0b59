//! A whole store read back into memory as the dataset and bake it was imported from, so every
//! command that takes `--dem` takes a store too, on the renderer's in-memory path. The bake
//! comes from the bake section; every page is read and checked (CRC, content, its tables
//! against the bake section); the samples' CRC-32 must equal the header's source checksum, so
//! what is drawn is bit for bit what was imported.

use std::path::Path;

use crate::bake::ErrorBake;
use crate::dataset::Dataset;
use crate::heightfield::Heightfield;

use super::error::PageId;
use super::read::Store;

/// Reads every page of the store at `path`: the padded dataset (level 0) and the bake (every
/// level's ε, level 0's min/max). `Err` names the file and the page or field.
pub fn load_store(path: &Path) -> Result<(Dataset, ErrorBake), String> {
    let store = Store::open(path).map_err(|e| e.to_string())?;
    let h = store.header().clone();
    let layout = store.layout().clone();
    let (w, hh) = (h.width as usize, h.height as usize);
    let q = layout.q as usize;
    let bake = store.read_bake().map_err(|e| e.to_string())?;
    store.check_consistency(&bake).map_err(|e| e.to_string())?;
    let mut heights = vec![0f32; w * hh];
    // Level 0 holds every sample; the coarser levels are read to check them and their tables.
    for (l, lv) in layout.levels.iter().enumerate() {
        for py in 0..lv.pages_y {
            for px in 0..lv.pages_x {
                let id = PageId {
                    level: l as u32,
                    px,
                    py,
                };
                let page = store.read_page(id).map_err(|e| e.to_string())?;
                page.check_tables(&bake)
                    .map_err(|e| format!("{}: {id}: {e}", path.display()))?;
                let r = page.rect;
                let (c0, r0) = (r.tx0 as usize * q, r.ty0 as usize * q);
                for j in 0..r.rows as usize {
                    let row = &page.samples[j * r.cols as usize..][..r.cols as usize];
                    if l == 0 {
                        heights[(r0 + j) * w + c0..][..r.cols as usize].copy_from_slice(row);
                    } else if let Some(i) = row.iter().enumerate().position(|(i, v)| {
                        let (c, rr) = ((c0 + i) << l, (r0 + j) << l);
                        v.to_bits() != heights[rr * w + c].to_bits()
                    }) {
                        return Err(format!(
                            "{}: {id}: sample ({i}, {j}) is not level 0's sample at its place",
                            path.display()
                        ));
                    }
                }
            }
        }
    }
    let ds = Dataset {
        hf: Heightfield {
            width: w,
            height: hh,
            spacing_x: h.spacing_x,
            spacing_y: h.spacing_y,
            heights,
            geo: h.geo.clone(),
            voids_filled: h.voids_filled as usize,
            spacing_note: h.spacing_note.clone(),
        },
        valid_width: h.valid_width as usize,
        valid_height: h.valid_height as usize,
        source: format!("{} (store of {})", path.display(), h.sources.join(", ")),
    };
    let sum = ds.checksum();
    if sum != h.source_checksum {
        return Err(format!(
            "{}: the samples read back have CRC-32 {sum:#010x}, the header says {:#010x}: the store does not hold what was imported",
            path.display(),
            h.source_checksum
        ));
    }
    Ok((ds, bake))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::{bake, BakeParams};
    use crate::dataset::load_dataset;
    use crate::store::{write_store, ImportParams};

    /// The demo DEM imported and read back whole: the same padded samples, bit for bit, and the
    /// same bake, table for table, as loading and baking the file.
    #[test]
    fn a_store_reads_back_as_its_dataset_and_bake() {
        let dem = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/dem/N47E011.hgt.zip");
        let ds = load_dataset(&dem).unwrap();
        let params = BakeParams {
            tile_size: 17,
            levels: 0,
        };
        let b = bake(&ds, params, &|_, _| {});
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("inn.aerie");
        write_store(
            &path,
            &ds,
            &b,
            &ImportParams {
                sources: vec!["N47E011.hgt.zip".into()],
                page_tiles: 8,
                zstd_level: 3,
            },
            &|_, _| {},
        )
        .unwrap();
        let (ds2, b2) = load_store(&path).unwrap();
        assert_eq!(ds2.hf.width, ds.hf.width);
        assert_eq!(
            (ds2.valid_width, ds2.valid_height),
            (ds.valid_width, ds.valid_height)
        );
        assert!(ds2
            .hf
            .heights
            .iter()
            .zip(&ds.hf.heights)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        assert_eq!(ds2.hf.geo, ds.hf.geo);
        assert_eq!(b2, b);
        // A flipped byte in a page is named, not loaded.
        let mut bytes = std::fs::read(&path).unwrap();
        let at = Store::open(&path).unwrap().pages()[3].offset as usize + 5;
        bytes[at] ^= 0x40;
        std::fs::write(&path, bytes).unwrap();
        let e = load_store(&path).unwrap_err();
        assert!(e.contains("inn.aerie") && e.contains("level"), "{e}");
    }
}
