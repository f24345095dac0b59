//! Zip containers (`.hgt.zip`, `.npz`) read in memory.

use std::path::Path;

use super::error::{format_err, size_err, DemError};

pub(crate) type Zip<'a> = zip::ZipArchive<std::io::Cursor<&'a [u8]>>;

/// Opens an in-memory zip; a corrupt archive is an error naming the file.
pub(crate) fn open_zip<'a>(path: &Path, bytes: &'a [u8]) -> Result<Zip<'a>, DemError> {
    zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| format_err(path, format!("not a readable zip archive: {e}")))
}

/// Names of the archive's entries in index order.
pub(crate) fn zip_names(zip: &Zip<'_>) -> Vec<String> {
    (0..zip.len())
        .map(|i| zip.name_for_index(i).unwrap_or_default().to_string())
        .collect()
}

/// Decompresses one entry, refusing to inflate more than `max_len` bytes (zip bombs).
pub(crate) fn read_zip_entry(
    path: &Path,
    zip: &mut Zip<'_>,
    index: usize,
    max_len: u64,
) -> Result<Vec<u8>, DemError> {
    use std::io::Read as _;
    let name = zip.name_for_index(index).unwrap_or_default().to_string();
    let entry_err = |e: &dyn std::fmt::Display| {
        format_err(path, format!("zip entry `{name}` cannot be read: {e}"))
    };
    let mut file = zip.by_index(index).map_err(|e| entry_err(&e))?;
    if file.size() > max_len {
        return Err(size_err(
            path,
            format!(
                "zip entry `{name}` is {} bytes, more than the {max_len} bytes accepted",
                file.size()
            ),
        ));
    }
    // The declared size is only a hint; do not trust it for a big up-front allocation.
    let mut out = Vec::with_capacity(file.size().min(1 << 26) as usize);
    (&mut file)
        .take(max_len + 1)
        .read_to_end(&mut out)
        .map_err(|e| entry_err(&e))?;
    if out.len() as u64 > max_len {
        return Err(size_err(
            path,
            format!("zip entry `{name}` inflates to more than the {max_len} bytes accepted"),
        ));
    }
    Ok(out)
}
