//! Output paths: every command creates the folders it writes into, so a fresh checkout's
//! `--out out/demo-still.png` works, and names the folder when it cannot. A run folder
//! (`fly`, `bench`) must be empty unless `--overwrite`, which removes only the files a previous
//! run of the same command writes there ([`RunFiles`]), so no stale frame sits next to a new
//! one and nothing else is lost. [`WriteFailures`] keeps a run going past a file it cannot
//! write, so its summary still says which files are missing.

use std::path::{Path, PathBuf};

use crate::app::failure::{bad_input, runtime, Failure};

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

/// The files one command writes into its output folder, by name: what `--overwrite` may remove.
#[derive(Debug, Clone, Copy)]
pub struct RunFiles {
    /// The command's name, for messages (`fly`).
    pub command: &'static str,
    /// Fixed file names at the top of the folder (`frames.csv`).
    pub names: &'static [&'static str],
    /// `(prefix, suffix)` pairs of numbered files at the top: `frame_` + digits + `.png`.
    pub numbered: &'static [(&'static str, &'static str)],
    /// `(prefix, suffix)` pairs with free text in between (`heatmap_` … `.png`).
    pub patterned: &'static [(&'static str, &'static str)],
    /// Numbered files inside sub-folders one level down (fly's channel folders).
    pub sub_numbered: &'static [(&'static str, &'static str)],
}

impl RunFiles {
    /// Whether `name`, at the top of the folder, is one of the command's files (or the
    /// temporary sibling of one, `.frame_0003.png.<anything>`).
    pub fn is_top(&self, name: &str) -> bool {
        self.top_exact(name) || temp_of(name, |n| self.top_exact(n))
    }

    /// Whether `name`, inside a sub-folder, is one of the command's files (or a temporary).
    pub fn is_sub(&self, name: &str) -> bool {
        let m = |n: &str| self.sub_numbered.iter().any(|&(p, s)| numbered(n, p, s));
        m(name) || temp_of(name, m)
    }

    fn top_exact(&self, name: &str) -> bool {
        self.names.contains(&name)
            || self.numbered.iter().any(|&(p, s)| numbered(name, p, s))
            || self.patterned.iter().any(|&(p, s)| {
                name.len() > p.len() + s.len() && name.starts_with(p) && name.ends_with(s)
            })
    }
}

/// `prefix` + one or more ASCII digits + `suffix`.
fn numbered(name: &str, prefix: &str, suffix: &str) -> bool {
    name.strip_prefix(prefix)
        .and_then(|r| r.strip_suffix(suffix))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

/// A temporary an interrupted write left next to a file `is_file` accepts: hidden, `.` + that
/// name + `.` + anything, or visible, that name + `.tmp…` / `.partial…`.
fn temp_of(name: &str, is_file: impl Fn(&str) -> bool) -> bool {
    let (rest, hidden) = match name.strip_prefix('.') {
        Some(rest) => (rest, true),
        None => (name, false),
    };
    rest.match_indices('.').any(|(i, _)| {
        let tail = &rest[i + 1..];
        i > 0
            && !tail.is_empty()
            && (hidden || tail.starts_with("tmp") || tail.starts_with("partial"))
            && is_file(&rest[..i])
    })
}

/// `aerie fly`: frames, channel frames, panoramas, `frames.csv`, `summary.json`.
pub const FLY_FILES: RunFiles = RunFiles {
    command: "fly",
    names: &["frames.csv", "summary.json"],
    numbered: &[("frame_", ".png"), ("panorama_", ".png")],
    patterned: &[],
    sub_numbered: &[("frame_", ".png")],
};

/// `aerie bench`: CSVs, summaries, charts and heat maps.
pub const BENCH_FILES: RunFiles = RunFiles {
    command: "bench",
    names: &[
        "results.csv",
        "summary.csv",
        "summary.md",
        "features.csv",
        "time_vs_error.png",
        "triangles_vs_error.png",
    ],
    numbered: &[],
    patterned: &[("heatmap_", ".png")],
    sub_numbered: &[],
};

/// Prepares the output folder of a run: creates it when missing; refuses a non-empty one
/// (exit 2, naming the folder and `--overwrite`) unless `overwrite`, which removes the files
/// `files` names (and sub-folders left empty by that) and keeps everything else. Returns how
/// many files were removed.
pub fn prepare_run_folder(
    flag: &str,
    out: &Path,
    overwrite: bool,
    files: &RunFiles,
) -> Result<usize, Failure> {
    if out.exists() && !out.is_dir() {
        return Err(bad_input(format!(
            "{flag} {}: is a file, expected a folder",
            out.display()
        )));
    }
    create_folder(flag, out, out)?;
    let entries = list(out)?;
    if entries.is_empty() {
        return Ok(0);
    }
    if !overwrite {
        let first = entries[0].file_name().unwrap_or_default().to_string_lossy();
        let n = entries.len();
        return Err(bad_input(format!(
            "{flag} {}: folder is not empty ({n} {}, e.g. {first}); pass --overwrite to \
             replace what an earlier `aerie {}` wrote there, or choose an empty folder",
            out.display(),
            if n == 1 { "entry" } else { "entries" },
            files.command
        )));
    }
    let mut removed = 0;
    for path in entries {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let meta = std::fs::symlink_metadata(&path).map_err(|e| io_failure(&path, "read", e))?;
        if meta.is_file() && files.is_top(&name) {
            remove(&path)?;
            removed += 1;
        } else if meta.is_dir() && !files.sub_numbered.is_empty() {
            let inner = list(&path)?;
            let ours: Vec<&PathBuf> = inner
                .iter()
                .filter(|p| {
                    p.is_file()
                        && files.is_sub(&p.file_name().unwrap_or_default().to_string_lossy())
                })
                .collect();
            for p in &ours {
                remove(p)?;
            }
            removed += ours.len();
            if !ours.is_empty() && ours.len() == inner.len() {
                std::fs::remove_dir(&path).map_err(|e| io_failure(&path, "remove folder", e))?;
            }
        }
    }
    Ok(removed)
}

/// The entries of `folder`, sorted by name (messages and removals in a stable order).
fn list(folder: &Path) -> Result<Vec<PathBuf>, Failure> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(folder).map_err(|e| io_failure(folder, "read folder", e))? {
        v.push(e.map_err(|e| io_failure(folder, "read folder", e))?.path());
    }
    v.sort();
    Ok(v)
}

