//! Tile selection, the decision half of the core technique (DESIGN.md "The terrain technique"):
//! for each clipmap level, the tiles of its ring; per tile an AABB from the baked min/max
//! (Earth curvature included) → frustum cull; the projected error
//! `ρ = ε·f·c / (z_min − ε)` (DESIGN.md, the bound that holds anywhere on screen) → the smallest
//! refinement r with ρ(ε(L−r)) ≤ τ. Pure CPU: plain data in, plain data out.

mod bound;
mod quadtree;
mod selection;
mod skirts;

pub use bound::{
    box_vertical_gain, curvature_interpolation_error, frustum_vertical_gain, min_view_depth,
    projected_error_px, tile_aabb,
};
pub use quadtree::{select_tiles, select_tiles_multi};
pub use selection::{
    DrawItem, LevelStats, LodMode, SelectParams, Selection, View, EARTH_RADIUS_M, MAX_REFINEMENT,
};
pub use skirts::neighbour_eps;

#[cfg(test)]
mod tests;
