//! Which pages of a store's imagery layer a level rectangle reads, and how their texels land
//! in it: `TerrainSource::gather_imagery`, the same whether the pages come from the streamed
//! cache or are read on the spot (a store loaded whole).

use super::{ImageryPage, Layout, PageId};

/// A rectangle of level texels and the pages holding its texels inside the raster.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageryRect {
    /// First texel per axis on its level's raster, and texels per axis (`rect.size · k`).
    pub texel: [i64; 2],
    pub size: [i64; 2],
    /// The pages, row by row, south first; empty when the rectangle misses the raster.
    pub pages: Vec<PageId>,
}

/// The texels of the level-`rect_level` rectangle of `rect_size` level samples from level-0
/// sample `rect_origin` (a `SampleRect`) at `k` texels per sample over a grid of `valid`
/// samples, and the pages of `layout` that hold them (texels outside the raster are in none:
/// transparent).
pub fn imagery_rect(
    layout: &Layout,
    k: u32,
    valid: [u32; 2],
    (rect_level, rect_origin, rect_size): (u32, [i64; 2], [u32; 2]),
) -> ImageryRect {
    let k = i64::from(k);
    let level = rect_level.min(layout.levels.len() as u32 - 1);
    let per = i64::from(layout.q * layout.page_tiles) * k;
    let extent = |n: u32| (i64::from(n) * k + (1 << level) - 1) >> level;
    let texel = [0, 1].map(|a| (rect_origin[a] >> rect_level) * k);
    let size = [0, 1].map(|a| i64::from(rect_size[a]) * k);
    // The level's last page also holds its edge sample's texels (past pages · per).
    let g = layout.levels[level as usize];
    let last = [g.pages_x, g.pages_y].map(|n| n.max(1) - 1);
    let span = |a: usize| {
        let (lo, hi) = (texel[a].max(0), (texel[a] + size[a]).min(extent(valid[a])));
        let page = |t: i64| ((t / per) as u32).min(last[a]);
        (lo < hi).then(|| (page(lo), page(hi - 1)))
    };
    let mut pages = Vec::new();
    if let (false, Some((px0, px1)), Some((py0, py1))) = (rect_size.contains(&0), span(0), span(1))
    {
        for py in py0..=py1 {
            for px in px0..=px1 {
                pages.push(PageId { level, px, py });
            }
        }
    }
    ImageryRect { texel, size, pages }
}

/// Copies the texels of `page` that lie in `r` into `out` (RGBA8, `r.size[0]` texels a row,
/// south row first).
pub fn copy_page_texels(r: &ImageryRect, page: &ImageryPage, out: &mut [u8]) {
    let ([x0, y0], [w, h]) = (r.texel, r.size);
    let [ox, oy] = [page.origin[0] as i64, page.origin[1] as i64];
    let [sw, sh] = [page.size[0] as i64, page.size[1] as i64];
    let (cx0, cx1) = (ox.max(x0), (ox + sw).min(x0 + w));
    let (cy0, cy1) = (oy.max(y0), (oy + sh).min(y0 + h));
    if cx0 >= cx1 {
        return;
    }
    let stride = w as usize * 4;
    for ty in cy0..cy1 {
        let src = (((ty - oy) * sw + (cx0 - ox)) * 4) as usize;
        let dst = (ty - y0) as usize * stride + ((cx0 - x0) * 4) as usize;
        let n = ((cx1 - cx0) * 4) as usize;
        out[dst..dst + n].copy_from_slice(&page.rgba[src..src + n]);
    }
}
