//! Tile selection, the decision half of the core technique (DESIGN.md "The terrain technique"):
//! for each clipmap level, the tiles of its ring; per tile an AABB from the baked min/max
//! (Earth curvature included) → frustum cull; the projected error
//! `ρ = ε·f·c / (z_min − ε)` (DESIGN.md, the bound that holds anywhere on screen) → the smallest
//! refinement r with ρ(ε(L−r)) ≤ τ. Pure CPU: plain data in, plain data out.

mod bound;
mod box_bounds;
mod carry;
mod cdlod;
pub mod cdlod_morph;
mod coarser_roots;
mod horizon;
mod node_cache;
mod parts;
mod quadtree;
mod seen_quadrants;
mod selection;
mod skirts;
mod tess_density;
mod tessellation;
mod walk;

pub use bound::{
    box_vertical_gain, curvature_interpolation_error, frustum_vertical_gain, min_view_depth,
    projected_error_px, tile_aabb,
};
pub use carry::{Carry, CarryStats, AGED_WALKS_PER_FRAME, AGE_GRACE};
pub use cdlod::{box_distance, cdlod_decide, cdlod_range_m, CdlodDecision};
pub use horizon::{footprint, Footprint, Horizon, HorizonSet, MAX_OCCLUDERS, SECTORS};
pub use node_cache::NodeCache;
pub use quadtree::{select_tiles, select_tiles_multi, select_tiles_multi_ready};
pub use selection::{AllReady, TileReadiness};
pub use selection::{
    DrawItem, LevelStats, LodMode, SelectParams, Selection, View, EARTH_RADIUS_M, MAX_REFINEMENT,
};
#[cfg(test)]
use skirts::neighbour_eps;
pub use skirts::{node_skirts, NodeSkirts, SkirtMemo, ALL_EDGES};
pub use tess_density::{sample_density, TessDensity, DEFAULT_TOL_M, TESS_LEVEL_CAP, TESS_PATCH};
pub use tessellation::{
    distance_factor, edge_factor, rounded_level, select_patches, triangles_emitted, Spacing,
    TessParams, TessPatch, TessPlacement, TessStats,
};

#[cfg(test)]
mod equivalence_tests;
#[cfg(test)]
mod tests;
