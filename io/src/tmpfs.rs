//! A really full disk for tests: a tiny tmpfs, mounted when the tests run as root with
//! `mount` available (CI containers), otherwise `None` with the reason so the test can say
//! that it skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A mounted tmpfs of a few KiB, unmounted and removed on drop.
#[derive(Debug)]
pub struct SmallTmpfs {
    dir: PathBuf,
}

impl SmallTmpfs {
    /// Mounts a tmpfs of `bytes` (rounded up to pages by the kernel) on a fresh folder under
    /// the system temporary folder. `Err` says why it cannot (not root, no `mount`, …).
    pub fn mount(bytes: u64) -> Result<Self, String> {
        #[cfg(unix)]
        {
            // SAFETY: geteuid has no preconditions and touches no memory.
            if unsafe { libc::geteuid() } != 0 {
                return Err("not running as root, cannot mount a tmpfs".into());
            }
        }
        static N: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("aerie-full-disk-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let out = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={bytes}"), "tmpfs"])
            .arg(&dir)
            .output();
        match out {
            Ok(o) if o.status.success() => Ok(Self { dir }),
            Ok(o) => {
                let _ = std::fs::remove_dir(&dir);
                Err(format!(
                    "mount -t tmpfs failed: {}",
                    String::from_utf8_lossy(&o.stderr).trim()
                ))
            }
            Err(e) => {
                let _ = std::fs::remove_dir(&dir);
                Err(format!("cannot run mount: {e}"))
            }
        }
    }

    /// The mount point.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Names in the mount point (tests check no temporary is left).
    pub fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.dir)
            .map(|r| {
                r.filter_map(|e| e.ok())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    }
}

impl Drop for SmallTmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.dir).status();
        let _ = std::fs::remove_dir(&self.dir);
    }
}
