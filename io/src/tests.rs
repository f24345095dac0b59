use std::io::Write;
use std::path::Path;

use super::*;

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn writes_replace_the_old_file_and_leave_no_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.csv");
    write_atomic(&p, b"old\n").unwrap();
    write_atomic(&p, b"new contents\n").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"new contents\n");
    assert_eq!(names(dir.path()), ["a.csv"]);
}

#[test]
fn a_full_disk_names_the_file_keeps_the_old_one_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("frame.png");
    std::fs::write(&p, b"the earlier picture").unwrap();
    let fs = FaultyFs::new(Faults::full_after(1000));
    let err = write_atomic_in(fs.shared(), &p, &[7u8; 5000]).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains(&p.display().to_string()), "{msg}");
    assert!(msg.contains("No space left on device"), "{msg}");
    assert_eq!(err.step, "write");
    assert_eq!(std::fs::read(&p).unwrap(), b"the earlier picture");
    assert_eq!(names(dir.path()), ["frame.png"]);
    // The space of the removed temporary is free again: a file that fits is written.
    assert_eq!(fs.used(), 0);
    write_atomic_in(fs.shared(), &p, &[1u8; 900]).unwrap();
    assert_eq!(std::fs::read(&p).unwrap().len(), 900);
}

#[test]
fn short_writes_are_retried_to_completion() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.json");
    let fs = FaultyFs::new(Faults {
        max_write: Some(3),
        ..Faults::default()
    });
    let bytes: Vec<u8> = (0..1000u32).map(|i| (i * 31) as u8).collect();
    write_atomic_in(fs.shared(), &p, &bytes).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), bytes);
    assert!(fs.writes() >= 334, "{}", fs.writes());
}

#[test]
fn eio_fsync_and_rename_failures_leave_nothing_behind() {
    let cases = [
        (
            Faults {
                eio_on_write: Some(2),
                max_write: Some(10),
                ..Faults::default()
            },
            "write",
        ),
        (
            Faults {
                sync_errno: Some(libc::EIO),
                ..Faults::default()
            },
            "fsync",
        ),
        (
            Faults {
                fail_rename: true,
                ..Faults::default()
            },
            "rename",
        ),
    ];
    for (faults, step) in cases {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.bin");
        let err = write_atomic_in(FaultyFs::new(faults).shared(), &p, &[1u8; 100]).unwrap_err();
        assert_eq!(err.step, step);
        let msg = err.to_string();
        assert!(
            msg.contains("out.bin") && msg.contains("Input/output error"),
            "{msg}"
        );
        assert!(
            names(dir.path()).is_empty(),
            "{step}: {:?}",
            names(dir.path())
        );
    }
}

#[test]
fn an_ignored_write_error_still_refuses_to_commit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("stats.csv");
    let fs = FaultyFs::new(Faults {
        eio_on_write: Some(1),
        ..Faults::default()
    });
    let mut f = AtomicFile::create_in(fs.shared(), &p).unwrap();
    f.write_all(b"header\n").unwrap();
    assert!(f.write_all(b"row 1\n").is_err());
    // The caller carries on regardless: the next write fails with the first error too.
    let again = f.write_all(b"row 2\n").unwrap_err().to_string();
    assert!(again.contains("stats.csv"), "{again}");
    let err = f.commit().unwrap_err();
    assert_eq!(err.step, "write");
    assert!(names(dir.path()).is_empty());
}

#[test]
fn dropping_an_uncommitted_file_removes_the_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.txt");
    let mut f = AtomicFile::create(&p).unwrap();
    f.write_all(b"half").unwrap();
    assert!(f.temp_path().exists());
    drop(f);
    assert!(names(dir.path()).is_empty());
}

#[test]
fn mapped_files_are_allocated_first_and_a_full_disk_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("dem.f32");
    let mut f = AtomicFile::create(&p).unwrap();
    let mut map = f.map_preallocated(4096).unwrap();
    map.iter_mut().enumerate().for_each(|(i, b)| *b = i as u8);
    f.flush_map(&map).unwrap();
    drop(map);
    f.commit().unwrap();
    let back = std::fs::read(&p).unwrap();
    assert_eq!(back.len(), 4096);
    assert_eq!(back[300], 300u16 as u8);

    let fs = FaultyFs::new(Faults::full_after(1 << 20));
    let q = dir.path().join("big.f32");
    let mut f = AtomicFile::create_in(fs.shared(), &q).unwrap();
    let err = f.map_preallocated(2 << 20).unwrap_err();
    assert_eq!(err.step, "allocate");
    assert!(err.to_string().contains("big.f32"), "{err}");
    drop(f);
    assert_eq!(names(dir.path()), ["dem.f32"]);
}

#[test]
fn reads_through_the_harness_see_short_reads_and_bad_sectors() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pages.bin");
    let bytes: Vec<u8> = (0..10_000u32).map(|i| (i % 251) as u8).collect();
    std::fs::write(&p, &bytes).unwrap();
    let short = FaultyFs::new(Faults {
        max_read: Some(7),
        ..Faults::default()
    });
    let f = short.open(&p).unwrap();
    let mut buf = vec![0u8; 4096];
    assert_eq!(f.read_at(&mut buf, 100).unwrap(), 7);
    f.read_exact_at(&mut buf, 100).unwrap();
    assert_eq!(buf, bytes[100..4196]);
    let eof = f.read_exact_at(&mut buf, 8000).unwrap_err();
    assert_eq!(eof.kind(), std::io::ErrorKind::UnexpectedEof);
    assert!(eof.to_string().contains("10000"), "{eof}");

    let bad = FaultyFs::new(Faults {
        eio_at_read_offset: Some(5000),
        ..Faults::default()
    });
    let f = bad.open(&p).unwrap();
    f.read_exact_at(&mut buf, 0).unwrap();
    let e = f.read_exact_at(&mut buf, 4096).unwrap_err();
    assert_eq!(e.raw_os_error(), Some(libc::EIO));
}

#[test]
fn a_real_full_tmpfs_gives_enospc_not_sigbus() {
    let disk = match tmpfs::SmallTmpfs::mount(64 * 1024) {
        Ok(d) => d,
        Err(why) => {
            eprintln!("skipped: {why}");
            return;
        }
    };
    let p = disk.path().join("frame.png");
    let err = write_atomic(&p, &vec![9u8; 256 * 1024]).unwrap_err();
    assert!(err.to_string().contains("No space left on device"), "{err}");
    assert!(err.to_string().contains("frame.png"), "{err}");
    assert!(disk.entries().is_empty(), "{:?}", disk.entries());
    // A map larger than the disk: posix_fallocate refuses it before any store can fault.
    let q = disk.path().join("bake");
    let mut f = AtomicFile::create(&q).unwrap();
    let err = f.map_preallocated(1 << 20).unwrap_err();
    assert_eq!(err.step, "allocate");
    drop(f);
    assert!(disk.entries().is_empty(), "{:?}", disk.entries());
    write_atomic(&p, &[1u8; 1000]).unwrap();
    assert_eq!(disk.entries(), ["frame.png"]);
}
