//! The host's questions about the ground, answered on the full-resolution surface: height of
//! terrain with its normal, and the first intersection of a line of sight.
//!
//! **Frame.** Local metres of the dataset: sample (col, row) of the padded heightfield is at
//! `x = col · spacing_x` (east), `y = row · spacing_y` (north), `z` = its height, the same
//! positions the terrain mesh is drawn at. Callers that hold geodetic points convert them to
//! this frame first.
//!
//! **Surface.** The level-0 triangles: every quad of four neighbouring samples split by
//! [`crate::mesh::TILE_DIAGONAL`] (south-west to north-east), exactly what is drawn at level 0
//! and what the error bake measures against. Only real data is terrain: the closed rectangle
//! from sample (0, 0) to sample (valid_width − 1, valid_height − 1). Padding
//! ([`crate::dataset::Dataset::is_padding`]) and everything outside answer `NoTerrain`, and a
//! line of sight never hits beyond the real data.
//!
//! **Reading heights.** Through [`SurfaceSource`]: per-tile maxima of every level (the bake's),
//! and the samples of level-0 tiles, which may be missing; a question that needs a missing tile
//! answers [`Lookup::Pending`] naming it. [`InMemorySource`] has every tile.
//!
//! Files: `source` (the trait, the in-memory source), `hierarchy` (maxima below a level-0
//! tile), `surface` (height of terrain), `ray` (line of sight).

mod hierarchy;
mod ray;
mod source;
mod surface;

pub use hierarchy::{build_tile as build_fine_tile, decode as decode_fine, fine_len};
pub use ray::{first_hit, Ray, RayError, RayHit};
pub use source::{InMemorySource, SourceError, SurfaceGrid, SurfaceSource, TileView};
pub use surface::{height_of_terrain, Ground};

/// An answer that may not be available: one for one with the host protocol's
/// ready / no terrain / pending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lookup<T> {
    /// The answer.
    Ready(T),
    /// No real terrain there (outside the data, over padding, or not a finite point).
    NoTerrain,
    /// Level-0 tile `tile` = [tx, ty] is needed and not resident; ask again once it is.
    Pending { tile: [u32; 2] },
}

impl<T> Lookup<T> {
    /// The answer, if ready.
    pub fn ready(self) -> Option<T> {
        match self {
            Lookup::Ready(t) => Some(t),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests;
