//! Where a refined-tile pool's slots lie in its array image (pure).
//!
//! A pool of r holds ring tiles of (2^r q + 1)² samples, one per slot. While the pool has no
//! more slots than the device has array layers, each slot is a layer of its own, the image
//! one slot wide. A bigger pool (small tiles keep the same bytes in many more slots: tiles of
//! 9 need about 4× the slots of tiles of 17, tiles of 5 about 16×) packs k × k slots into every
//! layer instead, k the smallest that fits the layers, so its slot count is limited by the
//! image's bytes, not by the layer count.
//!
//! Invariants (checked by the tests below): every slot has one place, no two slots overlap,
//! every place lies inside the image, and a node's texels are read inside its slot's cell —
//! the vertex shader clamps to the cell (`shaders/terrain.vert` `fetch`), finding the cell as
//! the multiple of the slot side at or below the texel the instance names.

/// A pool's layout in its image: slots of `side` texels a side, `per_row` × `per_row` to a
/// layer, `layers` layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolAtlas {
    pub side: u32,
    pub per_row: u32,
    pub layers: u32,
    /// Slots placed (the pool's capacity); the last layer may have unused cells.
    pub slots: u32,
}

use aerie_terrain::pool::{RefinedTilePool, TileKey};

use crate::render::jobs::{ImageUpload, TEXEL_BYTES};

/// Where one slot lies: its layer and the texel of its south-west sample in that layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotPlace {
    pub layer: u32,
    pub x: u32,
    pub y: u32,
}

/// The layers a pool may use and the widest layer it may have: the device's
/// `maxImageArrayLayers` and `maxImageDimension2D`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolLimits {
    pub max_layers: u32,
    pub max_side: u32,
}

impl PoolLimits {
    /// What the devices we run on give (lavapipe and the desktop GPUs: 2048 layers, 16384
    /// texels and more); the renderer fits its pools to the device's own limits.
    pub const COMMON: PoolLimits = PoolLimits {
        max_layers: 2048,
        max_side: 16384,
    };
}

impl PoolAtlas {
    /// The layout of `slots` slots of `side` texels within `limits`: one slot a layer when they
    /// fit the layers, else the fewest slots a row that fit them. Err names what does not fit.
    pub fn new(side: u32, slots: u32, limits: PoolLimits) -> Result<Self, String> {
        let side = side.max(1);
        let max_layers = limits.max_layers.max(1);
        let fits = |k: u32| {
            u64::from(slots).div_ceil(u64::from(k) * u64::from(k)) <= u64::from(max_layers)
        };
        let mut per_row = 1;
        while !fits(per_row) {
            per_row += 1;
            if u64::from(per_row) * u64::from(side) > u64::from(limits.max_side) {
                return Err(format!(
                    "{slots} slots of {side}² texels need more than {max_layers} layers of \
                     {}² texels",
                    limits.max_side
                ));
            }
        }
        let layers = slots.div_ceil(per_row * per_row).max(1);
        Ok(Self {
            side,
            per_row,
            layers,
            slots,
        })
    }

    /// The upload of refined tile `key` into slot `slot`: (2^r q + 1)² samples at stride
    /// 2^(L−r) from the tile's south-west corner, into the slot's cell.
    pub fn upload(&self, tile_quads: u32, key: &TileKey, slot: u32) -> ImageUpload {
        let tile = (tile_quads as i64) << key.level;
        let place = self.place(slot);
        ImageUpload {
            layer: place.layer,
            texel: [place.x, place.y],
            size: [self.side, self.side],
            origin_sample: [key.tx as i64 * tile, key.ty as i64 * tile],
            step: 1 << (key.level - key.refinement),
        }
    }

    /// The image's width and height, texels.
    pub fn width(&self) -> u32 {
        self.per_row * self.side
    }

    /// Slot `slot`'s place (`slot` < `slots`): layers fill cell by cell, row by row.
    pub fn place(&self, slot: u32) -> SlotPlace {
        debug_assert!(slot < self.slots.max(1), "slot {slot} of {}", self.slots);
        let per_layer = self.per_row * self.per_row;
        let cell = slot % per_layer;
        SlotPlace {
            layer: slot / per_layer,
            x: (cell % self.per_row) * self.side,
            y: (cell / self.per_row) * self.side,
        }
    }

