//! Files written next to pictures: PNG and CSV/JSON, all through [`aerie_io`]'s atomic writer
//! (temporary sibling, checked writes, fsync, rename): a full disk or a failed write leaves the
//! earlier file or nothing, never a 0-byte or cut file, and the error names the file and the
//! OS reason.

use std::path::Path;
use std::sync::Arc;

use aerie_io::FileSystem;

/// Writes an RGBA8 PNG atomically.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), String> {
    write_png_in(aerie_io::real(), path, width, height, rgba)
}

/// [`write_png`] on the given file system (tests inject faults through it).
pub fn write_png_in(
    fs: Arc<dyn FileSystem>,
    path: &Path,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> Result<(), String> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(format!(
            "{}: cannot write PNG: {} bytes of pixels for {width}x{height} RGBA (expected {expected})",
            path.display(),
            rgba.len()
        ));
    }
    // Encoded in memory first, so an encoder error and a disk error are told apart and the
    // disk sees one checked pass.
    let mut png = Vec::with_capacity(expected / 2 + 1024);
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )
    .map_err(|e| format!("{}: cannot encode PNG: {e}", path.display()))?;
    aerie_io::write_atomic_in(fs, path, &png).map_err(|e| e.to_string())
}

/// Writes a text file atomically.
pub fn write_text(path: &Path, text: &str) -> Result<(), String> {
    write_text_in(aerie_io::real(), path, text)
}

/// [`write_text`] on the given file system.
pub fn write_text_in(fs: Arc<dyn FileSystem>, path: &Path, text: &str) -> Result<(), String> {
    aerie_io::write_atomic_in(fs, path, text.as_bytes()).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use aerie_io::{Faults, FaultyFs};

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn png_round_trips_and_failures_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let px: Vec<u8> = (0..2 * 3 * 4).map(|i| i as u8 * 7).collect();
        write_png(&p, 2, 3, &px).unwrap();
        let back = image::open(&p).unwrap().to_rgba8();
        assert_eq!(back.as_raw(), &px);
        // A buffer too small for the size is refused and nothing is left behind.
        let q = dir.path().join("b.png");
        assert!(write_png(&q, 5, 5, &px).is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // Unwritable folder: an error naming the path.
        let err = write_png(Path::new("/nonexistent-dir/x.png"), 2, 3, &px).unwrap_err();
        assert!(err.contains("/nonexistent-dir/x.png"), "{err}");
    }

    /// Noise, so the PNG does not compress to a few bytes.
    fn noise(w: u32, h: u32) -> Vec<u8> {
        let mut x = 0x1234_5678u32;
        (0..w * h * 4)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                x as u8
            })
            .collect()
    }

    #[test]
    fn a_full_disk_leaves_no_empty_or_cut_png_and_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let px = noise(64, 64);
        let fs = FaultyFs::new(Faults::full_after(4096));
        for i in 0..3 {
            let p = dir.path().join(format!("frame_{i:04}.png"));
            let err = write_png_in(fs.shared(), &p, 64, 64, &px).unwrap_err();
            assert!(err.contains(&p.display().to_string()), "{err}");
            assert!(err.contains("No space left on device"), "{err}");
        }
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
        let t = dir.path().join("frames.csv");
        let err = write_text_in(fs.shared(), &t, &"0,1,2\n".repeat(1000)).unwrap_err();
        assert!(
            err.contains("frames.csv") && err.contains("No space left"),
            "{err}"
        );
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
        // What fits is written whole.
        write_text_in(fs.shared(), &t, "frame\n0\n").unwrap();
        assert_eq!(std::fs::read_to_string(&t).unwrap(), "frame\n0\n");
    }

    #[test]
    fn enospc_at_writeback_is_caught_before_the_rename() {
        // Delayed allocation: every write is taken, the full disk shows only at fsync. An
        // unsynced rename would put a 0-byte PNG under the name.
        let dir = tempfile::tempdir().unwrap();
        let fs = FaultyFs::new(Faults {
            sync_errno: Some(28),
            ..Faults::default()
        });
        let p = dir.path().join("frame_0025.png");
        let err = write_png_in(fs.shared(), &p, 64, 64, &noise(64, 64)).unwrap_err();
        assert!(
            err.contains("frame_0025.png") && err.contains("No space left"),
            "{err}"
        );
        assert!(err.contains("fsync"), "{err}");
        let j = dir.path().join("summary.json");
        let err = write_text_in(fs.shared(), &j, "{}\n").unwrap_err();
        assert!(
            err.contains("summary.json") && err.contains("No space left"),
            "{err}"
        );
        assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
    }

    #[test]
    fn a_real_full_tmpfs_leaves_no_empty_png() {
        let disk = match aerie_io::tmpfs::SmallTmpfs::mount(32 * 1024) {
            Ok(d) => d,
            Err(why) => {
                eprintln!("skipped (no small tmpfs: {why}); the injected ENOSPC test covers it");
                return;
            }
        };
        let px = noise(128, 128);
        let p = disk.path().join("out.png");
        let err = write_png(&p, 128, 128, &px).unwrap_err();
        assert!(
            err.contains("out.png") && err.contains("No space left"),
            "{err}"
        );
        let j = disk.path().join("out.json");
        let err = write_text(&j, &"x".repeat(64 * 1024)).unwrap_err();
        assert!(
            err.contains("out.json") && err.contains("No space left"),
            "{err}"
        );
        assert!(disk.entries().is_empty(), "{:?}", disk.entries());
    }
}
