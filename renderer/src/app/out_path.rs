//! Output paths: every command creates the folders it writes into, so a fresh checkout's
//! `--out out/demo-still.png` works, and names the folder when it cannot.

use std::path::{Path, PathBuf};

use crate::app::failure::{bad_input, Failure};

/// Makes sure `out` can be written as a file: creates its folder (and the folders above it)
/// when missing, and refuses a path that is a folder. `flag` names the argument in the error.
pub fn prepare_out_file(flag: &str, out: &Path) -> Result<(), Failure> {
    if out.is_dir() {
        return Err(bad_input(format!(
            "{flag} {}: is a folder, expected a file name",
            out.display()
        )));
    }
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_folder(flag, out, parent)?;
    }
    Ok(())
}

/// Creates the output folder `out` (and the folders above it) when missing.
pub fn prepare_out_folder(flag: &str, out: &Path) -> Result<(), Failure> {
    create_folder(flag, out, out)
}

/// `path` with `suffix` appended to its file name: the file written next to it
/// (`big.f32` → `big.f32.json`).
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

fn create_folder(flag: &str, out: &Path, folder: &Path) -> Result<(), Failure> {
    std::fs::create_dir_all(folder).map_err(|e| {
        bad_input(format!(
            "{flag} {}: cannot create folder {}: {e}",
            out.display(),
            folder.display()
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_folders_are_created() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a/b/c.png");
        prepare_out_file("--out", &file).unwrap();
        assert!(dir.path().join("a/b").is_dir());
        assert!(!file.exists(), "only the folder is made");
        let folder = dir.path().join("x/y");
        prepare_out_folder("--out", &folder).unwrap();
        assert!(folder.is_dir());
        // Existing folders and a bare file name are fine.
        prepare_out_file("--out", &file).unwrap();
        prepare_out_folder("--out", &folder).unwrap();
        prepare_out_file("--out", Path::new("frame.png")).unwrap();
    }

    #[test]
    fn a_folder_that_cannot_be_made_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let blocker = dir.path().join("file");
        std::fs::write(&blocker, b"x").unwrap();
        let out = blocker.join("sub/frame.png");
        let e = prepare_out_file("--out", &out).unwrap_err();
        assert_eq!(e.code, 2);
        let folder = blocker.join("sub").display().to_string();
        assert!(
            e.message.starts_with("--out ") && e.message.contains(&format!("folder {folder}")),
            "{}",
            e.message
        );
        let e = prepare_out_folder("--record", &blocker.join("d")).unwrap_err();
        assert!(e.message.starts_with("--record "), "{}", e.message);
        let e = prepare_out_file("--out", dir.path()).unwrap_err();
        assert!(e.message.contains("is a folder"), "{}", e.message);
    }

    #[test]
    fn suffixes_are_appended_to_the_whole_name() {
        assert_eq!(
            with_suffix(Path::new("d/big.f32"), ".json"),
            PathBuf::from("d/big.f32.json")
        );
        assert_eq!(
            with_suffix(Path::new("x.aerie-bake"), ".csv"),
            PathBuf::from("x.aerie-bake.csv")
        );
    }
}
