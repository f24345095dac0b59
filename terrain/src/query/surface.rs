//! Height of terrain and the surface normal at a point: the level-0 triangles of the quad
//! under it, split by [`mesh::TILE_DIAGONAL`] and evaluated with [`mesh::quad_surface`], the
//! function that defines what is drawn.

use glam::DVec3;

use crate::mesh::{quad_surface, Diagonal, TILE_DIAGONAL};

use super::source::{SurfaceGrid, SurfaceSource};
use super::Lookup;

/// The ground at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Height of terrain, metres (the dataset's vertical datum).
    pub height_m: f64,
    /// Unit normal of the triangle the point lies in, local east-north-up (z > 0).
    pub normal: DVec3,
}

/// One of a quad's two triangles as a plane over the quad's local coordinates (u east, v
/// north, both in [0, 1]): `z = base + du · u + dv · v`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Plane {
    pub(super) base: f64,
    pub(super) du: f64,
    pub(super) dv: f64,
}

impl Plane {
    #[inline]
    pub(super) fn z(&self, u: f64, v: f64) -> f64 {
        self.base + self.du * u + self.dv * v
    }

    /// Unit normal in metres: the plane rises `du / spacing_x` per metre east, `dv /
    /// spacing_y` per metre north.
    #[inline]
    pub(super) fn normal(&self, grid: &SurfaceGrid) -> DVec3 {
        DVec3::new(-self.du / grid.spacing_x, -self.dv / grid.spacing_y, 1.0).normalize()
    }
}

/// The four corner heights of a quad.
#[derive(Debug, Clone, Copy)]
pub(super) struct Quad {
    pub(super) sw: f64,
    pub(super) se: f64,
    pub(super) nw: f64,
    pub(super) ne: f64,
}

impl Quad {
    /// The triangle containing (u, v): for the south-west to north-east diagonal, `u ≥ v` is
    /// the south-east triangle (sw, se, ne) — the diagonal itself included, as in
    /// [`quad_surface`] — and `u < v` the north-west one (sw, ne, nw).
    #[inline]
    pub(super) fn plane(&self, u: f64, v: f64) -> Plane {
        match TILE_DIAGONAL {
            Diagonal::SouthWestToNorthEast => {
                if u >= v {
                    Plane {
                        base: self.sw,
                        du: self.se - self.sw,
                        dv: self.ne - self.se,
                    }
                } else {
                    Plane {
                        base: self.sw,
                        du: self.ne - self.nw,
                        dv: self.nw - self.sw,
                    }
                }
            }
        }
    }

    /// Signed distance-like value that is ≥ 0 on the south-east triangle's side of the
    /// diagonal (the side [`Quad::plane`] picks for `u ≥ v`).
    #[inline]
    pub(super) fn side(u: f64, v: f64) -> f64 {
        match TILE_DIAGONAL {
            Diagonal::SouthWestToNorthEast => u - v,
        }
    }

    #[inline]
    pub(super) fn max(&self) -> f64 {
        self.sw.max(self.se).max(self.nw).max(self.ne)
    }
}

/// The quad holding real point (x, y) and the point's coordinates in it, or `None` off the
/// real data. A point on a grid line belongs to the quad east (north) of it, except on the
/// data's east (north) border, where it belongs to the quad west (south) of it.
#[inline]
pub(super) fn locate(grid: &SurfaceGrid, x: f64, y: f64) -> Option<(usize, usize, f64, f64)> {
    let (east, north) = grid.real_extent_m();
    // Written so that NaN fails too.
    if !(x >= 0.0 && x <= east && y >= 0.0 && y <= north) {
        return None;
    }
    let (fx, fy) = (grid_coord(x, grid.spacing_x), grid_coord(y, grid.spacing_y));
    let col = (fx.floor() as usize).min(grid.valid_width - 2);
    let row = (fy.floor() as usize).min(grid.valid_height - 2);
    Some((col, row, fx - col as f64, fy - row as f64))
}

/// `x / spacing`, except that a point placed at a sample as the mesh places it (`col ·
/// spacing`) gives `col` exactly, whatever the division rounds to; so the height there is the
/// sample itself.
#[inline]
fn grid_coord(x: f64, spacing: f64) -> f64 {
    let f = x / spacing;
    let r = f.round();
    if r * spacing == x {
        r
    } else {
        f
    }
}

/// Height of terrain and normal at (x, y), local metres from sample (0, 0). `NoTerrain` off
/// the real data (outside the grid, over padding, or not finite); `Pending` when the tile
/// holding the point is not resident. The height equals [`quad_surface`] at the point, bit for
/// bit, so it is the height drawn at level 0; the normal is the containing triangle's, with
/// the conventions of [`Quad::plane`] on the diagonal and of [`locate`] on grid lines.
pub fn height_of_terrain<S: SurfaceSource + ?Sized>(src: &S, x: f64, y: f64) -> Lookup<Ground> {
    let grid = src.grid();
    let Some((col, row, u, v)) = locate(grid, x, y) else {
        return Lookup::NoTerrain;
    };
    let q = grid.tile_quads;
    let (tx, ty) = ((col / q) as u32, (row / q) as u32);
    let Some(tile) = src.tile(tx, ty) else {
        return Lookup::Pending { tile: [tx, ty] };
    };
    let (i, j) = (col % q, row % q);
    let c = Quad {
        sw: tile.h(i, j),
        se: tile.h(i + 1, j),
        nw: tile.h(i, j + 1),
        ne: tile.h(i + 1, j + 1),
    };
    Lookup::Ready(Ground {
        height_m: quad_surface(c.sw, c.se, c.nw, c.ne, u, v),
        normal: c.plane(u, v).normal(grid),
    })
}
