//! Writing a bake onto a full or failing disk: an error naming the file and the reason, never
//! `SIGBUS`, never a cut bake or a temporary left behind.

use std::path::Path;

use aerie_io::{Faults, FaultyFs};

use super::tests::ds;
use super::*;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn small_bake() -> (crate::dataset::Dataset, ErrorBake) {
    let d = ds(257, 257, |c, r| ((c * 7 + r * 13) % 17) as f32);
    let params = BakeParams {
        tile_size: 5,
        levels: 0,
    };
    let params = BakeParams {
        levels: params.resolve_levels(&d).unwrap(),
        ..params
    };
    let b = bake(&d, params, &|_, _| {});
    (d, b)
}

#[test]
fn enospc_midway_names_the_bake_keeps_the_old_one_and_leaves_no_temporary() {
    let (d, b) = small_bake();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("dem.f32.aerie-bake");
    write_bake(&p, &b).unwrap();
    let size = b.file_size();
    let fs = FaultyFs::new(Faults::full_after(size / 2));
    let err = write_bake_in(fs.shared(), &p, &b).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, BakeError::Write { .. }), "{msg}");
    assert!(msg.contains("dem.f32.aerie-bake"), "{msg}");
    assert!(msg.contains("No space left on device"), "{msg}");
    // The earlier bake is untouched and still reads; nothing else is in the folder.
    read_bake(&p, &d).unwrap();
    assert_eq!(names(dir.path()), ["dem.f32.aerie-bake"]);
    // Short writes and an EIO on a later write: complete file or nothing.
    let short = FaultyFs::new(Faults {
        max_write: Some(100),
        ..Faults::default()
    });
    let q = dir.path().join("other.aerie-bake");
    write_bake_in(short.shared(), &q, &b).unwrap();
    assert_eq!(
        read_bake(&q, &d).unwrap().source_checksum,
        b.source_checksum
    );
    let eio = FaultyFs::new(Faults {
        max_write: Some(100),
        eio_on_write: Some(3),
        ..Faults::default()
    });
    std::fs::remove_file(&q).unwrap();
    let err = write_bake_in(eio.shared(), &q, &b).unwrap_err().to_string();
    assert!(
        err.contains("other.aerie-bake") && err.contains("Input/output error"),
        "{err}"
    );
    assert_eq!(names(dir.path()), ["dem.f32.aerie-bake"]);
}

#[test]
fn a_real_full_disk_is_an_error_not_sigbus() {
    let disk = match aerie_io::tmpfs::SmallTmpfs::mount(16 * 1024) {
        Ok(d) => d,
        Err(why) => {
            eprintln!(
                "skipped (no small tmpfs: {why}); the injected ENOSPC test covers the writer"
            );
            return;
        }
    };
    let (d, b) = small_bake();
    assert!(b.file_size() > 16 * 1024, "{}", b.file_size());
    let p = disk.path().join("dem.f32.aerie-bake");
    let err = load_or_bake(&d, &p, b.params, false, &|_, _| {}).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, BakeError::Write { .. }), "{msg}");
    assert!(msg.contains("No space left on device"), "{msg}");
    assert!(disk.entries().is_empty(), "{:?}", disk.entries());
}
