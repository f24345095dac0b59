//! The host program: `tests/cigi-host/build.sh` builds the CIGI Class Library once into
//! `target/cigi-ccl/<arch>-<hash>/` and the host against it; here it is called once per test
//! process and architecture (a no-op after the first build: the script reuses its cache), so a
//! plain `cargo test` works without `make ccl` first.

use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

use crate::repo_root;

/// Where the CCL's source is: `$AERIE_CIGI_CCL`, else `../shared/tools/cigi-ccl` next to the
/// repository, else the unmodified copy in `third_party/cigi-ccl` (the order `build.sh` uses);
/// `Err` says where it looked.
pub fn ccl_source_dir() -> Result<PathBuf, String> {
    let candidates = match std::env::var_os("AERIE_CIGI_CCL") {
        Some(d) => vec![PathBuf::from(d)],
        None => vec![
            repo_root().join("../shared/tools/cigi-ccl"),
            repo_root().join("third_party/cigi-ccl"),
        ],
    };
    candidates
        .iter()
        .find(|d| d.join("include/CigiHostSession.h").is_file())
        .cloned()
        .ok_or_else(|| {
            format!(
                "the CIGI Class Library source is not at {} ($AERIE_CIGI_CCL, or \
                 ../shared/tools/cigi-ccl next to the repository, or third_party/cigi-ccl)",
                candidates
                    .iter()
                    .map(|d| d.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" nor ")
            )
        })
}

/// The CPU the host runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arch {
    /// This machine (little-endian x86-64 here and in CI).
    Native,
    /// A big-endian s390x host, cross-built and run under qemu-s390x: the CCL packs CIGI 3 in
    /// the CPU's byte order and never swaps what it sends, so only a big-endian CPU makes a
    /// big-endian host.
    S390x,
}

impl Arch {
    fn word(self) -> &'static str {
        match self {
            Arch::Native => "native",
            Arch::S390x => "s390x",
        }
    }

    /// The byte order its messages are in.
    pub fn byte_order(self) -> &'static str {
        match self {
            Arch::Native if cfg!(target_endian = "big") => "big",
            Arch::Native => "little",
            Arch::S390x => "big",
        }
    }
}

/// A built host program and how to start it.
#[derive(Debug, Clone)]
pub struct HostProgram {
    pub exe: PathBuf,
    /// The emulator it runs under, if any.
    pub runner: Option<&'static str>,
}

impl HostProgram {
    /// A command running the host with `args`.
    pub fn command(&self, args: &[String]) -> Command {
        let mut c = match self.runner {
            Some(r) => {
                let mut c = Command::new(r);
                c.arg(&self.exe);
                c
            }
            None => Command::new(&self.exe),
        };
        c.args(args);
        c
    }
}

fn build(arch: Arch) -> Result<HostProgram, String> {
    ccl_source_dir()?;
    let script = repo_root().join("tests/cigi-host/build.sh");
    let out = Command::new("bash")
        .arg(&script)
        .arg(arch.word())
        .current_dir(repo_root())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        return Err(format!(
            "{} {} failed ({}):\n{stderr}",
            script.display(),
            arch.word(),
            out.status
        ));
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let exe = PathBuf::from(stdout.lines().last().unwrap_or_default().trim());
    if !exe.is_file() {
        return Err(format!(
            "{} printed no host program path (stdout {stdout:?}, stderr {stderr})",
            script.display()
        ));
    }
    Ok(HostProgram {
        exe,
        runner: (arch == Arch::S390x).then_some("qemu-s390x"),
    })
}

/// The host program for `arch`, built (or found in the cache) once per test process.
pub fn host_program(arch: Arch) -> Result<&'static HostProgram, String> {
    static NATIVE: OnceLock<Result<HostProgram, String>> = OnceLock::new();
    static S390X: OnceLock<Result<HostProgram, String>> = OnceLock::new();
    let cell = match arch {
        Arch::Native => &NATIVE,
        Arch::S390x => &S390X,
    };
    cell.get_or_init(|| build(arch))
        .as_ref()
        .map_err(Clone::clone)
}
