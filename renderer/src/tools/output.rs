//! Files written next to pictures: PNG (written atomically, never partial) and CSV/JSON.

use std::path::{Path, PathBuf};

/// Writes an RGBA8 PNG through a temporary file in the same folder and renames it into place,
/// so a failure never leaves a partial PNG behind.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), String> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(format!(
            "{}: cannot write PNG: {} bytes of pixels for {width}x{height} RGBA (expected {expected})",
            path.display(),
            rgba.len()
        ));
    }
    let tmp = temp_sibling(path);
    let result = image::save_buffer_with_format(
        &tmp,
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
        image::ImageFormat::Png,
    );
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(format!("{}: cannot write PNG: {e}", path.display()));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: cannot write PNG: {e}", path.display())
    })
}

/// Writes a text file atomically (temporary sibling + rename).
pub fn write_text(path: &Path, text: &str) -> Result<(), String> {
    let tmp = temp_sibling(path);
    std::fs::write(&tmp, text)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            format!("{}: cannot write: {e}", path.display())
        })
}

fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.partial"))
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
