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
//! **Conventions.** Height of terrain is [`crate::mesh::quad_surface`] at the point, bit for
//! bit (a point at a sample, `x = col · spacing_x`, gives the sample itself). Its normal is the
//! unit normal (z > 0) of the triangle containing the point: on the diagonal, the south-east
//! triangle (the one `quad_surface` evaluates there); on a grid line, the quad east (north) of
//! it, except on the data's east (north) border, the quad west (south). A line-of-sight hit
//! is the first point of the ray on or below the surface (definition and the cases of rays
//! starting below ground or entering from outside: [`first_hit`]); its normal is the triangle
//! hit, and on an edge shared by two triangles either one's.
//!
//! **Reading heights.** Through [`SurfaceSource`]: per-tile maxima of every level (the bake's),
//! and the samples of level-0 tiles, which may be missing; a question that needs a missing tile
//! answers [`Lookup::Pending`] naming it. [`InMemorySource`] has every tile.
//!
//! **Speed and memory.** A line of sight descends a max-height quadtree front to back: the
//! bake's per-tile maxima above level-0 tiles, byte-quantised block maxima below them
//! ([`hierarchy`]: ≈ q²/3 bytes per tile, 0.33 byte per sample at m = 17, 84 MiB on a 16385²
//! grid), quads at the bottom; a ray above a node's maximum skips it whole. `query_timing`
//! (terrain/examples) and the `query` bench measure it.
//!
//! Files: `source` (the trait, the in-memory source), `hierarchy` (maxima below a level-0
//! tile), `surface` (height of terrain), `ray` (line of sight), `lookup` (the answer type).

pub mod hierarchy;
mod lookup;
mod ray;
mod source;
mod surface;

pub use lookup::Lookup;
pub use ray::{first_hit, Ray, RayError, RayHit};
pub use source::{InMemorySource, SourceError, SurfaceGrid, SurfaceSource, TileView};
pub use surface::{height_of_terrain, Ground};

#[cfg(test)]
mod tests;
