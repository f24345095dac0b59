//! Streaming a tile store ([`crate::store`]) to the renderer: [`StreamedStore`] is the
//! store as a [`crate::source::TerrainSource`] — decoded pages in a [`PageCache`] with an
//! explicit byte budget (least recently used out, the coarsest levels pinned), filled by
//! worker threads (`loader`) that read, decode and verify the pages a [`RequestQueue`] hands
//! them, most wanted first. The frame thread never waits on I/O or decompression: what is not
//! resident answers [`crate::source::NotResident`] and is asked for; a page that fails is
//! remembered, answered `failed: true`, and never read again.
//!
//! Files: `cache` (pure LRU within a budget, pins), `queue` (pure: dedupe, priority, replace),
//! `rect_pages` (pure: which pages a sample rectangle reads), `loader` (the worker threads),
//! `streamed` (`StreamedStore`), `surface` (the queries' `SurfaceSource` over the resident
//! level-0 pages); tests in `tests`.

mod cache;
mod loader;
mod queue;
mod rect_pages;
mod streamed;
mod surface;

pub use cache::{Inserted, PageCache};
pub use loader::Loaded;
pub use queue::RequestQueue;
pub use rect_pages::{rect_pages, RectPages};
pub use streamed::{LoaderStats, StreamParams, StreamedStore};
pub use surface::StreamedSurface;

#[cfg(test)]
mod tests;
