//! What the store's page files share (the tile store and its imagery layer): a page's bytes
//! read at their offset and checked against their CRC-32, and a batch of pages made on all
//! cores, each compressed with its worker's own zstd compressor, handed back in index order.

use std::ops::Range;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use aerie_io::InFile;

use super::error::{PageError, PageId};
use super::format::Layout;

/// The `len` bytes of page `id` at `offset` of `file` (named `path` in errors), whose CRC-32
/// must be `crc`: a short read or a mismatch is an error naming the page and its bytes.
pub fn read_verified(
    file: &dyn InFile,
    path: &Path,
    id: PageId,
    offset: u64,
    len: u32,
    crc: u32,
) -> Result<Vec<u8>, PageError> {
    let end = offset + u64::from(len);
    let mut buf = vec![0u8; len as usize];
    file.read_exact_at(&mut buf, offset)
        .map_err(|err| PageError::Read {
            path: path.to_path_buf(),
            page: id,
            offset,
            end,
            reason: err.to_string(),
        })?;
    let got = crc32fast::hash(&buf);
    if got != crc {
        return Err(PageError::Checksum {
            path: path.to_path_buf(),
            page: id,
            offset,
            end,
            got,
            want: crc,
        });
    }
    Ok(buf)
}

/// `make(page, compressor)` for every page of `batch` (index positions of `layout`) on all
/// cores, `tick` after each; the results in index order, or the first error.
pub fn par_pages<T: Send>(
    layout: &Layout,
    batch: Range<usize>,
    zstd_level: i32,
    tick: &(dyn Fn() + Sync),
    make: &(dyn Fn(PageId, &mut zstd::bulk::Compressor<'static>) -> Result<T, String> + Sync),
) -> Result<Vec<T>, String> {
    let n = batch.len();
    let threads = std::thread::available_parallelism()
        .map(|t| t.get())
        .unwrap_or(1)
        .clamp(1, n.max(1));
    let next = AtomicUsize::new(batch.start);
    type Part<T> = Vec<(usize, T)>;
    let parts: Vec<Result<Part<T>, String>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| -> Result<Part<T>, String> {
                    let mut out = Vec::new();
                    let mut z =
                        zstd::bulk::Compressor::new(zstd_level).map_err(|e| e.to_string())?;
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= batch.end {
                            return Ok(out);
                        }
                        let (level, px, py) = layout.page_at(i).expect("in layout");
                        out.push((i - batch.start, make(PageId { level, px, py }, &mut z)?));
                        tick();
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("page worker thread"))
            .collect()
    });
    let mut pages: Vec<Option<T>> = (0..n).map(|_| None).collect();
    for p in parts {
        for (i, page) in p? {
            pages[i] = Some(page);
        }
    }
    Ok(pages
        .into_iter()
        .map(|p| p.expect("every page made"))
        .collect())
}