    /// The texel the vertex shader reads for a slot texel `t` (inside the slot: 0..side, or
    /// one outside for a normal's neighbour) of a node whose south-west vertex the instance
    /// names at layer texel `sw` (`place` + the node's offset in the slot): the cell is the
    /// multiple of `side` at or below `sw`, and `t` is clamped into it. The CPU twin of
    /// `shaders/terrain.vert` `fetch`.
    pub fn read_texel(&self, sw: [u32; 2], t: [i64; 2]) -> [u32; 2] {
        let side = i64::from(self.side);
        [0, 1].map(|a| {
            let base = i64::from(sw[a]) / side * side;
            (t[a] + base).clamp(base, base + side - 1) as u32
        })
    }
}

/// A refined-tile pool's bookkeeping: its LRU, the samples per slot side, 2^r(m−1)+1, and
/// where its slots lie in the pool's image.
#[derive(Debug, Clone)]
pub struct PoolSlots {
    pub side: u32,
    pub lru: RefinedTilePool,
    pub atlas: PoolAtlas,
}

impl PoolSlots {
    /// An empty pool of `slots` slots of `side` samples a side, laid out for common devices
    /// (one slot a layer while they fit; `PlanState::fit_pools` lays it out for the device).
    pub fn new(side: u32, slots: u32) -> Self {
        let atlas = PoolAtlas::new(side, slots, PoolLimits::COMMON).unwrap_or(PoolAtlas {
            side,
            per_row: 1,
            layers: slots.max(1),
            slots,
        });
        Self {
            side,
            lru: RefinedTilePool::new(slots),
            atlas,
        }
    }

    pub fn slot_bytes(&self) -> u64 {
        self.side as u64 * self.side as u64 * TEXEL_BYTES
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: PoolLimits = PoolLimits {
        max_layers: 8,
        max_side: 64,
    };

    #[test]
    fn a_pool_within_the_layers_keeps_one_slot_a_layer() {
        let a = PoolAtlas::new(17, 8, LIMITS).unwrap();
        assert_eq!((a.per_row, a.layers, a.width()), (1, 8, 17));
        assert_eq!(
            a.place(5),
            SlotPlace {
                layer: 5,
                x: 0,
                y: 0
            }
        );
        // An empty pool still has a 1-layer image (every binding valid).
        assert_eq!(PoolAtlas::new(17, 0, LIMITS).unwrap().layers, 1);
    }

    #[test]
    fn a_pool_past_the_layers_packs_the_fewest_slots_a_row() {
        // 9 slots need 2 a row (4 a layer, 3 layers); 33 need 3 a row (9 a layer, 4 layers).
        let a = PoolAtlas::new(17, 9, LIMITS).unwrap();
        assert_eq!((a.per_row, a.layers, a.width()), (2, 3, 34));
        let b = PoolAtlas::new(17, 33, LIMITS).unwrap();
        assert_eq!((b.per_row, b.layers), (3, 4));
        // 3 a row of 17 is 51 ≤ 64; 4 a row would be 68: more than 144 slots do not fit.
        assert!(PoolAtlas::new(17, 72, LIMITS).is_ok());
        let err = PoolAtlas::new(17, 73, LIMITS).unwrap_err();
        assert!(
            err.contains("73 slots of 17²") && err.contains("8 layers"),
            "{err}"
        );
    }

    #[test]
    fn every_slot_has_its_own_cell_inside_the_image() {
        for slots in [1, 7, 8, 9, 30, 72] {
            let a = PoolAtlas::new(17, slots, LIMITS).unwrap();
            let mut seen = std::collections::HashSet::new();
            for s in 0..slots {
                let p = a.place(s);
                assert!(p.layer < a.layers, "{slots}: {p:?}");
                assert!(
                    p.x + a.side <= a.width() && p.y + a.side <= a.width(),
                    "{p:?}"
                );
                assert_eq!((p.x % a.side, p.y % a.side), (0, 0), "{p:?}");
                assert!(seen.insert((p.layer, p.x, p.y)), "slot {s} shares {p:?}");
            }
        }
    }

    #[test]
    fn reads_are_clamped_into_the_nodes_own_cell() {
        let a = PoolAtlas::new(17, 30, LIMITS).unwrap();
        let p = a.place(5); // 4 a layer: layer 1, cell (1, 0), texels 17..34 across
        assert_eq!((p.layer, p.x, p.y), (1, 17, 0));
        // A node 8 texels into the slot: its neighbours one outside the slot stay in the cell.
        let sw = [p.x + 8, p.y + 8];
        assert_eq!(a.read_texel(sw, [-1, -1]), [17, 0]);
        assert_eq!(a.read_texel(sw, [17, 5]), [33, 5]);
        assert_eq!(a.read_texel(sw, [16, 16]), [33, 16]);
        // The first cell of a row and the slot's own corner.
        assert_eq!(a.read_texel([0, 0], [-1, 17]), [0, 16]);
    }
}