fn remove(path: &Path) -> Result<(), Failure> {
    std::fs::remove_file(path).map_err(|e| io_failure(path, "remove", e))
}

fn io_failure(path: &Path, what: &str, e: std::io::Error) -> Failure {
    runtime(format!("{}: cannot {what}: {e}", path.display()))
}

/// One file a run could not write.
#[derive(Debug, Clone)]
pub struct FailedWrite {
    /// The frame it belongs to (None for CSVs, summaries, charts).
    pub frame: Option<u32>,
    pub path: PathBuf,
    /// The writer's message: the file and the OS reason.
    pub error: String,
}

/// The files of a run that could not be written. A run keeps going past a failed file (each
/// later file is tried again: space may come back, and the frames that did land stay
/// usable), still writes its CSV and summary listing the failures, and then exits 1 naming
/// the first one ([`WriteFailures::verdict`]).
#[derive(Debug, Default)]
pub struct WriteFailures {
    pub failed: Vec<FailedWrite>,
}

impl WriteFailures {
    /// Records the result of writing `path` (for `frame`); true when it was written.
    pub fn check(&mut self, frame: Option<u32>, path: &Path, r: Result<(), String>) -> bool {
        match r {
            Ok(()) => true,
            Err(error) => {
                self.failed.push(FailedWrite {
                    frame,
                    path: path.to_path_buf(),
                    error,
                });
                false
            }
        }
    }

    /// The frames with a file that was not written, ascending, each once.
    pub fn failed_frames(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.failed.iter().filter_map(|f| f.frame).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The failures for a summary: `[{"frame", "file", "error"}, …]`.
    pub fn json(&self) -> serde_json::Value {
        self.failed
            .iter()
            .map(|f| {
                serde_json::json!({
                    "frame": f.frame,
                    "file": f.path.display().to_string(),
                    "error": f.error,
                })
            })
            .collect()
    }

    /// Ok when every file was written; else exit 1 naming the first failed file and its
    /// reason, how many failed and which frames, and where the list is (`summary`, when it
    /// was written itself).
    pub fn verdict(&self, summary: Option<&Path>) -> Result<(), Failure> {
        let Some(first) = self.failed.first() else {
            return Ok(());
        };
        let frame = first
            .frame
            .map(|f| format!("frame {f}: "))
            .unwrap_or_default();
        let mut msg = format!("{frame}{}", first.error);
        let frames = self.failed_frames();
        if self.failed.len() > 1 || !frames.is_empty() {
            const SHOWN: usize = 12;
            let mut list: Vec<String> = frames.iter().take(SHOWN).map(u32::to_string).collect();
            if frames.len() > SHOWN {
                list.push(format!("… {} more", frames.len() - SHOWN));
            }
            msg.push_str(&format!(
                "; {} file(s) not written{}",
                self.failed.len(),
                if list.is_empty() {
                    String::new()
                } else {
                    format!(" (frames {})", list.join(", "))
                }
            ));
        }
        match summary {
            Some(s) => msg.push_str(&format!("; {} lists them", s.display())),
            None => msg.push_str("; no summary could be written"),
        }
        Err(runtime(msg))
    }
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

    #[test]
    fn run_files_are_recognised_by_name() {
        for n in [
            "frame_0000.png",
            "frame_12345.png",
            "panorama_0007.png",
            "frames.csv",
            "summary.json",
            ".frame_0003.png.partial",
            ".summary.json.tmp123",
            "frame_0004.png.tmp4711",
            "frames.csv.partial",
            "frames.csv.tmp",
        ] {
            assert!(FLY_FILES.is_top(n), "{n}");
        }
        for n in [
            "frame_.png",
            "frame_00a1.png",
            "frame_0001.jpg",
            "notes.txt",
            "hill.f32",
            ".frame_0003.png",
            "results.csv",
            ".hidden",
            "summary.json.bak",
        ] {
            assert!(!FLY_FILES.is_top(n), "{n}");
        }
        assert!(FLY_FILES.is_sub("frame_0002.png") && !FLY_FILES.is_sub("summary.json"));
        assert!(BENCH_FILES.is_top("heatmap_bounded_tau1_frame0004.png"));
        assert!(BENCH_FILES.is_top("summary.md") && !BENCH_FILES.is_top("frame_0000.png"));
        assert!(!BENCH_FILES.is_top("heatmap_.png"));
    }

    #[test]
    fn a_used_run_folder_needs_overwrite_which_removes_only_the_commands_files() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("flight");
        assert_eq!(
            prepare_run_folder("--out", &out, false, &FLY_FILES).unwrap(),
            0
        );
        assert!(out.is_dir(), "a missing folder is created");
        // An empty folder is fine without --overwrite.
        assert_eq!(
            prepare_run_folder("--out", &out, false, &FLY_FILES).unwrap(),
            0
        );
        for f in [
            "frame_0000.png",
            "frame_0199.png",
            "frames.csv",
            "notes.txt",
        ] {
            std::fs::write(out.join(f), b"x").unwrap();
        }
        std::fs::create_dir(out.join("left")).unwrap();
        std::fs::write(out.join("left/frame_0000.png"), b"x").unwrap();
        std::fs::create_dir(out.join("mine")).unwrap();
        std::fs::write(out.join("mine/frame_0000.png"), b"x").unwrap();
        std::fs::write(out.join("mine/keep.txt"), b"x").unwrap();
        let e = prepare_run_folder("--out", &out, false, &FLY_FILES).unwrap_err();
        assert_eq!(e.code, 2);
        assert!(
            e.message.contains(&out.display().to_string())
                && e.message.contains("--overwrite")
                && e.message.contains("not empty"),
            "{}",
            e.message
        );
        assert!(
            out.join("frame_0199.png").exists(),
            "nothing removed on refusal"
        );
        assert_eq!(
            prepare_run_folder("--out", &out, true, &FLY_FILES).unwrap(),
            5
        );
        let mut left: Vec<String> = walk(&out);
        left.sort();
        assert_eq!(left, ["mine", "mine/keep.txt", "notes.txt"]);
        // bench's --overwrite leaves a fly run's frames alone.
        std::fs::write(out.join("frame_0001.png"), b"x").unwrap();
        std::fs::write(out.join("summary.md"), b"x").unwrap();
        assert_eq!(
            prepare_run_folder("--out", &out, true, &BENCH_FILES).unwrap(),
            1
        );
        assert!(out.join("frame_0001.png").exists() && !out.join("summary.md").exists());
        // A file where the folder should be.
        let e = prepare_run_folder("--out", &out.join("notes.txt"), true, &FLY_FILES).unwrap_err();
        assert!(
            e.code == 2 && e.message.contains("is a file"),
            "{}",
            e.message
        );
    }

    fn walk(root: &Path) -> Vec<String> {
        let mut v = Vec::new();
        for e in std::fs::read_dir(root).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_dir() {
                for inner in walk(&p) {
                    v.push(format!("{rel}/{inner}"));
                }
            }
            v.push(rel);
        }
        v
    }

    #[test]
    fn write_failures_name_the_first_file_and_the_frames() {
        let mut w = WriteFailures::default();
        assert!(w.check(Some(0), Path::new("o/frame_0000.png"), Ok(())));
        assert!(w.verdict(None).is_ok());
        let err = |p: &str| {
            Err(format!(
                "{p}: cannot write PNG: No space left on device (os error 28)"
            ))
        };
        assert!(!w.check(
            Some(25),
            Path::new("o/frame_0025.png"),
            err("o/frame_0025.png")
        ));
        assert!(!w.check(
            Some(26),
            Path::new("o/left/frame_0026.png"),
            err("o/left/frame_0026.png")
        ));
        assert!(!w.check(
            Some(26),
            Path::new("o/panorama_0026.png"),
            err("o/panorama_0026.png")
        ));
        assert!(!w.check(None, Path::new("o/frames.csv"), err("o/frames.csv")));
        assert_eq!(w.failed_frames(), [25, 26]);
        let j = w.json();
        assert_eq!(j.as_array().unwrap().len(), 4);
        assert_eq!(j[0]["frame"], 25);
        assert_eq!(j[3]["frame"], serde_json::Value::Null);
        assert_eq!(j[3]["file"], "o/frames.csv");
        let e = w.verdict(Some(Path::new("o/summary.json"))).unwrap_err();
        assert_eq!(e.code, 1);
        assert!(
            e.message
                .starts_with("frame 25: o/frame_0025.png: cannot write PNG: No space")
                && e.message.contains("4 file(s) not written (frames 25, 26)")
                && e.message.ends_with("o/summary.json lists them"),
            "{}",
            e.message
        );
        let e = w.verdict(None).unwrap_err();
        assert!(
            e.message.ends_with("no summary could be written"),
            "{}",
            e.message
        );
    }
}
